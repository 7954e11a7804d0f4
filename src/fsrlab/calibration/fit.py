"""From a recorded run to a calibration: :func:`calibrate_run`.

The orchestration of the analysis topic: it reads what a run holds (its columns, its sidecar's
circuit) and passes it to the computations on arrays, and holds no model of its own --
polynomials and cross-validation are :mod:`fsrlab.calibration.polynomial`, the compensation
:mod:`fsrlab.calibration.compensation`, branches, cycles and eq. (13) :mod:`fsrlab.metrics.cycles`,
C_FSR decoding :mod:`fsrlab.circuits.decode`. The command line (``fsrlab calibrate``,
``fsrlab apply``, ``fsrlab hysteresis``) calls these functions and only renders.

A run's branches and cycles come from one rule (:func:`run_directions`, :func:`run_cycles`: the
``direction`` and ``cycle`` columns when the run has them, else found from the reference stress),
used alike by the calibration's cross-validation groups, by the compensation and by the
hysteresis error.

Examples
--------
Calibrate one run and estimate the stress of another (``bench.csv`` and ``other.csv`` are runs
in the format of docs/data-format.md)::

    from fsrlab.io.runformat import load_run
    from fsrlab.calibration.fit import calibrate_run
    from fsrlab.calibration.apply import apply_calibration
    cal = calibrate_run(load_run("bench.csv"), x="frequency_hz", compensate=True)
    est = apply_calibration(cal, load_run("other.csv"))["stress_pa_estimate"]

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5 (Figure 17), eq. (13).
"""

from __future__ import annotations

import numpy as np

from fsrlab.calibration.polynomial import PolynomialModel, default_groups
from fsrlab.calibration.readout import (
    C_FSR, _as_run, _named, _recorded, reference_reversed, run_readout, run_recorded_with, run_reference,
)
from fsrlab.calibration.result import Calibration, calibrate
from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.io.runformat import KNOWN_COLUMNS, Run
from fsrlab.metrics.cycles import row_cycles, run_hysteresis

__all__ = ["calibrate_run", "fit_causal_branches", "BranchFit", "binned_hysteresis_percent"]

#: Fewer readings than this: ``lag="auto"`` assumes no lag rather than searching (the search fits
#: 22 weights per fold at every lag). [1]
MIN_LAG_READINGS = 250
#: Fewest cycles or time blocks for ``lag="auto"`` to search (else no lag is assumed). [1]
MIN_LAG_GROUPS = 4
#: Fewest readings (above the floor, with a reference) the causal compensation is fitted on. [1]
MIN_COMPENSATION_READINGS = 60


def _oof(fam, x, y, groups, folds, transform, floor):
    """Out-of-fold estimate of a model family (the chosen candidate refitted without each fold)."""
    from fsrlab.calibration.models import fit_family

    _, gi = np.unique(groups, return_inverse=True)
    k = min(folds, int(gi.max()) + 1)
    fold = (np.arange(int(gi.max()) + 1) % k)[gi]
    out = np.full(x.size, np.nan)
    for f in range(k):
        tr = fold != f
        try:
            m = fit_family(fam, x[tr], y[tr], transform, floor)
        except (ValueError, np.linalg.LinAlgError):
            continue
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            out[~tr] = m(x[~tr])
    return out


def binned_hysteresis_percent(y, estimate, direction, bins: int = 10) -> float:
    """Hysteresis error of a calibrated estimate on a run without whole cycles. [%]

    Parameters
    ----------
    y : array_like
        Reference (the level). [unit of y]
    estimate : array_like
        Calibrated estimate. [unit of y]
    direction : array_like of int
        +1 loading, −1 unloading (0 rows ignored), from the reference.
    bins : int
        Level bins over the reference's range.

    Returns
    -------
    float
        ``100·max_bins |mean error loading − mean error unloading| / FS``, FS the reference's range:
        eq. (13) for a calibrated output (its loading and unloading curves at the same level differ
        by the difference of their errors), on level bins instead of matched branches; NaN when no
        bin holds both directions.
    """
    y = np.asarray(y, float)
    e = np.asarray(estimate, float) - y
    d = np.asarray(direction, int)
    ok = np.isfinite(y) & np.isfinite(e)
    y, e, d = y[ok], e[ok], d[ok]
    fs = float(np.ptp(y)) if y.size else 0.0
    if fs <= 0:
        return float("nan")
    b = np.clip(((y - y.min()) / fs * bins).astype(int), 0, bins - 1)
    worst = float("nan")
    for i in range(bins):
        lo, un = e[(b == i) & (d > 0)], e[(b == i) & (d < 0)]
        if lo.size >= 5 and un.size >= 5:
            v = abs(lo.mean() - un.mean())
            worst = v if not worst >= v else worst
    return 100 * worst / fs


def calibrate_run(run, x: str = "frequency_hz", degree: int | str = "auto", compensate: bool = False,
                  folds: int = 5, circuit: LM555Circuit | None = None, threshold: float = 0.05,
                  reference: str | None = None, model: str = "auto", lag: float | str = "auto",
                  max_lag_s: float | None = None, compensation_method: str = "auto") -> Calibration:
    """Calibrate a run's readout to its reference (force or stress).

    Parameters
    ----------
    run : Run or path
        A run with ``force_n`` or ``stress_pa`` and the readout.
    x : str
        Readout column, or ``c_fsr_farad`` (physics-informed, see :func:`run_readout`).
    degree : int or "auto"
        Polynomial degree 1..5 (the model is then that polynomial), or ``"auto"``.
    compensate : bool
        Also fit the causal hysteresis compensation (an extension beyond the paper; see
        ``compensation_method``) and record the hysteresis error of the estimate before and after.
    folds : int
        Cross-validation folds (≥ 2).
    circuit : LM555Circuit, optional
        Circuit for ``x="c_fsr_farad"`` (default: the sidecar's, else ``PAPER_CIRCUIT``).
    threshold : float
        Reversal threshold, a fraction of the span, where cycles come from the data. [1]
    reference : {"force_n", "stress_pa"}, optional
        The reference (default: ``stress_pa`` when the run has it, else ``force_n``).
    model : str
        ``"auto"`` (every family, chosen by grouped CV), a family (``polynomial``,
        ``conductance-polynomial``, ``conductance-power``, ``power``) or one candidate
        (``polynomial-3``, ``conductance-polynomial-2``).
    lag : float or "auto"
        Lag of the readout behind the reference [s] (rows without ``time_s``), or ``"auto"``:
        estimated (:func:`fsrlab.calibration.alignment.estimate_lag`) when the run has a ``time_s``
        column, at least :data:`MIN_LAG_READINGS` usable readings and :data:`MIN_LAG_GROUPS`
        cycles or time blocks, else 0; also 0 when the search finds the lag not identifiable on
        the run (``extra["lag_search"]`` then says why).
    max_lag_s : float, optional
        Half-width of the lag search (default 0.25 s, :data:`fsrlab.calibration.alignment.MAX_LAG_S`). [s]
    compensation_method : {"auto", "memory", "branches"}
        ``"auto"``: the causal play-operator model (:mod:`fsrlab.calibration.play`) and, when the
        run is made of whole loading-unloading cycles (at least 2 over 80 % of the reference range,
        holding at least 80 % of the readings), the branch polynomials with
        turning-point memory applied causally (:func:`fit_causal_branches`); the one with the
        smaller grouped cross-validated RMSE is kept, both are listed in
        ``extra["compensation_candidates"]`` and the choice in ``extra["compensation_choice"]``.
        ``"memory"`` or ``"branches"``: only that one.

    Returns
    -------
    Calibration
        ``model`` the best polynomial, ``family`` the chosen model when not a polynomial,
        ``lag_s``, ``floor``, ``memory``, ``uncertainty``, ``candidates``, ``cv_rmse``.

    Raises
    ------
    RunFormatError
        A column the run lacks, no reference.
    ValueError
        A parameter out of range, too few readings, a readout that does not respond, a reference
        that is reversed (mostly negative, its largest excursion below zero), a lag search without a minimum.
    """
    from fsrlab.calibration.alignment import estimate_lag, shift_reference
    from fsrlab.calibration.polynomial import fit_metrics, fingerprint
    from fsrlab.calibration.models import cross_validate_families, find_floor, resolution, transform_from_metadata

    run = _as_run(run)
    y_raw, y_name, y_unit = run_reference(run, reference)
    values, used = run_readout(run, x, circuit)
    unit = run.units.get(x) or KNOWN_COLUMNS.get(x, "F" if x == C_FSR else "")
    if compensation_method not in ("auto", "memory", "branches"):
        raise ValueError(f"compensation_method: must be auto, memory or branches, got {compensation_method!r}")
    both = np.isfinite(values) & np.isfinite(y_raw)
    if both.sum() < 3:
        raise ValueError(f"{run.path}: {x} and {y_name}: fewer than 3 readings with both values present")
    reversed_why = reference_reversed(y_raw[both])
    if reversed_why:
        raise ValueError(f"{run.path}: {y_name}: {reversed_why}: a load cell mounted or wired the wrong way round, "
                         "or the wrong column")
    from fsrlab.metrics.hysteresis import check_response

    try:
        check_response(y_raw[both], values[both], x)
    except ValueError as exc:
        raise ValueError(f"{run.path}: {exc}") from None
    t = run["time_s"] if "time_s" in run else np.arange(run.n_rows, dtype=float)
    floor = find_floor(values[both], y_raw[both])
    at_floor = floor.below(values) & np.isfinite(values) if floor is not None else np.zeros(run.n_rows, bool)
    # No tare: the reference at the floor is not at zero load (anything below the activation force),
    # and a constant offset of the load cell goes into the model's constant term.
    y = y_raw
    groups = default_groups(run.n_rows, row_cycles(np.where(np.isfinite(y), y, np.nan), *_recorded(run), threshold)
                            if np.isfinite(y).all() else None, folds)
    usable = np.isfinite(values) & ~at_floor
    search, lag_note = None, None
    with _named(run, x):
        if lag == "auto" and "time_s" not in run:
            lag_value = 0.0  # rows without times: nothing says how far apart they are
            lag_note = "not searched: the run has no time_s column, no lag assumed"
        elif lag == "auto" and int((usable & np.isfinite(y)).sum()) < MIN_LAG_READINGS:
            lag_value = 0.0  # too few readings to tell a lag from noise: none assumed
            lag_note = f"not searched: fewer than {MIN_LAG_READINGS} readings, no lag assumed"
        elif lag == "auto" and np.unique(groups[usable & np.isfinite(y)]).size < MIN_LAG_GROUPS:
            # With 2 or 3 cycles each fold trains the hysteresis model on one or two of them, and on
            # constant-rate triangles a shift can stand in for hysteresis: the error curve is noise.
            lag_value = 0.0
            lag_note = f"not searched: fewer than {MIN_LAG_GROUPS} cycles or time blocks, no lag assumed"
        elif lag == "auto":
            search = estimate_lag(t, values, y, groups, usable & np.isfinite(y), max_lag_s,
                                  3 if degree == "auto" else int(degree), folds)
            lag_value = float(f"{search.lag_s:.10g}")  # the grid's float noise (0.00999999...) off
        else:
            lag_value = float(lag)
            if not np.isfinite(lag_value):
                raise ValueError(f"lag: must be finite seconds or auto, got {lag!r}")
    ys = shift_reference(t, y, lag_value)
    ok = usable & np.isfinite(ys)
    xs, yv, gs = values[ok], ys[ok], groups[ok]
    transform = transform_from_metadata(x, run.metadata)
    fams = ("polynomial", "conductance-polynomial", "conductance-power", "power")
    only = None
    if model != "auto":
        fam, _, deg = model.rpartition("-")
        if model in fams:
            fams = (model,)
        elif fam in ("polynomial", "conductance-polynomial") and deg.isdigit():
            fams, only = (fam,), model
        else:
            raise ValueError(f"model: must be auto, {', '.join(fams)} or polynomial-1..5, conductance-polynomial-1..3, "
                             f"got {model!r}")
        if fams[0].startswith("conductance") and transform is None:
            raise ValueError(f"model: {model} needs the readout circuit: a 'divider' (r_m_ohm, vcc_v) or 'opamp' in "
                             "the run's sidecar with --x voltage_v, or --x c_fsr_farad")
    if degree != "auto":
        fams, only = ("polynomial",), f"polynomial-{int(degree)}"
    with _named(run, x):
        sel = cross_validate_families(xs, yv, gs, folds, transform, floor, families=fams,
                                      degree=int(only.rpartition("-")[2]) if only and only.startswith("polynomial")
                                      else None)
        if only is not None and only in sel.models:
            chosen = sel.models[only]
            chosen_cv = next(c.cv_rmse for c in sel.candidates if c.name == only)
        elif only is not None:
            raise ValueError(f"model: {only} cannot be fitted: too few readings for it")
        else:
            chosen, chosen_cv = sel.best, sel.best_cv_rmse
        # The polynomial of the calibration file: the chosen one, else the best polynomial (or a cubic).
        polys = [c for c in sel.candidates if c.name.startswith("polynomial-")]
        if chosen.family == "polynomial":
            pname = chosen.name
        elif polys:  # the lowest degree within 1 % of the best, as calibrate(degree="auto") chooses
            best_poly = min(c.cv_rmse for c in polys)
            pname = next(c.name for c in polys if c.cv_rmse <= 1.01 * best_poly)
        else:
            pname = "polynomial-3"
        cal = calibrate(xs, yv, degree=int(pname.rpartition("-")[2]), x_name=x, y_name=y_name, x_unit=unit,
                        y_unit=y_unit, source=str(run.path), circuit=used)
        if pname in sel.models and degree == "auto":  # the same numbers as the selection (its sums)
            p = sel.models[pname].params
            cal.model = PolynomialModel(np.asarray(p["chebyshev_coefficients"], float), p["center"], p["half_width"])
    from fsrlab.calibration.polynomial import CrossValidation

    poly_cv = [(int(c.name.rpartition("-")[2]), c.cv_rmse) for c in polys]
    if poly_cv:
        cal.cv = CrossValidation(degrees=[d for d, _ in poly_cv], rmse=[e for _, e in poly_cv], folds=min(folds, int(
            np.unique(gs).size)), groups=int(np.unique(gs).size), best_degree=cal.degree,
            untried=[d for d in range(1, 6) if d not in [d for d, _ in poly_cv]] if "polynomial" in fams and only is None
            else [])
    cal.family = None if chosen.family == "polynomial" else chosen
    cal.lag_s = None if "time_s" not in run else float(lag_value)
    if "time_s" not in run and lag_value != 0:
        cal.extra["lag_rows"] = float(lag_value)
    cal.floor = floor
    cal.candidates = [c.to_dict() for c in sel.candidates]
    yhat = cal(xs)
    met = fit_metrics(yv, yhat)
    cal.r2, cal.rmse, cal.max_error_percent_fs = met["r2"], met["rmse"], met["max_error_percent_fs"]
    fs = float(np.ptp(yv))
    cal.full_scale = fs
    cal.data_fingerprint = fingerprint(xs, yv)
    if search is not None:
        cal.extra["lag_search"] = search.to_dict()
    elif lag_note:
        cal.extra["lag_search"] = {"lag_s": 0.0, "method": lag_note}
    cal.recorded_with = run_recorded_with(run, np.isfinite(values) & np.isfinite(y_raw))
    plain_oof = np.full(run.n_rows, np.nan)
    plain_oof[ok] = _oof(chosen.name, xs, yv, gs, folds, transform, floor)
    full_scale = float(np.nanmax(yv))
    if not full_scale > 0:
        raise ValueError(f"{run.path}: {y_name}: no positive reference reading to calibrate against")
    w = np.where(ok, cal(values) / full_scale, np.where(at_floor, 0.0, np.nan))
    final_oof = plain_oof
    from fsrlab.calibration.play import causal_features, fit_memory
    from fsrlab.calibration.uncertainty import fit_uncertainty

    _, _, direction = causal_features(w, (), ())
    if compensate:
        if int(ok.sum()) < MIN_COMPENSATION_READINGS:
            raise ValueError(f"{run.path}: compensate: the causal compensation fits up to 24 weights and needs at least "
                             f"{MIN_COMPENSATION_READINGS} readings above the floor with a reference, got {int(ok.sum())}")
        row_s = float(np.median(np.diff(t))) if "time_s" in run and run.n_rows > 1 else 1.0
        candidates, fits = {}, {}
        if compensation_method in ("auto", "memory"):
            mf = fit_memory(w, ys, ok, groups, full_scale, row_s, folds, plain_oof=plain_oof)
            candidates.update(mf.candidates)
            fits[PLAY] = (mf.candidates[_best_variant(mf.candidates)], mf.oof, mf.fitted, mf.model)
        whole = _whole_cycles(run, y, ok, threshold)
        note = None
        if compensation_method == "branches" or (compensation_method == "auto" and whole):
            try:
                with _named(run, x):
                    bf = fit_causal_branches(values, ys, ok, groups, threshold, folds)
                candidates[BRANCHES] = bf.cv_rmse
                fits[BRANCHES] = (bf.cv_rmse, bf.oof, bf.fitted, bf.model)
            except ValueError as exc:
                if compensation_method == "branches":
                    raise
                note = f"branches not fitted: {exc}"
        elif compensation_method == "auto":
            note = ("branches not tried: the run is not made of whole loading-unloading cycles (fewer than 2 cycles "
                    "over 80 % of the range, or under 80 % of the readings on them)")
        chosen_name = min(fits, key=lambda k: fits[k][0])
        _, final_oof, fitted, model_obj = fits[chosen_name]
        if chosen_name == PLAY:
            cal.memory = model_obj
        else:
            cal.compensation = model_obj
        cal.extra["compensation_candidates"] = candidates
        cal.extra["compensation_choice"] = {
            "chosen": chosen_name, "by": "grouped cross-validation (whole cycles or time blocks held out), RMSE of "
            "the causal estimate", **({"note": note} if note else {})}
        before, after, how = _he_pair(run, ys, cal(values), fitted, ok, threshold)
        cal.compensation_he_percent = (before, after)
        cal.extra["hysteresis_error_method"] = how
    cal.cv_rmse = float(np.sqrt(np.nanmean((final_oof[ok] - yv) ** 2))) if np.isfinite(final_oof[ok]).any() \
        else float(chosen_cv)
    cal.uncertainty = fit_uncertainty(final_oof, ys, direction, resolution(values[ok]))
    if cal.memory is not None or cal.compensation is not None:
        cal.uncertainty_plain = fit_uncertainty(plain_oof, ys, direction, resolution(values[ok]))
    return cal


#: Causal reversal bands tried for the branch compensation, fractions of the readout span (with the
#: calibration's ``threshold``); the one with the smallest cross-validated RMSE is kept. [1]
CAUSAL_BANDS = (0.01, 0.02, 0.05)
#: Names of the two compensations in a calibration's ``compensation_candidates`` and ``compensation_choice``.
PLAY, BRANCHES = "play operators", "branches (causal)"


def _best_variant(candidates: dict) -> str:
    """The play-operator variant with the smallest cross-validated RMSE (``plain`` is not one)."""
    return min((k for k in candidates if k != "plain"), key=candidates.get)


def _whole_cycles(run: Run, y, ok, threshold: float) -> bool:
    """True when the run is made of whole loading-unloading cycles: the case the branch method describes.

    At least 2 cycles (:func:`run_cycles`' rule) each with ≥ 3 loading and ≥ 3 unloading readings
    among the fitted rows ``ok`` and a reference range of ≥ 80 % of the run's, together holding
    at least 80 % of the fitted rows. A hand-loaded run, with many of its readings on partial
    presses and minor loops, is not.
    """
    from fsrlab.metrics.cycles import row_directions

    if not np.isfinite(y).all() or not ok.any():
        return False
    cyc = row_cycles(y, *_recorded(run), threshold)
    d = row_directions(y, *_recorded(run), threshold)
    span = float(np.ptp(y[ok]))
    whole, rows = 0, 0
    for c in np.unique(cyc[ok & np.isfinite(cyc)]):
        m = ok & (cyc == c)
        if (d[m] > 0).sum() >= 3 and (d[m] < 0).sum() >= 3 and np.ptp(y[m]) >= 0.8 * span:
            whole += 1
            rows += int(m.sum())
    return whole >= 2 and rows >= 0.8 * int(ok.sum())


class BranchFit:
    """The causal branch compensation fitted on a run, with its grouped cross-validation.

    Parameters
    ----------
    model : DirectionAwareCalibration
        Fitted on every usable reading, ``causal=True``.
    cv_rmse : float
        RMSE of the out-of-fold causal estimate over the usable readings. [unit of y]
    oof, fitted : ndarray
        Out-of-fold and in-sample causal estimates of every row (NaN where not usable). [unit of y]
    cv_by_band : dict
        Cross-validated RMSE for each causal reversal band tried (fraction of the readout span). [unit of y]
    """

    def __init__(self, model, cv_rmse: float, oof: np.ndarray, fitted: np.ndarray, cv_by_band: dict):
        self.model, self.cv_rmse, self.oof, self.fitted, self.cv_by_band = model, cv_rmse, oof, fitted, cv_by_band


def fit_causal_branches(values, y, usable, groups, threshold: float = 0.05, folds: int = 5) -> BranchFit:
    """Fit loading/unloading polynomials with turning-point memory, applied causally, and cross-validate them.

    Parameters
    ----------
    values : array_like
        Readout of every row in time order. [unit of x]
    y : array_like
        The (aligned) reference of every row. [unit of y]
    usable : array_like of bool
        Rows fitted and scored (finite, above the floor).
    groups : array_like of int
        Cross-validation groups; the folds are those of :func:`fsrlab.calibration.play.fit_memory`
        (:func:`fsrlab.calibration.play.fold_assignment`).
    threshold : float
        Reversal threshold of the fit's (offline) branch labels, a fraction of the readout span;
        also one of the causal bands tried (with :data:`CAUSAL_BANDS`). [1]
    folds : int
        Folds.

    Returns
    -------
    BranchFit

    Raises
    ------
    ValueError
        Too few readings on a branch, or fewer than 2 groups.

    Notes
    -----
    Branches are labelled for the fit from the whole readout sequence
    (:func:`fsrlab.calibration.compensation.fit_direction_aware`; each branch's degree chosen by its
    own cross-validation on the whole run, then kept in the folds), and applied with causal labels
    (:class:`fsrlab.calibration.compensation.DirectionAwareCalibration` with ``causal=True``). Each
    fold's model is fitted with the held-out rows' reference removed and run over the whole
    readout sequence (the readout alone drives the labels and the memory), and its estimate of
    the held-out rows is kept; the causal band with the smallest out-of-fold RMSE is kept.
    """
    import dataclasses

    from fsrlab.calibration.compensation import causal_readout_directions, fit_direction_aware
    from fsrlab.calibration.play import fold_assignment

    use = np.asarray(usable, bool)
    xv = np.where(use, np.asarray(values, float), np.nan)
    yv = np.where(use, np.asarray(y, float), np.nan)
    fold, k = fold_assignment(groups, use, folds)
    model = dataclasses.replace(fit_direction_aware(xv, yv, threshold=threshold, folds=folds), causal=True)
    bands = tuple(sorted(set(CAUSAL_BANDS) | {float(threshold)}))
    # Each branch's degree as chosen on the whole run (a fold may hold too few branch runs to choose).
    degrees = (model.load_model.coefficients.size - 1, model.unload_model.coefficients.size - 1)
    rows = np.flatnonzero(use)
    oof = {band: np.full(xv.size, np.nan) for band in bands}
    # The labels depend on the readout, its calibrated range and the band only: once per band.
    labels = {band: causal_readout_directions(np.where(model.usable(xv), xv, np.nan), model.sign,
                                              dataclasses.replace(model, threshold=band).band) for band in bands}
    for f in range(k):
        held = rows[fold == f]
        yt = yv.copy()
        yt[held] = np.nan
        # The fold's branches, on the readout range of the whole run (the readout, not the reference).
        m = dataclasses.replace(fit_direction_aware(xv, yt, degrees, threshold, folds), x_low=model.x_low,
                                x_high=model.x_high, causal=True)
        for band in bands:
            mb = dataclasses.replace(m, threshold=band)
            oof[band][held] = mb.predict(xv, labels[band] if np.array_equal(mb.usable(xv), model.usable(xv))
                                         else None)[0][held]

    def rmse(est):
        e = est[use] - yv[use]
        return float(np.sqrt(np.nanmean(e * e))) if np.isfinite(e).any() else float("inf")

    cv = {band: rmse(oof[band]) for band in bands}
    best = min(bands, key=cv.get)
    model = dataclasses.replace(model, threshold=best)
    fitted = np.where(use, model.predict(xv)[0], np.nan)
    return BranchFit(model, cv[best], oof[best], fitted, cv)


def _he_pair(run: Run, y, plain, compensated, ok, threshold: float) -> tuple[float, float, str]:
    """Hysteresis error of the plain and the compensated estimate: eq. (13) on whole cycles, else on level bins."""
    from fsrlab.metrics.cycles import row_directions

    yy = np.where(ok, y, np.nan)
    try:
        keep = np.isfinite(yy)
        b = run_hysteresis(yy[keep], np.asarray(plain)[keep], threshold=threshold).percent
        a = run_hysteresis(yy[keep], np.asarray(compensated)[keep], threshold=threshold).percent
        return float(b), float(a), "eq. (13) on the run's loading-unloading cycles"
    except ValueError:
        pass
    keep = np.isfinite(yy)
    d = np.zeros(yy.size, int)
    d[keep] = row_directions(yy[keep], None, None, threshold)
    return (binned_hysteresis_percent(yy, plain, d), binned_hysteresis_percent(yy, compensated, d),
            "eq. (13) on 10 level bins (loading vs unloading mean error): the run has no whole cycles")
