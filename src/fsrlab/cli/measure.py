"""``fsrlab measure``: the force live from a calibration (N and g, the load cell's beside it), recorded as a run."""

from __future__ import annotations

import math
import sys
import threading
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli._common import areas, emit_json, fail, farads, pascals, plain_numbers, seconds
from fsrlab.cli._outputs import out_path
from fsrlab.cli.acquisition import (
    _AREA_HELP, _LOADCELL_HELP, _PEAK_HELP, _PERIOD_HELP, _PROFILE_HELP, _SENSOR_HELP, _check_out, _check_virtual,
    _LiveView, _fmt, _load_loadcell, _sensor_area, _sigterm_as_interrupt, _virtual_device, _window_ms,
)
from fsrlab.units import STANDARD_GRAVITY

def load_frame_calibration(cal: Path, command: str):
    """The calibration of ``--cal`` for a command that reads the meter's frames (frequency, duty, voltage).

    One line naming ``--cal`` (exit 2) when the file is missing, unreadable, or calibrates another readout.
    """
    from fsrlab.analysis.calibration_io import load_calibration

    if cal.is_dir():
        fail(f"{cal} is a directory, not a calibration file", "--cal")
    if not cal.exists():
        fail(f"{cal} does not exist; write one with fsrlab calibrate RUN.csv -o {cal}", "--cal")
    try:
        calibration = load_calibration(cal)
    except (ValueError, OSError) as exc:
        fail(str(exc), "--cal")
    if calibration.x_name not in ("frequency_hz", "duty_cycle", "voltage_v"):
        fail(f"{cal} calibrates {calibration.x_name}; fsrlab {command} reads frequency_hz, duty_cycle or voltage_v",
             "--cal")
    return calibration


def _estimator(cal):
    """The causal estimator of a calibration (:func:`fsrlab.analysis.pipeline.live_estimator`): one reading at
    a time, ``step(x) -> (estimate, uncertainty, in_range)``, with the compensation's memory between calls."""
    from fsrlab.analysis.pipeline import live_estimator

    return live_estimator(cal)


class _Live(_LiveView):
    """Live line of the force on stderr (rich, redrawn in place) when stderr is a terminal; notices as acquire's."""

    def _render(self, st) -> str:
        return self.title

    def show(self, text: str) -> None:
        if self.live is not None:
            self.live.update(f"{self.title}\n{text}")


@app.command("measure")
def measure(
    cal: Path = typer.Option(..., "--cal", metavar="CAL.json", help="Calibration JSON from fsrlab calibrate -o (readout -> stress_pa [Pa] or force_n [N])."),
    port: str = typer.Option(None, "--port", help="Serial port of the meter (/dev/ttyACM0, COM3, a pty) or 'auto'."),
    virtual: bool = typer.Option(False, "--virtual", help="Measure a virtual meter (its sensor follows --profile)."),
    out: Path = typer.Option(Path("measure.csv"), "--out", "-o", parser=out_path, help="Run file with the estimate (CSV + NAME.meta.json)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing run and its sidecar."),
    duration: float = typer.Option(None, "--duration", parser=seconds, metavar="TIME", help="Measure this long [s]: 10s, 1.5min (default: until Ctrl-C)."),
    window: float = typer.Option("100ms", "--window", parser=seconds, metavar="TIME", help="Measurement window [s], whole ms: 100ms, 0.25."),
    sensor: str = typer.Option(None, "--sensor", help=_SENSOR_HELP),
    area: float = typer.Option(None, "--area", parser=areas, metavar="AREA", help=_AREA_HELP),
    loadcell: Path = typer.Option(None, "--loadcell", metavar="LC.json", help=_LOADCELL_HELP),
    profile: str = typer.Option("triangle", "--profile", help=_PROFILE_HELP),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS", help="Virtual device: " + _PEAK_HELP[0].lower() + _PEAK_HELP[1:]),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help="Virtual device: " + _PERIOD_HELP[0].lower() + _PERIOD_HELP[1:]),
    c_off: float = typer.Option("1n", "--c-off", parser=farads, metavar="CAPACITANCE", help="Virtual circuit: C_off switched in by range 1 [F]: 1n, 470p."),
    seed: int = typer.Option(None, "--seed", help="Random seed of the virtual meter's noise (an integer)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No live display."),
    json_out: bool = typer.Option(False, "--json", help='Print {"frames", "dropped", "duration_s", "file", "estimated", "out_of_range", "last"} as JSON (forces in N).'),
) -> None:
    """Show the force live from a calibration (N and g; the load cell's reading beside it) and record it.

    Each window's readout goes through the calibration; the run gets the estimate
    (stress_pa_estimate [Pa], force_n_estimate [N] when an area is known or the calibration gives
    force) and in_range (1 inside the calibrated readout range, 0 outside; no estimate beyond 10 %
    of the range's span, as fsrlab apply). Stress becomes force with --sensor, --area or the
    virtual sensor's area.

    Examples:

    \b
      fsrlab measure --virtual --cal cal.json --duration 10s -o live.csv
      fsrlab measure --port auto --cal cal.json --sensor flexiforce-a201 --loadcell lc.json -o live.csv
    """
    from fsrlab.acquisition.recorder import record, result_dict
    from fsrlab.acquisition.serial_link import SerialLink

    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    if duration is not None and not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    window_ms = _window_ms(window)
    calibration = load_frame_calibration(cal, "measure")
    try:
        est = _estimator(calibration)
    except ValueError as exc:
        fail(f"{cal}: {exc}", "--cal")
    sensor_meta, area_m2 = _sensor_area(sensor, area)
    lc = _load_loadcell(loadcell)
    _check_out(out, overwrite, inputs=[cal, loadcell])
    device = None
    metadata: dict = {"sensor": sensor_meta} if sensor_meta else {}
    if virtual:
        _check_virtual(profile, peak, period, c_off, 0.0, 0.0, seed)
        device, source = _virtual_device(profile, peak, period, c_off, seed, 0.0, 0.0, True, 80, area_m2)
        if lc is None:
            lc = device.load_cell.calibration()
        port = device.open()
        metadata = {"origin": "fsrlab measure --virtual", **source.metadata(), **metadata}
        area_m2 = source.sensor.area_m2
    ref = est.reference  # "stress_pa" or "force_n"
    to_force = (lambda v: v) if ref == "force_n" else ((lambda v: v * area_m2) if area_m2 else None)
    columns = [f"{ref}_estimate", "in_range"] + (["force_n_estimate"] if ref != "force_n" and to_force else [])
    columns.append(f"{ref}_uncertainty")
    metadata["calibration"] = {"file": str(cal), "x": est.x, "reference": ref, "estimator": "live_estimator"}
    counts = {"estimated": 0, "out_of_range": 0}
    last: dict = {}
    g = STANDARD_GRAVITY

    with _Live(not quiet, f"fsrlab measure {out}  (Ctrl-C ends)") as live:
        def on_row(m, row):
            value = row.get(est.x)
            e, u, inside = est.step(value if value is not None and math.isfinite(value) else None)
            row = dict(row)
            row[f"{ref}_estimate"] = e
            row["in_range"] = (1 if inside else 0) if value is not None and math.isfinite(value) else None
            row[f"{ref}_uncertainty"] = u
            force = to_force(e) if (to_force and e is not None) else None
            if "force_n_estimate" in columns:
                row["force_n_estimate"] = force
            counts["estimated"] += e is not None
            counts["out_of_range"] += row["in_range"] == 0
            last.update({"time_s": row["time_s"], ref + "_estimate": e, "force_n": force,
                         "force_g": None if force is None else force / g * 1e3, "in_range": bool(inside),
                         "reference_force_n": row.get("force_n")})
            text = (f"force {_fmt(force, '.3f')} N = {_fmt(None if force is None else force / g * 1e3, '.0f')} g"
                    if to_force else f"stress {_fmt(e, '.0f')} Pa (no area: give --sensor or --area for a force)")
            if row.get("force_n") is not None:
                text += f"   load cell {row['force_n']:.3f} N"
            live.show(text + ("" if inside else "   (outside the calibrated range)"))
            return row

        try:
            with SerialLink(port) as link, _sigterm_as_interrupt():
                result = record(link, out, duration if duration is not None else 10 * 365 * 86400.0, window_ms=window_ms,
                                metadata=metadata, on_event=live.notice,
                                health=(lambda: device.failure) if device is not None else None, overwrite=overwrite,
                                loadcell=lc, extra_columns=columns, on_row=on_row,
                                stop=threading.Event())
        finally:
            if device is not None:
                device.close()
    info = {**result_dict(result), **counts, "last": last}
    if json_out:
        emit_json(info)
    else:
        shown = (f"last force {_fmt(last.get('force_n'), '.3f')} N" if to_force else
                 f"last stress {_fmt(last.get(ref + '_estimate'), '.0f')} Pa")
        typer.echo(f"{out}: {result.frames} windows, {counts['estimated']} estimated, {counts['out_of_range']} outside "
                   f"the calibrated range; {shown}")
    if result.failed:
        print(f"fsrlab: {plain_numbers(result.message)}", file=sys.stderr)
        raise typer.Exit(1)
