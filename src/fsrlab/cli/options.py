"""What the command modules share: option parsers, JSON output, one-line errors, and the options and helpers of
the recording commands (sensor and area, load cell, virtual device, window, live view, run loading, the meter's
circuit on --port), and the output
policy as the commands use it (``parser=out_path``, :func:`checked`, :func:`check_out`, the ``--overwrite`` help texts).

A command module imports these from here, never another command module's names.

Option parsers, for ``typer.Option(..., parser=...)``; each turns a bad value into a usage error
that :func:`fsrlab.cli.main` prints as one line naming the option ("fsrlab: error: Invalid value
for --r: '1m' is ambiguous: ..."), exit code 2; none accepts ``nan`` or ``inf``:

========================  ==================================================================
``ohms``                  resistance: 10k, 10kΩ, 10kohm, 4k7, 1M, 1meg; ``1m`` refused
``farads``                capacitance: 4.7n, 4.7nF, 470p, 4n7; ``1m`` refused
``volts``                 voltage: 5, 5V, 600mV
``hertz``                 frequency: 6478.5, 6.4785k, 6.4785kHz
``pascals``               stress: 322k, 322kPa, 4.73MPa
``metres``                length: 4.418n, 4.418nm; ``5m`` refused (metres or milli?)
``electronvolts``         energy in eV: 0.223, 0.223eV, 223meV
``seconds``               duration: 90, 90s, 1.5min, 2h, 500ms, 250us; ``1m`` refused
``fraction``              0.1 or 10%; a value above 1 without ``%`` is refused
``number``                a plain number without unit or prefix
``areas``                 area: 71.3mm2, 71.3mm², 0.713cm2, 7.13e-5m2 (a bare number is m²)
``masses``                mass: 500g, 0.5kg, 250mg, 0 (a bare number other than 0 is refused)
``mass_list``             comma-separated masses: 0,50g,100g,0.2kg (strictly increasing)
``eng``                   any engineering notation, unit letters ignored (lenient, older)
========================  ==================================================================
"""

from __future__ import annotations

import functools
import inspect
import json
import math
import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import typer

from fsrlab.errors import ParameterError
from fsrlab.io.jsonable import to_jsonable
from fsrlab.units import format_eng, parse_eng, parse_quantity

__all__ = ["eng", "ohms", "farads", "volts", "hertz", "pascals", "metres", "electronvolts", "seconds",
           "fraction", "number", "areas", "masses", "mass_list", "emit_json", "to_jsonable", "fail", "option_names",
           "plain_numbers"]


def eng(text: str | float) -> float:
    """Parse an option value in engineering notation (``10k``, ``4.7n``, ``1M``).

    Use as ``typer.Option(..., parser=eng)``; a bad value becomes a one-line usage error.
    """
    try:
        return parse_eng(text, name=None)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None


def _parser(name: str, quantity: str, doc: str) -> Callable[[str | float], float]:
    """An option parser for one quantity of :data:`fsrlab.units.QUANTITIES`."""

    def parse(text: str | float) -> float:
        try:
            return parse_quantity(text, quantity)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None

    parse.__name__ = parse.__qualname__ = name
    parse.__doc__ = doc
    return parse


ohms = _parser("ohms", "resistance", "Resistance [Ω]: 10k, 10kΩ, 10kohm, 4k7, 1M, 1meg; 1m is refused as ambiguous.")
farads = _parser("farads", "capacitance", "Capacitance [F]: 4.7n, 4.7nF, 470p, 4n7; 1m is refused as ambiguous.")
volts = _parser("volts", "voltage", "Voltage [V]: 5, 5V, 600mV; another quantity's unit is refused.")
hertz = _parser("hertz", "frequency", "Frequency [Hz]: 6478.5, 6.4785k, 6.4785kHz; another quantity's unit is refused.")
pascals = _parser("pascals", "stress", "Stress [Pa]: 322k, 322kPa, 4.73MPa; another quantity's unit is refused.")
metres = _parser("metres", "length", "Length [m]: 4.418n, 4.418nm; 5m is refused (5 m or 5 mm?).")
electronvolts = _parser("electronvolts", "energy", "Energy in electronvolts [eV]: 0.223, 0.223eV, 223meV.")
seconds = _parser("seconds", "duration", "Duration [s]: 90, 90s, 1.5min, 2h, 500ms, 250us; 1m is refused (minutes or "
        "milli?).")
fraction = _parser("fraction", "fraction", "Fraction: 0.1 or 10%; a value above 1 without % is refused, never read as "
        "percent.")
number = _parser("number", "number", "A plain finite number (2, 7.5, 1e3), without unit letters or prefixes.")

_MEASURE = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-zµ²0-9]*)$")
_AREA_UNITS = {"": 1.0, "m2": 1.0, "m²": 1.0, "cm2": 1e-4, "cm²": 1e-4, "mm2": 1e-6, "mm²": 1e-6}
_MASS_UNITS = {"kg": 1.0, "g": 1e-3, "mg": 1e-6}


def _measure(text: str | float, units: dict, what: str, examples: str) -> tuple[float, str]:
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        value, unit = float(text), ""
    else:
        m = _MEASURE.match(str(text).strip())
        if not m or m.group(2) not in units:
            raise typer.BadParameter(f"cannot read {text!r} as {what}; write e.g. {examples}")
        value, unit = float(m.group(1)) * units[m.group(2)], m.group(2)
    if not math.isfinite(value):
        raise typer.BadParameter(f"{text!r} is not a finite {what.split()[-1]}; write e.g. {examples}")
    return value, unit


def areas(text: str | float) -> float:
    """Area [m²]: 71.3mm2, 71.3mm², 0.713cm2, 7.13e-5m2; a bare number is in m²."""
    return _measure(text, _AREA_UNITS, "an area", "71.3mm2, 0.713cm2, 7.13e-5m2")[0]


def masses(text: str | float) -> float:
    """Mass [kg]: 500g, 0.5kg, 250mg; 0 without a unit; any other bare number is refused (g or kg?)."""
    value, unit = _measure(text, {**_MASS_UNITS, "": 1.0}, "a mass", "500g, 0.5kg, 250mg")
    if unit == "" and value != 0:
        raise typer.BadParameter(f"{text!r} has no unit: write {text}g or {text}kg (a mass in g, kg or mg)")
    return value


def mass_list(text: str) -> list[float]:
    """Comma-separated masses [kg], strictly increasing and ≥ 0: ``0,50g,100g,0.2kg``.

    A value in another unit, a negative mass, or a list that does not increase is refused, naming
    the value.
    """
    items = [t.strip() for t in str(text).split(",")]
    if not items or any(not t for t in items):
        raise typer.BadParameter(f"{text!r}: give comma-separated masses such as 0,50g,100g,200g (no empty item)")
    out: list[float] = []
    for t in items:
        try:
            v = masses(t)
        except typer.BadParameter as exc:
            raise typer.BadParameter(f"value {t!r}: {exc.message}") from None
        if v < 0:
            raise typer.BadParameter(f"value {t!r}: a mass must be >= 0")
        if out and not v > out[-1]:
            raise typer.BadParameter(f"value {t!r} is not larger than the mass before it ({out[-1] * 1e3:g} g): "
                                     "give the masses in increasing order")
        out.append(v)
    return out


def emit_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout."""
    typer.echo(json.dumps(to_jsonable(obj), indent=2))


def fail(message: str, field: str | None = None) -> None:
    """End the command with one line on stderr and exit code 2.

    Parameters
    ----------
    message : str
        What is wrong and what is allowed.
    field : str, optional
        The option or argument at fault, e.g. ``"--r"``.
    """
    raise typer.BadParameter(plain_numbers(message), param_hint=field)


# numpy >= 2 prints scalars as np.float64(37.8); arrays as array([1., 2.]).
_NUMPY_SCALAR = re.compile(r"\b(?:np|numpy)\.(?:float|int|uint|complex|bool|str)_?\d*\(([^()]*)\)")
_NUMPY_ARRAY = re.compile(r"\barray\((\[[^()]*\])(?:,\s*dtype=[\w.]+)?\)")


def plain_numbers(message: str) -> str:
    """``message`` with numpy reprs replaced by the plain values: ``np.float64(37.8)`` → ``37.8``.

    Parameters
    ----------
    message : str
        An error message, e.g. one a model wrote with ``{value!r}``.

    Returns
    -------
    str
        The message as a user should read it.
    """
    message = _NUMPY_SCALAR.sub(lambda m: m.group(1).strip("'\""), message)
    return _NUMPY_ARRAY.sub(lambda m: " ".join(m.group(1).split()), message)


@contextmanager
def option_names(mapping: dict[str, str]) -> Iterator[None]:
    """Re-raise a library error as the invalid value of the option its parameter is.

    An :class:`~fsrlab.errors.FsrlabError` whose ``parameter`` is in ``mapping`` becomes that option's
    invalid value with the error's ``reason`` (numpy reprs as plain numbers, :func:`plain_numbers`); its
    message is not read. Any other error passes as it is (``fsrlab.cli.main`` says it in one line).

    Parameters
    ----------
    mapping : dict
        Library parameter name → option, e.g. ``{"modulus_pa": "--modulus"}``.
    """
    from fsrlab.errors import FsrlabError

    try:
        yield
    except FsrlabError as exc:
        if exc.parameter in mapping:  # the library names its parameter: no message is read
            raise typer.BadParameter(plain_numbers(exc.reason), param_hint=mapping[exc.parameter]) from None
        raise


# ------------------------------------------------------------------ pieces the commands share

PROFILE_HELP = "Virtual stress profile: triangle, sine, steps or hold."
PEAK_HELP = "Peak stress of the profile [Pa]: 50k, 50kPa, 0.1MPa."
PERIOD_HELP = "Cycle time of the profile [s]: 4, 4s, 500ms, 1.5min."
C_OFF_HELP = "C_off switched in by range 1 [F]: 1n, 1nF, 470p."
CORRUPT_HELP = "Probability that a frame gets a bit flipped [1]: 0..1 or a percentage, 0.05 or 5%."
DROP_HELP = "Probability that a frame is not sent [1]: 0..1 or a percentage, 0.05 or 5%."
SEED_HELP = "Random seed of the virtual device's noise and faults (an integer)."
SENSOR_HELP = ("Sensor preset, for its sensing area (stress = force / area): flexiforce-a201 (9.53 mm diameter, "
                "71.3 mm²) or interlink-402 (12.7 mm diameter, 126.7 mm²).")
AREA_HELP = "Sensing area [m²] instead of a preset: 71.3mm2, 0.713cm2, 7.13e-5m2."
LOADCELL_HELP = ("Load-cell calibration JSON (fsrlab loadcell tare/scale): HX711 counts -> force_n [N]. "
                  "Default with --virtual: the virtual load cell's own parameters.")
NO_LOADCELL_HELP = "Virtual device: emulate a meter without an HX711 (ref_ok 0: reference columns empty)."
RATE_HELP = "Virtual device: the HX711's output data rate [samples/s]: 10 or 80."
SPEED_HELP = ("With --virtual: realtime (one window per window length of wall time, as hardware) or max (as fast as "
              "this computer runs the device; the recording time and the run's times are then the device's simulated "
              "clock).")


def sensor_area(sensor: str | None, area: float | None) -> tuple[dict | None, float | None]:
    """The sidecar's ``sensor`` and the area [m²] from --sensor or --area (None, None: neither)."""
    if sensor is not None and area is not None:
        fail("give --sensor or --area, not both", "--sensor")
    if sensor is not None:
        from fsrlab.physics.presets import SENSOR_PRESETS

        key = sensor.strip().lower()
        if key not in SENSOR_PRESETS:
            fail(f"must be one of {', '.join(SENSOR_PRESETS)}, got {sensor!r}", "--sensor")
        preset = SENSOR_PRESETS[key]
        return preset.to_dict(), preset.area_m2
    if area is not None:
        if not 1e-8 <= area <= 1.0:
            fail(f"must be from 0.01 mm² to 1 m², got {area:g} m²", "--area")
        return {"model": "unnamed sensor (--area)", "area_m2": area}, area
    return None, None


def virtual_sensor_option(sensor: str | None):
    """The sensor model and the sidecar's ``sensor`` when --sensor names a virtual sensor (virtual-fsr,
    paper-a201-1..4), else ``(None, None)``."""
    from fsrlab.bench.protocols import VIRTUAL_SENSORS, virtual_sensor

    key = (sensor or "").strip().lower()
    if key not in VIRTUAL_SENSORS:
        return None, None
    model, text = virtual_sensor(key)
    return model, {"model": text, "area_m2": model.area_m2}


def loadcell_option(path: Path | None, option: str = "--loadcell", scaled: bool = True):
    """The load-cell calibration of ``path`` (None: None); one line naming the option otherwise."""
    if path is None:
        return None
    from fsrlab.acquisition.loadcell import LoadCellError, load_loadcell

    if not path.exists():
        fail(f"{path} does not exist; write one with fsrlab loadcell tare", option)
    try:
        cal = load_loadcell(path)
    except (LoadCellError, OSError) as exc:
        fail(getattr(exc, "reason", None) or str(exc), option)  # the file's error, without the parameter's name
    if scaled and not cal.scaled:
        fail(f"{path} has a tare but no scale factor: run fsrlab loadcell scale --mass 500g --cal {path}", option)
    return cal


def check_rate(rate: int) -> None:
    if rate not in (10, 80):
        fail(f"must be 10 or 80 samples/s (the HX711's RATE pin), got {rate}", "--hx711-rate")


def check_virtual(profile: str, peak: float, period: float, c_off: float, corrupt: float, drop: float,
                   seed: int | None) -> None:
    """One-line errors, each naming its own option, for the virtual device's options."""
    from fsrlab.virtual.sources import PROFILE_KINDS

    if profile not in PROFILE_KINDS:
        fail(f"must be one of {', '.join(PROFILE_KINDS)}, got {profile!r}", "--profile")
    if not peak > 0:
        fail(f"must be > 0 Pa, got {peak:g} Pa", "--peak")
    if not period > 0:
        fail(f"must be > 0 s, got {period:g} s", "--period")
    if not c_off >= 0:
        fail(f"must be >= 0 F, got {c_off:g} F", "--c-off")
    for name, v in (("--corrupt", corrupt), ("--drop", drop)):
        if not 0 <= v <= 1:
            fail(f"must be in 0..1, got {v:g}", name)
    if seed is not None and seed < 0:
        fail(f"must be an integer >= 0, got {seed}", "--seed")


def make_virtual_device(profile: str, peak: float, period: float, c_off: float, seed: int | None,
                    corrupt: float, drop: float, load_cell: bool = True, rate: int = 80, area_m2: float | None = None,
                    sensor_model=None, speed: str = "realtime"):
    from fsrlab.acquisition.loadcell import LoadCellModel
    from fsrlab.physics.sensor import VirtualFSR
    from fsrlab.virtual.device import Faults, VirtualDevice
    from fsrlab.virtual.sources import VIRTUAL_CIRCUIT, PhysicsSource, StressProfile

    prof = StressProfile(kind=profile, peak_pa=peak, period_s=period)
    if sensor_model is not None:
        sensor = sensor_model
    else:
        sensor = VirtualFSR() if area_m2 is None else VirtualFSR(area_m2=area_m2)
    cell = LoadCellModel(rate_sps=rate) if load_cell else None
    try:
        source = PhysicsSource(prof, sensor=sensor, circuit=VIRTUAL_CIRCUIT.replace(c_off_farad=c_off))
    except ValueError:  # the sensor model has no valid response up to this stress
        fail(f"the virtual sensor model has no valid response up to {format_eng(peak, 'Pa')} (its resistance would not "
             "be positive); choose a smaller peak, e.g. 50k", "--peak")
    return VirtualDevice(source, faults=Faults(corrupt=corrupt, drop=drop), seed=seed, load_cell=cell,
                         speed=speed), source


def check_speed(speed: str, virtual: bool, flag: str = "--virtual") -> None:
    """One line naming ``--speed`` for a pacing other than realtime/max, or max on hardware."""
    if speed not in ("realtime", "max"):
        fail(f"must be realtime or max, got {speed!r}", "--speed")
    if speed == "max" and not virtual:
        fail(f"max is for a virtual bench ({flag}); hardware runs in real time", "--speed")


def window_ms_option(window_s: float) -> int:
    """The window in whole milliseconds, as the meter takes it (10 ms .. 60 s)."""
    from fsrlab.acquisition.protocol import WINDOW_MS_MAX, WINDOW_MS_MIN

    ms = round(window_s * 1000.0, 6)
    if not WINDOW_MS_MIN <= ms <= WINDOW_MS_MAX:
        fail(f"must be {WINDOW_MS_MIN} ms to {WINDOW_MS_MAX // 1000} s, got {window_s:g} s", "--window")
    if ms != int(ms):
        fail(f"the meter counts whole milliseconds, got {ms:g} ms: write {math.floor(ms)}ms or {math.ceil(ms)}ms",
             "--window")
    return int(ms)


from fsrlab.cli.console import Keyboard, LiveView, fmt_value, sigterm_as_interrupt  # noqa: E402,F401
from fsrlab.cli.outputs import OVERWRITE_DIR_HELP, OVERWRITE_HELP, check_out, checked, out_path  # noqa: E402,F401


def virtual_bench(steps, seed: int | None, area_m2: float | None, gravity_m_s2: float):
    """A virtual meter on a bench that places the plan's masses: ``(device, bench, place)``.

    ``place(step)`` starts that placement on the bench and returns its time since START [s] (the
    procedure's ``place``); the meter has the virtual device's emulated HX711. One line naming ``--masses``
    when the virtual sensor has no response up to the largest mass.
    """
    from fsrlab.physics.sensor import VirtualFSR
    from fsrlab.virtual.bench_source import BenchSource
    from fsrlab.virtual.device import VirtualDevice

    try:
        bench = BenchSource([s.mass_kg * gravity_m_s2 for s in steps],
                            sensor=VirtualFSR() if area_m2 is None else VirtualFSR(area_m2=area_m2))
    except ValueError:
        fail(f"the virtual sensor model has no valid response up to {max(s.mass_kg for s in steps) * 1e3:g} g on "
             "its area; choose smaller masses", "--masses")
    device = VirtualDevice(bench, seed=seed)

    def place(step) -> float:
        t = device.time_since_start()
        bench.place(step.index, t)
        return t
    return device, bench, place


GRAVITY_HELP = ("Local acceleration of gravity [m/s²], for mass -> force: 9.80665 (standard gravity g_n, the "
                "default), 9.81.")


def gravity_value(text: str | float) -> float:
    """Acceleration of gravity [m/s²]: a plain number, or with m/s2 / m/s²."""
    t = str(text).strip()
    for suffix in ("m/s²", "m/s2", "m/s^2"):
        if t.endswith(suffix):
            t = t[: -len(suffix)].strip()
    try:
        value = float(t)
    except ValueError:
        raise typer.BadParameter(f"cannot read {text!r} as an acceleration; write e.g. 9.80665 or 9.81m/s2") from None
    if not 9.7 <= value <= 9.9:
        raise typer.BadParameter(f"{value:g} m/s² is not an acceleration of gravity on Earth (9.7 to 9.9 m/s²)")
    return value


SKIP_HELP = ("Leave out each row with a bad cell (non-numeric, nan or inf, a value its column cannot hold such "
              "as 1e308 Hz) and count it, instead of stopping at the first; rows out of time order still stop.")


def warn(warnings: list[str]) -> None:
    for message in dict.fromkeys(warnings):
        typer.echo(f"fsrlab: warning: {message}", err=True)


@contextmanager
def reading_file(path: Path) -> Iterator[None]:
    """A file that cannot be read: one line naming it ("cannot read 'bench.csv': No such file or directory")."""
    try:
        yield
    except IsADirectoryError:
        raise ParameterError(f"'{path}' is a directory, not a file") from None
    except OSError as exc:
        raise ParameterError(f"cannot read '{path}': {exc.strerror or exc}") from None


def load_run_warned(path: Path, skip_bad_rows: bool, warnings: list[str]):
    """Load a run; what the user should know about it goes to ``warnings``."""
    from fsrlab.io.runformat import load_run

    with reading_file(path):
        run = load_run(path, skip_bad_rows=skip_bad_rows)
    if run.skipped:
        first = run.skipped[0].reason
        more = f" (and {len(run.skipped) - 1} more)" if len(run.skipped) > 1 else ""
        warnings.append(f"skipped {len(run.skipped)} bad row{'s' if len(run.skipped) > 1 else ''} "
                        f"(--skip-bad-rows): {first}{more}")
    note = run.incomplete()
    if note:
        warnings.append(note)
    return run


def skipped_json(run) -> dict:
    return {"skipped_rows": len(run.skipped),
            "skipped": [{"row": b.row, "column": b.column, "reason": b.reason} for b in run.skipped]}


def missing_column(path: Path, run, column: str, what: str = "", option: str | None = None) -> None:
    from fsrlab.io.shown import shown_list

    fail(f"{path}: column {column!r}{what} missing (columns: {shown_list(run.columns)})", option)


def load_frame_calibration(cal: Path, command: str):
    """The calibration of ``--cal`` for a command that reads the meter's frames (frequency, duty, voltage).

    One line naming ``--cal`` (exit 2) when the file is missing, unreadable, or calibrates another readout.
    """
    from fsrlab.calibration.document import load_calibration

    if cal.is_dir():
        fail(f"{cal} is a directory, not a calibration file", "--cal")
    if not cal.exists():
        fail(f"{cal} does not exist; write one with fsrlab calibrate RUN.csv -o {cal}", "--cal")
    try:
        calibration = load_calibration(cal)
    except (ValueError, OSError) as exc:
        fail(getattr(exc, "reason", str(exc)), "--cal")
    if calibration.x_name not in ("frequency_hz", "duty_cycle", "voltage_v"):
        fail(f"{cal} calibrates {calibration.x_name}; fsrlab {command} reads frequency_hz, duty_cycle or voltage_v",
             "--cal")
    return calibration


def meter_differences(cal, metadata: dict, range_: int) -> list[str]:
    """How the meter a calibration would be used with (its circuit in ``metadata``, its range) differs from the
    readout the calibration was recorded with: :func:`fsrlab.calibration.apply.readout_differences`."""
    from fsrlab.calibration.apply import readout_differences
    from fsrlab.io.recorded import recorded_with

    return readout_differences(cal, recorded_with(metadata, [range_]), "the meter has")


def refuse_other_meter(cal, metadata: dict, range_: int) -> None:
    """End the command with one line naming --cal (exit 2) where :func:`meter_differences` finds a difference."""
    differences = meter_differences(cal, metadata, range_)
    if differences:
        fail(f"{differences[0]}: the readout means another stress there; calibrate on a run recorded the same way",
             "--cal")


# ------------------------------------------------------------------ the meter's circuit, as the user gives it

# The options that describe a meter on --port: parameter, option, typer.Option's other arguments (--c-off's help
# is the command's: see meter_circuit_options).
_METER_OPTIONS = (
    ("r", "--r", {"parser": ohms, "metavar": "RESISTANCE", "help": "--port: the meter's 555 R = R_A = R_B [Ω], e.g. "
            "10k or 4k7; recorded in the sidecar with --c-off, --diode and --vcc, so that a calibration of another "
            "circuit is refused (without it the run records none and nothing can be checked)."}),
    ("c_off", "--c-off", {"parser": farads, "metavar": "CAPACITANCE"}),
    ("diode", "--diode", {"help": "--port: the meter's 555 has D1 in series with R_B (the paper's Fig. 16); with "
            "--r."}),
    ("diode_drop", "--diode-drop", {"parser": volts, "metavar": "VOLTAGE", "help": "--port: D1's forward drop [V], "
            "e.g. 0.6 (implies --diode; default 0: ideal); with --r."}),
    ("vcc", "--vcc", {"parser": volts, "metavar": "VOLTAGE", "help": "--port: the 555's supply [V], e.g. 5 or 3.3V "
            "(default 5); with --r."}),
    ("r_f", "--r-f", {"parser": ohms, "metavar": "RESISTANCE", "help": "--port: the op-amp readout's feedback resistor "
            "R_F [Ω] (eq. 38), e.g. 20k; recorded with --drive, for calibrations on voltage_v."}),
    ("drive", "--drive", {"parser": volts, "metavar": "VOLTAGE", "help": "--port: the voltage driving the FSR at the "
            "op-amp's input [V] (default -5, the paper's); with --r-f."}),
)
# The circuits' parameter names as options, for their messages.
_CIRCUIT_NAMES = {"r_ohm": "--r", "c_off_farad": "--c-off", "diode_drop_v": "--diode-drop", "vcc_v": "--vcc"}
_OPAMP_NAMES = {"r_f_ohm": "--r-f", "vcc_v": "--drive"}


@dataclass(frozen=True)
class MeterCircuit:
    """The meter's circuit as the user gives it: --r, --c-off, --diode, --diode-drop, --vcc (the LM555's) and --r-f,
    --drive (the op-amp readout's), None where not given; ``virtual_c_off``: the command's virtual meter takes
    --c-off too. A command gets it from :func:`meter_circuit_options`."""

    r: float | None = None
    c_off: float | None = None
    diode: bool = False
    diode_drop: float | None = None
    vcc: float | None = None
    r_f: float | None = None
    drive: float | None = None
    virtual_c_off: bool = False

    @property
    def virtual_c_off_farad(self) -> float:
        """The virtual meter's C_off [F]: --c-off, else the virtual circuit's (1 nF)."""
        from fsrlab.virtual.sources import VIRTUAL_CIRCUIT

        return VIRTUAL_CIRCUIT.c_off_farad if self.c_off is None else self.c_off

    def sidecar(self, range_: int | None = 0, virtual: str | None = None) -> dict:
        """The sidecar's ``circuit`` and ``opamp`` (``LM555Circuit.to_dict()``, ``OpAmpReadout.to_dict()``).

        ``range_`` is the range the meter records on (None: either, the live page switches it); ``virtual`` the
        option that chose a virtual meter (``"--virtual"``, ``"--twin"``; None: --port), whose circuit is the
        paper's: nothing is returned, and any of these options but a virtual --c-off ends the command. Without
        --r (--r-f) the LM555 (op-amp) is not described; a part given without it, or a range that switches C_off
        in without --c-off, ends the command with one line naming the option (exit 2).
        """
        from fsrlab.circuits.circuit import LM555Circuit, OpAmpReadout

        given = [option for name, option, _ in _METER_OPTIONS if getattr(self, name) not in (None, False)]
        if virtual is not None:
            stray = [o for o in given if not (o == "--c-off" and self.virtual_c_off)]
            if stray:
                fail("describes the meter on --port; the virtual meter's circuit is the paper's (R = 10 kΩ, D1, 5 V"
                     + ("; its C_off with --c-off)" if self.virtual_c_off else ")"), stray[0])
            return {}
        stray = [o for o in given if o in ("--c-off", "--diode", "--diode-drop", "--vcc")] if self.r is None else []
        if stray:
            fail("describes the meter's 555 with its R: give --r too (e.g. --r 10k), so that the run records the "
                 "circuit", stray[0])
        if self.drive is not None and self.r_f is None:
            fail("describes the op-amp readout with its R_F: give --r-f too (e.g. --r-f 20k)", "--drive")
        if self.r is not None and self.c_off is None and range_ != 0:
            fail(("--range 1 switches C_off in" if range_ == 1 else "the page's range switch puts C_off in")
                 + ": give its value (e.g. --c-off 1n) so that the run records it", "--c-off")
        if self.diode_drop is not None and not self.diode_drop >= 0:
            fail(f"must be a forward drop >= 0 V, got {self.diode_drop:g}", "--diode-drop")
        out: dict = {}
        if self.r is not None:
            with option_names(_CIRCUIT_NAMES):
                out["circuit"] = LM555Circuit(
                    r_ohm=self.r, c_off_farad=0.0 if self.c_off is None else self.c_off,
                    diode=self.diode or self.diode_drop is not None, diode_drop_v=self.diode_drop or 0.0,
                    vcc_v=5.0 if self.vcc is None else self.vcc).to_dict()
        if self.r_f is not None:
            with option_names(_OPAMP_NAMES):
                out["opamp"] = OpAmpReadout(self.r_f, -5.0 if self.drive is None else self.drive).to_dict()
        return out

    def warning(self, out: Path | None = None, cal: Path | None = None) -> str | None:
        """What a meter on --port described without --r says on stderr (None with --r): its run ``out`` records no
        circuit, and the calibration ``cal`` cannot be checked against it."""
        if self.r is not None:
            return None
        said = ((["calibrate and apply cannot refuse it as a run of another circuit"] if out is not None else [])
                + ([f"{cal} cannot be checked against the meter's 555"] if cal is not None else []))
        return (f"{out}: no circuit recorded" if out is not None else "no circuit given") + (
            " (give the meter's --r, and --c-off, --diode, --vcc as built): " + ", and ".join(said))


def meter_circuit_options(virtual_c_off: bool = False) -> Callable:
    """Give a recording command, after its --port, the options that describe the meter's circuit (--r, --c-off,
    --diode, --diode-drop, --vcc, --r-f, --drive); it receives them as one :class:`MeterCircuit`, ``meter``.

    Use under ``@app.command``; ``virtual_c_off``: the command's virtual meter takes --c-off too (its C_off).
    """
    c_off_help = C_OFF_HELP[:-1] + (" (virtual: default 1n; --port: the meter's" if virtual_c_off else
                                    " (--port: the "
                                    "meter's") + ", recorded with --r; needed with --r where range 1 is used)."

    def decorate(command: Callable) -> Callable:
        signature = inspect.signature(command)
        own = [p for p in signature.parameters.values() if p.name != "meter"]
        at = [p.name for p in own].index("port") + 1
        added = [inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                   annotation=bool if name == "diode" else float,
                                   default=typer.Option(False if name == "diode" else None, option,
                                                        **{"help": c_off_help, **kwargs}))
                 for name, option, kwargs in _METER_OPTIONS]

        @functools.wraps(command)
        def run(**kwargs):
            parts = {name: kwargs.pop(name) for name, _, _ in _METER_OPTIONS}
            meter = MeterCircuit(**parts, virtual_c_off=virtual_c_off)
            return command(**kwargs, meter=meter)

        # typer reads the options from the signature (the one given here) and their types from the annotations
        run.__signature__ = signature.replace(parameters=own[:at] + added + own[at:])
        run.__annotations__ = {k: v for k, v in command.__annotations__.items() if k != "meter"}
        return run
    return decorate

