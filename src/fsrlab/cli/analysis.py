"""``fsrlab hysteresis``, ``repeatability``, ``calibrate``, ``apply``, ``iso376``: what a user does with recorded runs.

Thin commands: they parse options and render; runs are calibrated by
:func:`fsrlab.calibration.runs.calibrate_runs` and converted by :func:`fsrlab.calibration.apply.apply_calibration`;
files follow docs/data-format.md. Warnings (an incomplete run,
skipped rows, an unchecked calibration) go to stderr, each once, when the command has a result;
a command that fails prints its one error line only.
"""

from __future__ import annotations

import math
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    OVERWRITE_HELP,
    SKIP_HELP,
    checked,
    emit_json,
    eng,
    fail,
    fraction,
    load_run_warned,
    missing_column,
    number,
    option_names,
    out_path,
    reading_file,
    skipped_json,
    warn,
)
from fsrlab.errors import ParameterError
from fsrlab.units import STANDARD_GRAVITY


@app.command("hysteresis")
def hysteresis(
    run_file: Path = typer.Argument(..., metavar="RUN.csv", help="A run (docs/data-format.md) with stress_pa [Pa] (or "
            "force_n [N] and the sensor area) and the quantity."),
    quantity: str = typer.Option("frequency_hz", "--quantity", "-q", help="Column whose hysteresis is measured: "
            "frequency_hz [Hz], duty_cycle [1], voltage_v [V], stress_pa_estimate [Pa], ..."),
    threshold: float = typer.Option(0.05, "--threshold", parser=fraction, help="Stress reversal threshold [1, a "
            "fraction of the stress span], 0.05 or 5%; used without a direction column."),
    reference: str = typer.Option(None, "--reference", help="Reference the branches follow: force_n [N] (no sensor "
            "area needed) or stress_pa [Pa] (default: stress_pa if the run has it, else force_n)."),
    unit: str = typer.Option(None, "--unit", help="Display unit of the reference level at the largest difference [N, "
            "g, Pa or kPa] (default kPa for stress, N for force); --json stays SI."),
    skip_bad_rows: bool = typer.Option(False, "--skip-bad-rows", help=SKIP_HELP),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Hysteresis error (eq. 13) of a run, per loading-unloading cycle and overall.

    A readout that does not respond to the stress (a dead or disconnected sensor: its median at
    the highest fifth of the stress range differs from that at the lowest by no more than its
    resolution and noise) has no hysteresis error: the command says so and exits with 2.

    Examples (files under examples/ in the fsrlab source tree):

    \b
      fsrlab hysteresis examples/bench.csv
      fsrlab hysteresis examples/bench.csv --quantity voltage_v --json
    """
    from fsrlab.bench.measurement import hysteresis_of_run

    if not 0 < threshold < 1:
        fail(f"must be a fraction in (0, 1), got {threshold:g}", "--threshold")
    warnings: list[str] = []
    run = load_run_warned(run_file, skip_bad_rows, warnings)
    if quantity not in run:
        missing_column(run_file, run, quantity, option="--quantity")
    if quantity in ("stress_pa", "force_n"):
        fail(f"{quantity} is a reference column: its hysteresis against the reference is the reference against "
             "itself; give a readout such as frequency_hz, voltage_v or stress_pa_estimate", "--quantity")
    _reference_option(run_file, run, reference)
    ref = reference or ("stress_pa" if "stress_pa" in run else "force_n")
    shown, factor = _unit_option(unit if unit is not None else ("kPa" if ref == "stress_pa" else None), ref)
    res = hysteresis_of_run(run, quantity, threshold, reference=ref)
    warn(warnings)
    if json_out:
        extra = {} if ref == "stress_pa" else {"reference": "force_n", "force_at_max_n": res.stress_at_max_pa}
        emit_json({**res.to_dict(), **extra, **(skipped_json(run) if skip_bad_rows else {})})
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"Hysteresis error of {quantity} (eq. 13), {run_file.name}")
    level = "σd" if ref == "stress_pa" else "Fd"
    for col in ("cycle", "HE (%)", f"{level} ({shown})"):
        table.add_column(col, justify="right")
    for n, c in zip(res.cycle_numbers, res.cycles, strict=True):
        table.add_row(str(n), f"{c.percent:.2f}", f"{c.stress_at_max_pa * factor:.4g}")
    table.add_row("overall", f"{res.percent:.2f}", f"{res.stress_at_max_pa * factor:.4g}")
    console = Console()
    console.print(table)
    console.print(res.method, style="dim")


@app.command("repeatability")
def repeatability(
    file: Path = typer.Argument(..., metavar="FILE.csv", help="CSV with columns load,sensor,reading (one row per "
            "reading; the readings in one unit, any)."),
    ddof: int = typer.Option(1, "--ddof", help="Divisor of RE2's standard deviation [1]: 1 for n − 1 (the sample std; "
            "reproduces the paper's Tables 4 and 5), 0 for n as printed in eq. (39)."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Repeatability errors RE1 and RE2 (eq. 39) per load and sensor, and their means per load.

    Examples (files under examples/ in the fsrlab source tree):

    \b
      fsrlab repeatability examples/repeatability.csv
      fsrlab repeatability examples/repeatability.csv --ddof 0 --json
    """
    from fsrlab.io.tables import load_grouped_csv
    from fsrlab.metrics.repeatability import grouped_repeatability

    if ddof not in (0, 1):
        fail(f"must be 0 or 1, got {ddof}", "--ddof")
    with reading_file(file):
        loads, sensors, readings = load_grouped_csv(file)
    try:
        res = grouped_repeatability(loads, sensors, readings, ddof=ddof)
    except ValueError as exc:  # a group's problem, said with the file it is in
        raise ParameterError(f"{file}: {getattr(exc, 'reason', exc)}") from None
    if json_out:
        emit_json(res.to_dict())
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"Repeatability (eq. 39, RE2 with divisor {'n − 1' if ddof else 'n'}), {file.name}")
    for col in ("load", "sensor", "n", "mean", "RE1 (%)", "RE2 (%)"):
        table.add_column(col, justify="right")
    for g in res.groups:
        table.add_row(str(g.load), str(g.sensor), str(g.n), f"{g.mean:.6g}", f"{g.re1_percent:.2f}",
                      f"{g.re2_percent:.2f}")
    for m in res.means:
        table.add_row(str(m.load), "mean", "", "", f"{m.re1_percent:.2f}", f"{m.re2_percent:.2f}")
    Console().print(table)


_GRAMS_PER_NEWTON = 1e3 / STANDARD_GRAVITY


def _reference_option(run_file: Path, run, reference: str | None) -> None:
    """Check --reference against the run (one line naming what the run has)."""
    if reference is not None and reference not in ("force_n", "stress_pa"):
        fail(f"must be force_n or stress_pa, got {reference!r}", "--reference")
    if reference is None and "force_n" not in run and "stress_pa" not in run:
        raise ParameterError(f"{run_file}: no reference: column 'force_n' [N] or 'stress_pa' [Pa] missing (columns: "
                             f"{', '.join(run.columns)})")
    if reference == "force_n" and "force_n" not in run:
        missing_column(run_file, run, "force_n", " (the reference)", "--reference")
    if reference == "stress_pa" and "stress_pa" not in run and "force_n" not in run:
        missing_column(run_file, run, "stress_pa", " (the reference)", "--reference")


def _unit_option(unit: str | None, reference: str) -> tuple[str, float]:
    """Display unit and factor from the reference's unit (SI inside)."""
    base = "N" if reference == "force_n" else "Pa"
    if unit is None or unit == base:
        return base, 1.0
    if unit == "g" and base == "N":
        return "g", _GRAMS_PER_NEWTON
    if unit == "kPa" and base == "Pa":
        return "kPa", 1e-3
    fail(f"must be N or g for force_n, Pa or kPa for stress_pa; got {unit!r} for {reference}", "--unit")
    raise AssertionError  # fail() raises


@app.command("calibrate")
def calibrate_cmd(
    runs: list[Path] = typer.Argument(..., metavar="RUN.csv [RUN2.csv ...]", help="One or more runs of the same sensor "
            "and readout, each with the reference force_n [N] or stress_pa [Pa] and the readout; time_s [s] optional "
            "(row order otherwise)."),
    x: str = typer.Option("frequency_hz", "--x", help="Readout to calibrate: any numeric column, e.g. frequency_hz "
            "[Hz], duty_cycle [1], voltage_v [V], reading [counts] (a run from fsrlab import), or c_fsr_farad [F]: "
            "C_FSR decoded from frequency_hz and duty_cycle through the circuit of the run's sidecar."),
    reference: str = typer.Option(None, "--reference", help="Reference column: force_n [N] (no sensor area needed) or "
            "stress_pa [Pa] (default: stress_pa if the run has it, else force_n)."),
    compensate: bool = typer.Option(False, "--compensate", help="Also try the causal hysteresis and creep compensation "
            "(play operators with memory, exponential averages; extension beyond the paper): fitted to what the static "
            "curve leaves unless refitting the curve with it wins held out, its correction weighted by the held-out "
            "error, kept only when it lowers that error by more than 1.645 standard errors and 5 % of the MSE, and in "
            "every held-out part."),
    unit: str = typer.Option(None, "--unit", help="Display unit of the errors in the table [N, g, Pa or kPa] (default: "
            "the reference's, N or Pa); --json and the file stay SI."),
    lag: str = typer.Option("0", "--lag", help="Lag of the readout behind the reference [s] (rows without time_s), "
            "e.g. 0.02, 0 or auto (a shift of whole rows searched, kept only when it wins held out). Default 0: the "
            "estimate is of the reference as recorded, and a delay of the reference is tried."),
    rail: float = typer.Option(None, "--rail", parser=eng, help="Full scale of a divider's readout [unit of the "
            "readout], e.g. 5 for a voltage read across a divider on 5 V, 3.3 on 3.3 V: the FSR's conductance ratio "
            "V/(rail − V) is then tried as the curve's variable (default: the run's sidecar, or the ADC's full scale "
            "for integer counts). Every reading must lie below it."),
    between_runs: float = typer.Option(None, "--between-runs", parser=fraction, help="Relative standard uncertainty "
            "between recordings [1, a fraction], e.g. 0.2 or 20%: the floor of the uncertainty's term for what changes "
            "from one recording to the next (default 15%; the held-out runs' gain spread when larger). From the setup: "
            "1–8% for a film pressed by a robot, about 20% for an FSR placed by hand from one session to the next "
            "(docs/calibration.md)."),
    skip_bad_rows: bool = typer.Option(False, "--skip-bad-rows", help=SKIP_HELP),
    output: Path = typer.Option(None, "--output", "-o", parser=out_path, help="Write the calibration to this JSON "
            "file."),
    overwrite: bool = typer.Option(False, "--overwrite", help=OVERWRITE_HELP),
    json_out: bool = typer.Option(False, "--json", help="Print JSON: model, how choices were scored and each step's "
            "result, held-out RMSE [reference unit and % FS], lag_s and delay_s [s], candidates, ..."),
) -> None:
    """Calibrate readout → force or stress, every choice scored where it will be used.

    A monotone curve (in the readout, a divider's conductance for analogRead counts or with
    --rail, or the readout's logarithm when every reading is above zero), then a delay of the
    reference (a load cell that reports late), a lag (--lag auto) and the hysteresis and creep
    terms (their correction weighted by the held-out error), each kept only when it beats the
    simpler calibration on another run (or, with one run, on later blocks of it) by more than one
    standard error and by 5 % of its MSE -- otherwise the simpler calibration is written and the
    output says why. The uncertainty comes from those held-out errors. The file records the
    readout range and the circuit and range the runs were recorded with, which fsrlab apply
    checks. See docs/calibration.md.

    Examples (files under examples/ in the fsrlab source tree):

    \b
      fsrlab calibrate examples/bench.csv --compensate -o cal.json
      fsrlab calibrate examples/bench.csv examples/other.csv --x frequency_hz --compensate --json
    """
    from fsrlab.calibration.runs import check_arguments

    check_arguments(x, reference, compensate, rail, between_runs)  # before any run is read
    if output is not None:
        checked(output, "--output", overwrite=overwrite, inputs=runs)
    _calibrate_held_out(runs, x, reference, compensate, unit, lag, skip_bad_rows, output, json_out, rail=rail,
                        between_runs=between_runs)


def _lag_option(lag: str) -> float | str:
    """``--lag``: "auto" or a finite number of seconds (one line naming the option otherwise)."""
    if lag == "auto":
        return lag
    try:
        value = number(lag)
    except typer.BadParameter as exc:
        fail(f"must be auto or a lag in seconds such as 0.02, got {lag!r} ({exc.message})", "--lag")
    if not math.isfinite(value):
        fail(f"must be auto or a finite lag in seconds, got {lag!r}", "--lag")
    return value


def _calibrate_held_out(run_files: list[Path], x: str, reference: str | None, compensate: bool, unit: str | None,
                        lag: str, skip_bad_rows: bool, output: Path | None, json_out: bool,
                        rail: float | None = None, between_runs: float | None = None) -> None:
    """``fsrlab calibrate`` (:func:`fsrlab.calibration.runs.calibrate_runs`): the calibration, its file,
    and its JSON or table."""
    from fsrlab.calibration.document import save_calibration
    from fsrlab.calibration.runs import calibrate_runs, reference_column

    warnings: list[str] = []
    runs = [load_run_warned(run_file, skip_bad_rows, warnings) for run_file in run_files]
    _unit_option(unit, reference_column(runs, reference))
    with option_names({"lag": "--lag"}):  # the run's columns, the reference, the rail: the library's checks
        cal = calibrate_runs(runs, x=x, reference=reference, compensate=compensate, lag=_lag_option(lag), rail=rail,
                             between_runs=between_runs)
    sel = cal.selection
    fs = cal.full_scale
    out = {"method": "held-out", "scheme": sel.scheme, "model": cal.model_name, "reference": cal.y_name,
           "unit": cal.y_unit, "runs": [str(p) for p in run_files], "lag_s": cal.lag_s, "lag_rows": sel.lag_rows,
           "delay_s": cal.model.delay_s, "heldout_rmse": sel.heldout_rmse,
           "heldout_rmse_percent_fs": 100 * sel.heldout_rmse / fs,
           "heldout_rmse_plain": sel.heldout_rmse_plain, "full_scale": fs, "readout_range": list(cal.x_range),
           "compensated": cal.model.has_memory, "uncertainty_relative": cal.model.uncertainty.relative,
           "gain_spread": sel.gain_spread, "readout_variables": sel.readout, "steps": sel.steps,
           "candidates": sel.candidates}
    if output is not None:
        save_calibration(cal, output, overwrite=True, inputs=run_files)  # checked by the command already
    warn(warnings)
    if json_out:
        emit_json(out)
        return
    _calibration_table(cal, run_files, unit, between_runs, out["heldout_rmse_percent_fs"], compensate, output)


def _calibration_table(cal, run_files: list[Path], unit: str | None, between_runs: float | None, percent_fs: float,
                       compensate: bool, output: Path | None) -> None:
    """``fsrlab calibrate``'s table: the model, how it was chosen, its errors and uncertainty."""
    from rich.console import Console
    from rich.table import Table

    sel = cal.selection
    u, k = _unit_option(unit, cal.y_name)
    console = Console()
    table = Table(title=f"Calibration {cal.y_name}({cal.x_name}), {', '.join(p.name for p in run_files)}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("model", cal.model_name)
    table.add_row("choices scored by", sel.scheme)
    table.add_row("lag (s)", f"{cal.lag_s:.4g}")
    table.add_row("reference delay (s)", f"{cal.model.delay_s:.4g}")
    table.add_row(f"held-out RMSE ({u})", f"{k * sel.heldout_rmse:.4g}")
    table.add_row("held-out RMSE (% FS)", f"{percent_fs:.3f}")
    if cal.model.has_memory:
        table.add_row(f"held-out RMSE without compensation ({u})", f"{k * sel.heldout_rmse_plain:.4g}")
    table.add_row(f"readout range ({cal.x_unit or '1'})", f"{cal.x_range[0]:.6g} … {cal.x_range[1]:.6g}")
    if sel.readout:
        table.add_row("readout variable", f"{', '.join(sel.readout.get('used', []))} ({sel.readout.get('why', '')})")
    rel, spread = cal.model.uncertainty.relative, sel.gain_spread
    floor = "the floor given by --between-runs" if between_runs is not None else "the assumed floor"
    parts = "runs'" if len(run_files) > 1 else "blocks'"
    table.add_row("relative uncertainty between runs (%)", f"{100 * rel:.3g} " + (
        ("(given by --between-runs)" if between_runs is not None else "(assumed)") if spread is None else
        f"(the held-out {parts} gain spread)" if spread >= rel else
        f"({floor}; the held-out {parts} gains spread only {100 * spread:.2g} %"
        + ("; calibrate from two or more runs to see what changes between them)" if len(run_files) == 1 else ")")))
    scores = {c["name"]: c["heldout_rmse"] for c in sel.candidates}
    first = sel.steps[0]
    table.add_row(f"static curve: {first['chosen']}", f"chosen of {first['tried']}, held-out RMSE "
                  f"{k * scores[first['chosen']]:.4g} {u}")
    if first.get("averaged"):
        table.add_row(f"static estimate: mean of {len(first['averaged'])}", ", ".join(first["averaged"]))
    for s in sel.steps[1:]:
        kept = "kept" + (f" (weight {s['weight']:.2f})" if "weight" in s else "")
        rmse = s.get("heldout_rmse_at_weight_1", scores.get(s["tried"]))
        table.add_row(f"{s['step']}: {s['tried']}", (kept if s["kept"] else "not kept")
                      + ("" if rmse is None else f", held-out RMSE {k * rmse:.4g} {u}"
                         + (" at weight 1" if s.get("weight", 1.0) < 1.0 else "")))
    console.print(table)
    refused = [s for s in sel.steps if s["step"] == "memory" and not s["kept"]]
    if compensate and refused:
        console.print(f"compensation: {refused[0]['step']} not kept: {refused[0]['why']}")
    if output is not None:
        console.print(f"wrote {output}")


@app.command("apply")
def apply_cmd(
    cal_file: Path = typer.Argument(..., metavar="CAL.json", help="A calibration written by fsrlab calibrate -o."),
    run_file: Path = typer.Argument(..., metavar="RUN.csv", help="The run to convert."),
    output: Path = typer.Option(..., "--output", "-o", parser=out_path, help="Output run: the input columns plus "
            "<reference>_estimate and <reference>_uncertainty [N or Pa] and in_range [1]."),
    no_compensation: bool = typer.Option(False, "--no-compensation", help="Use the plain model even if the calibration "
            "holds a compensation."),
    margin: float = typer.Option(None, "--margin", parser=fraction, help="How far beyond the calibrated readout range "
            "an estimate is still written [1, a fraction of the range's span], e.g. 0.1 or 10%; beyond it the estimate "
            "is left empty (default: every reading). The memory takes every reading whatever the margin, so no "
            "estimate inside the range changes with it; every reading outside the range has in_range = 0."),
    force: bool = typer.Option(False, "--force", help="Apply even to a run recorded with another circuit or range than "
            "the calibration."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing output run and its sidecar; without "
            "it an existing one stops the command. An input (or its sidecar) is never replaced."),
    skip_bad_rows: bool = typer.Option(False, "--skip-bad-rows", help=SKIP_HELP + " Skipped rows are not written."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON: rows written, estimated, missing (with the "
            "reasons), in and out of the readout range; when the run has the reference, its agreement with the "
            "estimate."),
) -> None:
    """Apply a calibration to a run: adds <reference>_estimate, <reference>_uncertainty and in_range.

    The estimate runs causally in row order (the compensation's memory goes forward in time, as
    it would live). Readings at the readout's floor (a calibration file of an earlier fsrlab) are
    below activation (no estimate). Readings
    outside the calibrated readout range are flagged (in_range = 0); beyond the margin their
    estimate is left empty. A run recorded with another circuit or range than the calibration is
    refused unless --force. When the run also has the reference (a validation run), the estimate is
    compared with it over the loaded rows (reference above 5 % of its largest): RMSE, mean error, the
    line reference ≈ slope × estimate + intercept, and the share of errors within ±2u, with a warning
    below 90 %.

    Examples (files under examples/ in the fsrlab source tree):

    \b
      fsrlab apply examples/calibration.json examples/other.csv -o estimate.csv
      fsrlab apply examples/calibration.json examples/other.csv -o estimate.csv --no-compensation --json --overwrite
    """
    from fsrlab.calibration.apply import apply_calibration, check_readout
    from fsrlab.calibration.document import load_calibration
    from fsrlab.calibration.result import as_margin
    from fsrlab.errors import FsrlabError, ProvenanceError
    from fsrlab.io.runwriter import write_run

    as_margin(margin)  # before any file is read
    with reading_file(cal_file):
        try:
            cal = load_calibration(cal_file)
        except FsrlabError as exc:  # the file's fault: named as the argument CAL.json
            fail(exc.reason, "CAL.json")
    warnings: list[str] = []
    run = load_run_warned(run_file, skip_bad_rows, warnings)
    cal.readout(run)  # a run without the calibration's readout: one line naming the file and the column
    checked(output, "--output", overwrite=overwrite, inputs=[cal_file, run_file], kind="run")
    if cal.recorded_with is None:
        warnings.append(f"{cal_file} does not record the circuit and range its data were recorded with (written by an "
                        f"earlier fsrlab, or not from a run): {run_file} is not checked against them")
    if cal.read_only:
        warnings.append(f"{cal_file} was written by the earlier cross-validated engine: applied read-only"
                        + (f"; {cal.model.note}" if cal.model.note else ""))
    differences = check_readout(cal, run)
    if differences and not force:
        raise ProvenanceError(f"{differences[0]}: the same readout means another stress there; calibrate on a run "
                              "recorded the same way, or give --force to apply anyway")
    est = apply_calibration(cal, run, compensation=not no_compensation, margin=margin, force=force)
    info = est.metadata["calibration"]
    for difference in info.get("forced", []):
        warnings.append(f"applied with --force although {difference}")
    write_run(output, est.columns, est.metadata, overwrite=True)  # through temporary files and renames
    n = info["counts"]
    estimate_col = f"{cal.y_name}_estimate"
    agreed = None
    if cal.y_name in est:  # a validation run: the estimate against the reference recorded with it
        from fsrlab.metrics.agreement import agreement

        uncertainty_col = f"{cal.y_name}_uncertainty"
        agreed = agreement(est[cal.y_name], est[estimate_col], est[uncertainty_col] if uncertainty_col in est else None)
        if agreed is not None and agreed.warning(cal.y_unit):
            warnings.append(f"{run_file}: {agreed.warning(cal.y_unit)}")
    warn(warnings)
    if json_out:
        emit_json({"output": str(output), "rows": est.n_rows, "estimated": n["estimated"], "missing": n["missing"],
                   "missing_reasons": {k: n[k] for k in ("no_readout", "not_decodable", "beyond_margin",
                                                          "below_activation")},
                   "in_range": n["in_range"], "out_of_range": n["out_of_range"],
                   "extrapolated": n["extrapolated"], "readout_range": info["readout_range"],
                   "margin_percent": None if info["margin"] is None else 100 * info["margin"],
                   "method": info["method"], "model": info["model"],
                   "reference": cal.y_name, "unit": cal.y_unit, "lag_s": info["lag_s"],
                   "columns": [estimate_col, f"{cal.y_name}_uncertainty", "in_range"],
                   "agreement": None if agreed is None else agreed.to_dict(), **skipped_json(run)})
        return
    lo, hi = info["readout_range"]
    lines = [f"wrote {output} ({est.n_rows} rows, {estimate_col} by {info['method']})"]
    if n["extrapolated"] or n["beyond_margin"]:
        beyond = ("" if info["margin"] is None else f", {n['beyond_margin']} beyond the {100 * info['margin']:g} % "
                  "margin left empty")
        lines.append(f"  outside the calibrated readout range {lo:.6g} … "
                f"{hi:.6g}{' ' + cal.x_unit if cal.x_unit else ''}: "
                     f"{n['extrapolated']} extrapolated (in_range = 0){beyond}")
    if n["below_activation"]:
        lines.append(f"  below activation (readout at its floor, no estimate): {n['below_activation']} rows")
    if n["no_readout"] or n["not_decodable"]:
        lines.append(f"  without an estimate: {n['no_readout']} rows without a readout"
                     + (f", {n['not_decodable']} not decodable" if n["not_decodable"] else ""))
    if agreed is not None:
        u = cal.y_unit
        cover = "" if agreed.coverage is None else f", ±2u covers {100 * agreed.coverage:.0f} %"
        lines.append(f"  against {cal.y_name} in the run ({agreed.rows()}): RMSE {agreed.rmse:.4g} {u} "
                     f"({agreed.rmse_percent_span:.3g} % of its span), mean error {agreed.bias:+.3g} {u}, "
                     f"{agreed.line(u)}{cover}")
    typer.echo("\n".join(lines))


@app.command("iso376")
def iso376_cmd(
    file: Path = typer.Argument(..., metavar="FILE.csv", help="Long CSV: series,rotation_deg [°],force_n "
            "[N],reading[,direction]; force_n = 0 rows are zero readings."),
    creep: str = typer.Option(None, "--creep", help="Readings 30 s and 300 s after applying the largest force [unit of "
            "the readings], as 'I30,I300', e.g. 8396.6,8404.8."),
    degree: int = typer.Option(3, "--degree", help="Degree 1..3 [1] of the interpolation equation for fc."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """ISO 376:2011 quantities (b, b', fc, f0, v, c) and the class they reach (beyond the paper).

    Examples (files under examples/ in the fsrlab source tree):

    \b
      fsrlab iso376 examples/iso376.csv
      fsrlab iso376 examples/iso376.csv --creep 8396.6,8404.8 --json
    """
    from fsrlab.io.tables import load_iso376_csv
    from fsrlab.metrics.iso376 import iso376

    if degree not in (1, 2, 3):
        fail(f"must be 1, 2 or 3, got {degree}", "--degree")
    creep_readings = None
    if creep is not None:
        cells = creep.split(",")
        if len(cells) != 2:
            fail(f"write two readings as I30,I300, got {creep!r}", "--creep")
        try:
            creep_readings = tuple(number(c.strip()) for c in cells)
        except typer.BadParameter as exc:
            fail(f"write two finite readings as I30,I300, got {creep!r} ({exc.message})", "--creep")
    with reading_file(file):
        forces, series = load_iso376_csv(file)
    with option_names({"creep_readings": "--creep", "interpolation_degree": "--degree"}):
        res = iso376(forces, series, creep_readings, degree)
    out = {"forces_n": res.forces_n, "b_percent": res.b, "b_prime_percent": res.b_prime, "fc_percent": res.fc,
           "f0_percent": res.f0, "v_percent": res.v, "c_percent": res.c, "classes": res.classes,
           "instrument_class": res.instrument_class, "missing": res.missing, "notes": res.notes}
    if json_out:
        emit_json(out)
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"ISO 376:2011 quantities, {file.name}")
    for col in ("quantity", "worst (%)", "class"):
        table.add_column(col, justify="right")
    for name in ("b", "b_prime", "fc", "f0", "v", "c"):
        w = res.worst(name)
        table.add_row(name.replace("_prime", "'"), "—" if w is None else f"{w:.4f}", res.classes.get(name, "—"))
    console = Console()
    console.print(table)
    console.print(f"instrument class: {res.instrument_class}")
    for name, why in res.missing.items():
        console.print(f"{name.replace('_prime', chr(39))}: needs "
                f"{why}" + (" (--creep)" if name == "c" else ""), style="dim")
    for note in res.notes:
        console.print(note, style="dim")
