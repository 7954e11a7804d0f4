"""Time alignment of a reference and a readout recorded side by side (an extension beyond the paper).

A load cell read by an HX711 at 10–80 samples/s and a readout averaged over a window do not
describe the same instant: the readout of a row reflects the force some time ``lag_s`` earlier (a
negative lag: later). fsrlab estimates the lag from −0.25 s to +0.25 s (:data:`MAX_LAG_S`, at
least ±2 rows) in whole rows, then in quarter rows around the best (the reference linearly
interpolated in time), by one of three criteria:

* ``"memory"`` (default): the smallest grouped cross-validated RMSE of a model *with* hysteresis
  and creep -- a Chebyshev quintic in the normalised readout z plus the play-operator and creep
  terms of :mod:`fsrlab.calibration.play` computed on z -- so that the lag explains only what
  hysteresis cannot (the design is computed once; each lag refits the weights from per-fold sums).
  On a synthetic bench run (:mod:`fsrlab.virtual.synthetic`, seed 1, triangles at a constant
  rate) it finds 0 ms where ``"xcorr"`` finds +100 ms and ``"cv"`` +450 ms; on the hand-loaded
  runs of :mod:`fsrlab.virtual.handloaded` it finds +10 ms at 80 SPS and −30 ms at 10 SPS (the
  generator's closed form: +7.75 and −36 ms; the HX711's sample-and-hold makes the reference
  late), and a readout delayed by 3 rows moves it by 60 ms.

  The rows before the readout has swung both ways by twice the largest play-operator threshold
  are left out of the criterion: there the operators still hold their starting state, which no
  later row has, so the cycle that holds them is an extrapolation when it is held out. On the
  virtual bench's spring runs (4 triangles to 10 kPa, true lag 0) that one held-out cycle's error
  (230 Pa against 28–36 Pa for the others at lag 0) decided the lag: −0.235 s, and a compensated
  hysteresis error of 29 % instead of 0.8 %. Without those rows the search finds 0 to ±10 ms there,
  and a reference delayed by 50 or 120 ms (or a readout) within a quarter row of the delay.

  Identifiability: hysteresis that does not depend on the rate leaves the instant of a reversal
  where it is, a lag moves it, so only the reversals tell the two apart. Along a ramp a lag is an
  offset by direction, which the play operators reproduce; on a sine a phase shift is an elliptic
  loop, which they reproduce too. The search therefore reports ``plausible_s``, the whole-row lags
  whose out-of-fold error is within one standard error (paired over the cross-validation groups)
  of the best, and takes the lag as *not identifiable* -- ``lag_s`` 0, ``identifiable`` False and a
  ``note`` -- when they span more than :data:`IDENTIFIABLE_SPAN` of the search range (a sine drive:
  0.35 to 0.6 of it; the virtual bench's triangles and the hand-loaded runs: at most 0.12) or when
  the rows judged hold fewer than :data:`MIN_REVERSALS` reversals (one motor-driven triangle: the
  search found −150 ms for a true +8 ms). Taking the smallest lag within one standard error of the
  best instead was tried and not kept: with 4 to 6 cycles it moved a known −50 ms delay to −10 ms
  and did not find the lag on a sine either.
* ``"xcorr"``: the largest correlation between the changes over 5 rows (slower than
  tremor, noise and an HX711's sample-and-hold steps) of the readout and of the shifted reference.
  Hysteresis flattens the readout just after a reversal, which this criterion takes for a delay;
* ``"cv"``: the smallest grouped cross-validated RMSE of a degree-``k`` polynomial
  ``y(t − lag) ≈ P(x(t))`` (:func:`fsrlab.calibration.polynomial.cross_validate_degrees`). A
  single-valued curve cannot follow hysteresis, and a time shift narrows the loop, so on a
  hysteretic sensor this criterion overstates the lag (on the hand-loaded runs of
  :mod:`fsrlab.virtual.handloaded`: 50 ms where ``"xcorr"`` finds 0 to 10 ms).

An optimum at the end of the search range is no optimum: the caller is told (one line) rather than
given a lag at the boundary.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.calibration.polynomial import cross_validate_degrees

__all__ = ["LagSearch", "shift_reference", "estimate_lag", "SMOOTH_ROWS", "MAX_LAG_S", "IDENTIFIABLE_SPAN",
           "MIN_REVERSALS", "REVERSAL_SWING"]

#: Default half-width of the lag search: an HX711 at 10 SPS holds a sample up to 0.1 s, a readout
#: window is up to 0.1 s; beyond that, on constant-rate triangles, a shift by a fraction of a ramp
#: can stand in for hysteresis. [s]
MAX_LAG_S = 0.25
#: Rows over which "xcorr" takes the changes of readout and reference. [1]
SMOOTH_ROWS = 5
#: "memory": the lag counts as not identifiable when the lags within one standard error of the
#: minimum span more than this fraction of the search range (a sine drive: 0.35-0.6; the virtual
#: bench's triangles and the hand-loaded runs: at most 0.12; noisy synthetic triangles: 0.2-0.3). [1]
IDENTIFIABLE_SPAN = 0.3
#: "memory": fewest reversals of the readout (by :data:`REVERSAL_SWING` of its range) in the rows
#: judged for the lag to count as identifiable. [1]
MIN_REVERSALS = 2
#: Swing that makes a reversal for :data:`MIN_REVERSALS`, a fraction of the readout's range. [1]
REVERSAL_SWING = 0.1


@dataclass(frozen=True)
class LagSearch:
    """The lag that minimises the cross-validated error, and the error curve.

    Parameters
    ----------
    lag_s : float
        Estimated lag: the readout at t goes with the reference at ``t − lag_s``. [s] (rows
        when the run has no time column)
    lags_s : ndarray
        Lags tried. [s]
    cv_rmse : ndarray
        The criterion at each lag: cross-validated RMSE [unit of y] (``"cv"``), or
        1 − correlation of the changes [1] (``"xcorr"``).
    method : str
        ``"memory"``, ``"xcorr"`` or ``"cv"``.
    plausible_s : tuple of float, optional
        ``"memory"``: the least and the largest whole-row lag whose error is not worse than the
        minimum's by more than one standard error of the difference (paired over the
        cross-validation groups). [s]
    identifiable : bool
        ``"memory"``: False when the plausible lags span more than :data:`IDENTIFIABLE_SPAN`
        of the search range, or the rows judged hold fewer than :data:`MIN_REVERSALS` reversals:
        the run does not tell a lag from a hysteresis loop, and ``lag_s`` is 0.
    note : str
        Why the lag is not identifiable (empty when it is).
    """

    lag_s: float
    lags_s: np.ndarray
    cv_rmse: np.ndarray
    method: str = "cv"
    plausible_s: tuple | None = None
    identifiable: bool = True
    note: str = ""

    def to_dict(self) -> dict:
        """JSON form: the lag, the criterion, the search range and (``"memory"``) the plausible lags."""
        out = {"lag_s": self.lag_s, "method": self.method,
               "range_s": [float(self.lags_s.min()), float(self.lags_s.max())]}
        if self.plausible_s is not None:
            out["plausible_s"] = [float(v) for v in self.plausible_s]
            out["identifiable"] = bool(self.identifiable)
            if self.note:
                out["note"] = self.note
        return out


def shift_reference(t, y, lag_s: float) -> np.ndarray:
    """The reference at ``t − lag_s`` for every row, linearly interpolated (NaN beyond the record).

    Parameters
    ----------
    t : array_like
        Row times, increasing. [s]
    y : array_like
        Reference (NaN rows are left out of the interpolation). [unit of y]
    lag_s : float
        Lag. [s]

    Returns
    -------
    ndarray
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if lag_s == 0:
        return y.copy()
    ok = np.isfinite(t) & np.isfinite(y)
    if ok.sum() < 2:
        return np.full(y.shape, np.nan)
    return np.interp(t - lag_s, t[ok], y[ok], left=np.nan, right=np.nan)


def estimate_lag(t, x, y, groups, usable=None, max_lag_s: float | None = None, degree: int = 3,
                 folds: int = 5, method: str = "memory") -> LagSearch:
    """Estimate the lag between reference and readout by the cross-validated error.

    Parameters
    ----------
    t : array_like
        Row times [s] (or row numbers).
    x, y : array_like
        Readout and reference.
    groups : array_like of int
        Cross-validation groups.
    usable : array_like of bool, optional
        Rows that may enter the fit (e.g. not at the readout's floor).
    max_lag_s : float, optional
        Search from ``-max_lag_s`` to ``+max_lag_s`` (default :data:`MAX_LAG_S`, and at least 2
        rows). [s]
    degree : int
        Degree of the polynomial judged at each lag.
    folds : int
        Cross-validation folds.
    method : {"memory", "xcorr", "cv"}
        The criterion (see the module's docstring).

    Returns
    -------
    LagSearch
        ``cv_rmse`` holds the criterion at each lag: the RMSE for ``"memory"`` and ``"cv"``,
        ``1 − correlation`` for ``"xcorr"``.

    Raises
    ------
    ValueError
        ``lag: ...`` when the error keeps falling towards an end of the search range (no minimum
        inside it) or does not change with the lag at all.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    g = np.asarray(groups)
    use = np.ones(x.size, bool) if usable is None else np.asarray(usable, bool)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    if not dt > 0:
        raise ValueError("time_s: rows must be in increasing time to estimate a lag")
    if max_lag_s is None:
        max_lag_s = MAX_LAG_S
    if not (np.isfinite(max_lag_s) and max_lag_s > 0):
        raise ValueError(f"max_lag_s: must be a positive number of seconds, got {max_lag_s!r}")
    steps = max(int(round(max_lag_s / dt)), 2)

    def cv(lag: float) -> float:
        ys = shift_reference(t, y, lag)
        ok = use & np.isfinite(x) & np.isfinite(ys)
        res = cross_validate_degrees(x[ok], ys[ok], g[ok], degrees=[degree], folds=folds, tolerance=0.0)
        return res.rmse[0]

    if method not in ("memory", "xcorr", "cv"):
        raise ValueError(f"method: must be memory, xcorr or cv, got {method!r}")
    sign = 1.0
    okxy = use & np.isfinite(x) & np.isfinite(y)
    if okxy.sum() > 2 and np.ptp(x[okxy]) > 0 and np.ptp(y[okxy]) > 0:
        sign = 1.0 if np.corrcoef(x[okxy], y[okxy])[0, 1] >= 0 else -1.0

    span = SMOOTH_ROWS

    def changes(v: np.ndarray) -> np.ndarray:
        # Change over `span` rows: slower than tremor, noise and the HX711's sample-and-hold steps.
        return v[span:] - v[:-span]

    use_d = use[span:] & use[:-span]
    dx = changes(sign * x)

    def xcorr(lag: float) -> float:
        dy = changes(shift_reference(t, y, lag))
        ok = np.isfinite(dx) & np.isfinite(dy) & use_d
        if ok.sum() < 3 or np.ptp(dx[ok]) == 0 or np.ptp(dy[ok]) == 0:
            return 1.0
        return 1.0 - float(np.corrcoef(dx[ok], dy[ok])[0, 1])

    if method == "memory":
        return _memory_search(t, x, y, g, use, steps, dt, sign, folds)
    if method == "xcorr":
        lags = np.arange(-4 * steps, 4 * steps + 1) * dt / 4
        errs = np.array([xcorr(lag) for lag in lags])
        i = int(np.argmin(errs))
        if errs[i] > 0.8:
            raise ValueError("lag: the changes of readout and reference hardly correlate (r < 0.2) at any lag within "
                             f"±{steps * dt:.4g} s: no maximum to find (does the readout respond to the reference?)")
        if i in (0, lags.size - 1):
            raise ValueError(f"lag: the correlation keeps rising towards a lag of {lags[i]:+.4g} s, the end of the "
                             f"search range (±{steps * dt:.4g} s): no maximum inside it; check that readout and "
                             "reference belong to the same recording")
        return LagSearch(lag_s=float(lags[i]), lags_s=lags, cv_rmse=errs, method="xcorr")
    return _grid_search(lambda lags: np.array([cv(lag) for lag in lags]), steps, dt, "cv")


def _grid_search(criterion, steps: int, dt: float, method: str) -> LagSearch:
    """The lag of least ``criterion(lags)`` (an array of errors): whole rows over ±steps, then quarter rows
    around the best; one line when the error is flat or keeps falling towards an end of the range."""
    coarse = np.arange(-steps, steps + 1) * dt
    errs = criterion(coarse)
    i = int(np.argmin(errs))
    if np.ptp(errs) <= 1e-9 * max(errs.max(), 1e-300):
        raise ValueError("lag: the cross-validated error does not change with the lag: no minimum to find "
                         "(does the readout respond to the reference?)")
    if i in (0, coarse.size - 1):
        raise ValueError(f"lag: the cross-validated error keeps falling towards a lag of {coarse[i]:+.4g} s, the end "
                         f"of the search range (±{steps * dt:.4g} s): no minimum inside it; check that readout and "
                         "reference belong to the same recording")
    fine = coarse[i] + np.array([-0.75, -0.5, -0.25, 0.25, 0.5, 0.75]) * dt
    lags = np.concatenate([coarse, fine])
    allerr = np.concatenate([errs, criterion(fine)])
    order = np.argsort(lags)
    lags, allerr = lags[order], allerr[order]
    return LagSearch(lag_s=float(lags[int(np.argmin(allerr))]), lags_s=lags, cv_rmse=allerr, method=method)


def _memory_search(t, x, y, g, use, steps, dt, sign, folds) -> LagSearch:
    """The "memory" criterion: grouped CV RMSE of a model with hysteresis (play operators) at each lag."""
    from fsrlab.physics.history import turning_points
    from fsrlab.calibration.play import CREEP_TIME_CONSTANTS_S, THRESHOLDS, causal_features

    ok = use & np.isfinite(x)
    if ok.sum() < 10:
        raise ValueError("lag: too few readings to estimate a lag")
    u = sign * x
    lo, hi = float(np.min(u[ok])), float(np.max(u[ok]))
    if not hi > lo:
        raise ValueError("lag: the readout does not vary; no lag to find")
    z = np.where(ok, (u - lo) / (hi - lo), np.where(np.isfinite(x), 0.0, np.nan))
    alphas = tuple(1.0 - np.exp(-dt / tau) for tau in CREEP_TIME_CONSTANTS_S)
    p, sm, _ = causal_features(z, THRESHOLDS, alphas)
    c = 2 * z - 1
    cheb = [np.ones_like(c), c]
    for _ in range(4):
        cheb.append(2 * c * cheb[-1] - cheb[-2])
    hyst = p - z[:, None]
    a = np.column_stack(cheb + [hyst, z[:, None] * hyst, sm - z[:, None]])
    # Rows usable at every lag (the shifted reference is NaN within `steps` rows of either end).
    rows = ok & np.all(np.isfinite(a), axis=1)
    rows[: steps + 2] = False
    rows[-(steps + 2):] = False
    # Rows before the readout has swung both ways by twice the largest threshold hold the operators'
    # starting state, which no later row has: held out, their cycle is an extrapolation whose error
    # swamps the criterion (the virtual bench's first cycle: lag -0.235 s instead of 0). Left out
    # when enough rows remain.
    settled = rows & (np.arange(rows.size) >= _memory_settled(z, 2 * max(THRESHOLDS)))
    if np.unique(g[settled]).size >= 2 and settled.sum() >= 10 * a.shape[1]:
        rows = settled
    idx = np.flatnonzero(rows)
    if idx.size < 10 * a.shape[1]:
        raise ValueError("lag: too few readings to estimate a lag")
    a = a[idx]
    _, gi = np.unique(g[idx], return_inverse=True)
    k = min(folds, int(gi.max()) + 1)
    if k < 2:
        raise ValueError("groups: cross-validation needs at least 2 groups (cycles or blocks)")
    fold = (np.arange(int(gi.max()) + 1) % k)[gi]
    parts = [a[fold == f] for f in range(k)]
    grams = [af.T @ af for af in parts]
    total = sum(grams)
    lam = 1e-8 * np.trace(total) / total.shape[0] * np.eye(total.shape[0])
    solves = [np.linalg.inv(total - gf + lam) for gf in grams]
    scale = float(np.nanstd(y[idx])) or 1.0

    def crits(lags) -> np.ndarray:
        """CV RMSE at every lag at once: the weights of each fold from per-fold sums."""
        ys = np.column_stack([shift_reference(t, y, lag)[idx] for lag in lags]) / scale
        ys = np.where(np.isfinite(ys), ys, 0.0)
        bs = [parts[f].T @ ys[fold == f] for f in range(k)]  # (m, lags) per fold
        btot = sum(bs)
        sse = np.zeros(len(lags))
        for f in range(k):
            beta = solves[f] @ (btot - bs[f])
            yf = ys[fold == f]
            sse += (yf * yf).sum(0) - 2 * (beta * bs[f]).sum(0) + (beta * (grams[f] @ beta)).sum(0)
        return scale * np.sqrt(np.clip(sse, 0.0, None) / idx.size)

    # Which whole-row lags the groups cannot tell from the best: out-of-fold squared error per group,
    # paired against the best lag's (the level of each cycle cancels).
    coarse = np.arange(-steps, steps + 1) * dt
    ys = np.column_stack([shift_reference(t, y, lag)[idx] for lag in coarse]) / scale
    ys = np.where(np.isfinite(ys), ys, 0.0)
    bs = [parts[f].T @ ys[fold == f] for f in range(k)]
    btot = sum(bs)
    ng = int(gi.max()) + 1
    mse = np.zeros((ng, coarse.size))
    for f in range(k):
        res = ys[fold == f] - parts[f] @ (solves[f] @ (btot - bs[f]))
        np.add.at(mse, gi[fold == f], res * res)
    mse /= np.bincount(gi, minlength=ng)[:, None]
    diff = mse - mse[:, [int(np.argmin(mse.mean(0)))]]
    se = diff.std(0, ddof=1) / np.sqrt(ng)
    near = coarse[diff.mean(0) <= se]
    plausible = (float(near.min()), float(near.max()))
    flat = np.ptp(mse.mean(0)) <= 1e-9 * max(mse.mean(0).max(), 1e-300)  # _grid_search says so
    # A lag and a loop differ only where the load reverses: fewer than MIN_REVERSALS reversals in the
    # rows judged, or plausible lags spanning most of the range (a smooth periodic drive), and no lag
    # is assumed.
    reversals = turning_points(z[idx], REVERSAL_SWING).size - 2
    wide = plausible[1] - plausible[0] > IDENTIFIABLE_SPAN * (coarse[-1] - coarse[0])
    if not flat and (reversals < MIN_REVERSALS or wide):
        why = (f"{max(reversals, 0)} reversal(s) of the readout in the rows judged, fewer than {MIN_REVERSALS}"
               if reversals < MIN_REVERSALS else
               f"lags from {plausible[0]:+.3g} to {plausible[1]:+.3g} s fit within one standard error of the best")
        return LagSearch(0.0, coarse, scale * np.sqrt(mse.mean(0)), "memory", plausible, False,
                         f"lag not identifiable on this run ({why}): a lag and a hysteresis loop fit it alike; "
                         "no lag assumed (set one with --lag)")
    found = _grid_search(crits, steps, dt, "memory")
    return LagSearch(found.lag_s, found.lags_s, found.cv_rmse, "memory", plausible, True)


def _memory_settled(z: np.ndarray, swing: float) -> int:
    """First row after which every play operator up to ``swing``/2 has moved both ways.

    The readout ``z`` (NaN rows skipped) must rise by ``swing`` above its lowest value so far and
    then fall by ``swing`` below the highest value since (or fall, then rise). Before that the
    operators still hold their starting state. ``z.size`` when it never does.
    """
    lo = hi = None
    first = 0  # +1: rose by `swing` first, -1: fell first, 0: neither yet
    for i, v in enumerate(z.tolist()):
        if v != v:  # NaN
            continue
        if lo is None:
            lo = hi = v
            continue
        if first == 0:
            lo, hi = min(lo, v), max(hi, v)
            if v - lo >= swing:
                first, hi = 1, v
            elif hi - v >= swing:
                first, lo = -1, v
        elif first == 1:
            hi = max(hi, v)
            if hi - v >= swing:
                return i
        else:
            lo = min(lo, v)
            if v - lo >= swing:
                return i
    return z.size
