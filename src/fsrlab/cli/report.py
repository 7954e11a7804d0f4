"""``fsrlab paper``: the reproduction report."""

from __future__ import annotations

from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import OVERWRITE_DIR_HELP, checked, emit_json, fail, out_path


@app.command("paper")
def paper(
    out: Path = typer.Option(Path("report"), "--out", "-o", parser=out_path, help="Directory for index.html, "
            "paper.json and the PNG figures; created if missing."),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_DIR_HELP),
    json_out: bool = typer.Option(False, "--json", help="Print the paths written as JSON instead of a summary."),
) -> None:
    """Reproduce every figure and table of the paper, with the paper's values beside ours and the errata.

    Examples (the report in ./report, then open report/index.html; the files written, as JSON):

    \b
      fsrlab paper
      fsrlab paper --out /tmp/fsrlab-report --json
    """
    import atexit
    import gc

    from fsrlab.reports.paper import write_report

    # When the process ends, its objects need no last cyclic garbage collection: Python's would take about
    # 0.2 s after the report is written (matplotlib, scipy); refcounting still frees what it can.
    atexit.register(gc.freeze)
    # A file where the directory should be: say so before building anything.
    for parent in (out, *out.parents):
        if parent.exists() and not parent.is_dir():
            fail(f"{parent} is a file, not a directory", "--out")
    checked(out, "--out", overwrite=overwrite, kind="dir")
    from rich.console import Console

    console = Console(stderr=True)
    try:
        with console.status("building report") as status:
            result = write_report(out, progress=lambda name: status.update(f"building report: {name}"),
                                  overwrite=True)  # checked above
    except OSError as exc:
        fail(f"cannot write the report into {out}: {exc.strerror or exc}", "--out")
    if json_out:
        emit_json({"index": result.index, "json": result.json, "figures": result.figures,
                   "errata": sum(len(s.errata) for s in result.sections)})
    else:
        typer.echo(str(result.index.resolve()))
