"""From a recorded run to a calibration, and from a calibration to the stress of another run.

The orchestration of the analysis topic: it reads what a run holds (its columns, its sidecar's
circuit) and passes it to the computations on arrays, and holds no model of its own --
polynomials and cross-validation are :mod:`fsrlab.analysis.calibration`, the compensation
:mod:`fsrlab.analysis.compensation`, branches, cycles and eq. (13) :mod:`fsrlab.analysis.cycles`,
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

    from fsrlab.runformat import load_run
    from fsrlab.analysis.pipeline import calibrate_run, apply_calibration
    cal = calibrate_run(load_run("bench.csv"), x="frequency_hz", compensate=True)
    est = apply_calibration(cal, load_run("other.csv"))["stress_pa_estimate"]

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5 (Figure 17), eq. (13).
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from fsrlab.analysis.calibration import Calibration, PolynomialModel, calibrate, default_groups
from fsrlab.analysis.cycles import RunHysteresis, row_cycles, row_directions, run_hysteresis
from fsrlab.circuits.circuit import LM555Circuit, readout_from_metadata
from fsrlab.runformat import KNOWN_COLUMNS, Run, RunFormatError, load_run

__all__ = [
    "ESTIMATE_COLUMN",
    "IN_RANGE_COLUMN",
    "MARGIN",
    "run_directions",
    "run_cycles",
    "run_groups",
    "run_circuit",
    "decode_capacitance",
    "run_readout",
    "calibrate_run",
    "fit_causal_branches",
    "BranchFit",
    "run_reference",
    "binned_hysteresis_percent",
    "live_estimator",
    "LiveEstimator",
    "run_recorded_with",
    "check_readout",
    "apply_calibration",
    "hysteresis_of_run",
]

#: Column that :func:`apply_calibration` adds: the calibrated stress. [Pa]
ESTIMATE_COLUMN = "stress_pa_estimate"
#: Column that :func:`apply_calibration` adds: 1 where the readout lies in the calibrated readout
#: range, 0 where the estimate is extrapolated or left out, empty where there is no readout. [1]
IN_RANGE_COLUMN = "in_range"
#: Default margin beyond the calibrated readout range, as a fraction of its span, within which an
#: estimate is still written (extrapolated, flagged); beyond it the estimate is left empty. [1]
MARGIN = 0.10
#: Fewer readings than this: ``lag="auto"`` assumes no lag rather than searching (the search fits
#: 22 weights per fold at every lag). [1]
MIN_LAG_READINGS = 250
#: Fewest cycles or time blocks for ``lag="auto"`` to search (else no lag is assumed). [1]
MIN_LAG_GROUPS = 4
#: Fewest readings (above the floor, with a reference) the causal compensation is fitted on. [1]
MIN_COMPENSATION_READINGS = 60
#: The decoded-capacitance variable of the physics-informed calibration. [F]
C_FSR = "c_fsr_farad"

# Sidecar keys that describe a file, not the data; an estimate written from a run drops them.
_FILE_KEYS = ("complete", "rows", "closed", "created", "format", "version", "columns")


def _as_run(run) -> Run:
    return run if isinstance(run, Run) else load_run(run)


@contextmanager
def _named(run: Run, x: str):
    """Re-raise a computation's ValueError about its arrays ``x``, ``y`` naming the run's columns."""
    try:
        yield
    except RunFormatError:
        raise
    except ValueError as exc:
        message = str(exc)
        for lead, name in (("x, y: ", f"{x} and stress_pa: "), ("x: ", f"{x}: ")):
            if message.startswith(lead):
                raise ValueError(f"{run.path}: {name}{message[len(lead):]}") from None
        if message.startswith("degree: "):
            raise
        raise ValueError(f"{run.path}: {message}") from None


def _recorded(run: Run):
    """The run's own ``direction`` and ``cycle`` columns (None where absent): the only place read."""
    return run.columns.get("direction"), run.columns.get("cycle")


def run_directions(run: Run, threshold: float = 0.05) -> np.ndarray:
    """Direction of every reading: the ``direction`` column, else found from the reference stress.

    Parameters
    ----------
    run : Run
        A loaded run (:func:`fsrlab.runformat.load_run`).
    threshold : float
        Reversal threshold as a fraction of the stress span, used without a direction column. [1]

    Returns
    -------
    ndarray of int
        +1 loading, -1 unloading, 0 hold or unknown (see :func:`fsrlab.analysis.cycles.row_directions`).
    """
    return row_directions(run.stress_pa(), *_recorded(run), threshold)


def run_cycles(run: Run, threshold: float = 0.05) -> np.ndarray:
    """Cycle number of every reading: the ``cycle`` column, else numbered from :func:`run_directions`.

    Parameters
    ----------
    run : Run
        A loaded run.
    threshold : float
        Reversal threshold as a fraction of the stress span. [1]

    Returns
    -------
    ndarray of float
        Cycle numbers (NaN where the cycle column is empty); a new cycle starts where loading
        follows unloading (:func:`fsrlab.analysis.cycles.cycle_numbers`).
    """
    return row_cycles(run.stress_pa(), *_recorded(run), threshold)


def run_groups(run: Run, folds: int = 5, threshold: float = 0.05) -> np.ndarray:
    """Cross-validation groups of a run: its cycles, kept whole.

    Parameters
    ----------
    run : Run
        A loaded run.
    folds : int
        Contiguous blocks to cut the run into when it has fewer than 2 cycles.
    threshold : float
        Reversal threshold for cycles found from the stress. [1]

    Returns
    -------
    ndarray of int
        Group of each reading (:func:`fsrlab.analysis.calibration.default_groups` of :func:`run_cycles`).
    """
    return default_groups(run.n_rows, run_cycles(run, threshold), folds)


def run_circuit(run: Run, circuit: LM555Circuit | None = None) -> LM555Circuit:
    """The LM555 circuit a run was recorded with.

    Parameters
    ----------
    run : Run
        A loaded run.
    circuit : LM555Circuit, optional
        Returned as is when given.

    Returns
    -------
    LM555Circuit
        ``circuit``, else the sidecar's (:func:`fsrlab.circuits.circuit.readout_from_metadata`),
        else :data:`fsrlab.physics.params.PAPER_CIRCUIT` (R = 10 kΩ, ideal D1, no C_off).
    """
    if circuit is not None:
        return circuit
    found, _ = readout_from_metadata(run.metadata)
    if found is not None:
        return found
    from fsrlab.physics.params import PAPER_CIRCUIT

    return PAPER_CIRCUIT


def decode_capacitance(frequency_hz, duty_cycle, circuit: LM555Circuit | None = None, range_=None) -> np.ndarray:
    """C_FSR of every reading, decoded from frequency and duty cycle (physics-informed calibration variable).

    Parameters
    ----------
    frequency_hz, duty_cycle : array_like
        555 readings (NaN where missing).
    circuit : LM555Circuit, optional
        The circuit (default :data:`fsrlab.physics.params.PAPER_CIRCUIT`).
    range_ : array_like, optional
        The run's ``range`` column: 1 where C_off was switched in, 0 where it was out
        (:meth:`LM555Circuit.on_range`). Without it, the circuit's C_off applies to every reading.

    Returns
    -------
    ndarray
        C_FSR [F] by :meth:`LM555Circuit.decode`; NaN where a reading or its range is missing, or
        the reading is impossible for the circuit (e.g. one noisy duty cycle outside the reachable
        range), so that one bad window does not stop a whole run.

    Raises
    ------
    ValueError
        A range other than 0 or 1, or columns of different lengths.
    """
    if circuit is None:
        from fsrlab.physics.params import PAPER_CIRCUIT

        circuit = PAPER_CIRCUIT
    f = np.asarray(frequency_hz, dtype=float)
    d = np.asarray(duty_cycle, dtype=float)
    if f.shape != d.shape:
        raise ValueError("frequency_hz and duty_cycle must have the same length")
    ok = np.isfinite(f) & np.isfinite(d)
    if range_ is None:
        states = [(circuit, ok)]
    else:
        r = np.asarray(range_, dtype=float)
        if r.shape != f.shape:
            raise ValueError("range_ must have one value per reading")
        bad = np.isfinite(r) & ~np.isin(r, (0.0, 1.0))
        if bad.any():
            raise ValueError(f"range_: must be 0 (C_off out) or 1 (C_off in), got {r[bad][0]:g}")
        states = [(circuit.on_range(0), ok & (r == 0)), (circuit.on_range(1), ok & (r == 1))]
    out = np.full(f.shape, np.nan)
    for circ, m in states:
        if m.any():
            out[m] = np.asarray(circ.decode(f[m], d[m], check=False).c_fsr_farad, dtype=float)
    return out


def run_readout(run: Run, x: str, circuit: LM555Circuit | None = None) -> tuple[np.ndarray, LM555Circuit | None]:
    """The calibration variable of a run: a column, or C_FSR decoded through the run's circuit.

    Parameters
    ----------
    run : Run
        A loaded run.
    x : str
        A column (``frequency_hz``, ``duty_cycle``, ``voltage_v``, ...), or ``c_fsr_farad``: C_FSR
        decoded from ``frequency_hz`` and ``duty_cycle`` (when the run has no such column),
        honouring the ``range`` column.
    circuit : LM555Circuit, optional
        Circuit for the decoding (default: :func:`run_circuit`).

    Returns
    -------
    values : ndarray
        One value per reading (NaN where missing or not decodable).
    circuit : LM555Circuit or None
        The circuit decoded through, or None for a column.

    Raises
    ------
    RunFormatError
        A column the run lacks.
    """
    if x == C_FSR and x not in run:
        run.require("frequency_hz", "duty_cycle")
        circ = run_circuit(run, circuit)
        return decode_capacitance(run["frequency_hz"], run["duty_cycle"], circ, run.columns.get("range")), circ
    return run[x], None


def run_reference(run: Run, reference: str | None = None) -> tuple[np.ndarray, str, str]:
    """The reference of a run: ``force_n`` [N] or ``stress_pa`` [Pa].

    Parameters
    ----------
    run : Run
        A loaded run.
    reference : {"force_n", "stress_pa"}, optional
        Which one (default: ``stress_pa`` when the run has it, else ``force_n``). ``stress_pa``
        from a run with only ``force_n`` needs the sidecar's sensor area (:meth:`Run.stress_pa`).

    Returns
    -------
    values : ndarray
    name : str
    unit : str
        ``"N"`` or ``"Pa"``.

    Raises
    ------
    ValueError
        ``reference`` not one of the two.
    RunFormatError
        The run has no such reference.
    """
    if reference not in (None, "force_n", "stress_pa"):
        raise ValueError(f"reference: must be force_n or stress_pa, got {reference!r}")
    if reference is None:
        reference = "stress_pa" if "stress_pa" in run else ("force_n" if "force_n" in run else None)
    if reference is None:
        raise RunFormatError(f"{run.path}: no reference: the run has neither 'force_n' nor 'stress_pa' "
                             f"(columns: {', '.join(run.columns)})")
    if reference == "stress_pa":
        return run.stress_pa(), "stress_pa", "Pa"
    return run["force_n"], "force_n", "N"


def _oof(fam, x, y, groups, folds, transform, floor):
    """Out-of-fold estimate of a model family (the chosen candidate refitted without each fold)."""
    from fsrlab.analysis.models import fit_family

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
        estimated (:func:`fsrlab.analysis.alignment.estimate_lag`) when the run has a ``time_s``
        column, at least :data:`MIN_LAG_READINGS` usable readings and :data:`MIN_LAG_GROUPS`
        cycles or time blocks, else 0; also 0 when the search finds the lag not identifiable on
        the run (``extra["lag_search"]`` then says why).
    max_lag_s : float, optional
        Half-width of the lag search (default 0.25 s, :data:`fsrlab.analysis.alignment.MAX_LAG_S`). [s]
    compensation_method : {"auto", "memory", "branches"}
        ``"auto"``: the causal play-operator model (:mod:`fsrlab.analysis.memory`) and, when the
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
        that is mostly negative, a lag search without a minimum.
    """
    from fsrlab.analysis.alignment import estimate_lag, shift_reference
    from fsrlab.analysis.calibration import fit_metrics, fingerprint
    from fsrlab.analysis.models import cross_validate_families, find_floor, resolution, transform_from_metadata

    run = _as_run(run)
    y_raw, y_name, y_unit = run_reference(run, reference)
    values, used = run_readout(run, x, circuit)
    unit = run.units.get(x) or KNOWN_COLUMNS.get(x, "F" if x == C_FSR else "")
    if compensation_method not in ("auto", "memory", "branches"):
        raise ValueError(f"compensation_method: must be auto, memory or branches, got {compensation_method!r}")
    both = np.isfinite(values) & np.isfinite(y_raw)
    if both.sum() < 3:
        raise ValueError(f"{run.path}: {x} and {y_name}: fewer than 3 readings with both values present")
    neg = float(np.mean(y_raw[both] < 0))
    if neg > 0.5:
        raise ValueError(f"{run.path}: {y_name}: the reference is mostly negative ({100 * neg:.0f} % of the readings "
                         "below 0): a load cell mounted or wired the wrong way round, or the wrong column")
    from fsrlab.analysis.hysteresis import check_response

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
    from fsrlab.analysis.calibration import CrossValidation

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
    from fsrlab.analysis.memory import causal_features, fit_memory, fit_uncertainty

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
    from fsrlab.analysis.cycles import row_directions

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
        Cross-validation groups; the folds are those of :func:`fsrlab.analysis.memory.fit_memory`
        (:func:`fsrlab.analysis.memory.fold_assignment`).
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
    (:func:`fsrlab.analysis.compensation.fit_direction_aware`; each branch's degree chosen by its
    own cross-validation on the whole run, then kept in the folds), and applied with causal labels
    (:class:`fsrlab.analysis.compensation.DirectionAwareCalibration` with ``causal=True``). Each
    fold's model is fitted with the held-out rows' reference removed and run over the whole
    readout sequence (the readout alone drives the labels and the memory), and its estimate of
    the held-out rows is kept; the causal band with the smallest out-of-fold RMSE is kept.
    """
    import dataclasses

    from fsrlab.analysis.compensation import causal_readout_directions, fit_direction_aware
    from fsrlab.analysis.memory import fold_assignment

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
    from fsrlab.analysis.cycles import row_directions

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


def live_estimator(cal: Calibration, margin: float = MARGIN, compensation: bool = True):
    """A causal estimator of a calibration: readings in, estimates out, one at a time.

    Parameters
    ----------
    cal : Calibration
        From :func:`calibrate_run` or :func:`fsrlab.analysis.calibration_io.load_calibration`.
    margin : float
        Beyond the calibrated readout range by more than this fraction of its span, a reading
        gets no estimate. [1]
    compensation : bool
        Use the calibration's causal compensation when it holds one.

    Returns
    -------
    LiveEstimator
        ``step(readout) -> (estimate or None, standard uncertainty or None, in_range)`` keeps its
        memory between calls; ``reference`` (``"force_n"`` or ``"stress_pa"``) and ``x`` (the
        readout column) name the quantities. For a calibration on ``c_fsr_farad`` the reading to
        step is C_FSR [F], decoded from the frequency and duty cycle (:func:`decode_capacitance`).
        The compensation is the calibration's play-operator model, or its causal branch
        polynomials when those were chosen (:func:`calibrate_run`); a calibration with only the
        earlier offline branch compensation (older files) steps without compensation.
    """
    from fsrlab.analysis.memory import CausalEstimator

    if not margin >= 0:
        raise ValueError(f"margin: must be a fraction >= 0 of the calibrated span, got {margin!r}")
    memory = cal.memory if compensation else None
    branches = _causal_branches(cal) if compensation and memory is None else None
    fs = memory.full_scale if memory is not None else (cal.full_scale or 1.0)
    has = cal.memory is not None or _causal_branches(cal) is not None
    table = cal.uncertainty_plain if (has and memory is None and branches is None) else cal.uncertainty
    return CausalEstimator(cal, cal.x_range, margin, cal.floor, memory, table, fs, cal.y_name, cal.x_name,
                           branches=branches)


def _causal_branches(cal: Calibration):
    """The calibration's branch compensation when it is the causal one (else None)."""
    comp = cal.compensation
    return comp if comp is not None and getattr(comp, "causal", False) else None


#: The live estimator's type (see :func:`live_estimator`).
from fsrlab.analysis.memory import CausalEstimator as LiveEstimator  # noqa: E402


def run_recorded_with(run: Run, used=None):
    """What a run was recorded with: its sidecar's circuits and the ranges of its readings.

    Parameters
    ----------
    run : Run
        A loaded run.
    used : array_like of bool, optional
        The readings that count (default all).

    Returns
    -------
    RecordedWith
        See :func:`fsrlab.analysis.provenance.recorded_with`.
    """
    from fsrlab.analysis.provenance import recorded_with

    try:
        return recorded_with(run.metadata, run.columns.get("range"), used)
    except ValueError as exc:
        raise RunFormatError(f"{run.path}: its sidecar's circuit: {exc}") from None


def check_readout(cal: Calibration, run: Run, circuit: LM555Circuit | None = None) -> list[str]:
    """How a run's readout differs from the one a calibration was recorded with.

    Parameters
    ----------
    cal : Calibration
        The calibration (its ``recorded_with`` and, for C_FSR, its decoding circuit).
    run : Run
        The run it would be applied to.
    circuit : LM555Circuit, optional
        The circuit C_FSR is decoded through, when not the calibration's.

    Returns
    -------
    list of str
        One sentence per difference naming the run's and the calibration's value (see
        :func:`fsrlab.analysis.provenance.mismatches`); empty when nothing known differs or when
        the calibration does not record what it was recorded with (``cal.recorded_with`` None).
    """
    from fsrlab.analysis.provenance import mismatches

    if cal.recorded_with is None:
        return []
    name = "the calibration" if cal.path is None else str(cal.path)
    decode = (circuit if circuit is not None else cal.circuit) if cal.x_name == C_FSR else None
    found = mismatches(cal.x_name, cal.recorded_with, run_recorded_with(run), decode)
    return [f"{run.path} was recorded with {a}, {name} with {b}" for a, b in found]


def apply_calibration(cal: Calibration, run, compensation: bool = True, circuit: LM555Circuit | None = None,
                      margin: float = MARGIN, force: bool = False) -> Run:
    """The run with the stress its calibration estimates, ready for :func:`fsrlab.runwriter.write_run`.

    Parameters
    ----------
    cal : Calibration
        From :func:`calibrate_run` or :func:`fsrlab.analysis.calibration_io.load_calibration`.
    run : Run or path
        The run to convert; it needs the calibration's readout column (or ``frequency_hz`` and
        ``duty_cycle`` for a calibration on ``c_fsr_farad``).
    compensation : bool
        Use the calibration's direction-aware compensation when it holds one (else the polynomial).
    circuit : LM555Circuit, optional
        Circuit for decoding C_FSR (default: the calibration's, else the run's, see :func:`run_circuit`).
    margin : float
        How far beyond the calibrated readout range an estimate is still written, as a fraction
        of the range's span (default :data:`MARGIN`, 10 %; ``inf``: never left empty); beyond it
        the estimate is left empty. [1]
    force : bool
        Apply even where the run's readout differs from the calibration's (:func:`check_readout`).

    Returns
    -------
    Run
        The input columns plus ``stress_pa_estimate`` [Pa] and ``in_range`` (1 inside the
        calibrated readout range, 0 outside, empty without a readout). An estimate is empty where
        the readout is missing, cannot be decoded (C_FSR), or lies beyond the margin. Its metadata
        is the input's without the file keys (``complete``, ``rows``, ...), with the units of the
        new columns and a ``calibration`` entry: file when known, readout, degree, method, data
        fingerprint, creation time, ``readout_range``, ``margin``, ``counts`` (rows ``estimated``,
        ``in_range``, ``out_of_range`` (with a readout outside the range), ``extrapolated``
        (estimated outside the range), ``missing`` (without an estimate) and, per reason,
        ``no_readout``, ``not_decodable``, ``beyond_margin``) and, when forced, ``forced`` (the
        differences). ``path`` is the input run's.

    Raises
    ------
    RunFormatError
        The run lacks the calibration's readout.
    ValueError
        The run's readout differs from the calibration's and ``force`` is false (one line naming
        both), or ``margin`` is negative.

    Notes
    -----
    Readings beyond the margin are treated as missing before the estimate is computed, so that
    one corrupt reading does not bend the compensation's branch detection for the whole run
    (see :meth:`fsrlab.analysis.compensation.DirectionAwareCalibration.predict` for gaps).
    """
    run = _as_run(run)
    if not margin >= 0:
        raise ValueError(f"margin: must be a fraction >= 0 of the calibrated span, got {margin!r}")
    if cal.x_name not in run and cal.x_name != C_FSR:
        raise RunFormatError(f"{run.path}: column {cal.x_name!r} (the calibration's readout) missing "
                             f"(columns: {', '.join(run.columns)})")
    differences = check_readout(cal, run, circuit)
    if differences and not force:
        raise ValueError(f"{differences[0]}: the readout means another stress; calibrate on a run recorded the "
                         "same way, or force it")
    values, _ = run_readout(run, cal.x_name, circuit if circuit is not None else cal.circuit)
    given = np.isfinite(values)
    lo, hi = cal.x_range
    span = hi - lo
    estimate_col, uncertainty_col = f"{cal.y_name}_estimate", f"{cal.y_name}_uncertainty"
    below = np.zeros_like(given)
    if compensation and cal.compensation is not None and cal.memory is None and _causal_branches(cal) is None:
        # An earlier calibration file: the offline branch method (it needs the whole run).
        inside = given & (values >= lo) & (values <= hi)
        kept = given if margin == np.inf else given & (values >= lo - margin * span) & (values <= hi + margin * span)
        est, how = cal.compensation(np.where(kept, values, np.nan)), "direction-aware compensation"
        unc = np.full(values.shape, np.nan)
    else:
        est, unc, inside, reason = live_estimator(cal, margin, compensation).run(values)
        below = reason == 2
        kept = given & (reason != 3)
        how = ("causal play-operator compensation" if compensation and cal.memory is not None
               else "causal branch compensation (loading/unloading polynomials, turning-point memory)"
               if compensation and _causal_branches(cal) is not None
               else f"{cal.model_name}" if cal.family is not None else f"polynomial of degree {cal.degree}")
    no_readout = ~given
    not_decodable = np.zeros_like(given)
    if cal.x_name == C_FSR and C_FSR not in run:
        parts = np.isfinite(run["frequency_hz"]) & np.isfinite(run["duty_cycle"])
        no_readout, not_decodable = ~given & ~parts, ~given & parts
    columns = dict(run.columns)
    columns[estimate_col] = est
    columns[uncertainty_col] = unc
    columns[IN_RANGE_COLUMN] = np.where(given, inside.astype(float), np.nan)
    counts = {"estimated": int(np.isfinite(est).sum()), "in_range": int(inside.sum()),
              "out_of_range": int((given & ~inside).sum()), "extrapolated": int((np.isfinite(est) & ~inside).sum()),
              "missing": int((~np.isfinite(est)).sum()),
              "no_readout": int(no_readout.sum()), "not_decodable": int(not_decodable.sum()),
              "beyond_margin": int((given & ~kept & ~below).sum()), "below_activation": int(below.sum())}
    meta = {k: v for k, v in run.metadata.items() if k not in _FILE_KEYS}
    meta["units"] = dict(run.units, **{estimate_col: cal.y_unit, uncertainty_col: cal.y_unit, IN_RANGE_COLUMN: "1"})
    source = {} if cal.path is None else {"file": str(cal.path)}
    meta["calibration"] = {**source, "x": cal.x_name, "reference": cal.y_name, "model": cal.model_name,
                           "degree": cal.degree, "method": how, "lag_s": cal.lag_s,
                           "data_fingerprint": cal.data_fingerprint, "created": cal.created,
                           "readout_range": [lo, hi], "margin": margin, "counts": counts}
    if differences:
        meta["calibration"]["forced"] = differences
    return Run(path=run.path, columns=columns, metadata=meta)


def hysteresis_of_run(run, quantity: str = "frequency_hz", threshold: float = 0.05,
                      reference: str | None = None) -> RunHysteresis:
    """Hysteresis error (eq. 13) of one column of a run, per cycle and overall.

    Parameters
    ----------
    run : Run or path
        A run with ``stress_pa`` (or ``force_n``) and the quantity.
    quantity : str
        Column whose hysteresis is measured (``frequency_hz``, ``voltage_v``, ``stress_pa_estimate``, ...).
    threshold : float
        Reversal threshold as a fraction of the stress span, used without a direction column. [1]
    reference : {"force_n", "stress_pa"}, optional
        The reference the branches follow (default: ``stress_pa`` when the run has it, else
        ``force_n``, which needs no sensor area; the result's "stress" is then a force [N]).

    Returns
    -------
    RunHysteresis
        See :func:`fsrlab.analysis.cycles.run_hysteresis`.

    Raises
    ------
    ValueError
        No complete cycle, or the quantity does not respond to the stress (a dead sensor,
        :func:`fsrlab.analysis.hysteresis.check_response`).
    """
    import dataclasses
    import re

    run = _as_run(run)
    stress, ref_name, ref_unit = run_reference(run, reference)
    if quantity in ("stress_pa", "force_n"):
        raise ValueError(f"quantity: {quantity} is a reference column (the {ref_name} the branches follow, or it "
                         "divided by the area); give a readout such as frequency_hz")
    q = run[quantity]
    # eq. (13)'s functions speak of stresses [Pa]; on a force reference their levels are newtons.
    in_unit = (lambda text: text) if ref_unit == "Pa" else (lambda text: re.sub(r"(\d) Pa\b", r"\1 " + ref_unit, text))
    try:
        res = run_hysteresis(stress, q, *_recorded(run), threshold, name=quantity)
    except RunFormatError:
        raise
    except ValueError as exc:
        raise ValueError(f"{run.path}: {in_unit(str(exc))}") from None
    return res if ref_unit == "Pa" else dataclasses.replace(res, method=in_unit(res.method))
