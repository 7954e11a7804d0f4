"""Hysteresis compensation by a direction-aware calibration with turning-point memory.

**Extension beyond the paper.** The paper calibrates frequency to stress with one cubic
(Figure 17); a single-valued curve cannot follow a hysteretic sensor, so the calibrated force keeps
the sensor's hysteresis error. Here the loading and the unloading branches get their own
polynomial, and the branch in use is found from the readout sequence itself (its reversals beyond
a threshold, :func:`fsrlab.analysis.cycles.readout_directions`), so no reference is needed when the
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
for the major loop and approximate for minor loops. Branch labels use the whole run (the reversal
is confirmed after the readout has moved back by the threshold, then dated to the extremum), so
this is an offline correction of recorded runs.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eq. (13), Figure 17.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.analysis.calibration import PolynomialModel, calibrate
from fsrlab.analysis.cycles import readout_directions

__all__ = ["DirectionAwareCalibration", "fit_direction_aware", "CompensationResult", "compare_compensation"]


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
    """

    load_model: PolynomialModel
    unload_model: PolynomialModel
    x_low: float
    x_high: float
    sign: float
    threshold: float

    def __call__(self, x) -> np.ndarray:
        """Estimate y along a readout sequence in time order (NaN readings give NaN)."""
        return self.predict(x)[0]

    def predict(self, x) -> tuple[np.ndarray, np.ndarray]:
        """Estimate y and the branch of each reading.

        Parameters
        ----------
        x : array_like
            Readout in time order; NaN where a reading is missing.

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
        gap within a branch keeps the memory.
        """
        x = np.asarray(x, dtype=float)
        with np.errstate(over="ignore", invalid="ignore"):
            ok = np.isfinite(x) & np.isfinite(self.load_model(x)) & np.isfinite(self.unload_model(x))
        x = np.where(ok, x, np.nan)
        lab = readout_directions(x, self.sign, self.threshold)
        y = np.full(x.size, np.nan)
        # "up" = towards larger stress; the memory weights use the readout in stress order.
        u = self.sign * x
        u_lo, u_hi = sorted((self.sign * self.x_low, self.sign * self.x_high))
        starts = np.flatnonzero(np.diff(lab) != 0) + 1
        bounds = np.concatenate([[0], starts, [x.size]])
        prev_y, prev_u = None, None
        for a, b in zip(bounds[:-1], bounds[1:]):
            seg = np.arange(a, b)
            seg = seg[ok[seg]]
            if seg.size == 0:
                continue
            if a > 0 and not ok[a - 1]:
                prev_y = None  # the reversal fell in a gap: its turning point was not observed
            loading = lab[a] > 0
            model = self.load_model if loading else self.unload_model
            base = model(x[seg])
            if prev_y is not None:
                offset = prev_y - float(model(self.sign * prev_u))
                if loading:
                    w = (u_hi - u[seg]) / max(u_hi - prev_u, 1e-300)
                else:
                    w = (u[seg] - u_lo) / max(prev_u - u_lo, 1e-300)
                base = base + offset * np.clip(w, 0.0, 1.0)
            y[seg] = base
            # The reversal ending this segment: its extremum reading (turning points are extrema).
            k = seg[np.argmax(u[seg])] if loading else seg[np.argmin(u[seg])]
            prev_y, prev_u = (float(y[k]), float(u[k])) if np.isfinite(y[k]) else (None, None)
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
        }

    @classmethod
    def from_dict(cls, d: dict) -> "DirectionAwareCalibration":
        """Inverse of :meth:`to_dict`."""
        def model(m):
            return PolynomialModel(np.asarray(m["chebyshev_coefficients"], float), float(m["x_center"]),
                                   float(m["x_half_width"]))

        return cls(model(d["load"]), model(d["unload"]),
                   float(d["x_low"]), float(d["x_high"]), float(d["sign"]), float(d["threshold"]))


def fit_direction_aware(x, y, degree: int | str = "auto", threshold: float = 0.05, folds: int = 5) -> DirectionAwareCalibration:
    """Fit the loading and unloading curves of a run with loading-unloading cycles.

    Parameters
    ----------
    x : array_like
        Readout in time order (frequency [Hz], ...).
    y : array_like
        Reference stress [Pa].
    degree : int or "auto"
        Degree of each branch polynomial (1..5), or ``"auto"``: chosen per branch by
        cross-validation over contiguous blocks of that branch's readings (whole branches of a
        cycle stay together when there are enough cycles).
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
    for d in (1, -1):
        m = ok & (lab == d)
        if m.sum() <= 7:
            raise ValueError(f"the run has too few {'loading' if d > 0 else 'unloading'} readings "
                             "(needs loading-unloading cycles)")
        # Groups: one per branch run (a cycle's branch), or contiguous blocks if there are few.
        runs = np.cumsum(np.diff(lab, prepend=lab[0]) != 0)[m]
        groups = runs if np.unique(runs).size >= 2 else None
        models.append(calibrate(x[m], y[m], degree=degree, groups=groups, folds=folds).model)
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
    from fsrlab.analysis.cycles import run_hysteresis

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
