"""``fsrlab bench``: the bench protocols (spring cycles, dead-weight re-placements, a creep hold)."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    Keyboard,
    LiveView,
    MeterCircuit,
    check_out,
    check_speed,
    checked,
    emit_json,
    fail,
    loadcell_option,
    mass_list,
    masses,
    meter_circuit_options,
    out_path,
    pascals,
    plain_numbers,
    seconds,
    sensor_area,
    sigterm_as_interrupt,
    virtual_sensor_option,
    warn,
    window_ms_option,
)

_PROTOCOLS = ("spring", "weights", "creep")


@app.command("bench")
@meter_circuit_options()
def bench(
    protocol: str = typer.Argument(..., metavar="PROTOCOL", help="spring (cycles 0 → peak → 0), weights (dead-weight "
            "re-placements, Tables 4/5) or creep (a held mass)."),
    virtual: bool = typer.Option(False, "--virtual", help="Run on the Python virtual device (a model of the meter on a "
            "pty); unattended."),
    twin: bool = typer.Option(False, "--twin", help="Run on the digital twin (the firmware in simavr on a pty); "
            "unattended."),
    speed: str = typer.Option("realtime", "--speed", help="With --virtual or --twin: realtime (as hardware, for "
            "watching) or max (as fast as this computer runs the bench; the run's times stay the simulated clock)."),
    port: str = typer.Option(None, "--port", help="Serial port of a real meter (/dev/ttyACM0, COM3, a pty) or 'auto': "
            "you are prompted for each step."),
    out: Path = typer.Option(None, "--out", "-o", parser=out_path, help="Run file (CSV + NAME.meta.json sidecar; "
            "weights: NAME.placements.csv beside it) [default: PROTOCOL.csv]."),
    sensor: str = typer.Option(None, "--sensor", help="Sensor: a preset for its sensing area (flexiforce-a201, "
            "interlink-402; the virtual FSR gets that area), or with --virtual/--twin a virtual sensor: virtual-fsr "
            "(default), paper-a201-1 .. paper-a201-4 (the sensors fitted to the paper's §6; with --port only their "
            "area)."),
    peak: float = typer.Option("10k", "--peak", parser=pascals, metavar="STRESS", help="spring: peak stress [Pa]: 10k, "
            "10kPa, 0.05MPa (the paper's bench: 10 kPa)."),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help="spring: duration of one cycle "
            "[s]: 4s, 500ms, 1min."),
    cycles: int = typer.Option(3, "--cycles", help="spring: loading-unloading cycles [1]: 3, 10."),
    masses_opt: str = typer.Option("200g,400g", "--masses", metavar="MASSES", help="weights: masses placed, "
            "increasing, comma-separated [kg]: 200g,400g (g, kg or mg); the plan is 0 → each → back to 0, per cycle."),
    repeat: int = typer.Option(5, "--repeat", help="weights: how often each mass is placed again [1]: 5 as in Tables 4 "
            "and 5."),
    mass: float = typer.Option("200g", "--mass", parser=masses, metavar="MASS", help="creep: the mass held [kg]: 200g, "
            "0.5kg."),
    hold: float = typer.Option("60s", "--hold", parser=seconds, metavar="TIME", help="creep: how long the mass stays "
            "on [s]: 60s, 5min (recorded with up to 2 s unloaded before and 5 s after)."),
    settle_hold: float = typer.Option("1s", "--settle-hold", parser=seconds, metavar="TIME", help="weights: steady "
            "time recorded per placement [s]: 1s, 200ms."),
    window: float = typer.Option("20ms", "--window", parser=seconds, metavar="TIME", help="Measurement window [s], "
            "whole ms: 20ms, 100ms."),
    seed: int = typer.Option(None, "--seed", help="Random seed of the virtual meter's noise (an integer)."),
    loadcell: Path = typer.Option(None, "--loadcell", metavar="LC.json", help="Load-cell calibration JSON (fsrlab "
            "loadcell tare/scale) [counts → N]; a virtual meter uses its own."),
    report: Path = typer.Option(None, "--report", metavar="DIR", parser=out_path, help="Also write the measurement "
            "report of the run (index.html) into this directory."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing run and its sidecar (weights: and "
            "its placements file), and write the --report into a directory that is not empty. An input is never "
            "replaced."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Virtual bench: do not print its steps (prompts for a "
            "person are always shown)."),
    json_out: bool = typer.Option(False, "--json",
                                  help='Print {"file", "frames", "dropped", "duration_s", "protocol", "device", '
                                       '"placements", "report"} as JSON.'),
    meter: MeterCircuit = MeterCircuit(),
) -> None:
    """Run a bench protocol (spring cycles, dead-weight re-placements, a creep hold) into a run file.

    spring: cycles from 0 to --peak and back, --period each, as on the paper's stepper-motor bench
    (Figure 19, Table 3); weights: 0 → each of --masses → back to 0, --repeat times, each placement
    recorded once stable (Tables 4 and 5: RE1/RE2 from NAME.placements.csv); creep: --mass held for
    --hold. --virtual and --twin run unattended (the virtual bench applies the loads); with --port
    you are prompted for each step (Enter to go on), and the meter's circuit as built (--r, --c-off,
    --diode, --vcc; --r-f, --drive) goes into the sidecar for calibrate and apply to compare. Ctrl-C
    keeps the rows recorded. With --report DIR the measurement report of the run follows (fsrlab report).

    Examples:

    \b
      fsrlab bench spring --virtual --cycles 3 --period 3s --out spring.csv --report spring-report
      fsrlab bench weights --port auto --r 10k --diode --sensor flexiforce-a201 --repeat 5 --out weights.csv
    """
    from fsrlab.bench.protocols import run_protocol, twin_status

    if protocol not in _PROTOCOLS:
        fail(f"must be one of {', '.join(_PROTOCOLS)}, got {protocol!r}", "PROTOCOL")
    if int(virtual) + int(twin) + int(port is not None) != 1:
        fail("give exactly one of --virtual, --twin and --port PORT|auto", "--port")
    check_speed(speed, virtual or twin, "--virtual or --twin")
    out = out if out is not None else Path(f"{protocol}.csv")
    window_ms = window_ms_option(window)
    if seed is not None and seed < 0:
        fail(f"must be an integer >= 0, got {seed}", "--seed")
    plan = _plan(protocol, window_ms, cycles, peak, period, masses_opt, repeat, settle_hold, mass, hold)
    if twin:
        ok, reason = twin_status()
        if not ok:
            fail(f"{reason}; use --virtual for the Python virtual device", "--twin")
    circuits = meter.sidecar(0, None if port is not None else "--twin" if twin else "--virtual")  # on range 0
    area_m2 = None
    if (sensor or "").strip().lower() == "virtual-fsr" and port is not None:
        fail(f"{sensor!r} is a virtual sensor; with --port give a preset for the area (flexiforce-a201, "
             "interlink-402)", "--sensor")
    sensor_obj, sensor_meta = virtual_sensor_option(sensor) if port is None else (None, None)
    if sensor_obj is None:  # with --port a paper sensor's name gives its area
        sensor_meta, area_m2 = sensor_area(sensor, None)
    cal = loadcell_option(loadcell)
    check_out(out, overwrite, inputs=[loadcell])
    if protocol == "weights":
        checked(out.with_name(out.stem + ".placements.csv"), "--out", overwrite=overwrite, inputs=[loadcell])
    if report is not None:
        _check_report_dir(report)
        checked(report, "--report", overwrite=overwrite, inputs=[out, loadcell], kind="dir",
                names=("index.html", "report.json"))
    device = "virtual" if virtual else "twin" if twin else "port"
    announce, confirm = _announcer(device, quiet)
    if device != "port" and sensor_obj is None:
        from fsrlab.bench.protocols import virtual_sensor

        sensor_obj = virtual_sensor((sensor or "virtual-fsr").strip().lower())[0]

    try:
        with sigterm_as_interrupt(), LiveView(not quiet and protocol != "weights",
                                                f"fsrlab bench {protocol} -> {out}") as view:
            run = run_protocol(plan, out, device=device, port=port, sensor=sensor_obj, area_m2=area_m2, seed=seed,
                               window_ms=window_ms, loadcell=cal, announce=announce, confirm=confirm,
                               overwrite=overwrite, settle={"hold_s": settle_hold} if protocol == "weights" else None,
                               metadata={**circuits, **({"sensor": sensor_meta} if sensor_meta else {})},
                               on_status=view.update,
                               speed=speed)
    except KeyboardInterrupt:  # Ctrl-C before the recording began (while asked to start): nothing recorded
        raise typer.Abort() from None
    except ValueError as exc:
        # The virtual sensor's model refuses a stress beyond its range (before any device is opened).
        if device != "port" and any(t in str(exc) for t in ("stress_pa", "no valid response", "resistance")):
            fail(f"the virtual sensor model has no valid response at this load ({exc}); choose a smaller one",
                 "--peak" if protocol == "spring" else "--masses" if protocol == "weights" else "--mass")
        raise
    _finish(run, out, report, protocol, device, meter, json_out)


def _plan(protocol: str, window_ms: int, cycles: int, peak: float, period: float, masses_opt: str, repeat: int,
          settle_hold: float, mass: float, hold: float):
    """The protocol's plan from its options; one line naming the option out of range."""
    from fsrlab.bench.protocols import CreepPlan, SpringPlan, WeightsPlan

    try:
        if protocol == "spring":
            if not 1 <= cycles <= 100000:
                fail(f"must be 1 to 100000 cycles, got {cycles}", "--cycles")
            if not peak > 0:
                fail(f"must be > 0 Pa, got {peak:g} Pa", "--peak")
            if not period > 2 * window_ms / 1000.0:
                fail(f"must be longer than two windows ({2 * window_ms / 1000.0:g} s), got {period:g} s", "--period")
            return SpringPlan(peak_pa=peak, cycles=cycles, period_s=period)
        if protocol == "weights":
            try:
                m = mass_list(masses_opt)
            except typer.BadParameter as exc:
                fail(exc.message, "--masses")
            if not 1 <= repeat <= 1000:
                fail(f"must be 1 to 1000, got {repeat}", "--repeat")
            if not window_ms / 1000.0 <= settle_hold <= 3600:
                fail(f"must be one window ({window_ms / 1000.0:g} s) to 1 h, got {settle_hold:g} s", "--settle-hold")
            try:
                return WeightsPlan(masses_kg=tuple(m), repeat=repeat)
            except ValueError as exc:
                fail(str(exc).replace("masses_kg", "masses"), "--masses")
        if not mass > 0:
            fail(f"must be > 0 kg, got {mass:g} kg", "--mass")
        if not 2 * window_ms / 1000.0 < hold <= 7 * 86400:
            fail(f"must be longer than two windows and at most 7 days, got {hold:g} s", "--hold")
        return CreepPlan(mass_kg=mass, hold_s=hold, before_s=min(2.0, hold / 4), after_s=min(5.0, hold / 2))
    except ValueError as exc:
        fail(str(exc), "--" + protocol)


def _announcer(device: str, quiet: bool):
    """How the bench says its steps (``announce``) and reads a person's answer (``confirm``; None unattended)."""
    if device == "port":
        keyboard = Keyboard()

        def announce(text: str) -> None:
            if "press Enter" in text:
                keyboard.drain()  # a line typed before the question does not answer it
            print(f"fsrlab: {text}", file=sys.stderr, flush=True)
        return announce, keyboard.answer

    def announce_virtual(text: str) -> None:
        if not quiet:
            print(f"fsrlab: virtual bench: {text.split(', then press Enter')[0]}", file=sys.stderr, flush=True)
    return announce_virtual, None


def _finish(run, out: Path, report: Path | None, protocol: str, device: str, meter: MeterCircuit,
            json_out: bool) -> None:
    """The report when asked, the summary printed, and the exit code of a recording that failed or stopped short."""
    from fsrlab.acquisition.recorder import result_dict

    result = run.result
    report_index = None
    if report is not None and not result.failed and result.frames:
        from fsrlab.reports.run_report import write_run_report

        # --report was checked before the recording (the output policy); the run is its input.
        report_index = write_run_report(out, report, placements=run.placements, overwrite=True).index
    info = {**result_dict(result), "protocol": run.protocol, "device": run.device,
            "placements": None if run.placements is None else str(run.placements),
            "report": None if report_index is None else str(report_index)}
    if run.summary:
        info.update({"recorded": run.summary["recorded"], "skipped": run.summary["skipped"]})
    if json_out:
        emit_json(info)
    else:
        typer.echo(f"{out}: {protocol} on {run.device}, {result.frames} windows, {result.dropped} dropped, "
                   f"{result.duration_s:.1f} s" + (f"; per placement: {run.placements}" if run.placements else "")
                   + (f"; report: {report_index}" if report_index else ""))
        if device == "port" and not result.failed and (note := meter.warning(out)):
            warn([note])
    if result.failed:
        print(f"fsrlab: {plain_numbers(result.message)}", file=sys.stderr)
        raise typer.Exit(1)
    if run.summary and not run.summary.get("completed") and result.ended != "interrupted":
        print(f"fsrlab: the plan did not finish ({result.ended}): {run.summary['recorded']} steps recorded",
              file=sys.stderr)
        raise typer.Exit(1)


def _check_report_dir(report: Path) -> None:
    """A report directory that is a file, or under one: one line naming --report."""
    for parent in (report, *report.parents):
        if parent.exists() and not parent.is_dir():
            fail(f"{parent} is a file, not a directory", "--report")
