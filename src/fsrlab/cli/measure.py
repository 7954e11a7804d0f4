"""``fsrlab measure``: the force live from a calibration (N and g, the load cell's beside it), recorded as a run."""

from __future__ import annotations

import math
import sys
import threading
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    AREA_HELP,
    LOADCELL_HELP,
    PEAK_HELP,
    PERIOD_HELP,
    PROFILE_HELP,
    SENSOR_HELP,
    LiveView,
    MeterCircuit,
    areas,
    check_out,
    check_virtual,
    emit_json,
    fail,
    fmt_value,
    load_frame_calibration,
    loadcell_option,
    make_virtual_device,
    meter_circuit_options,
    out_path,
    pascals,
    plain_numbers,
    refuse_other_meter,
    seconds,
    sensor_area,
    sigterm_as_interrupt,
    warn,
    window_ms_option,
)
from fsrlab.units import STANDARD_GRAVITY


def _estimator(cal):
    """The calibration's estimator (:meth:`fsrlab.calibration.result.Calibration.estimator`): one reading at
    a time, ``step(x, t) -> (estimate, uncertainty, in_range)``, with the memory between calls."""
    return cal.estimator()


class _RowEstimates:
    """The recorder's ``on_row``: each window's readout through the calibration's estimator (its time ages the
    memory), the estimate, in_range and uncertainty (and the force, when an area gives one) added to the row,
    counted, kept as the last, and shown on the live line."""

    def __init__(self, est, columns: list[str], to_force, live: _Live):
        self.est, self.columns, self.to_force, self.live = est, columns, to_force, live
        self.counts = {"estimated": 0, "out_of_range": 0}
        self.last: dict = {}

    def __call__(self, m, row):
        est, ref, to_force, g = self.est, self.est.reference, self.to_force, STANDARD_GRAVITY
        value = row.get(est.x)
        t = row.get("time_s")  # the memory's creep ages by the row's time, not by the calibration's row step
        e, u, inside = est.step(value if value is not None and math.isfinite(value) else None,
                                t if t is not None and math.isfinite(t) else None)
        row = dict(row)
        row[f"{ref}_estimate"] = e
        row["in_range"] = (1 if inside else 0) if value is not None and math.isfinite(value) else None
        row[f"{ref}_uncertainty"] = u
        force = to_force(e) if (to_force and e is not None) else None
        if "force_n_estimate" in self.columns:
            row["force_n_estimate"] = force
        self.counts["estimated"] += e is not None
        self.counts["out_of_range"] += row["in_range"] == 0
        self.last.update({"time_s": row["time_s"], ref + "_estimate": e, "force_n": force,
                          "force_g": None if force is None else force / g * 1e3, "in_range": bool(inside),
                          "reference_force_n": row.get("force_n")})
        text = (f"force {fmt_value(force, '.3f')} N = {fmt_value(None if force is None else force / g * 1e3, '.0f')} g"
                if to_force else f"stress {fmt_value(e, '.0f')} Pa (no area: give --sensor or --area for a force)")
        if row.get("force_n") is not None:
            text += f"   load cell {row['force_n']:.3f} N"
        self.live.show(text + ("" if inside else "   (outside the calibrated range)"))
        return row


class _Live(LiveView):
    """Live line of the force on stderr (rich, redrawn in place) when stderr is a terminal; notices as acquire's."""

    def _render(self, st) -> str:
        return self.title

    def show(self, text: str) -> None:
        if self.live is not None:
            self.live.update(f"{self.title}\n{text}")


@app.command("measure")
@meter_circuit_options(virtual_c_off=True)
def measure(
    cal: Path = typer.Option(..., "--cal", metavar="CAL.json", help="Calibration JSON from fsrlab calibrate -o "
            "(readout -> stress_pa [Pa] or force_n [N])."),
    port: str = typer.Option(None, "--port", help="Serial port of the meter (/dev/ttyACM0, COM3, a pty) or 'auto'."),
    virtual: bool = typer.Option(False, "--virtual", help="Measure a virtual meter (its sensor follows --profile)."),
    out: Path = typer.Option(Path("measure.csv"), "--out", "-o", parser=out_path, help="Run file with the estimate "
            "(CSV + NAME.meta.json)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing run and its sidecar."),
    duration: float = typer.Option(None, "--duration", parser=seconds, metavar="TIME", help="Measure this long [s]: "
            "10s, 1.5min (default: until Ctrl-C)."),
    window: float = typer.Option("100ms", "--window", parser=seconds, metavar="TIME", help="Measurement window [s], "
            "whole ms: 100ms, 0.25."),
    sensor: str = typer.Option(None, "--sensor", help=SENSOR_HELP),
    area: float = typer.Option(None, "--area", parser=areas, metavar="AREA", help=AREA_HELP),
    loadcell: Path = typer.Option(None, "--loadcell", metavar="LC.json", help=LOADCELL_HELP),
    profile: str = typer.Option("triangle", "--profile", help=PROFILE_HELP),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS",
                               help="Virtual device: " + PEAK_HELP[0].lower() + PEAK_HELP[1:]),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME",
                                 help="Virtual device: " + PERIOD_HELP[0].lower() + PERIOD_HELP[1:]),
    seed: int = typer.Option(None, "--seed", help="Random seed of the virtual meter's noise (an integer)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No live display."),
    json_out: bool = typer.Option(False, "--json",
                                  help='Print {"frames", "dropped", "duration_s", "file", "estimated", "out_of_range", '
                                       '"last"} as JSON (forces in N).'),
    meter: MeterCircuit = MeterCircuit(),
) -> None:
    """Show the force live from a calibration (N and g; the load cell's reading beside it) and record it.

    Each window's readout goes through the calibration; the run gets the estimate
    (stress_pa_estimate [Pa], force_n_estimate [N] when an area is known or the calibration gives
    force) and in_range (1 inside the calibrated readout range, 0 outside; every reading estimated
    and fed to the memory, as fsrlab apply). Stress becomes force with --sensor, --area or the
    virtual sensor's area. A calibration recorded with another circuit than the meter's (with --port
    the one --r, --c-off, --diode, --vcc and --r-f, --drive describe, which the run's sidecar records)
    or on range 1 only is refused (exit 2); without --r it cannot be checked (a warning).

    Examples (the first calibration, from a clone's examples/, was fitted on 0 to 50 kPa: the virtual
    meter's default --peak 50k stays in its range):

    \b
      fsrlab measure --virtual --cal examples/calibration.json --duration 10s -o live.csv
      fsrlab measure --port auto --r 10k --diode --cal cal.json --sensor flexiforce-a201 -o live.csv
    """
    from fsrlab.acquisition.recorder import record, result_dict
    from fsrlab.acquisition.serial_link import SerialLink

    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    if duration is not None and not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    window_ms = window_ms_option(window)
    calibration = load_frame_calibration(cal, "measure")
    try:
        est = _estimator(calibration)
    except ValueError as exc:
        fail(f"{cal}: {exc}", "--cal")
    circuits = meter.sidecar(0, "--virtual" if virtual else None)  # measure records on range 0
    sensor_meta, area_m2 = sensor_area(sensor, area)
    lc = loadcell_option(loadcell)
    check_out(out, overwrite, inputs=[cal, loadcell])
    device = None
    metadata: dict = {**circuits, **({"sensor": sensor_meta} if sensor_meta else {})}
    if virtual:
        check_virtual(profile, peak, period, meter.virtual_c_off_farad, 0.0, 0.0, seed)
        device, source = make_virtual_device(profile, peak, period, meter.virtual_c_off_farad, seed, 0.0, 0.0, True, 80,
                                             area_m2)
        if lc is None:
            lc = device.load_cell.calibration()
        metadata = {"origin": "fsrlab measure --virtual", **source.metadata(), **metadata}
        area_m2 = source.sensor.area_m2
    refuse_other_meter(calibration, metadata, 0)  # before the device is opened
    if virtual:
        port = device.open()
    elif note := meter.warning(out, cal):
        warn([note])
    ref = est.reference  # "stress_pa" or "force_n"
    to_force = (lambda v: v) if ref == "force_n" else ((lambda v: v * area_m2) if area_m2 else None)
    columns = [f"{ref}_estimate", "in_range"] + (["force_n_estimate"] if ref != "force_n" and to_force else [])
    columns.append(f"{ref}_uncertainty")
    metadata["calibration"] = {"file": str(cal), "x": est.x, "reference": ref, "estimator": "Calibration.estimator"}
    with _Live(not quiet, f"fsrlab measure {out}  (Ctrl-C ends)") as live:
        on_row = _RowEstimates(est, columns, to_force, live)
        try:
            with SerialLink(port) as link, sigterm_as_interrupt():
                result = record(link, out, duration if duration is not None else 10 * 365 * 86400.0,
                                window_ms=window_ms,
                                metadata=metadata, on_event=live.notice,
                                health=(lambda: device.failure) if device is not None else None, overwrite=overwrite,
                                loadcell=lc, extra_columns=columns, on_row=on_row,
                                stop=threading.Event())
        finally:
            if device is not None:
                device.close()
    counts, last = on_row.counts, on_row.last
    info = {**result_dict(result), **counts, "last": last}
    if json_out:
        emit_json(info)
    else:
        shown = (f"last force {fmt_value(last.get('force_n'), '.3f')} N" if to_force else
                 f"last stress {fmt_value(last.get(ref + '_estimate'), '.0f')} Pa")
        typer.echo(f"{out}: {result.frames} windows, {counts['estimated']} estimated, {counts['out_of_range']} outside "
                   f"the calibrated range; {shown}")
    if result.failed:
        print(f"fsrlab: {plain_numbers(result.message)}", file=sys.stderr)
        raise typer.Exit(1)
