"""``fsrlab acquire`` and ``fsrlab virtual-device``: record an fsrlab meter, or emulate one on a pty.

Also the pieces the other recording commands share (``loadcell``, ``weights``, ``measure``): the
sensor and its area (``--sensor``/``--area``), the load-cell calibration (``--loadcell``), the virtual
device's load cell (``--no-loadcell``, ``--hx711-rate``).
"""

from __future__ import annotations

import math
import signal
import sys
from contextlib import contextmanager
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli._common import areas, emit_json, fail, farads, fraction, pascals, plain_numbers, seconds
from fsrlab.cli._outputs import out_path
from fsrlab.units import format_eng

_PROFILE_HELP = "Virtual stress profile: triangle, sine, steps or hold."
_PEAK_HELP = "Peak stress of the profile [Pa]: 50k, 50kPa, 0.1MPa."
_PERIOD_HELP = "Cycle time of the profile [s]: 4, 4s, 500ms, 1.5min."
_C_OFF_HELP = "C_off switched in by range 1 [F]: 1n, 1nF, 470p."
_CORRUPT_HELP = "Probability that a frame gets a bit flipped [1]: 0..1 or a percentage, 0.05 or 5%."
_DROP_HELP = "Probability that a frame is not sent [1]: 0..1 or a percentage, 0.05 or 5%."
_SEED_HELP = "Random seed of the virtual device's noise and faults (an integer)."
_SENSOR_HELP = ("Sensor preset, for its sensing area (stress = force / area): flexiforce-a201 (9.53 mm diameter, "
                "71.3 mm²) or interlink-402 (12.7 mm diameter, 126.7 mm²).")
_AREA_HELP = "Sensing area [m²] instead of a preset: 71.3mm2, 0.713cm2, 7.13e-5m2."
_LOADCELL_HELP = ("Load-cell calibration JSON (fsrlab loadcell tare/scale): HX711 counts -> force_n [N]. "
                  "Default with --virtual: the virtual load cell's own parameters.")
_NO_LOADCELL_HELP = "Virtual device: emulate a meter without an HX711 (ref_ok 0: reference columns empty)."
_RATE_HELP = "Virtual device: the HX711's output data rate [samples/s]: 10 or 80."


def _sensor_area(sensor: str | None, area: float | None) -> tuple[dict | None, float | None]:
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


def _virtual_sensor(sensor: str | None):
    """The sensor model and the sidecar's ``sensor`` when --sensor names a virtual sensor (virtual-fsr,
    paper-a201-1..4), else ``(None, None)``."""
    from fsrlab.acquisition.protocols import VIRTUAL_SENSORS, virtual_sensor

    key = (sensor or "").strip().lower()
    if key not in VIRTUAL_SENSORS:
        return None, None
    model, text = virtual_sensor(key)
    return model, {"model": text, "area_m2": model.area_m2}


def _load_loadcell(path: Path | None, option: str = "--loadcell", scaled: bool = True):
    """The load-cell calibration of ``path`` (None: None); one line naming the option otherwise."""
    if path is None:
        return None
    from fsrlab.acquisition.loadcell import LoadCellError, load_loadcell

    if not path.exists():
        fail(f"{path} does not exist; write one with fsrlab loadcell tare", option)
    try:
        cal = load_loadcell(path)
    except (LoadCellError, OSError) as exc:
        fail(str(exc), option)
    if scaled and not cal.scaled:
        fail(f"{path} has a tare but no scale factor: run fsrlab loadcell scale --mass 500g --cal {path}", option)
    return cal


def _check_rate(rate: int) -> None:
    if rate not in (10, 80):
        fail(f"must be 10 or 80 samples/s (the HX711's RATE pin), got {rate}", "--hx711-rate")


@contextmanager
def _sigterm_as_interrupt():
    """Let SIGTERM end a recording like Ctrl-C (file closed, device stopped)."""
    def handler(signum, frame):  # noqa: ARG001
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread (e.g. called from a test thread): leave it
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _check_virtual(profile: str, peak: float, period: float, c_off: float, corrupt: float, drop: float,
                   seed: int | None) -> None:
    """One-line errors, each naming its own option, for the virtual device's options."""
    from fsrlab.acquisition.virtual_device import PROFILE_KINDS

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


def _virtual_device(profile: str, peak: float, period: float, c_off: float, seed: int | None,
                    corrupt: float, drop: float, load_cell: bool = True, rate: int = 80, area_m2: float | None = None,
                    sensor_model=None):
    from fsrlab.acquisition.loadcell import LoadCellModel
    from fsrlab.acquisition.virtual_device import VIRTUAL_CIRCUIT, Faults, PhysicsSource, StressProfile, VirtualDevice
    from fsrlab.physics.sensor import VirtualFSR

    prof = StressProfile(kind=profile, peak_pa=peak, period_s=period)
    sensor = sensor_model if sensor_model is not None else VirtualFSR() if area_m2 is None else VirtualFSR(area_m2=area_m2)
    cell = LoadCellModel(rate_sps=rate) if load_cell else None
    try:
        source = PhysicsSource(prof, sensor=sensor, circuit=VIRTUAL_CIRCUIT.replace(c_off_farad=c_off))
    except ValueError:  # the sensor model has no valid response up to this stress
        fail(f"the virtual sensor model has no valid response up to {format_eng(peak, 'Pa')} (its resistance would not "
             "be positive); choose a smaller peak, e.g. 50k", "--peak")
    return VirtualDevice(source, faults=Faults(corrupt=corrupt, drop=drop), seed=seed, load_cell=cell), source


def _window_ms(window_s: float) -> int:
    """The window in whole milliseconds, as the meter takes it (10 ms .. 60 s)."""
    from fsrlab.acquisition.protocol import WINDOW_MS_MAX, WINDOW_MS_MIN

    ms = round(window_s * 1000.0, 6)
    if not WINDOW_MS_MIN <= ms <= WINDOW_MS_MAX:
        fail(f"must be {WINDOW_MS_MIN} ms to {WINDOW_MS_MAX // 1000} s, got {window_s:g} s", "--window")
    if ms != int(ms):
        fail(f"the meter counts whole milliseconds, got {ms:g} ms: write {math.floor(ms)}ms or {math.ceil(ms)}ms",
             "--window")
    return int(ms)


def _check_out(out: Path, overwrite: bool, inputs=()) -> None:
    """Refuse an output that exists (unless ``overwrite``), is an input or an input's sidecar, or cannot be
    written, before any device is touched (the output policy, :mod:`fsrlab.outputs`)."""
    from fsrlab.cli._outputs import checked

    checked(out, "--out", overwrite=overwrite, inputs=inputs, kind="run")


def _fmt(value: float, spec: str) -> str:
    return "—" if value is None or not math.isfinite(value) else format(value, spec)


class _LiveView:
    """Rich live table of the recording on stderr (frames/s, frequency, duty cycle, dropped), and notices."""

    def __init__(self, enabled: bool, title: str) -> None:
        from rich.console import Console

        self.console = Console(stderr=True)
        self.enabled = enabled and self.console.is_terminal
        self.title = title
        self.live = None

    def __enter__(self) -> "_LiveView":
        if self.enabled:
            from rich.live import Live

            self.live = Live(self._render(None), console=self.console, transient=True, refresh_per_second=8)
            self.live.__enter__()
        return self

    def _render(self, st):
        from rich.table import Table

        table = Table(title=self.title, show_header=True, header_style="bold")
        for col in ("time (s)", "frames", "frames/s", "frequency (Hz)", "duty cycle (%)", "dropped", "corrupt", "resets"):
            table.add_column(col, justify="right")
        if st is not None:
            table.add_row(f"{st.elapsed_s:.1f}", str(st.frames), f"{st.frames_per_s:.1f}", _fmt(st.frequency_hz, ".1f"),
                          _fmt(st.duty_cycle * 100 if st.duty_cycle == st.duty_cycle else math.nan, ".2f"),
                          str(st.dropped), str(st.bad_frames), str(st.resets))
        return table

    def update(self, st) -> None:
        if self.live is not None:
            self.live.update(self._render(st))

    def notice(self, text: str) -> None:
        """One line on stderr, above the live table when there is one (shown even with --quiet)."""
        if self.live is not None:
            self.console.print(f"fsrlab: {text}", markup=False, highlight=False)
        else:
            print(f"fsrlab: {text}", file=sys.stderr, flush=True)

    def __exit__(self, *exc) -> None:
        if self.live is not None:
            self.live.__exit__(*exc)


@app.command("acquire")
def acquire(
    port: str = typer.Option(None, "--port", help="Serial port (/dev/ttyACM0, COM3, a pty) or 'auto' to find an Uno by USB id."),
    virtual: bool = typer.Option(False, "--virtual", help="Record from a virtual device (pty, physics and 555 models) instead of hardware."),
    duration: float = typer.Option("60s", "--duration", parser=seconds, metavar="TIME", help="Recording time [s]: 90, 90s, 1.5min, 2h, 500ms (a bare m is refused: minutes or milliseconds?)."),
    out: Path = typer.Option(Path("run.csv"), "--out", "-o", parser=out_path, help="Run file (CSV + NAME.meta.json sidecar, docs/data-format.md)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing run file and its sidecar; without it an existing one stops the command before the device is touched."),
    window: float = typer.Option("100ms", "--window", parser=seconds, metavar="TIME", help="Measurement window [s], 10ms to 60s in whole milliseconds (the meter counts ms): 20ms, 100ms, 0.25, 1s."),
    stall: float = typer.Option(None, "--stall", parser=seconds, metavar="TIME", help="No frame for this long [s] is reported as a gap (default: 5 windows, at least 2s); a device still silent at the end fails the run (exit 1)."),
    range_: int = typer.Option(0, "--range", help="C_off range switch [1]: 0 (off) or 1 (C_off connected)."),
    baud: int = typer.Option(115200, "--baud", help="Line rate [bit/s]; protocol v1: 115200."),
    profile: str = typer.Option("triangle", "--profile", help=_PROFILE_HELP),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS", help="Virtual device: " + _PEAK_HELP[0].lower() + _PEAK_HELP[1:]),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help="Virtual device: " + _PERIOD_HELP[0].lower() + _PERIOD_HELP[1:]),
    c_off: float = typer.Option("1n", "--c-off", parser=farads, metavar="CAPACITANCE", help="Virtual circuit: " + _C_OFF_HELP),
    seed: int = typer.Option(None, "--seed", help=_SEED_HELP),
    corrupt: float = typer.Option("0", "--corrupt", parser=fraction, metavar="FRACTION", help="Virtual device (tests): " + _CORRUPT_HELP[0].lower() + _CORRUPT_HELP[1:]),
    drop: float = typer.Option("0", "--drop", parser=fraction, metavar="FRACTION", help="Virtual device (tests): " + _DROP_HELP[0].lower() + _DROP_HELP[1:]),
    sensor: str = typer.Option(None, "--sensor", help=_SENSOR_HELP),
    area: float = typer.Option(None, "--area", parser=areas, metavar="AREA", help=_AREA_HELP),
    loadcell: Path = typer.Option(None, "--loadcell", metavar="LC.json", help=_LOADCELL_HELP),
    no_loadcell: bool = typer.Option(False, "--no-loadcell", help=_NO_LOADCELL_HELP),
    hx711_rate: int = typer.Option(80, "--hx711-rate", help=_RATE_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No live display (notices of gaps still go to stderr)."),
    json_out: bool = typer.Option(False, "--json", help='Print {"frames", "dropped", "duration_s", "file"} as JSON, and "no_reference" (windows without a load-cell conversion) for a protocol-2 device.'),
) -> None:
    """Record measurement windows (frequency, duty cycle, A0 voltage) from an fsrlab meter into a run file.

    Written row by row: Ctrl-C or a kill loses at most the window in progress, and an existing run
    is replaced only with --overwrite. A protocol-2 meter adds the load cell's reference_raw and
    force_n (with --loadcell; empty, never 0, in windows without an HX711 conversion, which are
    counted); with --sensor or --area, stress_pa = force_n / area. Exit code 1, with one line saying why and the rows so far
    kept, when the device is unplugged, fails, stays silent until the end, or no valid window
    arrives; the sidecar's "ended" says the same and "gaps" lists the silences.

    Examples:

    \b
      fsrlab acquire --virtual --duration 10s --window 20ms --out bench.csv
      fsrlab acquire --port auto --duration 1.5min --window 100ms --range 1 --out bench.csv --overwrite
    """
    from fsrlab.acquisition.recorder import record, result_dict
    from fsrlab.acquisition.serial_link import SerialLink

    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    if not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    window_ms = _window_ms(window)
    if stall is not None and not stall > window_ms / 1000.0:
        fail(f"must be longer than one window ({window_ms / 1000.0:g} s), got {stall:g} s", "--stall")
    if range_ not in (0, 1):
        fail(f"must be 0 or 1, got {range_}", "--range")
    if not baud > 0:
        fail(f"must be > 0 bit/s, got {baud}", "--baud")
    for name, v in (("--corrupt", corrupt), ("--drop", drop)):
        if not 0 <= v <= 1:
            fail(f"must be in 0..1, got {v:g}", name)
    _check_rate(hx711_rate)
    sensor_meta, area_m2 = _sensor_area(sensor, area)
    cal = _load_loadcell(loadcell)
    _check_out(out, overwrite, inputs=[loadcell])
    device = None
    metadata: dict = {"sensor": sensor_meta} if sensor_meta else {}
    reference = health = None
    if virtual:
        _check_virtual(profile, peak, period, c_off, corrupt, drop, seed)
        device, source = _virtual_device(profile, peak, period, c_off, seed, corrupt, drop, not no_loadcell,
                                         hx711_rate, area_m2)
        if cal is None and device.load_cell is not None:
            cal = device.load_cell.calibration()
        port = device.open()
        virtual_meta = source.metadata()
        if sensor_meta:
            virtual_meta["sensor"] = {**sensor_meta, "virtual_model": virtual_meta["sensor"]["model"]}
        metadata = {"origin": "fsrlab acquire --virtual (VirtualFSR -> LM555 astable and op-amp -> meter model "
                              "fsrlab.acquisition.meter -> emulated firmware over a pty)",
                    **virtual_meta,
                    "notes": f"virtual stress profile {profile}, peak {peak:g} Pa, period {period:g} s; "
                             "stress_pa is the applied (reference) stress, force_n the emulated load cell's "
                             "reading" + ("" if device.load_cell else " (no HX711 emulated: empty)")}
        area_m2 = source.sensor.area_m2
        reference = lambda frame: device.reference(frame.seq)  # noqa: E731
        health = lambda: device.failure  # noqa: E731
    try:
        with SerialLink(port, baud=baud) as link, _sigterm_as_interrupt(), \
                _LiveView(not quiet, f"fsrlab acquire {link.port} -> {out}") as view:
            result = record(link, out, duration, window_ms=window_ms, range_=range_, metadata=metadata,
                            reference=reference, on_status=view.update, on_event=view.notice, stall_s=stall,
                            health=health, overwrite=overwrite, loadcell=cal, area_m2=area_m2)
    finally:
        if device is not None:
            device.close()
    if json_out:
        emit_json(result_dict(result))
    else:
        typer.echo(f"{out}: {result.frames} windows, {result.dropped} dropped, {result.duration_s:.1f} s "
                   f"({result.stats.bad_frames} corrupt lines, {result.stats.resets} device resets, "
                   f"{len(result.gaps)} gaps)"
                   + (f"; {result.no_reference} windows without a load-cell reading" if result.reference else ""))
    if result.failed:
        print(f"fsrlab: {plain_numbers(result.message)}", file=sys.stderr)
        raise typer.Exit(1)


@app.command("virtual-device")
def virtual_device(
    duration: float = typer.Option(None, "--duration", parser=seconds, metavar="TIME", help="Run this long [s]: 90, 90s, 1.5min, 2h (default: until Ctrl-C)."),
    profile: str = typer.Option("triangle", "--profile", help=_PROFILE_HELP),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS", help=_PEAK_HELP),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help=_PERIOD_HELP),
    c_off: float = typer.Option("1n", "--c-off", parser=farads, metavar="CAPACITANCE", help=_C_OFF_HELP),
    seed: int = typer.Option(None, "--seed", help=_SEED_HELP),
    corrupt: float = typer.Option("0", "--corrupt", parser=fraction, metavar="FRACTION", help=_CORRUPT_HELP),
    drop: float = typer.Option("0", "--drop", parser=fraction, metavar="FRACTION", help=_DROP_HELP),
    json_out: bool = typer.Option(False, "--json", help='Print {"port": PATH} as JSON (one line) instead of the bare path.'),
) -> None:
    """Emulate an fsrlab meter on a pseudo-terminal; prints its path (open it with --port PATH or any serial tool).

    Exit code 1, with one line saying why, if the emulated device fails.

    Examples:

    \b
      fsrlab virtual-device --duration 10min --profile sine --peak 80k --period 2s
      fsrlab virtual-device --corrupt 1% --drop 0.5% --seed 1
    """
    import json

    if duration is not None and not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    _check_virtual(profile, peak, period, c_off, corrupt, drop, seed)
    device, _ = _virtual_device(profile, peak, period, c_off, seed, corrupt, drop)
    path = device.open(thread=False)
    typer.echo(json.dumps({"port": path}) if json_out else path)
    sys.stdout.flush()
    try:
        with _sigterm_as_interrupt():
            device.serve(duration)
    except KeyboardInterrupt:
        pass
    finally:
        device.close()
    if device.error is not None:
        print(f"fsrlab: {plain_numbers(device.failure.replace('device thread failed', 'virtual device failed'))}",
              file=sys.stderr)
        raise typer.Exit(1)
