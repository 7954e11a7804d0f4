"""Report section: the paper's experiment (§6) on fsrlab's virtual bench, beside the printed values.

The four fitted "paper sensors" (:func:`fsrlab.physics.paper_sensor.paper_sensors`) run the paper's
protocols through its two readouts and fsrlab's meter model (:func:`fsrlab.paper.experiment.run_experiment`):
spring cycles 0 → 10 kPa → 0 (Figure 19, Table 3) and five re-placements of 200 g and 400 g
(Tables 4 and 5); Figure 17's fits are redone on the first sensor's cycle. This module draws and
words the results; ``data["experiment"]`` puts each printed value beside the virtual bench's, split
into ``targets`` (what the preset was fitted to, :func:`fsrlab.paper.split.targets`) and ``predictions``
(every other printed number of §6 the bench produces, :func:`fsrlab.paper.split.predictions`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fsrlab.paper.experiment import Experiment, run_experiment
from fsrlab.paper.holdout import cross_readout_spreads
from fsrlab.paper.preset_fit import (
    FIT_PARAMETERS,
    SHARED_FIT_PARAMETERS,
    SPREADS,
    preset_targets,
    quick_response,
    re2_design_per_sensor,
)
from fsrlab.paper.split import TOLERANCES, predictions, trivial_baseline
from fsrlab.paper.split import targets as fit_targets
from fsrlab.physics.paper_sensor import DEAD_WEIGHT_AREA_M2, PAPER_SENSOR_COMMON, paper_sensors
from fsrlab.reference import paper_values
from fsrlab.reports.figures import new_figure, save
from fsrlab.reports.model import Erratum, Figure, Section, Table

_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red")


def _branch_order(exp: Experiment, key: str) -> str:
    """Which branch lies above, from the mean unloading − loading difference of all sensors' cycles."""
    diffs = []
    for c in exp.cycles:
        sl, ql, su, qu = c.branches(key)
        diffs.append(np.nanmean(np.interp(sl, su[::-1], qu[::-1]) - ql))
    return "unloading above loading" if np.mean(diffs) > 0 else "loading above unloading"


def _fig19(outdir: Path, exp: Experiment, key: str, scale: float, unit: str, label: str, printed_range,
           name: str) -> Path:
    fig, ax = new_figure(6.4, 4.2)
    ax.axhspan(printed_range[0], printed_range[1], color="0.9", zorder=0, label="paper's range (Fig. 19)")
    for i, (c, color) in enumerate(zip(exp.cycles, _COLORS, strict=False), start=1):
        sl, ql, su, qu = c.branches(key)
        ax.plot(sl / 1e3, ql * scale, "-", color=color, lw=1.4, label=f"sensor {i} loading")
        ax.plot(su / 1e3, qu * scale, "--", color=color, lw=1.2, label=f"sensor {i} unloading")
    ax.set_xlabel("σ (kPa)")
    ax.set_ylabel(f"{label} ({unit})")
    ax.set_title(f"{label} vs stress, virtual bench (paper sensors 1–4, meter model)")
    ax.legend(fontsize=7, ncol=2)
    return save(fig, outdir / name)


def _fig17(outdir: Path, exp: Experiment) -> Path:
    from fsrlab.paper.polyfit import fit_polynomial

    c = exp.cycles[0]
    sl, fl, su, fu = c.branches("frequency_hz")
    f_all, s_all = np.concatenate([fl, fu]), np.concatenate([sl, su])
    fig, axes = new_figure(10.0, 4.0, ncols=2, sharey=True)
    grid = np.linspace(np.nanmin(f_all), np.nanmax(f_all), 100)
    for ax, deg, lab in ((axes[0], 1, "(a) linear"), (axes[1], 3, "(b) cubic")):
        fit = fit_polynomial(f_all, s_all, deg)
        ax.plot(fl / 1e3, sl / 1e3, ".", ms=4, color="tab:blue", label="loading")
        ax.plot(fu / 1e3, su / 1e3, ".", ms=4, color="tab:orange", label="unloading")
        ax.plot(grid / 1e3, fit(grid) / 1e3, "k-", lw=1.4, label=f"fit on both branches, R² = {fit.r2:.4f}")
        fu_at = np.interp(sl, su[::-1], fu[::-1])
        mean_fit = fit_polynomial(0.5 * (fl + fu_at), sl, deg)
        ax.plot(grid / 1e3, mean_fit(grid) / 1e3, "k:", lw=1.4,
                label=f"fit on the branch means, R² = {mean_fit.r2:.4f}")
        ax.set_xlabel("f (kHz)")
        ax.set_title(f"{lab}: σ(f), virtual sensor 1")
        ax.legend(fontsize=8)
    axes[0].set_ylabel("σ (kPa)")
    return save(fig, outdir / "experiment_fig17.png")


def _table3(exp: Experiment, printed: dict) -> tuple[Table, dict]:
    t3 = printed["table3_hysteresis_error_percent"]
    tm, pm = exp.he_traditional, exp.he_proposed
    rows = [[s, a, b, b - a, c, d, d - c] for s, a, b, c, d in zip(t3["sensor"], t3["traditional"], tm,
                                                                        t3["proposed"], pm, strict=True)]
    rows.append(["mean", t3["traditional_mean"], float(tm.mean()), float(tm.mean()) - t3["traditional_mean"],
                 t3["proposed_mean"], float(pm.mean()), float(pm.mean()) - t3["proposed_mean"]])
    data = {"sensor": t3["sensor"],
            "traditional": {"printed": t3["traditional"], "virtual_bench": tm.tolist(),
                            "residual_pp": (tm - np.array(t3["traditional"])).tolist()},
            "proposed": {"printed": t3["proposed"], "virtual_bench": pm.tolist(),
                         "residual_pp": (pm - np.array(t3["proposed"])).tolist()},
            "mean": {"traditional": {"printed": t3["traditional_mean"], "virtual_bench": float(tm.mean())},
                     "proposed": {"printed": t3["proposed_mean"], "virtual_bench": float(pm.mean())}},
            "status": "fitted: every row is a target of the preset's fit"}
    table = Table(
        title="Table 3 (fitted): HE of the traditional (op-amp voltage) and proposed (555 frequency) readouts",
        columns=["sensor", "HE_TM paper (%)", "HE_TM fitted, bench (%)", "residual (pp)", "HE_PM paper (%)",
                 "HE_PM fitted, bench (%)", "residual (pp)"],
        rows=rows,
        note="fsrlab: eq. (13) by fsrlab.metrics.cycles.run_hysteresis on one virtual spring cycle 0 → 10 kPa → 0 "
             "(40 stepper positions per ramp, one 100 ms meter window each) of each fitted paper sensor; voltage "
             "through eq. (38) (R_F = 20 kΩ, Vcc = −5 V) and the Uno's 10-bit ADC, frequency through the Fig. 16 "
             "LM555 (D1 ideal, R = 10 kΩ) and the 62.5 ns timer. The preset was fitted to these rows on the "
             "closed forms without the meter: this table shows that the meter and bench keep the fit, not a "
             "prediction; the residuals include the meter's quantization and noise.")
    return table, data


def _repeat_table(exp: Experiment, printed: dict, key: str, attr: str, re_attr: str, unit: str,
                  title: str, expected: dict, status: str) -> tuple[Table, dict]:
    tab = printed[key]
    rows, data = [], {}
    for label, ws in exp.weights.items():
        p = tab[label]
        got_mean = [float(getattr(w, attr).mean()) for w in ws]
        re1 = [float(getattr(w, re_attr).re1_percent) for w in ws]
        re2 = [float(getattr(w, re_attr).re2_percent) for w in ws]
        p_mean = [float(np.mean(r)) for r in p["readings"]]
        for i in range(len(ws)):
            rows.append([label, str(i + 1), p_mean[i], got_mean[i], got_mean[i] / p_mean[i], p["RE1_percent"][i],
                         re1[i], p["RE2_percent"][i], re2[i]])
        rows.append([label, "mean", float(np.mean(p_mean)), float(np.mean(got_mean)),
                     float(np.mean(got_mean) / np.mean(p_mean)), p["mean_RE1"], float(np.mean(re1)), p["mean_RE2"],
                     float(np.mean(re2))])
        rows.append([label, "expected mean", "", "", "", "", "", p["mean_RE2"], expected[label]])
        data[label] = {
            "mean_reading": {"printed": p_mean, "virtual_bench": got_mean},
            "readings": {"printed": p["readings"], "virtual_bench": [getattr(w, attr).tolist() for w in ws]},
            "RE1_percent": {"printed": p["RE1_percent"], "virtual_bench": re1},
            "RE2_percent": {"printed": p["RE2_percent"], "virtual_bench": re2},
            "mean_RE1_percent": {"printed": p["mean_RE1"], "virtual_bench": float(np.mean(re1))},
            "mean_RE2_percent": {"printed": p["mean_RE2"], "virtual_bench": float(np.mean(re2)),
                                 "expected": expected[label]},
        }
    data["unit"] = unit
    data["status"] = status
    table = Table(
        title=title,
        columns=["load", "sensor", f"mean reading paper ({unit})", f"mean reading fsrlab ({unit})", "ratio",
                 "RE1 paper (%)", "RE1 fsrlab (%)", "RE2 paper (%)", "RE2 fsrlab (%)"],
        rows=rows,
        note=f"{status}. fsrlab: five virtual re-placements per sensor and load "
             "(fsrlab.paper.experiment.dead_weights): "
             "each draws the placement's stress factor, contact-resistance factor and loaded-area factor (the "
             "preset's three placement spreads, fitted to the mean RE2 of Tables 4 and 5) and a read time of 2–10 s "
             "(creep); one 100 ms meter window per reading; eq. (39) with the "
             f"sample standard deviation. The weight loads {DEAD_WEIGHT_AREA_M2 * 1e6:.0f} mm² (an assumption: "
             "400 g ↔ 10 kPa, see docs/experiment.md).")
    return table, data


def _fit_table(sensors, fits: list, targets: list) -> tuple[Table, dict]:
    keys = list(targets[0])
    names = {"f0": "f at 0 kPa (Fig. 19a) [kHz]", "f10": "f at 10 kPa (Fig. 19a) [kHz]",
             "v0": "V0 at 0 kPa (Fig. 19b) [V]", "v10": "V0 at 10 kPa (Fig. 19b) [V]",
             "f200": "f at 200 g (Table 4 mean) [kHz]", "f400": "f at 400 g (Table 4 mean) [kHz]",
             "he_tm": "HE_TM (Table 3) [%]", "he_pm": "HE_PM (Table 3) [%]"}
    scale = {"f0": 1e-3, "f10": 1e-3, "f200": 1e-3, "f400": 1e-3}
    rows = []
    for k in keys:
        row = [names[k]]
        for got, want in zip(fits, targets, strict=True):
            row += [want[k] * scale.get(k, 1.0), got[k] * scale.get(k, 1.0)]
        rows.append(row)
    params = [{k: getattr(s, k) for k in (*PAPER_SENSOR_COMMON, *SHARED_FIT_PARAMETERS, *FIT_PARAMETERS, *SPREADS)}
              for s in sensors]
    data = {"names": [s.name for s in sensors], "parameters": params,
            "fixed": list(PAPER_SENSOR_COMMON), "shared_fitted": list(SHARED_FIT_PARAMETERS),
            "own_fitted": list(FIT_PARAMETERS),
            "fit": {k: {"printed": [t[k] for t in targets], "fitted": [g[k] for g in fits],
                        "residual": [g[k] - t[k] for g, t in zip(fits, targets, strict=True)]} for k in keys}}
    cols = ["printed number"] + [c for i in range(1, 5) for c in (f"paper {i}", f"fit {i}")]
    table = Table(title="The fitted paper-sensor preset: each printed number it was fitted to, and the fit's value",
                  columns=cols, rows=rows, fmt="{:.3g}",
                  note="Least-squares fit (scipy.optimize.least_squares, scripts/fit_paper_sensor.py) of six "
                       "parameters per sensor: modulus, separation and area unloading exponents, conductive area "
                       "fraction and growth, dielectric/conductive area ratio; shared parameters held (60 films, "
                       "R_C0 = 30 kΩ, σ_c = 5 kPa). Evaluated on the closed forms "
                       "(fsrlab.paper.preset_fit.quick_response), no meter. Figure 19's ends are axis ranges, "
                       "fitted at half weight. Then three placement spreads, shared, to the mean RE2 of Tables 4 "
                       "and 5. Parameters: paper.json experiment.preset.")
    return table, data


def _fig17_table(exp: Experiment, printed: dict) -> tuple[Table, dict]:
    p = printed["figure17_fit_r2"]
    f17 = exp.fig17
    label = {"both": "both branches (every reading)", "loading": "loading branch only",
             "unloading": "unloading branch only", "means": "mean of the two branches per stress"}
    rows = [["paper Figure 17", p["linear"], p["cubic"]]]
    rows += [[f"fsrlab sensor 1, {label[k]}", v["linear"], v["cubic"]] for k, v in f17.items()]
    table = Table(title="Figure 17: R² of linear and cubic σ(f) fits, paper vs virtual sensor 1",
                  columns=["data fitted", "linear R²", "cubic R²"], rows=rows, fmt="{:.4f}",
                  note="fsrlab.paper.experiment.figure17_fits (fsrlab.paper.polyfit.fit_polynomial, degree 1 and "
                       "3) on the spring cycle of the fitted Table 3 (a prediction: R² was not fitted).")
    return table, {"printed": {"linear": p["linear"], "cubic": p["cubic"]}, "virtual_bench": f17}


def _erratum_x1(exp: Experiment, printed: dict) -> Erratum:
    from fsrlab.paper.experiment import figure17_counterexample

    p, f17 = printed["figure17_fit_r2"], exp.fig17
    cx = figure17_counterexample()
    return Erratum(
        key="X1",
        title="Figure 17's R² does not say which data were fitted; on the virtual sensors' cycle both branches "
              "give far less",
        paper=f"Figure 17: σ(f) fitted with a line (R² = {p['linear']}) and a cubic (R² = {p['cubic']}), 3–10 kHz, "
              "0–10 kPa; Table 3: HE of the frequency 14–19 %. The paper does not say which branches or which "
              "sensor were fitted.",
        fsrlab=(f"On the virtual sensor 1 (fitted to Table 3, HE_PM {exp.he_proposed[0]:.1f} %), a single-valued σ(f) "
                "on "
                f"both branches reaches R² = {f17['both']['linear']:.4f} (linear) and {f17['both']['cubic']:.4f} "
                f"(cubic); its loading branch alone {f17['loading']['linear']:.4f} and {f17['loading']['cubic']:.4f}, "
                f"its unloading branch {f17['unloading']['linear']:.4f} and {f17['unloading']['cubic']:.4f}, the "
                f"branch means {f17['means']['linear']:.4f} and {f17['means']['cubic']:.4f}. The printed values do "
                "not follow from this model's loop on both branches, but they do not rule out both branches: a loop "
                f"whose gap sits at the steep low-stress end (HE {cx['he_percent']:.1f} %) gives R² = "
                f"{cx['linear']:.4f} (linear) and {cx['cubic']:.4f} (cubic) on both branches. Which data and how the "
                "gap was distributed cannot be told without the paper's raw data."),
        evidence="fsrlab.paper.experiment.figure17_fits on the virtual spring cycle (this section, Table "
                 "'Figure 17'); fsrlab.paper.experiment.figure17_counterexample (f = 3 + 7·√(σ/10 kPa) kHz on "
                 "loading, gap x·exp(−x/0.03)·(1 − x)); tests/paper/test_errata_evidence.py.")


def _fmt(v) -> str:
    return "" if v is None else (f"{v:.4g}" if isinstance(v, float) else str(v))


def _targets_table(rows: list) -> Table:
    body = []
    for t in rows:
        scale = 1e-3 if t["unit"] == "Hz" else 1.0
        unit = "kHz" if t["unit"] == "Hz" else t["unit"]
        body.append([t["id"], t["source"], f"{t['quantity']} [{unit}]", _fmt(t["printed"] * scale),
                     ", ".join(_fmt(v * scale) for v in t["fitted"]), ", ".join(_fmt(v * scale) for v in t["residual"]),
                     "; ".join(t["tunes"])])
    return Table(title=f"Targets: the {len(rows)} printed numbers of §6 the preset was fitted to (fitted, not "
            "predicted)",
                 columns=["id", "source", "quantity", "printed", "fitted", "residual", "sets"], rows=body,
                 note="fsrlab.paper.split.targets, from the fit's own list (fsrlab.paper.preset_fit.fit_target_list). "
                      "Fitted values: the fit's closed forms (quick_response; one per sensor using the number) and, "
                      "for the mean RE2, the linearised spread model (re2_design). A good match here shows the fit "
                      "worked, nothing more.")


def _predictions_table(rows: list) -> Table:
    body = [[p["id"], p["source"], f"{p['quantity']} [{p['unit']}]", _fmt(p["printed"]), _fmt(p["predicted"]),
             _fmt(p["residual"]), _fmt(p.get("expected")), "yes" if p["within_tolerance"] else "no"] for p in rows]
    n_ok = sum(p["within_tolerance"] for p in rows)
    tol = TOLERANCES
    return Table(title=f"Predictions: {len(rows)} printed numbers of §6 the fit did not use, {n_ok} within tolerance",
                 columns=["id", "source", "quantity", "printed", "virtual bench", "residual", "expected (linearised)",
                          "within tolerance"], rows=body,
                 note="fsrlab.paper.split.predictions on the seed-0 virtual bench. Tolerances stated in "
                      f"docs/experiment.md before comparing: readings within ±{tol['reading']['relative']:.0%}; "
                      f"RE1/RE2 within a factor {tol['re']['factor']:g} or {tol['re']['absolute_pp']:g} pp; "
                      f"R² within {tol['r2']['absolute']:g}.")


def build(outdir: Path) -> Section:
    """Build the experiment section into ``outdir``."""
    outdir = Path(outdir)
    printed = paper_values()
    sensors = paper_sensors()
    exp = run_experiment(sensors)
    fits = [quick_response(s) for s in sensors]
    targets = [preset_targets(i) for i in range(1, 5)]

    t3, d3 = _table3(exp, printed)
    a, re2_printed, labels, a_per = re2_design_per_sensor(sensors)
    sd2 = np.array([getattr(sensors[0], n) for n in SPREADS]) ** 2
    expected = dict(zip(labels, np.sqrt(a @ sd2).tolist(), strict=True))
    expected_per = {lab: np.sqrt(a_per[j] @ sd2).tolist() for j, lab in enumerate(labels)}
    t4, d4 = _repeat_table(exp, printed, "table4_repeatability_capacitive_kHz", "frequency_khz", "re_frequency",
                           "kHz", "Table 4: re-placements, proposed readout (555 frequency)",
                           {k: expected[f"table4 {k}"] for k in ("200g", "400g")},
                           "Readings' means fitted (targets); mean RE2 fitted (through the spreads); per-sensor "
                           "RE1/RE2 and mean RE1 predicted")
    t5, d5 = _repeat_table(exp, printed, "table5_repeatability_traditional_V", "voltage_v", "re_voltage", "V",
                           "Table 5: re-placements, traditional readout (op-amp voltage)",
                           {k: expected[f"table5 {k}"] for k in ("200g", "400g")},
                           "Mean RE2 fitted (through the spreads); readings, per-sensor RE1/RE2 and mean RE1 "
                           "predicted")
    tf, dfit = _fit_table(sensors, fits, targets)
    t17, d17 = _fig17_table(exp, printed)
    tgt = fit_targets(sensors, fits, expected)
    pred = predictions(exp, expected_per)
    trivial = trivial_baseline(pred)
    cross = cross_readout_spreads(a, re2_printed, labels, fit_on="table5")

    f_all = np.concatenate([c.columns["frequency_hz"] for c in exp.cycles])
    v_all = np.concatenate([c.columns["voltage_v"] for c in exp.cycles])
    f_rng = [float(np.nanmin(f_all)) / 1e3, float(np.nanmax(f_all)) / 1e3]
    v_rng = [float(np.nanmin(v_all)), float(np.nanmax(v_all))]
    order_f, order_v = _branch_order(exp, "frequency_hz"), _branch_order(exp, "voltage_v")
    p19a = _fig19(outdir, exp, "frequency_hz", 1e-3, "kHz", "f", (3, 10), "experiment_fig19a.png")
    p19b = _fig19(outdir, exp, "voltage_v", 1.0, "V", "V0", (0.4, 1.0), "experiment_fig19b.png")
    p17 = _fig17(outdir, exp)

    misses = _misses(exp, fits, expected, expected_per, pred, cross, d5, order_f, order_v)
    intro = _intro(exp, tgt, pred, trivial, misses)
    figures = _figures(exp, printed, (p19a, p19b, p17), f_rng, v_rng, order_f, order_v)
    data = {"experiment": {
        "bench": {"spring_cycle": "0 -> 10 kPa -> 0, 40 positions per ramp, one 100 ms window each",
                  "dead_weight_area_m2": DEAD_WEIGHT_AREA_M2, "masses_kg": {"200g": 0.2, "400g": 0.4},
                  "placements": 5, "circuit": "LM555 Fig. 16, D1 ideal, R = 10 kOhm, C_off not switched in",
                  "opamp": "eq. 38, R_F = 20 kOhm, Vcc = -5 V"},
        "targets": tgt,
        "predictions": pred,
        "trivial_baseline": trivial,
        "tolerances": TOLERANCES,
        "cross_readout_spreads": cross,
        "preset": dfit,
        "table3": d3, "table4": d4, "table5": d5, "figure17": d17,
        "figure19": {"frequency_range_kHz": {"printed": [3, 10], "virtual_bench": f_rng},
                     "voltage_range_V": {"printed": [0.4, 1.0], "virtual_bench": v_rng},
                     "branch_order": {"paper_text": "not stated", "frequency": order_f, "voltage": order_v}},
        "misses": misses,
    }}
    return Section(key="experiment", title="The experiment (§6)", intro=intro, figures=figures,
                   tables=[_targets_table(tgt), _predictions_table(pred), t3, t4, t5, t17, tf],
                   errata=[_erratum_x1(exp, printed)], data=data)


def _misses(exp, fits, expected: dict, expected_per: dict, pred: list, cross: dict, d5: dict, order_f: str,
            order_v: str) -> list[str]:
    """What the virtual bench does not reproduce, and why: one sentence each."""
    t5_ratio = d5["200g"]["mean_reading"]
    v_ratio = float(np.mean(t5_ratio["virtual_bench"]) / np.mean(t5_ratio["printed"]))
    e4 = [expected[f"table4 {k}"] for k in ("200g", "400g")]
    e5 = [expected[f"table5 {k}"] for k in ("200g", "400g")]
    f0_lo, f0_hi = min(g["f0"] for g in fits) / 1e3, max(g["f0"] for g in fits) / 1e3
    v10_lo, v10_hi = min(g["v10"] for g in fits), max(g["v10"] for g in fits)
    re2_200 = [p["predicted"] for p in pred if p["id"].startswith("table5.200g.sensor") and p["id"].endswith("RE2")]
    c4 = [cross["rows"][f"table4 {k}"]["predicted"] for k in ("200g", "400g")]
    misses = [
        f"Table 5's voltages: the virtual op-amp reads {v_ratio:.1f}× the printed mean at 200 g. At the stress where "
        "Table 4's frequencies put the weights on Figure 19a (5–10 kPa), Figure 19b reads 0.6–1 V, while Table 5 "
        "prints 0.18–0.44 V, below Figure 19b's zero-stress 0.4 V; one sensor cannot give both (a different fixture, "
        "supply or gain in §6.2 would, none is printed).",
        "Per-sensor repeatability: every sensor of the preset has nearly the same placement sensitivity, so the "
        "expected RE2 is the same for all four (Table 5 at 200 g: "
        + ", ".join(f"{v:.1f}" for v in expected_per["table5 200g"]) + " %; this seed's five placements: "
        + ", ".join(f"{v:.1f}" for v in re2_200) + " %) where the paper prints 9, 4, 2, 4 %. Only the mean RE2 "
        "was fitted; the pattern across sensors is not predicted.",
        f"Repeatability means: the spreads fitted to the four mean RE2 give {e4[0]:.2f} % / {e4[1]:.2f} % "
        f"(Table 4, printed 1 % / 1 %) and {e5[0]:.2f} % / {e5[1]:.2f} % (Table 5, printed 5 % / 6 %). Fitted "
        f"to Table 5's two means alone, they predict Table 4's as {c4[0]:.2f} % / {c4[1]:.2f} % (printed 1 % / 1 %).",
        f"Branch order in Figure 19: every mechanism here (separation and area memory, creep) keeps the composite "
        f"compressed on unloading, so fsrlab reads higher on unloading (f: {order_f}; V0: {order_v}). The paper's "
        "text does not say which branch lies above, and the transcription does not carry the figure: not compared.",
        f"Figure 19's ends (targets): the fit reaches f(0) = {f0_lo:.2f}–{f0_hi:.2f} kHz for the axis's 3 kHz and "
        f"V0(10 kPa) = {v10_lo:.2f}–{v10_hi:.2f} V for 1 V, Table 4's 200 g readings pulling the other way.",
        "Figure 17: see erratum X1.",
    ]
    return misses


def _intro(exp, tgt, pred: list, trivial: dict, misses: list[str]) -> str:
    """The section's text: the paper sensors, what was fitted and what is predicted, the misses."""
    n_ok = sum(p["within_tolerance"] for p in pred)
    return (
        "Paper §6 on fsrlab's virtual bench. Four 'paper sensors' (fsrlab.physics.paper_sensor.paper_sensors, "
        "--sensor paper-a201-1..4) extend the paper's film physics (separation with memory, eqs. 1 and 9; "
        "tunnelling, eqs. 10–12 and 16–18; eq. 14) with the mechanisms §6 names and leaves out, each an extension: "
        "a contact resistance R_C(σ) solved with u = V − R_C·I (Fig. 3), an effective conductive area A(σ) with its "
        "own unloading memory shared by R_FSR and C_FSR, the voltage dependence of R_FSR (5 V across the FSR in the "
        "op-amp readout, about 2.5 V in the 555), logarithmic creep under a held load, and sensor-to-sensor and "
        "placement-to-placement spread. The area's hysteresis cancels in the 555's R_FSR·C_FSR and stays whole in the "
        "op-amp's conductance: that is the mechanism behind Table 3's ordering.\n\n"
        f"Fitted, not reproduced: the preset was fitted (scripts/fit_paper_sensor.py) to {len(tgt)} printed numbers "
        "(table 'Targets'): Table 3's rows, Table 4's mean readings, Figure 19's axis ends and the mean RE2 of "
        "Tables 4 and 5. On the virtual bench (meter model included) the fitted Table 3 means are "
        f"{exp.he_traditional.mean():.2f} % / {exp.he_proposed.mean():.2f} % (paper 23.35 % / 16.31 %): the bench "
        "keeps "
        f"the fit. The other {len(pred)} printed numbers of §6 the bench produces are predictions (table "
        f"'Predictions'); {n_ok} of {len(pred)} lie within the tolerances of docs/experiment.md, all of them "
        f"repeatability numbers, whose level the fitted mean RE2 sets: a trivial predictor ({trivial['predictor']}) "
        f"meets {trivial['within_tolerance']} of the same {trivial['n']}, the bench "
        f"{trivial['bench_within_tolerance']}. "
        "Without the paper's raw data fsrlab can show that a sensor model with the mechanisms §6 names can be fitted "
        "to Tables 3–4 and Figure 19's ranges and keeps Table 3's ordering; it cannot reproduce Tables 3–5 from "
        "independent measurements, and the predictions below mostly miss. A held-out fit (Table 4 left out) and the "
        "mechanisms tried on the misses are in docs/experiment.md.\n\n"
        "Misses, and why:\n\n" + "\n\n".join(f"• {s}" for s in misses))


def _figures(exp, printed: dict, paths, f_rng, v_rng, order_f: str, order_v: str) -> list[Figure]:
    """Figures 19a, 19b and 17 as drawn on the virtual bench, each with the paper's beside."""
    p19a, p19b, p17 = paths
    return [
        Figure(filename=p19a.name, title="Figure 19a: 555 frequency vs stress, loading and unloading (virtual bench)",
               paper="Figure 19a: f ≈ 3–10 kHz over 0–10 kPa, loading and unloading (one sensor).",
               fsrlab=f"Four fitted sensors through the Fig. 16 circuit and the meter model: f {f_rng[0]:.2f}–"
                      f"{f_rng[1]:.2f} kHz (the axis ends are targets); {order_f}."),
        Figure(filename=p19b.name, title="Figure 19b: op-amp voltage vs stress, loading and unloading (virtual bench)",
               paper="Figure 19b: V0 ≈ 0.4–1 V over 0–10 kPa (R_F = 20 kΩ, Vcc = −5 V).",
               fsrlab=f"V0 {v_rng[0]:.3f}–{v_rng[1]:.3f} V (10-bit ADC, 4.9 mV steps; the axis ends are targets); "
                      f"{order_v}."),
        Figure(filename=p17.name, title="Figure 17: linear and cubic σ(f) on the virtual spring cycle",
               paper=f"R² = {printed['figure17_fit_r2']['linear']} (linear), {printed['figure17_fit_r2']['cubic']} "
                     "(cubic).",
               fsrlab=f"On both branches {exp.fig17['both']['linear']:.4f} / {exp.fig17['both']['cubic']:.4f}; on the "
                      f"branch means {exp.fig17['means']['linear']:.4f} / {exp.fig17['means']['cubic']:.4f} "
                      "(erratum X1)."),
    ]

