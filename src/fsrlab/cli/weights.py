"""``fsrlab weights``: the guided known-weight calibration (place masses, wait until stable, record)."""

from __future__ import annotations

import sys
import threading
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    AREA_HELP,
    GRAVITY_HELP,
    SENSOR_HELP,
    Keyboard,
    MeterCircuit,
    areas,
    check_out,
    checked,
    emit_json,
    fail,
    fraction,
    gravity_value,
    loadcell_option,
    mass_list,
    meter_circuit_options,
    out_path,
    plain_numbers,
    seconds,
    sensor_area,
    sigterm_as_interrupt,
    virtual_bench,
    warn,
    window_ms_option,
)
from fsrlab.io.outputs import write_text_atomic


@app.command("weights")
@meter_circuit_options()
def weights(
    masses: str = typer.Option(..., "--masses", metavar="MASSES", help="Masses to place, increasing, comma-separated "
            "[kg]: 0,50g,100g,200g,500g (g, kg or mg; 0 needs no unit)."),
    port: str = typer.Option(None, "--port", help="Serial port of the meter (/dev/ttyACM0, COM3, a pty) or 'auto'."),
    virtual: bool = typer.Option(False, "--virtual", help="A virtual meter and a virtual bench that places the masses "
            "itself (runs unattended)."),
    out: Path = typer.Option(Path("weights.csv"), "--out", "-o", parser=out_path, help="Run file (CSV + NAME.meta.json "
            "sidecar; NAME.placements.csv beside it)."),
    repeat: int = typer.Option(1, "--repeat", help="Cycles of placements [1], for repeatability (RE1, RE2 as in Tables "
            "4 and 5): 1, 3, 5."),
    unload: bool = typer.Option(False, "--unload", help="After the largest mass, unload in reverse (direction -1), for "
            "hysteresis."),
    loadcell: Path = typer.Option(None, "--loadcell", metavar="LC.json", help="Load-cell calibration JSON: force_n is "
            "then the load cell's reading, force_nominal_n stays m·g."),
    sensor: str = typer.Option(None, "--sensor", help=SENSOR_HELP),
    area: float = typer.Option(None, "--area", parser=areas, metavar="AREA", help=AREA_HELP),
    x: str = typer.Option("frequency_hz", "--x", help="Readout judged for stability and written as reading: "
            "frequency_hz [Hz], duty_cycle [1] or voltage_v [V]."),
    window: float = typer.Option("100ms", "--window", parser=seconds, metavar="TIME", help="Measurement window [s], "
            "whole ms: 20ms, 100ms, 0.25."),
    settle_windows: int = typer.Option(10, "--settle-windows", help="Windows over which the readout's drift is judged "
            "[1]: 10 (at least 2)."),
    max_drift: float = typer.Option("0.5%", "--max-drift", parser=fraction, metavar="FRACTION", help="Stable when the "
            "readout's relative drift over --settle-windows is at most this [1]: 0.5%, 0.002."),
    timeout: float = typer.Option("30s", "--timeout", parser=seconds, metavar="TIME", help="Not stable after this long "
            "[s]: ask again (then skip the step): 30s, 1min."),
    hold: float = typer.Option("1s", "--hold", parser=seconds, metavar="TIME", help="Steady time recorded per step "
            "[s]: 1s, 2s, 500ms."),
    gravity: float = typer.Option("9.80665", "--gravity", parser=gravity_value, metavar="ACCELERATION",
                                  help=GRAVITY_HELP),
    seed: int = typer.Option(None, "--seed", help="Random seed of the virtual meter's noise (an integer)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing run and its sidecar."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Virtual bench: do not print its steps (prompts for a "
            "person are always shown)."),
    json_out: bool = typer.Option(False, "--json",
                                  help='Print {"frames", "dropped", "duration_s", "file", "recorded", "skipped", '
                                       '"placements"} as JSON.'),
    meter: MeterCircuit = MeterCircuit(),
) -> None:
    """Guided known-weight calibration: place each mass, wait until the reading is stable, record it.

    For each step the command asks for the mass (the total on the sensor), waits for Enter, then
    waits until the readout's relative drift over the last --settle-windows windows (second half's
    mean minus first half's, over the mean) is at most --max-drift, and records --hold seconds of
    steady windows. Not stable within --timeout: asked again, then the step is skipped. The run has
    force_n (m·g, or the load cell's with --loadcell; force_nominal_n keeps m·g), stress_pa (with
    an area: --sensor, --area or the virtual sensor), step, direction, cycle, and load (g), sensor,
    reading for fsrlab repeatability; NAME.placements.csv holds one mean reading per placement.
    With --port the meter's circuit as built (--r, --c-off, --diode, --vcc; --r-f, --drive) goes into
    the sidecar, for calibrate and apply to compare. Ctrl-C keeps the rows recorded.

    Examples:

    \b
      fsrlab weights --virtual --masses 0,100g,200g,400g --repeat 3 --unload --window 20ms --hold 200ms -o w.csv
      fsrlab weights --port auto --r 10k --diode --masses 0,50g,100g,200g,500g --repeat 5 --unload -o w.csv
    """
    from fsrlab.acquisition.recorder import record
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.bench.weights import WeightsProcedure, plan_steps

    try:
        masses_kg = mass_list(masses)
    except typer.BadParameter as exc:
        fail(exc.message, "--masses")
    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    window_ms = _check_options(masses, masses_kg, repeat, x, window, settle_windows, max_drift, timeout, hold, seed)
    circuits = meter.sidecar(0, "--virtual" if virtual else None)  # recorded on range 0
    sensor_meta, area_m2 = sensor_area(sensor, area)
    cal = loadcell_option(loadcell)
    check_out(out, overwrite, inputs=[loadcell])
    checked(out.with_name(out.stem + ".placements.csv"), "--out", overwrite=overwrite, inputs=[loadcell])
    steps = plan_steps(masses_kg, repeat, unload)
    stop = threading.Event()
    device = bench = None
    metadata: dict = {**circuits, **({"sensor": sensor_meta} if sensor_meta else {})}
    if virtual:
        device, bench, place = virtual_bench(steps, seed, area_m2, gravity)
        port = device.open()
        vmeta = bench.metadata()
        if sensor_meta:
            vmeta["sensor"] = {**sensor_meta, "virtual_model": vmeta["sensor"]["model"]}
        metadata = {"origin": "fsrlab weights --virtual (virtual bench placing the masses -> VirtualFSR -> LM555 "
                              "and op-amp -> meter model -> emulated firmware over a pty)", **vmeta}
        area_m2 = bench.sensor.area_m2

        def announce(text: str) -> None:
            if not quiet:
                print(f"fsrlab: virtual bench: {text.split(', then press Enter')[0]}", file=sys.stderr, flush=True)

        def confirmed() -> str:
            return "ok"
    else:
        keyboard = Keyboard()

        def announce(text: str) -> None:
            print(f"fsrlab: {text}", file=sys.stderr, flush=True)

        def place(step) -> None:
            keyboard.drain()

        confirmed = keyboard.answer
    unit = {"frequency_hz": "Hz", "duty_cycle": "1", "voltage_v": "V"}[x]
    force_source = "load cell (--loadcell)" if cal is not None else "nominal (mass × g)"
    metadata["units"] = {"load": "g", "sensor": "1", "reading": unit}
    metadata["weights"] = {"masses_kg": masses_kg, "repeat": repeat, "unload": unload, "gravity_m_s2": gravity,
                           "force_n": force_source, "reading": x,
                           "stability": {"criterion": "relative drift of the readout (mean of the second half "
                                                      "of the last windows minus the first half's, over their mean)",
                                         "settle_windows": settle_windows, "max_drift": max_drift,
                                         "timeout_s": timeout, "hold_s": hold}}
    proc = WeightsProcedure(steps, announce, confirmed, place, stop, x=x, gravity_m_s2=gravity,
                            use_loadcell=cal is not None, area_m2=area_m2, settle_windows=settle_windows,
                            max_drift=max_drift, timeout_s=timeout, hold_s=hold)
    columns = ["step", "direction", "cycle", "force_nominal_n", "force_n"] + (["stress_pa"] if area_m2 else []) + [
        "load", "sensor", "reading"]
    # No time limit: a person may take long to place a mass; the plan's end (or Ctrl-C) stops it.
    budget = 10 * 365 * 86400.0
    try:
        with SerialLink(port) as link, sigterm_as_interrupt():
            result = record(link, out, budget, window_ms=window_ms, metadata=metadata, stop=stop,
                            on_event=lambda text: print(f"fsrlab: {text}", file=sys.stderr, flush=True),
                            health=(lambda: device.failure) if device is not None else None, overwrite=overwrite,
                            loadcell=cal, extra_columns=columns, on_row=proc.on_row,
                            final_metadata=lambda: {"weights": {**metadata["weights"], **proc.summary()}})
    finally:
        if device is not None:
            device.close()
    _finish(proc.summary(), result, out, x, len(steps), force_source, virtual, meter, json_out)


def _check_options(masses: str, masses_kg: list, repeat: int, x: str, window: float, settle_windows: int,
                   max_drift: float, timeout: float, hold: float, seed: int | None) -> int:
    """The window in ms; one line naming the option out of range."""
    from fsrlab.bench.weights import READOUTS

    if len(masses_kg) < 2:
        fail(f"give at least two masses, e.g. 0,100g; got {masses!r}", "--masses")
    if not 1 <= repeat <= 1000:
        fail(f"must be 1 to 1000 cycles, got {repeat}", "--repeat")
    if x not in READOUTS:
        fail(f"must be one of {', '.join(READOUTS)}, got {x!r}", "--x")
    window_ms = window_ms_option(window)
    if not 2 <= settle_windows <= 10000:
        fail(f"must be 2 to 10000 windows, got {settle_windows}", "--settle-windows")
    if not 0 < max_drift <= 1:
        fail(f"must be in (0, 1], got {max_drift:g}", "--max-drift")
    if not timeout >= settle_windows * window_ms / 1000.0:
        fail(f"must be at least --settle-windows windows ({settle_windows * window_ms / 1000.0:g} s), got {timeout:g} "
             "s",
             "--timeout")
    if not window_ms / 1000.0 <= hold <= 3600:
        fail(f"must be one window ({window_ms / 1000.0:g} s) to 1 h, got {hold:g} s", "--hold")
    if seed is not None and seed < 0:
        fail(f"must be an integer >= 0, got {seed}", "--seed")
    return window_ms


def _finish(summary: dict, result, out: Path, x: str, n_steps: int, force_source: str, virtual: bool,
            meter: MeterCircuit, json_out: bool) -> None:
    """The placements table written, the summary printed, and the exit code of a recording that failed or stopped
    short."""
    from fsrlab.acquisition.recorder import result_dict
    from fsrlab.bench.weights import placements_table

    placements = out.with_name(out.stem + ".placements.csv")
    try:
        write_text_atomic(placements, placements_table(summary, x))
    except OSError as exc:
        print(f"fsrlab: cannot write {placements}: {exc.strerror}", file=sys.stderr)
    info = {**result_dict(result), "recorded": summary["recorded"], "skipped": summary["skipped"],
            "completed": summary["completed"], "placements": str(placements)}
    if json_out:
        emit_json(info)
    else:
        typer.echo(f"{out}: {summary['recorded']} of {n_steps} steps recorded ({summary['skipped']} skipped), "
                   f"{result.frames} windows; force_n: {force_source}; per placement: {placements}")
        if not virtual and not result.failed and (note := meter.warning(out)):
            warn([note])
    if result.failed:
        print(f"fsrlab: {plain_numbers(result.message)}", file=sys.stderr)
        raise typer.Exit(1)
    if not summary["completed"] and result.ended != "interrupted":
        print(f"fsrlab: the plan did not finish ({result.ended}): {summary['recorded']} steps "
              "recorded", file=sys.stderr)
        raise typer.Exit(1)
