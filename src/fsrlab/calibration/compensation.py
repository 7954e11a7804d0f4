"""Hysteresis compensation by a direction-aware calibration with turning-point memory.

**Extension beyond the paper.** The paper calibrates frequency to stress with one cubic
(Figure 17); a single-valued curve cannot follow a hysteretic sensor, so the calibrated force keeps
the sensor's hysteresis error. Here the loading and the unloading branches get their own
polynomial, and the branch in use is found from the readout sequence itself (its reversals beyond
a threshold, :func:`fsrlab.metrics.cycles.readout_directions`), so no reference is needed when the
calibration is applied.

Turning-point memory: a branch that starts at a reversal starts from the estimate reached there
(no jump), and the offset to its major curve decays linearly to zero at the far end of the
calibrated range, where loading and unloading curves meet. For the readout x_r at the reversal,
the estimate y_r reached there, the major curves L (loading) and U (unloading), and the calibrated
readout range [x_lo, x_hi] (x increasing with stress)::

    loading after a reversal:    y = L(x) + (y_r - L(x_r)) (x_hi - x)/(x_hi - x_r)
    unloading after a reversal:  y = U(x) + (y_r - U(x_r)) (x - x_lo)/(x_r - x_lo)

A minor loop therefore starts on the estimate at its reversal and is pulled onto the major branch
as it proceeds -- the simplest rule with the wiping-out flavour of Preisach models; it is exact
for the major loop and approximate for minor loops.

Direction. The fit labels branches from the whole run (:func:`fsrlab.metrics.cycles.readout_directions`:
a reversal is confirmed once the readout has moved back by the threshold, then dated back to the
extremum), which is not causal. A calibration with ``causal=True`` (what ``fsrlab calibrate``
writes since the branch method takes part in the compensation choice) labels the readings it
*applies* to causally instead (:func:`causal_readout_directions`): the branch switches at the
reading that confirms the reversal, the readings between the extremum and that one stay on the
old branch, and the turning point is the extremum seen so far. Every estimate then depends on
past readings only, so :class:`BranchState` steps it live with the same numbers as
:meth:`DirectionAwareCalibration.predict` offline. Older files (no ``causal`` key) keep the
offline labels.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eq. (13), Figure 17.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.calibration.polynomial import PolynomialModel
from fsrlab.calibration.result import calibrate
from fsrlab.metrics.cycles import readout_directions

__all__ = ["causal_readout_directions", "DirectionAwareCalibration", "BranchState", "fit_direction_aware",
           "CompensationResult", "compare_compensation"]


def causal_readout_directions(x, sign: float, band: float) -> np.ndarray:
    """Label readings +1 (loading) / −1 (unloading) causally, from the readings so far only.

    Parameters
    ----------
    x : array_like
        Readout in time order; NaN readings keep the previous label (the first ones: loading).
    sign : {+1, −1}
        +1 if the readout grows with stress, −1 if it falls.
    band : float
        Reversal threshold in readout units (> 0): the label switches at the first reading that
        lies this far back from the extremum of the current branch. [unit of x]

    Returns
    -------
    ndarray of int
        +1 or −1 for every reading. A run starts loading (the sensor starts from rest).

    Notes
    -----
    With u = sign·x: on loading, the running maximum m follows u while u ≥ m; a reading with
    u < m − band switches to unloading and restarts m at u (symmetrically on unloading). This is
    a play operator of half-width ``band`` on u, read for its direction.
    """
    x = np.asarray(x, dtype=float)
    lab = np.ones(x.size, dtype=int)
    label, ext = 1, None
    for i, v in enumerate((sign * x).tolist()):
        if v == v:  # finite (NaN != NaN)
            if ext is None:
                ext = v
            elif label > 0:
                if v > ext:
                    ext = v
                elif v < ext - band:
                    label, ext = -1, v
            else:
                if v < ext:
                    ext = v
                elif v > ext + band:
                    label, ext = 1, v
        lab[i] = label
    return lab


@dataclass(frozen=True)
class DirectionAwareCalibration:
    """Separate loading and unloading polynomials with turning-point memory (an extension).

    Parameters
    ----------
    load_model, unload_model : PolynomialModel
        Major loading and unloading curves y(x).
    x_low, x_high : float
        Calibrated readout range.
    sign : float
        +1 if the readout grows with stress, -1 if it falls.
    threshold : float
        Reversal threshold as a fraction of the readout span. [1]
    causal : bool
        Label branches causally when applied (:func:`causal_readout_directions` with a band of
        ``threshold`` × the calibrated span), so that the estimate can be stepped live
        (:class:`BranchState`); False: offline labels from the whole sequence (older files).
    """

    load_model: PolynomialModel
    unload_model: PolynomialModel
    x_low: float
    x_high: float
    sign: float
    threshold: float
    causal: bool = False

    def __post_init__(self) -> None:
        if not (np.isfinite(self.x_low) and np.isfinite(self.x_high) and self.x_low < self.x_high):
            raise ValueError(f"x_low, x_high must be finite with x_low < x_high, got {self.x_low!r}, {self.x_high!r}")
        if self.sign not in (1.0, -1.0):
            raise ValueError(f"sign must be +1 or -1, got {self.sign!r}")
        if not 0 < self.threshold < 1:
            raise ValueError(f"threshold must be a fraction of the readout span in (0, 1), got {self.threshold!r}")

    @property
    def band(self) -> float:
        """The causal reversal band, ``threshold`` × the calibrated readout span. [unit of x]"""
        return self.threshold * abs(self.x_high - self.x_low)

    def usable(self, x) -> np.ndarray:
        """True where a reading is finite and both branch polynomials are finite at it."""
        x = np.asarray(x, dtype=float)
        with np.errstate(over="ignore", invalid="ignore"):
            return np.isfinite(x) & np.isfinite(self.load_model(x)) & np.isfinite(self.unload_model(x))

    def __call__(self, x) -> np.ndarray:
        """Estimate y along a readout sequence in time order (NaN readings give NaN)."""
        return self.predict(x)[0]

    def predict(self, x, labels=None) -> tuple[np.ndarray, np.ndarray]:
        """Estimate y and the branch of each reading.

        Parameters
        ----------
        x : array_like
            Readout in time order; NaN where a reading is missing.
        labels : array_like of int, optional
            The branch labels of ``x`` when already computed (the labels this calibration would
            give ``x``; :func:`fsrlab.calibration.fit.fit_causal_branches` reuses them across folds).

        Returns
        -------
        y : ndarray
            Estimate [unit of y]; NaN where the reading is missing or a branch polynomial has no
            finite value at it (a corrupt reading such as 1e308 Hz), which count as missing.
        direction : ndarray of int
            +1 loading, -1 unloading.

        Notes
        -----
        Missing readings are gaps: they take no part in finding the branches. The turning-point
        memory restarts (the branch after it follows its major curve) where the reversal falls in
        a gap, so that the turning point was not observed, or where its estimate is not finite; a
        gap within a branch keeps the memory. With ``causal`` the labels are
        :func:`causal_readout_directions` and each estimate depends on earlier readings only
        (stepping :class:`BranchState` gives the same numbers). Both polynomials are evaluated
        once over the whole sequence; a branch's offset reads the new branch's curve at the
        turning-point reading.
        """
        x = np.asarray(x, dtype=float)
        ok = self.usable(x)
        x = np.where(ok, x, np.nan)
        if labels is not None:
            lab = np.asarray(labels, dtype=int)
        else:
            lab = (causal_readout_directions(x, self.sign, self.band) if self.causal
                   else readout_directions(x, self.sign, self.threshold))
        with np.errstate(invalid="ignore"):
            curves = {True: self.load_model(x), False: self.unload_model(x)}
        y = np.full(x.size, np.nan)
        # "up" = towards larger stress; the memory weights use the readout in stress order.
        u = self.sign * x
        u_lo, u_hi = sorted((self.sign * self.x_low, self.sign * self.x_high))
        starts = np.flatnonzero(np.diff(lab) != 0) + 1
        bounds = np.concatenate([[0], starts, [x.size]]).tolist()
        okl = ok.tolist()
        prev = None  # (y_r, u_r, row) of the turning point
        for a, b in zip(bounds[:-1], bounds[1:]):
            seg = np.arange(a, b)[ok[a:b]]
            if seg.size == 0:
                continue
            if a > 0 and not okl[a - 1]:
                prev = None  # the reversal fell in a gap: its turning point was not observed
            loading = bool(lab[a] > 0)
            curve = curves[loading]
            base = curve[seg]
            if prev is not None:
                prev_y, prev_u, k = prev
                offset = prev_y - float(curve[k])
                if loading:
                    w = (u_hi - u[seg]) / max(u_hi - prev_u, 1e-300)
                else:
                    w = (u[seg] - u_lo) / max(prev_u - u_lo, 1e-300)
                base = base + offset * np.clip(w, 0.0, 1.0)
            y[seg] = base
            # The reversal ending this segment: its extremum reading (turning points are extrema).
            k = int(seg[np.argmax(u[seg])] if loading else seg[np.argmin(u[seg])])
            prev = (float(y[k]), float(u[k]), k) if np.isfinite(y[k]) else None
        return y, lab

    def to_dict(self) -> dict:
        """JSON form (stored under ``"compensation"`` in a calibration file)."""
        return {
            "model": "direction-aware polynomials with turning-point memory (fsrlab extension)",
            "load": {"chebyshev_coefficients": self.load_model.coefficients.tolist(),
                     "x_center": self.load_model.center, "x_half_width": self.load_model.half_width},
            "unload": {"chebyshev_coefficients": self.unload_model.coefficients.tolist(),
                       "x_center": self.unload_model.center, "x_half_width": self.unload_model.half_width},
            "x_low": self.x_low, "x_high": self.x_high, "sign": self.sign, "threshold": self.threshold,
            "causal": self.causal,
        }

    @classmethod
    def from_dict(cls, d: dict) -> "DirectionAwareCalibration":
        """Inverse of :meth:`to_dict` (a file without ``causal`` is an older, offline one)."""
        def model(m):
            return PolynomialModel(np.asarray(m["chebyshev_coefficients"], float), float(m["x_center"]),
                                   float(m["x_half_width"]))

        return cls(model(d["load"]), model(d["unload"]),
                   float(d["x_low"]), float(d["x_high"]), float(d["sign"]), float(d["threshold"]),
                   bool(d.get("causal", False)))


class BranchState:
    """Steps a causal :class:`DirectionAwareCalibration` one reading at a time (the live path).

    Parameters
    ----------
    comp : DirectionAwareCalibration
        With ``causal=True``.

    Notes
    -----
    :meth:`step` reproduces :meth:`DirectionAwareCalibration.predict` reading by reading: the
    same causal labels, the same turning point (the first extremum of the branch just left) and
    the same memory offset, evaluated with the same floating-point operations.
    """

    def __init__(self, comp: DirectionAwareCalibration):
        if not comp.causal:
            raise ValueError("comp: only a causal branch calibration can be stepped")
        self.comp = comp
        self.u_lo, self.u_hi = sorted((comp.sign * comp.x_low, comp.sign * comp.x_high))
        self.label = 1
        self.ext = None  # (u, y) of the current branch's extremum so far
        self.prev = None  # (y_r, u_r) of the turning point the branch started from
        self.offset = None
        self.last_missing = False
        self.started = False

    def step(self, x: float | None) -> float | None:
        """Take one reading (None or NaN: missing); return the estimate or None. [unit of y]"""
        c = self.comp
        xa = np.array([np.nan if x is None else float(x)])
        if not c.usable(xa)[0]:
            self.last_missing = self.started or self.last_missing
            return None
        u = float(c.sign * xa[0])
        switched = False
        if not self.started:
            self.started, self.ext = True, None
        elif self.label > 0 and u < self.ext[0] - c.band:
            switched = True
        elif self.label < 0 and u > self.ext[0] + c.band:
            switched = True
        if switched:
            self.prev = None if (self.last_missing or not np.isfinite(self.ext[1])) else (self.ext[1], self.ext[0])
            self.label = -self.label
            self.ext = None
            self.offset = None
        loading = self.label > 0
        model = c.load_model if loading else c.unload_model
        base = model(xa)
        if self.prev is not None:
            if self.offset is None:
                self.offset = self.prev[0] - float(model(c.sign * self.prev[1]))
            if loading:
                w = (self.u_hi - c.sign * xa) / max(self.u_hi - self.prev[1], 1e-300)
            else:
                w = (c.sign * xa - self.u_lo) / max(self.prev[1] - self.u_lo, 1e-300)
            base = base + self.offset * np.clip(w, 0.0, 1.0)
        y = float(base[0])
        if self.ext is None or (u > self.ext[0] if loading else u < self.ext[0]):
            self.ext = (u, y)
        self.last_missing = False
        return y if np.isfinite(y) else None


def fit_direction_aware(x, y, degree: int | str | tuple = "auto", threshold: float = 0.05,
                        folds: int = 5) -> DirectionAwareCalibration:
    """Fit the loading and unloading curves of a run with loading-unloading cycles.

    Parameters
    ----------
    x : array_like
        Readout in time order (frequency [Hz], ...).
    y : array_like
        Reference stress [Pa].
    degree : int, (int, int) or "auto"
        Degree of each branch polynomial (1..5), or (loading, unloading) degrees, or ``"auto"``:
        chosen per branch by cross-validation over contiguous blocks of that branch's readings
        (whole branches of a cycle stay together when there are enough cycles).
    threshold : float
        Reversal threshold as a fraction of the readout span. [1]
    folds : int
        Folds of the cross-validation.

    Returns
    -------
    DirectionAwareCalibration

    Raises
    ------
    ValueError
        If the run lacks readings on one of the branches.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape != y.shape:
        raise ValueError("x and y must have the same length")
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 16:
        raise ValueError("x, y: too few readings for a direction-aware calibration (at least 16)")
    sign = 1.0 if np.corrcoef(x[ok], y[ok])[0, 1] >= 0 else -1.0
    lab = readout_directions(x, sign, threshold)
    lo, hi = float(x[ok].min()), float(x[ok].max())
    models = []
    per_branch = tuple(degree) if isinstance(degree, (tuple, list)) else (degree, degree)
    for d, deg in zip((1, -1), per_branch):
        m = ok & (lab == d)
        if m.sum() <= 7:
            raise ValueError(f"the run has too few {'loading' if d > 0 else 'unloading'} readings "
                             "(needs loading-unloading cycles)")
        # Groups: one per branch run (a cycle's branch), or contiguous blocks if there are few.
        runs = np.cumsum(np.diff(lab, prepend=lab[0]) != 0)[m]
        groups = runs if np.unique(runs).size >= 2 else None
        models.append(calibrate(x[m], y[m], degree=deg, groups=groups, folds=folds).model)
    return DirectionAwareCalibration(models[0], models[1], lo, hi, sign, float(threshold))


@dataclass(frozen=True)
class CompensationResult:
    """Hysteresis error of the calibrated stress, plain calibration versus compensated, same data.

    Parameters
    ----------
    he_before_percent : float
        Eq. (13) on the stress estimated by the plain polynomial (one curve for both branches). [%]
    he_after_percent : float
        Eq. (13) on the stress estimated by the direction-aware calibration. [%]
    rmse_before_pa, rmse_after_pa : float
        RMSE of the two estimates against the reference. [Pa]
    plain : Calibration
        The plain calibration.
    compensated : DirectionAwareCalibration
        The compensation.
    """

    he_before_percent: float
    he_after_percent: float
    rmse_before_pa: float
    rmse_after_pa: float
    plain: object
    compensated: DirectionAwareCalibration

    @property
    def ratio(self) -> float:
        """HE before / HE after."""
        return self.he_before_percent / self.he_after_percent if self.he_after_percent > 0 else float("inf")


def compare_compensation(x, stress_pa, degree: int = 3, branch_degree: int | str = "auto", threshold: float = 0.05,
                         direction=None, cycle=None, plain=None) -> CompensationResult:
    """Fit plain and compensated calibrations on a run and compare the hysteresis of their estimates.

    Parameters
    ----------
    x : array_like
        Readout in time order.
    stress_pa : array_like
        Reference stress. [Pa]
    degree : int
        Degree of the plain polynomial (the paper's cubic: 3).
    branch_degree : int or "auto"
        Degree of each branch of the compensation (see :func:`fit_direction_aware`).
    threshold : float
        Reversal threshold. [1]
    direction, cycle : array_like, optional
        The run's columns, used only to split the reference into cycles for eq. (13).
    plain : Calibration, optional
        A plain calibration already fitted (default: degree ``degree`` on the same data).

    Returns
    -------
    CompensationResult
    """
    from fsrlab.metrics.cycles import run_hysteresis

    x = np.asarray(x, dtype=float)
    s = np.asarray(stress_pa, dtype=float)
    if plain is None:
        plain = calibrate(x, s, degree=degree)
    comp = fit_direction_aware(x, s, branch_degree, threshold)
    est_plain = plain(x)
    est_comp = comp(x)
    he0 = run_hysteresis(s, est_plain, direction, cycle, threshold).percent
    he1 = run_hysteresis(s, est_comp, direction, cycle, threshold).percent
    ok = np.isfinite(x) & np.isfinite(s)
    r0 = float(np.sqrt(np.mean((est_plain[ok] - s[ok]) ** 2)))
    r1 = float(np.sqrt(np.mean((est_comp[ok] - s[ok]) ** 2)))
    return CompensationResult(he0, he1, r0, r1, plain, comp)
