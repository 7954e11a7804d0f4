"""``fsrlab demo``: the whole measurement chain on a virtual bench, then the reproduction report (``make demo``)."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import OVERWRITE_DIR_HELP, checked, emit_json, fail, out_path, seconds


@app.command("demo")
def demo(
    out: Path = typer.Option(Path("demo"), "--out", "-o", parser=out_path, help="Directory for the runs, the "
            "calibration, both reports and index.html; created if missing."),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_DIR_HELP),
    device: str = typer.Option("auto", "--device", help="The virtual bench: auto (the digital twin when it can run, "
            "else the Python virtual device), twin or virtual."),
    sensor: str = typer.Option(None, "--sensor", help="The virtual sensor: paper-a201-1 (default) .. paper-a201-4 "
            "(fitted to the paper's §6) or virtual-fsr."),
    cycles: int = typer.Option(4, "--cycles", help="Spring cycles per run [1]: 4."),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help="Duration of one spring cycle "
            "[s]: 4s, 2s."),
    speed: str = typer.Option("max", "--speed", help="The virtual bench's pace: max (as fast as this computer runs it, "
            "the three runs at once; the runs' times stay the simulated clock) or realtime (as hardware, one run after "
            "the other)."),
    repeat: int = typer.Option(5, "--repeat", help="Placements of each dead weight [1]: 5 as in Tables 4 and 5."),
    no_paper: bool = typer.Option(False, "--no-paper", help="Leave out the reproduction report (fsrlab paper)."),
    json_out: bool = typer.Option(False, "--json",
                                  help='Print {"index", "device", "total_s", "steps", "files", "numbers"} as JSON (HE '
                                       'and RE in %, times in s).'),
) -> None:
    """The measurement chain on a virtual bench: record, calibrate, compensate, report; then the paper report.

    Spring cycles (a calibration run and a test run) and dead-weight re-placements on the digital
    twin when it can run, else on the Python virtual device (it says which); a calibration with the
    causal hysteresis compensation; the estimate of the test run; the measurement report of the test
    run (HE of f and V0, RE1/RE2, ISO 376, calibration); the reproduction report; eight sensors on
    one meter (a scan of 2 s, calibrated per channel, and the cross-talk matrix); an index.html
    linking both. The virtual bench runs faster than real time (--speed max; --speed realtime records
    as hardware would, one run after the other). Prints each step as it goes, then the path of
    index.html.

    Examples:

    \b
      fsrlab demo
      fsrlab demo --out /tmp/demo --cycles 2 --period 2s --repeat 2 --no-paper --json
    """
    from fsrlab.bench.demo import DemoSettings
    from fsrlab.reports.demo import run_demo

    if device not in ("auto", "twin", "virtual"):
        fail(f"must be auto, twin or virtual, got {device!r}", "--device")
    if not 1 <= cycles <= 1000:
        fail(f"must be 1 to 1000 cycles, got {cycles}", "--cycles")
    if not 0.5 <= period <= 3600:
        fail(f"must be 0.5 s to 1 h, got {period:g} s", "--period")
    if speed not in ("realtime", "max"):
        fail(f"must be realtime or max, got {speed!r}", "--speed")
    if not 2 <= repeat <= 100:
        fail(f"must be 2 to 100 (RE needs two placements), got {repeat}", "--repeat")
    for parent in (out, *out.parents):
        if parent.exists() and not parent.is_dir():
            fail(f"{parent} is a file, not a directory", "--out")
    from fsrlab.bench.demo import remove_stale_staging

    for gone in remove_stale_staging(out):  # left by a demo killed outright: never a finished run
        print(f"fsrlab demo: removed {gone}, left by a demo that was killed", file=sys.stderr)
    checked(out, "--out", overwrite=overwrite, kind="dir")
    if device == "twin":
        from fsrlab.bench.protocols import twin_status

        ok, reason = twin_status()
        if not ok:
            fail(f"{reason}; use --device virtual", "--device")
    if sensor is not None:
        from fsrlab.bench.demo import demo_sensor

        try:
            demo_sensor(sensor)
        except ValueError as exc:
            fail(str(exc).split(": ", 1)[-1], "--sensor")

    def progress(line: str) -> None:
        print(f"fsrlab demo: {line}", file=sys.stderr, flush=True)

    res = run_demo(out, DemoSettings(cycles=cycles, period_s=period, repeat=repeat, speed=speed), sensor=sensor,
                   device=device,
                   paper=not no_paper, progress=progress)
    if json_out:
        emit_json({"index": str(res.index), "device": res.device, "total_s": res.total_s,
                   "steps": [{"step": t, "seconds": d} for t, d in res.steps],
                   "files": {k: str(v) for k, v in res.files.items()}, "numbers": res.numbers})
    else:
        typer.echo(str(res.index.resolve()))
