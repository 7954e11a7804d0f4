"""The printed numbers of §6 split into what the paper-sensor preset was fitted to and what it predicts.

:func:`targets` lists every printed number the preset's fits use (:func:`fsrlab.paper.preset_fit.fit_target_list`,
the fit's own list), each with the value the fit reached; :func:`predictions` lists every other printed
number of §6 that the virtual bench (:func:`fsrlab.paper.experiment.run_experiment`) produces, each with
the bench's value and whether it lies within the tolerance :data:`TOLERANCES` (docs/experiment.md; they
landed with the comparison). :func:`trivial_baseline` counts the same repeatability predictions for a
predictor that knows only the fitted mean RE2. No printed number is in both lists.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §6, Figures 17 and 19, Tables 3–5.
"""

from __future__ import annotations

import numpy as np

from fsrlab.errors import ParameterError

__all__ = ["TOLERANCES", "within_tolerance", "targets", "predictions", "range_to_sd_ratio", "trivial_baseline"]

#: Tolerance of each kind of prediction (docs/experiment.md, "Targets and predictions"):
#: ``reading``: |predicted/printed − 1| ≤ 0.25 (the four sensors' printed means at one load span ×1.4);
#: ``re``: predicted/printed within a factor 2, or within 1 pp (five placements: the sample standard
#: deviation of 5 draws lies within 0.35–1.67 σ 95 % of the time; the tables print integers);
#: ``r2``: |ΔR²| ≤ 0.01.
TOLERANCES = {"reading": {"relative": 0.25}, "re": {"factor": 2.0, "absolute_pp": 1.0}, "r2": {"absolute": 0.01}}


def within_tolerance(kind: str, printed: float, predicted: float) -> bool:
    """Whether ``predicted`` meets :data:`TOLERANCES` ``[kind]`` against ``printed``.

    Parameters
    ----------
    kind : {"reading", "re", "r2"}
        The kind of printed number.
    printed : float
        The paper's value.
    predicted : float
        The virtual bench's value.

    Returns
    -------
    bool
    """
    if kind not in TOLERANCES:
        raise ParameterError(f"must be one of {sorted(TOLERANCES)}, got {kind!r}", parameter="kind")
    if not np.isfinite(predicted):
        return False
    tol = TOLERANCES[kind]
    if kind == "reading":
        return bool(abs(predicted / printed - 1.0) <= tol["relative"])
    if kind == "r2":
        return bool(abs(predicted - printed) <= tol["absolute"])
    if abs(predicted - printed) <= tol["absolute_pp"]:
        return True
    return bool(printed > 0 and predicted > 0 and 1 / tol["factor"] <= predicted / printed <= tol["factor"])


def targets(sensors, fits: list, expected_re2: dict) -> list:
    """The fit's targets with the values the fit reached.

    Parameters
    ----------
    sensors : sequence of PaperFSR
        The preset (:func:`fsrlab.physics.paper_sensor.paper_sensors`).
    fits : list of dict
        :func:`fsrlab.paper.preset_fit.quick_response` of each sensor (the fit's own evaluation).
    expected_re2 : dict
        :func:`fsrlab.paper.preset_fit.re2_design`'s linearised mean RE2 by label (what the spread fit
        sees). [%]

    Returns
    -------
    list of dict
        :func:`fsrlab.paper.preset_fit.fit_target_list`'s entries with ``fitted`` (one value per sensor
        using it, in ``unit``) and ``residual`` (fitted − printed), then Table 3's two printed means,
        which no residual uses but which are means of fitted rows (``key`` None).
    """
    from fsrlab.paper.preset_fit import fit_target_list
    from fsrlab.reference import paper_values

    out = []
    for t in fit_target_list():
        if t["key"] in expected_re2:
            fitted = [float(expected_re2[t["key"]])]
        else:
            fitted = [float(fits[i - 1][t["key"]]) for i in t["sensors"]]
        out.append({**t, "fitted": fitted, "residual": [f - t["printed"] for f in fitted]})
    t3 = paper_values()["table3_hysteresis_error_percent"]
    for side, key in (("traditional", "he_tm"), ("proposed", "he_pm")):
        fitted = float(np.mean([f[key] for f in fits]))
        printed = float(t3[f"{side}_mean"])
        out.append({"id": f"table3.{side}.mean", "source": "Table 3", "unit": "%", "key": None,
                    "quantity": f"mean of the four sensors' HE ({side}); the mean of four fitted rows",
                    "printed": printed, "printed_values": [printed], "sensors": [1, 2, 3, 4],
                    "tunes": ["nothing directly: each row is a target"], "fitted": [fitted],
                    "residual": [fitted - printed]})
    return out


def _entry(ident: str, source: str, quantity: str, unit: str, kind: str, printed, predicted,
           printed_values=None, **extra) -> dict:
    printed, predicted = float(printed), float(predicted)
    return {"id": ident, "source": source, "quantity": quantity, "unit": unit, "kind": kind, "printed": printed,
            "printed_values": list(printed_values) if printed_values is not None else [printed],
            "predicted": predicted, "residual": predicted - printed,
            "relative_residual": predicted / printed - 1.0 if printed else None,
            "within_tolerance": within_tolerance(kind, printed, predicted), **extra}


def predictions(exp, expected_re2_per_sensor: dict | None = None) -> list:
    """Every printed number of §6 not fitted that the virtual bench produces, beside the bench's value.

    Parameters
    ----------
    exp : Experiment
        :func:`fsrlab.paper.experiment.run_experiment` of the preset (seed 0).
    expected_re2_per_sensor : dict, optional
        ``{"table4 200g": [4 values], ...}``: the linearised expected RE2 of each sensor (added as
        ``expected``; the judgement uses the five-placement value the bench produced). [%]

    Returns
    -------
    list of dict
        ``id``, ``source``, ``quantity``, ``unit``, ``kind`` (of :data:`TOLERANCES`), ``printed``,
        ``predicted``, ``residual``, ``relative_residual``, ``within_tolerance``: per sensor and
        load RE1 and RE2 of Tables 4 and 5 and their printed mean RE1 (``implied_by_target``: the
        mean RE2 target that sets it, RE1 ≈ :func:`range_to_sd_ratio` × RE2 for five readings), Table 5's mean reading
        per
        sensor, and Figure 17's R² (fitted on both branches of sensor 1's cycle: the paper does not
        say which data it fitted, erratum X1).
    """
    from fsrlab.reference import paper_values

    p = paper_values()
    exp_re2 = expected_re2_per_sensor or {}
    out = []
    for t_key, name, attr, re_attr, unit in (
            ("table4_repeatability_capacitive_kHz", "table4", "frequency_khz", "re_frequency", "kHz"),
            ("table5_repeatability_traditional_V", "table5", "voltage_v", "re_voltage", "V")):
        source = name.replace("table", "Table ")
        for load, ws in exp.weights.items():
            tab = p[t_key][load]
            re1 = [float(getattr(w, re_attr).re1_percent) for w in ws]
            re2 = [float(getattr(w, re_attr).re2_percent) for w in ws]
            for i, w in enumerate(ws):
                if name == "table5":
                    readings = [float(v) for v in tab["readings"][i]]
                    out.append(_entry(f"{name}.{load}.sensor{i + 1}.mean_reading", source,
                                      f"mean of the five {load} readings (op-amp V0), sensor {i + 1}", unit,
                                      "reading", np.mean(readings), float(getattr(w, attr).mean()),
                                      printed_values=readings))
                out.append(_entry(f"{name}.{load}.sensor{i + 1}.RE1", source, f"RE1 at {load}, sensor {i + 1}",
                                  "%", "re", tab["RE1_percent"][i], re1[i]))
                extra = {}
                if f"{name} {load}" in exp_re2:
                    extra["expected"] = float(exp_re2[f"{name} {load}"][i])
                out.append(_entry(f"{name}.{load}.sensor{i + 1}.RE2", source, f"RE2 at {load}, sensor {i + 1}",
                                  "%", "re", tab["RE2_percent"][i], re2[i], **extra))
            out.append(_entry(f"{name}.{load}.mean_RE1", source, f"mean RE1 of the four sensors at {load}", "%", "re",
                              tab["mean_RE1"], float(np.mean(re1)), implied_by_target=f"{name}.{load}.mean_RE2"))
    f17 = p["figure17_fit_r2"]
    for deg in ("linear", "cubic"):
        out.append(_entry(f"figure17.{deg}_r2", "Figure 17", f"R² of the {deg} σ(f) fit (sensor 1, both branches)",
                          "1", "r2", f17[deg], exp.fig17["both"][deg],
                          other_data={k: v[deg] for k, v in exp.fig17.items() if k != "both"}))
    return out


def range_to_sd_ratio(n: int = 5) -> float:
    """E[range] / E[sample standard deviation] of ``n`` normal draws, d2(n)/c4(n): E[RE1]/E[RE2]. [1]

    Parameters
    ----------
    n : int
        Readings in a set (the paper's tables: 5).

    Returns
    -------
    float
        2.474 for n = 5 (d2 = 2.326, c4 = 0.9400).

    Notes
    -----
    ``d2(n) = ∫ 1 − Φ(x)^n − (1 − Φ(x))^n dx`` (the expected range in units of σ) and
    ``c4(n) = √(2/(n−1)) Γ(n/2)/Γ((n−1)/2)`` (the sample standard deviation's bias), both standard
    results for normal samples.
    """
    from scipy.integrate import quad
    from scipy.special import gammaln
    from scipy.stats import norm

    if int(n) != n or n < 2:
        raise ParameterError(f"must be an integer >= 2, got {n!r}", parameter="n")
    d2 = quad(lambda x: 1.0 - norm.cdf(x) ** n - norm.sf(x) ** n, -np.inf, np.inf)[0]
    c4 = np.sqrt(2.0 / (n - 1)) * np.exp(gammaln(n / 2) - gammaln((n - 1) / 2))
    return float(d2 / c4)


def trivial_baseline(pred: list) -> dict:
    """How many repeatability predictions a predictor that knows only each table's fitted mean RE2 meets.

    The bench's repeatability predictions take their level from the mean RE2 of Tables 4 and 5, which
    the preset is fitted to. The trivial predictor gives every sensor its table's printed mean RE2, and
    :func:`range_to_sd_ratio` (five readings) times it for each RE1 and the mean RE1; its count within
    the same :data:`TOLERANCES` is what the bench's count should be read against.

    Parameters
    ----------
    pred : list of dict
        :func:`predictions`.

    Returns
    -------
    dict
        ``predictor`` (text), ``n`` (repeatability predictions), ``within_tolerance`` (the trivial
        predictor's count), ``bench_within_tolerance`` (the bench's count over the same predictions) and
        ``rows`` (``{id: trivial value}``).
    """
    from fsrlab.reference import paper_values

    p = paper_values()
    tables = {"table4": p["table4_repeatability_capacitive_kHz"], "table5": p["table5_repeatability_traditional_V"]}
    ratio = range_to_sd_ratio(5)
    rows, hits, bench = {}, 0, 0
    for e in pred:
        if e["kind"] != "re":
            continue
        name, load, what = e["id"].split(".")[0], e["id"].split(".")[1], e["id"].split(".")[-1]
        mean_re2 = float(tables[name][load]["mean_RE2"])
        value = mean_re2 if what == "RE2" else ratio * mean_re2
        rows[e["id"]] = value
        hits += within_tolerance("re", e["printed"], value)
        bench += bool(e["within_tolerance"])
    return {"predictor": f"each table's printed mean RE2 for every sensor, {ratio:.2f}× it for RE1 (five readings)",
            "n": len(rows), "within_tolerance": int(hits), "bench_within_tolerance": int(bench), "rows": rows}
