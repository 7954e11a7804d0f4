"""``fsrlab hysteresis``, ``repeatability``, ``calibrate``, ``apply``: what a user does with recorded runs.

Thin commands: they parse options and render; runs are calibrated, converted and measured by
:mod:`fsrlab.analysis.pipeline`; files follow docs/data-format.md.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from fsrlab.cli import app
from fsrlab.cli._common import emit_json, fail, farads, fraction, ohms

_DEGREES = ("auto", "1", "2", "3", "4", "5")


def _load(path: Path):
    from fsrlab.runformat import load_run

    return load_run(path)


def _missing(path: Path, run, column: str, what: str = "", option: str | None = None) -> None:
    fail(f"{path}: column {column!r}{what} missing (columns: {', '.join(run.columns)})", option)


@app.command("hysteresis")
def hysteresis(
    run_file: Path = typer.Argument(..., metavar="RUN.csv", help="A run (docs/data-format.md) with stress_pa (or force_n) and the quantity."),
    quantity: str = typer.Option("frequency_hz", "--quantity", "-q", help="Column whose hysteresis is measured (frequency_hz, duty_cycle, voltage_v, ...)."),
    threshold: float = typer.Option(0.05, "--threshold", parser=fraction, help="Stress reversal threshold, fraction of the stress span (0..1 or %, e.g. 0.05 or 5%), used without a direction column."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Hysteresis error (eq. 13) of a run, per loading-unloading cycle and overall."""
    from fsrlab.analysis.pipeline import hysteresis_of_run

    run = _load(run_file)
    if quantity not in run:
        _missing(run_file, run, quantity, option="--quantity")
    if not 0 < threshold < 1:
        fail(f"must be a fraction in (0, 1), got {threshold:g}", "--threshold")
    res = hysteresis_of_run(run, quantity, threshold)
    if json_out:
        emit_json(res.to_dict())
        return
    table = Table(title=f"Hysteresis error of {quantity} (eq. 13), {run_file.name}")
    for col in ("cycle", "HE (%)", "σd (kPa)"):
        table.add_column(col, justify="right")
    for n, c in zip(res.cycle_numbers, res.cycles):
        table.add_row(str(n), f"{c.percent:.2f}", f"{c.stress_at_max_pa / 1e3:.2f}")
    table.add_row("overall", f"{res.percent:.2f}", f"{res.stress_at_max_pa / 1e3:.2f}")
    console = Console()
    console.print(table)
    console.print(res.method, style="dim")


@app.command("repeatability")
def repeatability(
    file: Path = typer.Argument(..., metavar="FILE.csv", help="CSV with columns load,sensor,reading (one row per reading)."),
    ddof: int = typer.Option(1, "--ddof", help="1: sample std (n − 1), reproduces the paper's Tables 4 and 5; 0: divisor n as printed in eq. (39)."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Repeatability errors RE1 and RE2 (eq. 39) per load and sensor, and their means per load."""
    from fsrlab.analysis.repeatability import grouped_repeatability
    from fsrlab.tables import load_grouped_csv

    if ddof not in (0, 1):
        fail(f"must be 0 or 1, got {ddof}", "--ddof")
    res = grouped_repeatability(*load_grouped_csv(file), ddof=ddof)
    if json_out:
        emit_json(res.to_dict())
        return
    table = Table(title=f"Repeatability (eq. 39, RE2 with divisor {'n − 1' if ddof else 'n'}), {file.name}")
    for col in ("load", "sensor", "n", "mean", "RE1 (%)", "RE2 (%)"):
        table.add_column(col, justify="right")
    for g in res.groups:
        table.add_row(str(g.load), str(g.sensor), str(g.n), f"{g.mean:.6g}", f"{g.re1_percent:.2f}", f"{g.re2_percent:.2f}")
    for m in res.means:
        table.add_row(str(m.load), "mean", "", "", f"{m.re1_percent:.2f}", f"{m.re2_percent:.2f}")
    Console().print(table)


@app.command("calibrate")
def calibrate_cmd(
    run_file: Path = typer.Argument(..., metavar="RUN.csv", help="A run with the reference stress_pa (or force_n) and the readout."),
    x: str = typer.Option("frequency_hz", "--x", help="Readout column to calibrate (frequency_hz, duty_cycle, voltage_v), or c_fsr_farad: C_FSR decoded from frequency_hz and duty_cycle (physics-informed)."),
    degree: str = typer.Option("auto", "--degree", help="Polynomial degree 1..5, or auto (cross-validation keeping whole cycles together)."),
    compensate: bool = typer.Option(False, "--compensate", help="Also fit the direction-aware hysteresis compensation (extension beyond the paper) and report HE before/after."),
    folds: int = typer.Option(5, "--folds", help="Cross-validation folds (≥ 2)."),
    r: float = typer.Option(None, "--r", parser=ohms, help="555 R for --x c_fsr_farad [Ω] (default: the run's sidecar, else 10k)."),
    c_off: float = typer.Option(None, "--c-off", parser=farads, help="C_off for --x c_fsr_farad [F] (default: sidecar, else 0)."),
    output: Path = typer.Option(None, "--output", "-o", help="Write the calibration to this JSON file."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Calibrate readout → stress with a polynomial of degree 1–5 (paper Figure 17 uses 1 and 3)."""
    from fsrlab.analysis.calibration_io import save_calibration
    from fsrlab.analysis.pipeline import calibrate_run, run_circuit

    if degree not in _DEGREES:
        fail(f"must be auto or 1..5, got {degree!r}", "--degree")
    if folds < 2:
        fail(f"must be >= 2, got {folds}", "--folds")
    run = _load(run_file)
    if x not in run and x != "c_fsr_farad":
        _missing(run_file, run, x, option="--x")
    circuit = None
    parts = {k: v for k, v in (("r_ohm", r), ("c_off_farad", c_off)) if v is not None}
    if x == "c_fsr_farad" and parts:
        circuit = run_circuit(run).replace(**parts)
    cal = calibrate_run(run, x=x, degree="auto" if degree == "auto" else int(degree), compensate=compensate,
                        folds=folds, circuit=circuit)
    out = {"degree": cal.degree, "r2": cal.r2, "rmse_pa": cal.rmse, "max_error_percent_fs": cal.max_error_percent_fs,
           "coefficients": cal.model.power_coefficients().tolist()}
    if compensate:
        out["hysteresis_error_before_percent"], out["hysteresis_error_after_percent"] = cal.compensation_he_percent
    if output is not None:
        save_calibration(cal, output)
    if json_out:
        emit_json(out)
        return
    console = Console()
    table = Table(title=f"Calibration stress_pa({x}), {run_file.name}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("degree", str(cal.degree) + (" (chosen by grouped CV)" if cal.cv else ""))
    table.add_row("R²", f"{cal.r2:.5f}")
    table.add_row("RMSE (Pa)", f"{cal.rmse:.4g}")
    table.add_row("max error (% FS)", f"{cal.max_error_percent_fs:.3f}")
    if cal.cv:
        for d, e in zip(cal.cv.degrees, cal.cv.rmse):
            table.add_row(f"CV RMSE degree {d} (Pa)", f"{e:.4g}")
    if compensate:
        table.add_row("HE of calibrated stress, plain (%)", f"{out['hysteresis_error_before_percent']:.3f}")
        table.add_row("HE with compensation (%)", f"{out['hysteresis_error_after_percent']:.3f}")
    console.print(table)
    console.print("coefficients (ascending powers of x): " + ", ".join(f"{c:.6g}" for c in out["coefficients"]))
    if output is not None:
        console.print(f"wrote {output}")


@app.command("apply")
def apply_cmd(
    cal_file: Path = typer.Argument(..., metavar="CAL.json", help="A calibration written by fsrlab calibrate -o."),
    run_file: Path = typer.Argument(..., metavar="RUN.csv", help="The run to convert."),
    output: Path = typer.Option(..., "--output", "-o", help="Output run: the input columns plus stress_pa_estimate."),
    no_compensation: bool = typer.Option(False, "--no-compensation", help="Use the plain polynomial even if the calibration holds a compensation."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Apply a calibration to a run: adds a stress_pa_estimate column [Pa]."""
    from fsrlab.analysis.calibration_io import load_calibration
    from fsrlab.analysis.pipeline import ESTIMATE_COLUMN, apply_calibration
    from fsrlab.runformat import write_run

    cal = load_calibration(cal_file)
    run = _load(run_file)
    if cal.x_name not in run and cal.x_name != "c_fsr_farad":
        _missing(run_file, run, cal.x_name, " (the calibration's readout)")
    est = apply_calibration(cal, run, compensation=not no_compensation)
    how = est.metadata["calibration"]["method"]
    if output.resolve() == run_file.resolve():
        fail("must differ from the input run", "--output")
    write_run(output, est.columns, est.metadata)
    n_out = int(np.sum(~np.isfinite(est[ESTIMATE_COLUMN])))
    if json_out:
        emit_json({"output": str(output), "rows": run.n_rows, "missing": n_out})
        return
    typer.echo(f"wrote {output} ({run.n_rows} rows, stress_pa_estimate by {how})")


@app.command("iso376")
def iso376_cmd(
    file: Path = typer.Argument(..., metavar="FILE.csv", help="Long CSV: series,rotation_deg,force_n,reading[,direction]; force_n = 0 rows are zero readings."),
    creep: str = typer.Option(None, "--creep", help="Readings 30 s and 300 s after applying the largest force, as 'I30,I300'."),
    degree: int = typer.Option(3, "--degree", help="Degree 1..3 of the interpolation equation for fc."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """ISO 376:2011 quantities (b, b', fc, f0, v, c) and the class they reach (beyond the paper)."""
    from fsrlab.analysis.iso376 import iso376
    from fsrlab.tables import load_iso376_csv

    if degree not in (1, 2, 3):
        fail(f"must be 1, 2 or 3, got {degree}", "--degree")
    creep_readings = None
    if creep is not None:
        try:
            a, b = (float(v) for v in creep.split(","))
        except ValueError:
            fail(f"write two readings as I30,I300, got {creep!r}", "--creep")
        creep_readings = (a, b)
    forces, series = load_iso376_csv(file)
    res = iso376(forces, series, creep_readings, degree)
    out = {"forces_n": res.forces_n, "b_percent": res.b, "b_prime_percent": res.b_prime, "fc_percent": res.fc,
           "f0_percent": res.f0, "v_percent": res.v, "c_percent": res.c, "classes": res.classes,
           "instrument_class": res.instrument_class, "missing": res.missing}
    if json_out:
        emit_json(out)
        return
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
        console.print(f"{name}: needs {why}", style="dim")
