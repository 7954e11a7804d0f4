"""``fsrlab creep``: the readout's drift under held loads (drift per decade of time, time constant).

Thin command: it loads the run the way the other analysis commands do (``--skip-bad-rows``, the
incomplete-run warning: helpers of :mod:`fsrlab.cli.analysis`), calls
:func:`fsrlab.metrics.creep.creep_of_run` and renders a table, JSON or a figure.
"""

from __future__ import annotations

from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    SKIP_HELP,
    checked,
    emit_json,
    fail,
    fraction,
    load_run_warned,
    missing_column,
    option_names,
    out_path,
    seconds,
    skipped_json,
    warn,
)
from fsrlab.io.outputs import atomic_path

_PLOT_SUFFIXES = (".png", ".svg", ".pdf")


def _number(value: float, fmt: str) -> str:
    return "—" if value != value else format(value, fmt)  # NaN: not determined


@app.command("creep")
def creep_cmd(
    run_file: Path = typer.Argument(..., metavar="RUN.csv", help="A run (docs/data-format.md) with time_s [s], the "
            "reference force_n [N] or stress_pa [Pa], and the readout."),
    x: str = typer.Option("frequency_hz", "--x", help="Readout column whose drift is measured [its unit]: frequency_hz "
            "[Hz], duty_cycle [1], voltage_v [V], or any numeric column."),
    reference: str = typer.Option(None, "--reference", help="Reference column the holds are found on [N or Pa]: "
            "force_n or stress_pa (default: force_n if the run has it, else stress_pa)."),
    min_hold: float = typer.Option(5.0, "--min-hold", parser=seconds, help="Shortest hold reported [s], e.g. 5s, "
            "500ms, 2min."),
    band: float = typer.Option(0.02, "--band", parser=fraction, help="Half-width of the hold band [1, a fraction of "
            "full scale = the largest |reference|], 0.02 or 2%; in (0, 50 %)."),
    settle: float = typer.Option(None, "--settle", parser=seconds, help="Time after each hold's start left out of the "
            "fits, while the load settles [s], e.g. 0.5s; shorter than --min-hold (default: 0.5 s, at most a fifth of "
            "--min-hold)."),
    plot: Path = typer.Option(None, "--plot", metavar="FILE.png", parser=out_path, help="Also draw the readout against "
            "log time per hold into this figure [.png, .svg or .pdf]."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing --plot file. An input is never "
            "replaced."),
    skip_bad_rows: bool = typer.Option(False, "--skip-bad-rows", help=SKIP_HELP),
    json_out: bool = typer.Option(False, "--json", help="Print JSON (units in the keys; null where not determined)."),
) -> None:
    """Creep of a readout under held loads: drift per decade of time and time constant, per hold.

    A hold is a stretch of at least --min-hold over which the reference (running median of 5
    readings; empty cells left out) stays within ±--band of full scale. Per loaded hold, after
    --settle: drift per decade = b of the line a + b·log10(t − t0), in % of a (the reading at
    t0 + 1 s), signed; τ of r∞ − Δ·exp(−(t − t0)/τ), or "—" when the hold does not determine it
    (τ beyond the hold, a step, no change beyond the noise); total drift in % of the first readings.
    Holds at zero load are rests and are left out. docs/creep.md has the definitions.

    Examples (files under examples/ in the fsrlab source tree):

    \b
      fsrlab creep examples/creep.csv
      fsrlab creep examples/creep.csv --x voltage_v --min-hold 10s --band 3% --json
    """
    from fsrlab.metrics.creep import REFERENCES, creep_of_run

    settle = _checked_options(band, min_hold, settle, reference, plot, overwrite, run_file)
    warnings: list[str] = []
    run = load_run_warned(run_file, skip_bad_rows, warnings)
    if x not in run:
        missing_column(run_file, run, x, option="--x")
    if reference is not None and reference not in run:
        missing_column(run_file, run, reference, option="--reference")
    held = reference or next((c for c in REFERENCES if c in run), None)
    if x in ("time_s", held):
        fail(f"must be a readout column, not the {'time' if x == 'time_s' else 'reference'} {x!r}", "--x")
    with option_names({"band": "--band", "min_hold_s": "--min-hold", "settle_s": "--settle"}):
        res = creep_of_run(run, x=x, reference=reference, band=band, min_hold_s=min_hold, settle_s=settle)
    if plot is not None:
        _save_plot(res, plot)
    warn(warnings)
    if json_out:
        emit_json({**res.to_dict(), **(skipped_json(run) if skip_bad_rows else {}),
                   **({"plot": str(plot)} if plot is not None else {})})
        return
    _print_holds(res, x, run_file, plot)


def _checked_options(band: float, min_hold: float, settle: float | None, reference: str | None, plot: Path | None,
                     overwrite: bool, run_file: Path) -> float:
    """creep's options checked before the run is read; the settling time (its default filled in). [s]"""
    from fsrlab.metrics.creep import REFERENCES

    if not 0 < band < 0.5:
        fail(f"must be a fraction of full scale in (0, 50 %), got {100 * band:g} %", "--band")
    if not min_hold > 0:
        fail(f"must be > 0 s, got {min_hold:g} s", "--min-hold")
    if settle is None:
        settle = min(0.5, min_hold / 5)
    if not 0 <= settle < min_hold:
        fail(f"must be >= 0 s and shorter than --min-hold ({min_hold:g} s), got {settle:g} s", "--settle")
    if reference is not None and reference not in REFERENCES:
        fail(f"must be force_n or stress_pa, got {reference!r}", "--reference")
    if plot is not None:
        if plot.suffix.lower() not in _PLOT_SUFFIXES:
            fail(f"must end in .png, .svg or .pdf, got '{plot}'", "--plot")
        checked(plot, "--plot", overwrite=overwrite, inputs=[run_file])
    return settle


def _print_holds(res, x: str, run_file: Path, plot: Path | None) -> None:
    """The holds as a table, the settings below it and why a drift or τ was not determined."""
    from rich.console import Console
    from rich.table import Table

    ru = res.reference_unit or "1"
    table = Table(title=f"Creep of {x} under held {res.reference}, {run_file.name}")
    for col in ("t0 (s)", "duration (s)", f"{res.reference} ({ru})", "drift (%/decade)", "τ (s)",
                "total drift (%)"):
        table.add_column(col, justify="right")
    notes = []
    for k, h in enumerate(res.holds, start=1):
        tau = _number(h.first_order.tau_s, ".3g")
        if not h.first_order.determined:
            notes.append(f"hold {k}: τ not determined: {h.first_order.note}")
        if h.log.note:
            notes.append(f"hold {k}: drift not determined: {h.log.note}")
        table.add_row(f"{h.hold.start_s:.6g}", f"{h.hold.duration_s:.4g}", f"{h.hold.level:.4g}",
                      _number(h.drift_percent_per_decade, "+.3f"), tau, _number(h.total_drift_percent, "+.3f"))
    console = Console()
    console.print(table)
    console.print(f"band ±{100 * res.band:g} % of full scale ({res.full_scale:.4g} {ru}), holds ≥ {res.min_hold_s:g} "
            "s, "
                  f"first {res.settle_s:g} s of each left out; drift in % of the reading at t0 + 1 s"
                  + (f"; {res.unloaded} unloaded hold(s) left out" if res.unloaded else ""), style="dim")
    for note in notes:
        console.print(note, style="dim")
    if plot is not None:
        console.print(f"wrote {plot}")


def _save_plot(res, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    try:
        res.plot(ax=ax)
        fig.tight_layout()
        try:
            with atomic_path(path) as tmp:
                fig.savefig(tmp, format=path.suffix.lower()[1:])
        except IsADirectoryError:
            fail(f"'{path}' is a directory, not a file", "--plot")
        except OSError as exc:
            fail(f"cannot write '{path}': {exc.strerror or exc}", "--plot")
    finally:
        plt.close(fig)
