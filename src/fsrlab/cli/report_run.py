"""``fsrlab report``: the measurement report of a recorded run (HE, RE1/RE2, ISO 376, calibration)."""

from __future__ import annotations

from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import OVERWRITE_DIR_HELP, checked, emit_json, fail, out_path


def _existing(path: Path | None, option: str) -> None:
    if path is not None and not path.is_file():
        fail(f"{path} does not exist" if not path.exists() else f"{path} is not a file", option)


@app.command("report")
def report(
    run: Path = typer.Argument(..., metavar="RUN.csv", help="The recorded run (fsrlab bench, acquire, weights, "
            "measure)."),
    out: Path = typer.Option(..., "--out", "-o", parser=out_path, help="Directory for index.html, report.json and the "
            "PNGs; created if missing."),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_DIR_HELP),
    weights_run: Path = typer.Option(None, "--weights", metavar="WEIGHTS.csv", help="A dead-weight run (fsrlab bench "
            "weights) for RE1/RE2 of f and V0 and ISO 376 (default: the run itself when it is one)."),
    placements: Path = typer.Option(None, "--placements", metavar="P.csv", help="A placements CSV (load [g], sensor, "
            "reading [Hz]; NAME.placements.csv of fsrlab bench weights, or a table like Table 4) for RE1/RE2 of the "
            "frequency per load and sensor, without a weights run."),
    cal: Path = typer.Option(None, "--cal", metavar="CAL.json", help="Calibration JSON (fsrlab calibrate) applied to "
            "the run; default: the run calibrated on itself."),
    no_calibration: bool = typer.Option(False, "--no-calibration", help="Leave the calibration part out (no --cal, no "
            "self-calibration)."),
    json_out: bool = typer.Option(False, "--json", help="Print the report's numbers (report.json, with HE in %, RE in "
            "%, ISO 376 in %) as JSON."),
) -> None:
    """Measurement report of a recorded run: HE of f and V0 side by side, RE1/RE2, ISO 376, calibration.

    The hysteresis error (eq. 13) per cycle and overall of the capacitive readout (555 frequency)
    and the resistive one (op-amp V0) as in Table 3; RE1/RE2 (eq. 39) per load from dead-weight
    placements as in Tables 4 and 5; the ISO 376 quantities and class when the placements allow
    them (else what is missing); the calibration (model, held-out error, lag, uncertainty) and the HE of
    its compensated estimate; plots of the loops and of the estimate. Prints the path of index.html.

    Examples:

    \b
      fsrlab report examples/bench.csv --out report-run
      fsrlab report examples/other.csv --cal examples/calibration.json --placements examples/repeatability.csv --out r2
    """
    from fsrlab.reports.run_report import write_run_report

    _existing(run, "RUN.csv")
    _existing(weights_run, "--weights")
    _existing(placements, "--placements")
    _existing(cal, "--cal")
    if cal is not None and no_calibration:
        fail("give --cal or --no-calibration, not both", "--cal")
    for parent in (out, *out.parents):
        if parent.exists() and not parent.is_dir():
            fail(f"{parent} is a file, not a directory", "--out")
    checked(out, "--out", overwrite=overwrite, inputs=[run, weights_run, placements, cal], kind="dir",
            names=("index.html", "report.json"))
    try:
        files = write_run_report(run, out, placements=placements, weights_run=weights_run, calibration=cal,
                                 calibrate=not no_calibration, overwrite=True)  # checked above
    except OSError as exc:
        if exc.filename and Path(exc.filename).parent == out:
            fail(f"cannot write the report into {out}: {exc.strerror or exc}", "--out")
        raise
    if json_out:
        emit_json({"index": str(files.index), **files.report.to_dict()})
    else:
        typer.echo(str(files.index.resolve()))
