"""``fsrlab loadcell tare|scale``: calibrate the load cell under the sensor (HX711 offset and scale factor)."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    GRAVITY_HELP,
    check_rate,
    checked,
    emit_json,
    fail,
    gravity_value,
    loadcell_option,
    masses,
    out_path,
    plain_numbers,
    seconds,
    sigterm_as_interrupt,
    window_ms_option,
)


@app.command("loadcell")
def loadcell(
    action: str = typer.Argument(..., metavar="ACTION", help="tare: read the unloaded cell, write its offset to -o; "
                                 "scale: read it with --mass on, add the scale factor to --cal."),
    port: str = typer.Option(None, "--port", help="Serial port of the meter (/dev/ttyACM0, COM3, a pty) or 'auto'."),
    virtual: bool = typer.Option(False, "--virtual", help="Use a virtual meter with its emulated load cell; the "
            "virtual bench places the mass itself."),
    out: Path = typer.Option(None, "--out", "-o", metavar="LC.json", parser=out_path, help="tare: the load-cell "
            "calibration file to write (LC.json); scale: write the tare with its scale factor here instead of adding "
            "it to --cal."),
    cal: Path = typer.Option(None, "--cal", metavar="LC.json", help="scale: the tare's calibration file (LC.json); the "
            "scale factor is added to it (or written to -o)."),
    mass: float = typer.Option(None, "--mass", parser=masses, metavar="MASS", help="scale: the known mass on the cell "
            "[kg]: 500g, 0.5kg, 250mg."),
    gravity: float = typer.Option("9.80665", "--gravity", parser=gravity_value, metavar="ACCELERATION",
                                  help=GRAVITY_HELP),
    capacity: float = typer.Option(None, "--capacity", parser=masses, metavar="MASS", help="tare: the cell's rated "
            "capacity [kg], stored (a scale mass below 5 % of it warns): 5kg, 1kg, 500g."),
    duration: float = typer.Option("3s", "--duration", parser=seconds, metavar="TIME", help="Reading time [s]: 3s, 5, "
            "1.5s."),
    window: float = typer.Option("100ms", "--window", parser=seconds, metavar="TIME", help="Measurement window [s], "
            "whole ms: 100ms, 0.5s."),
    hx711_rate: int = typer.Option(80, "--hx711-rate", help="Virtual load cell: HX711 output data rate [samples/s]: 10 "
            "or 80."),
    seed: int = typer.Option(None, "--seed", help="Random seed of the virtual meter's noise (an integer)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing -o file; without it an existing one "
            "stops the command before the meter is read. The --cal file is never replaced by -o (scale without -o adds "
            "the factor to it)."),
    json_out: bool = typer.Option(False, "--json", help="Print the calibration written (offset_counts [count], "
            "scale_counts_per_n [count/N], noise) as JSON."),
) -> None:
    """Calibrate the load cell: tare (offset, nothing on the cell), then scale (counts per newton from a known mass).

    Like the HX711 libraries' tare() and set_scale(), kept in a small JSON file with the date, the
    mass and g used and the noise of the readings; fsrlab acquire --loadcell LC.json turns the raw
    counts into force_n = (raw - offset) / scale. A tare is refused while the reading drifts (the
    second half of the window means differs from the first by more than 4 standard errors and 0.1 % of the span); a
    scale mass below 5 % of --capacity warns.

    Examples:

    \b
      fsrlab loadcell tare --virtual --capacity 5kg -o lc.json
      fsrlab loadcell scale --virtual --mass 500g --cal lc.json
    """
    action = action.strip().lower()
    if action not in ("tare", "scale"):
        fail(f"must be tare or scale, got {action!r}", "ACTION")
    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    window_ms = _reading_options(duration, window, hx711_rate, seed)
    tare, target = _files(action, out, cal, mass, capacity, overwrite)
    readings = _read(action, port, virtual, mass, gravity, seed, hx711_rate, duration, window_ms, target)
    result, warning = _calibration(action, readings, tare, mass, gravity, capacity, target)
    result.save(target)
    if warning:
        print(f"fsrlab: warning: {warning}", file=sys.stderr)
    _say(action, result, readings, target, mass, gravity, json_out)


def _reading_options(duration: float, window: float, hx711_rate: int, seed: int | None) -> int:
    """The window in ms; one line naming the option for a duration, rate or seed out of range."""
    if not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    window_ms = window_ms_option(window)
    if duration < 5 * window_ms / 1000.0:
        fail(f"must be at least 5 windows ({5 * window_ms / 1000.0:g} s) to judge the reading's stability, "
             f"got {duration:g} s", "--duration")
    check_rate(hx711_rate)
    if seed is not None and seed < 0:
        fail(f"must be an integer >= 0, got {seed}", "--seed")
    return window_ms


def _files(action: str, out: Path | None, cal: Path | None, mass: float | None, capacity: float | None,
           overwrite: bool):
    """The tare read from --cal (scale) and the file to write, checked before the meter is read."""
    if action == "tare":
        if out is None:
            fail("tare needs the file to write, e.g. -o lc.json", "--out")
        if mass is not None or cal is not None:
            fail("--mass and --cal belong to scale (fsrlab loadcell scale --mass 500g --cal lc.json)", "--mass")
        if capacity is not None and not capacity > 0:
            fail(f"must be > 0 kg, got {capacity:g} kg", "--capacity")
        return None, checked(out, "--out", overwrite=overwrite)
    if cal is None:
        fail("scale needs the tare's file, e.g. --cal lc.json", "--cal")
    if mass is None or not mass > 0:
        fail("scale needs the known mass > 0 on the cell, e.g. --mass 500g", "--mass")
    if capacity is not None:
        fail("the capacity is given at the tare (fsrlab loadcell tare --capacity 5kg)", "--capacity")
    tare = loadcell_option(cal, "--cal", scaled=False)
    if out is None:
        return tare, cal  # the scale factor added to the tare's file, as asked
    from fsrlab.io.outputs import same_file

    if same_file(out, cal):
        fail(f"{out} is the --cal file; leave -o out to add the scale factor to it", "--out")
    return tare, checked(out, "--out", overwrite=overwrite, inputs=[cal])


def _read(action, port, virtual: bool, mass, gravity: float, seed, hx711_rate: int, duration: float, window_ms: int,
          target: Path):
    """The load cell's readings over ``duration`` (the virtual bench loads it itself); a link's failure ends the
    command (no board: one line naming --port, exit 2; otherwise exit 1)."""
    from fsrlab.acquisition.loadcell_reading import NoLoadCell, read_reference
    from fsrlab.acquisition.serial_link import LinkError, SerialLink

    device = None
    if virtual:
        from fsrlab.acquisition.loadcell import LoadCellModel
        from fsrlab.physics.sensor import A201_AREA_M2
        from fsrlab.virtual.device import VirtualDevice
        from fsrlab.virtual.sources import ConstantSource

        # The virtual bench: the cell unloaded for a tare, the mass on it for a scale.
        force = 0.0 if action == "tare" else mass * gravity
        device = VirtualDevice(ConstantSource(stress_pa=force / A201_AREA_M2), seed=seed,
                               load_cell=LoadCellModel(rate_sps=hx711_rate))
        port = device.open()
    try:
        with SerialLink(port) as link, sigterm_as_interrupt():
            if not virtual:
                what = "nothing on the load cell" if action == "tare" else f"{mass * 1e3:g} g on the load cell"
                print(f"fsrlab: reading for {duration:g} s with {what}; keep it still", file=sys.stderr)
            return read_reference(link, duration, window_ms)
    except NoLoadCell as exc:
        print(f"fsrlab: {exc}", file=sys.stderr)
        raise typer.Exit(1) from None
    except LinkError as exc:
        if exc.parameter == "port" and not virtual:  # no board, or the port cannot be opened: as every command says it
            fail(exc.reason, "--port")
        print(f"fsrlab: {plain_numbers(str(exc))}", file=sys.stderr)
        raise typer.Exit(1) from None
    except KeyboardInterrupt:
        print(f"fsrlab: interrupted: nothing written to {target}", file=sys.stderr)
        raise typer.Exit(1) from None
    finally:
        if device is not None:
            device.close()


def _calibration(action: str, readings, tare, mass, gravity: float, capacity, target: Path):
    """The tare or the scale from the readings, and a warning (or None); a refused one ends the command, exit 1."""
    from fsrlab.acquisition.loadcell import LoadCellError, scale_from_readings, tare_from_readings

    try:
        if action == "tare":
            result, warning = tare_from_readings(readings.means, None if capacity is None else capacity * gravity), None
        else:
            result, warning = scale_from_readings(tare, readings.means, mass, gravity)
    except LoadCellError as exc:
        print(f"fsrlab: {exc}; {target} not written", file=sys.stderr)
        raise typer.Exit(1) from None
    if action == "tare" and capacity is not None:
        result.tare["capacity_kg"] = capacity
        result.tare["gravity_m_s2"] = gravity
    (result.tare if action == "tare" else result.scale)["conversions"] = readings.conversions
    return result, warning


def _say(action: str, result, readings, target: Path, mass, gravity: float, json_out: bool) -> None:
    summary = {"file": str(target), "action": action, "offset_counts": result.offset_counts,
               "scale_counts_per_n": result.scale_counts_per_n, "capacity_n": result.capacity_n,
               "windows": len(readings.means), "conversions": readings.conversions,
               "noise_counts": (result.tare if action == "tare" else result.scale)["noise_counts"]}
    if action == "scale":
        summary["mass_kg"], summary["gravity_m_s2"] = mass, gravity
        summary["noise_n"] = result.scale["noise_n"]
    if json_out:
        emit_json(summary)
    elif action == "tare":
        typer.echo(f"{target}: offset {result.offset_counts:.1f} counts (noise {summary['noise_counts']:.1f} counts, "
                   f"{summary['windows']} windows); next: fsrlab loadcell scale --mass 500g --cal {target}")
    else:
        typer.echo(f"{target}: scale {result.scale_counts_per_n:.2f} counts/N from {mass * 1e3:g} g at g = {gravity:g} "
                   f"m/s² (noise {summary['noise_n'] * 1e3:.2f} mN = {summary['noise_n'] / gravity * 1e6:.2f} mg)")
