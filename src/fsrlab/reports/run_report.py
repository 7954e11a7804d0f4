"""The measurement report of a recorded run: ``index.html``, ``report.json`` and PNGs (``fsrlab report``).

It renders :func:`fsrlab.bench.measurement.measure_run` with :mod:`fsrlab.reports.html` and
:mod:`fsrlab.reports.figures`; the paper's printed values (Tables 3–5) stand beside the run's own
for scale, not as a target (a different sensor on a different bench).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

from fsrlab.reports.model import Figure, Section, Table

__all__ = ["RunReportFiles", "build_sections", "write_run_report"]


@dataclass
class RunReportFiles:
    """What :func:`write_run_report` wrote.

    Attributes
    ----------
    index : Path
        ``index.html``.
    json : Path
        ``report.json`` (:meth:`RunReport.to_dict`).
    figures : list of Path
        The PNGs.
    report : RunReport
        The numbers.
    """

    index: Path
    json: Path
    figures: list
    report: object


def _f(v, spec: str = ".2f") -> str:
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def _loops_figure(rep, outdir: Path) -> Figure | None:
    from fsrlab.reports.figures import new_figure, save

    drawn = [h for h in rep.hysteresis if h.result is not None]
    if not drawn:
        return None
    fig, axes = new_figure(width=11.0, height=4.2, ncols=len(drawn))
    axes = list(axes) if len(drawn) > 1 else [axes]
    scale = 1e-3 if rep.reference == "stress_pa" else 1.0
    unit = "kPa" if rep.reference == "stress_pa" else rep.reference_unit
    for a, h in zip(axes, drawn, strict=True):
        r = h.result
        for c in r.cycles:
            a.plot(c.stress_pa * scale, c.q_load, "-", color="tab:blue", alpha=0.35, lw=0.9)
            a.plot(c.stress_pa * scale, c.q_unload, "-", color="tab:orange", alpha=0.35, lw=0.9)
        if r.overall is not None and r.overall.stress_pa is not None:
            a.plot(r.overall.stress_pa * scale, r.overall.q_load, "-", color="tab:blue", lw=2, label="loading (mean)")
            a.plot(r.overall.stress_pa * scale, r.overall.q_unload, "-", color="tab:orange", lw=2,
                   label="unloading (mean)")
        a.set_xlabel(f"reference {rep.reference} [{unit}]")
        q_unit = "Hz" if h.quantity == "frequency_hz" else "V" if h.quantity == "voltage_v" else ""
        a.set_ylabel(f"{h.quantity} [{q_unit}]")
        a.set_title(f"{h.label}: HE {h.percent:.2f} %")
        a.legend(loc="upper left", fontsize=8)
    name = "loops.png"
    save(fig, outdir / name)
    return Figure(name, "Loading and unloading loops of f and V0 against the reference",
                  "Figure 19a/b: frequency 3–10 kHz and op-amp voltage 0.4–1 V over 0–10 kPa, loading above "
                  "unloading, for four FlexiForce A201 sensors.",
                  "Each cycle faint, the mean branches bold. " + "; ".join(
                      f"{h.label}: HE {_f(h.percent)} % overall" for h in drawn) + ".")


def _estimate_units(rep) -> tuple[dict, str, str, float, str]:
    """The calibration summary, the reference's name and unit, and the plots' scale and unit (kPa for stress)."""
    cal = rep.calibration or {}
    y_name, y_unit = cal.get("y", rep.reference), cal.get("y_unit", rep.reference_unit)
    stress = y_name == "stress_pa"
    return cal, y_name, y_unit, 1e-3 if stress else 1.0, "kPa" if stress else y_unit


def _estimate_time_figure(rep, outdir: Path) -> Figure | None:
    """The estimate with its ±2u band and the reference over time (where the estimate strays, and when)."""
    import numpy as np

    from fsrlab.reports.figures import new_figure, save

    est, ref = rep.curves.get("estimate"), rep.curves.get("estimate_reference")
    t, u = rep.curves.get("time"), rep.curves.get("estimate_uncertainty")
    if est is None or ref is None or t is None:
        return None
    cal, y_name, y_unit, scale, unit = _estimate_units(rep)
    fig, ax = new_figure(width=9.6, height=3.8)
    ax.plot(t, ref * scale, "k-", lw=1, label=f"reference {y_name}")
    ax.plot(t, est * scale, "-", lw=0.9, color="tab:green", label="estimate")
    has_u = u is not None and np.isfinite(u).any()
    if has_u:
        ax.fill_between(t, (est - 2 * u) * scale, (est + 2 * u) * scale, color="tab:green", alpha=0.2, lw=0,
                        label="estimate ± 2u")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"{y_name} [{unit}]")
    ag = rep.agreement
    cover = "" if ag is None or ag.coverage is None else f"; ±2u covers {100 * ag.coverage:.0f} %"
    ax.set_title("the estimate over time" + cover)
    ax.legend(loc="upper right", fontsize=8)
    name = "estimate_time.png"
    save(fig, outdir / name)
    return Figure(name, "The estimate and its ±2u band over time", "The paper shows no estimate over time.",
                  ("Black: the reference recorded with the run; green: the "
                   "estimate" + (" with its ±2u band" if has_u else "")
                   + (f"; on this run's loaded rows, RMSE {_f(ag.rmse, '.4g')} {y_unit}{cover}." if ag else ".")))


def _estimate_figure(rep, outdir: Path) -> Figure | None:
    import numpy as np

    from fsrlab.reports.figures import new_figure, save

    est = rep.curves.get("estimate")
    ref = rep.curves.get("estimate_reference")
    if est is None or ref is None or rep.estimate is None:
        return None
    cal, y_name, _, scale, unit = _estimate_units(rep)
    fig, ax = new_figure(width=6.4, height=4.6)
    ok = np.isfinite(est) & np.isfinite(ref)
    ax.plot(ref[ok] * scale, est[ok] * scale, ".", ms=2.5, color="tab:green", label="estimate")
    lim = [float(np.nanmin(ref[ok])) * scale, float(np.nanmax(ref[ok])) * scale] if ok.any() else [0, 1]
    ax.plot(lim, lim, "k--", lw=1, label="ideal")
    ax.set_xlabel(f"reference {y_name} [{unit}]")
    ax.set_ylabel(f"estimate [{unit}]")
    ax.set_title(f"calibrated estimate: HE {_f(rep.estimate.percent)} %")
    ax.legend(loc="upper left", fontsize=8)
    name = "estimate.png"
    save(fig, outdir / name)
    return Figure(name, "The compensated estimate against the reference",
                  "The paper fits linear and cubic polynomials of frequency to stress (Figure 17) and does not "
                  "compensate the hysteresis.",
                  f"Model {cal.get('model')} on {cal.get('x')} ({cal.get('source')}), with the causal hysteresis "
                  f"compensation: HE of the estimate {_f(rep.estimate.percent)} %.")


def build_sections(rep, outdir: Path) -> list[Section]:
    """The report's sections for a :class:`~fsrlab.bench.measurement.RunReport` (PNGs written into ``outdir``).

    Parameters
    ----------
    rep : RunReport
        From :func:`fsrlab.bench.measurement.measure_run`.
    outdir : Path
        Where the PNGs go.

    Returns
    -------
    list of Section
    """
    from fsrlab.reference import paper_values

    paper = paper_values()
    run = Section("run", "The run",
                  f"File {rep.path}: {rep.rows} rows over {_f(rep.duration_s, '.1f')} s; reference column "
                  f"{rep.reference} [{rep.reference_unit}].")
    return [run, _hysteresis_section(rep, outdir, paper["table3_hysteresis_error_percent"]),
            _repeatability_section(rep, paper), _iso376_section(rep), _creep_section(rep),
            _calibration_section(rep, outdir)]


def _hysteresis_section(rep, outdir: Path, t3: dict) -> Section:
    """Eq. (13) per cycle of both readouts, as Table 3, with the paper's means beside."""
    hs = {h.quantity: h for h in rep.hysteresis}
    f, v = hs.get("frequency_hz"), hs.get("voltage_v")
    n = max((len(h.cycles) for h in rep.hysteresis), default=0)
    rows = [[f"cycle {k + 1}", _f(v.cycles[k]) if v and k < len(v.cycles) else "—",
             _f(f.cycles[k]) if f and k < len(f.cycles) else "—"] for k in range(n)]
    rows.append(["overall (mean branches)", _f(v.percent) if v else "—", _f(f.percent) if f else "—"])
    rows.append(["paper, Table 3 mean of 4 sensors", f"{t3['traditional_mean']:.2f}", f"{t3['proposed_mean']:.2f}"])
    reasons = " ".join(f"{h.label}: {h.reason or h.note}." for h in rep.hysteresis if h.reason or h.note)
    hyst = Section("hysteresis", "Hysteresis error (eq. 13): resistive vs capacitive readout (as Table 3)",
                   "Eq. (13) per loading-unloading cycle of the run and on the mean branches, for the traditional "
                   "op-amp readout (V0, eq. 38) and the proposed 555 frequency. " + reasons,
                   tables=[Table("Hysteresis error [%]", ["", "traditional (V0)", "proposed (f)"], rows,
                                 "The paper's row is its four sensors' mean on its bench, for scale.")])
    fig = _loops_figure(rep, outdir)
    if fig is not None:
        hyst.figures.append(fig)

    return hyst


def _repeatability_section(rep, paper: dict) -> Section:
    """RE1 and RE2 per load (eq. 39), as Tables 4 and 5, with the paper's means beside."""
    if rep.repeatability:
        rrows = []
        for p in rep.repeatability:
            key = "table4_repeatability_capacitive_kHz" if p.quantity == "frequency_hz" else \
                "table5_repeatability_traditional_V"
            printed = paper[key].get(f"{p.load_g:g}g")
            rrows.append([("f [Hz]" if p.quantity == "frequency_hz" else "V0 [V]"), f"{p.load_g:g} "
                    "g", str(p.sensor), p.n,
                          _f(p.mean, ".4g"), _f(p.re1_percent, ".3f"), _f(p.re2_percent, ".3f"),
                          f"{printed['mean_RE1']:g} / {printed['mean_RE2']:g}" if printed else "—"])
        rtable = Table("RE1 and RE2 per load (eq. 39, sample standard deviation)",
                       ["readout", "load", "sensor", "placements", "mean", "RE1 [%]", "RE2 [%]",
                        "paper mean RE1 / RE2 [%]"],
                       rrows, f"From the {rep.repeatability_source}: each mass reached from below once per cycle.")
        rep_sec = Section("repeatability", "Repeatability (eq. 39, as Tables 4 and 5)", tables=[rtable])
    else:
        rep_sec = Section("repeatability", "Repeatability (eq. 39, as Tables 4 and 5)",
                          f"Not computed: {rep.repeatability_reason}.")

    return rep_sec


def _iso376_section(rep) -> Section:
    """The ISO 376 quantities and the class they reach (extension)."""
    if rep.iso376 is not None:
        r = rep.iso376
        names = {"b": "reproducibility b", "b_prime": "repeatability b'", "fc": "interpolation fc",
                 "f0": "zero f0", "v": "reversibility v", "c": "creep c"}
        irows = [[names[k], _f(r.worst(k), ".3f"), r.classes.get(k, "—"), r.missing.get(k, "")] for k in names]
        why = "; ".join(f"{k}: {m}" for k, m in r.missing.items())
        iso = Section("iso376", "ISO 376 quantities and class (extension)",
                      f"Instrument class: {r.instrument_class}" + (f" (missing: {why})" if r.instrument_class ==
                                                                     "incomplete" else "") + ". " + " ".join(r.notes),
                      tables=[Table(f"ISO 376 on {rep.iso376_readout}, worst over the forces "
                                    f"{', '.join(format(x, '.3g') for x in r.forces_n)} N",
                                    ["quantity", "worst [%]", "class reached", "what is missing"], irows)])
    else:
        iso = Section("iso376", "ISO 376 quantities and class (extension)", f"Not computed: {rep.iso376_reason}.")

    return iso


def _creep_section(rep) -> Section:
    """Creep per held load (extension)."""
    if rep.creep:
        crows = [["f [Hz]" if c["quantity"] == "frequency_hz" else "V0 [V]", f"{c['start_s']:.1f}",
                  f"{c['duration_s']:.1f}", f"{c['level']:.4g} {c['reference_unit']}",
                  _f(c["drift_percent_per_decade"], ".3f"), _f(c["total_drift_percent"], ".3f"),
                  "not determined" if c["tau_s"] is None else f"{c['tau_s']:.3g}"] for c in rep.creep]
        creep_sec = Section("creep", "Creep under a held load (extension)",
                            "Each hold of the reference of at least 5 s (fsrlab.metrics.creep, docs/creep.md): "
                            "the readout's drift per decade of time (% of its value 1 s into the hold), its total "
                            "drift over the hold and, when the data determine it, a first-order time constant.",
                            tables=[Table("Creep per hold", ["readout", "start [s]", "duration [s]", "level",
                                                             "drift [%/decade]", "total drift [%]", "τ [s]"],
                                          crows)])
    else:
        creep_sec = Section("creep", "Creep under a held load (extension)", f"Not computed: {rep.creep_reason}.")

    return creep_sec


def _calibration_section(rep, outdir: Path) -> Section:
    """The calibration, its uncertainty, the compensated estimate and, on a validation run, their agreement."""
    cal = rep.calibration
    if cal is not None:
        u = cal["y_unit"]
        crow = [[f"model (chosen by held-out error: {cal['scheme']})", cal["model"]],
                ["readout", cal["x"]], ["reference", f"{cal['y']} [{u}]"], ["source", cal["source"]],
                ["held-out RMSE", f"{_f(cal['heldout_rmse'], '.4g')} {u}"],
                ["R² (in sample)", _f(cal["r2"], ".4f")],
                ["lag of the readout", f"{_f(cal['lag_s'], '.3f')} s"],
                *([["delay of the reference (estimate from the readout this much earlier)",
                    f"{_f(cal['delay_s'], '.3f')} s"]] if cal.get("delay_s") else []),
                ["standard uncertainty, median / largest bin", f"{_f(cal['uncertainty_median'], '.4g')} / "
                                                                f"{_f(cal['uncertainty_max'], '.4g')} {u}"],
                ["causal compensation", "yes" if cal["compensated"] else "no"]]
        if rep.estimate is not None:
            crow.append(["HE of the estimate on this run", f"{_f(rep.estimate.percent)} %"
                         + (f" ({rep.estimate.reason})" if rep.estimate.reason else "")])
        ag = rep.agreement
        if ag is not None:  # a given calibration on a run that has its reference
            crow += [[f"on this run ({ag.rows()}): RMSE, in % of its span",
                      f"{_f(ag.rmse, '.4g')} {u}, {_f(ag.rmse_percent_span, '.3g')} %"],
                     ["on this run: mean error; reference ≈ slope × estimate + intercept",
                      f"{ag.bias:+.3g} {u}; {ag.line(u)}"],
                     ["on this run: errors within ±2u", "—" if ag.coverage is None else f"{100 * ag.coverage:.0f} %"]]
        text = " ".join(t for t in (rep.calibration_reason, ag and ag.warning(u)) if t)
        calsec = Section("calibration", "Calibration, uncertainty and compensation (extension)",
                         text, tables=[Table("Calibration", ["", "value"], crow)])
        for draw in (_estimate_figure, _estimate_time_figure):
            fig = draw(rep, outdir)
            if fig is not None:
                calsec.figures.append(fig)
    else:
        calsec = Section("calibration", "Calibration, uncertainty and compensation (extension)",
                         f"Not computed: {rep.calibration_reason}.")
    return calsec


def write_run_report(run, outdir, placements=None, weights_run=None, calibration=None,
                     calibrate: bool = True, overwrite: bool = False) -> RunReportFiles:
    """Measure a run and write its report (``index.html``, ``report.json``, PNGs) into ``outdir``.

    The output policy (:mod:`fsrlab.io.outputs`): ``outdir`` is refused when it holds anything unless
    ``overwrite=True``; it is never one of the inputs (the run, ``weights_run``, ``placements``, the
    calibration's file) or an input's sidecar, nor empty. Each file is written atomically.

    Parameters
    ----------
    run : Run or path
        The run.
    outdir : path-like
        The report's directory, created if missing.
    placements, weights_run, calibration, calibrate
        As :func:`fsrlab.bench.measurement.measure_run`.
    overwrite : bool
        Write into a directory that is not empty (its files of the same names are replaced).

    Returns
    -------
    RunReportFiles

    Raises
    ------
    OutputError
        ``outdir`` refused (a :class:`~fsrlab.errors.ParameterError` naming ``outdir``).
    """
    from fsrlab.bench.measurement import measure_run
    from fsrlab.errors import ParameterError
    from fsrlab.io.outputs import check_output
    from fsrlab.reports.html import render_html

    if not isinstance(overwrite, bool):
        raise ParameterError(f"must be True or False, got {overwrite!r}", parameter="overwrite")
    outdir = check_output(outdir, "outdir", overwrite=overwrite, kind="dir", names=("index.html", "report.json"),
                          inputs=[_input_path(p) for p in (run, weights_run, placements, calibration)])
    rep = measure_run(run, placements=placements, weights_run=weights_run, calibration=calibration,
                      calibrate=calibrate)
    outdir.mkdir(parents=True, exist_ok=True)
    sections = build_sections(rep, outdir)
    from fsrlab.io.jsonable import to_jsonable
    from fsrlab.io.outputs import write_text_atomic

    # Each file under a temporary name, then renamed: an interrupted report never leaves half a file.
    index = write_text_atomic(outdir / "index.html", render_html(
        sections, outdir, title=f"Measurement report: {rep.path.name}", command="fsrlab report", errata=False))
    js = write_text_atomic(outdir / "report.json", json.dumps(to_jsonable(rep.to_dict()), indent=1, allow_nan=False))
    figures = [outdir / f.filename for s in sections for f in s.figures]
    return RunReportFiles(index, js, figures, rep)


def _input_path(value):
    """The file an input was read from: a path as given, a run's or a calibration's ``path``, else None."""
    if isinstance(value, (str, os.PathLike)):
        return value if os.fspath(value).strip() else None
    found = getattr(value, "path", None)
    return found if isinstance(found, (str, os.PathLike)) else None
