"""The estimator that turns readings into estimates one at a time, with memory (what ``fsrlab measure`` and
``fsrlab live`` step, and what :func:`fsrlab.calibration.apply.apply_calibration` runs over a whole run).

:class:`CausalEstimator` evaluates the plain calibration, the floor, the play-operator compensation
(:mod:`fsrlab.calibration.play`) or the causal branch polynomials (:mod:`fsrlab.calibration.compensation`)
and the uncertainty table (:mod:`fsrlab.calibration.uncertainty`) in row order.
"""

from __future__ import annotations

import bisect
import math

from typing import TYPE_CHECKING

import numpy as np

from fsrlab.calibration.compensation import BranchState
from fsrlab.calibration.heldout_runs import MARGIN as cal_margin
from fsrlab.calibration.heldout_runs import RunCalibration
from fsrlab.calibration.play import CausalState, causal_features

if TYPE_CHECKING:
    from fsrlab.calibration.result import Calibration

__all__ = ["MARGIN", "CausalEstimator", "LiveEstimator", "live_estimator"]

#: Default margin beyond the calibrated readout range, as a fraction of its span, within which an
#: estimate is still written (extrapolated, flagged); beyond it the estimate is left empty. [1]
MARGIN = 0.10


class CausalEstimator:
    """Estimates from readings one at a time, with memory (what ``fsrlab measure`` steps).

    Parameters
    ----------
    base : callable
        The plain calibration ŷ₀(x). [unit of y]
    x_range : (float, float)
        Calibrated readout range. [unit of x]
    margin : float
        Fraction of the range's span beyond which a reading is left without an estimate. [1]
    floor : Floor, optional
        Readings at the floor: "below activation" (no estimate).
    memory : MemoryModel, optional
        The compensation (without it: the plain estimate).
    uncertainty : Uncertainty, optional
        The uncertainty table (without it: no uncertainty).
    full_scale : float
        FS of w = ŷ₀/FS. [unit of y]
    reference, x : str
        The reference column (``force_n`` or ``stress_pa``) and the readout column.
    branches : DirectionAwareCalibration, optional
        A causal branch compensation (:mod:`fsrlab.calibration.compensation`, ``causal=True``) to use
        instead of ``memory``: the estimate is its branch polynomial with turning-point memory,
        stepped by :class:`fsrlab.calibration.compensation.BranchState`.

    Notes
    -----
    ``step(readout)`` returns ``(estimate, uncertainty, in_range)``: estimate and uncertainty in
    the reference's unit (None without an estimate: no reading, a reading at the floor, or beyond
    the margin), ``in_range`` True when the reading lies in the calibrated range. A missing reading
    leaves the memory as it is; a reading at the floor moves it to zero load.
    """

    def __init__(self, base, x_range, margin, floor, memory, uncertainty, full_scale, reference, x, branches=None):
        self.base = base
        self.lo, self.hi = (float(v) for v in x_range)
        self.margin = float(margin)
        self.floor = floor
        self.memory = memory
        self.uncertainty = uncertainty
        self.full_scale = float(full_scale)
        self.reference = reference
        self.x = x
        span = self.hi - self.lo
        self.kept = (self.lo - self.margin * span, self.hi + self.margin * span) if np.isfinite(self.margin) \
            else (-np.inf, np.inf)
        if branches is not None and memory is not None:
            raise ValueError("memory, branches: one compensation at a time")
        self.branches = branches
        self.branch_state = None
        if branches is not None:
            self.branch_state = BranchState(branches)
        self.state = CausalState(memory.thresholds if memory else (), memory.alphas if memory else ())
        self._h = max(1e-9 * max(abs(self.lo), abs(self.hi)), 1e-6 * span)

    def slope(self, x):
        """dŷ₀/dx by a central difference. [unit of y / unit of x]"""
        x = np.asarray(x, dtype=float)
        return np.abs(self.base(x + self._h) - self.base(x - self._h)) / (2 * self._h)

    def step(self, readout: float | None, t: float | None = None) -> tuple[float | None, float | None, bool]:
        """Take one reading; return (estimate or None, standard uncertainty or None, in_range). ``t`` [s] is
        accepted like :class:`fsrlab.calibration.heldout_runs.RunEstimator`'s and not used: this
        calibration's memory counts readings."""
        if readout is None:
            return None, None, False
        x = float(readout)
        if not math.isfinite(x):
            return None, None, False
        if self.floor is not None and self.floor.sign * (x - self.floor.threshold) <= 0:
            self.state.advance(0.0)
            if self.branch_state is not None:
                self.branch_state.step(None)  # a gap for the branch labels
            return None, None, False
        if not self.kept[0] <= x <= self.kept[1]:
            if self.branch_state is not None:
                self.branch_state.step(None)
            return None, None, False
        # One call for the estimate and the slope (elementwise: the same numbers as the offline path).
        y0, up, down = self.base(np.array([x, x + self._h, x - self._h])).tolist()
        if not math.isfinite(y0):
            if self.branch_state is not None:
                self.branch_state.step(None)
            return None, None, False
        w = y0 / self.full_scale
        self.state.advance(w)
        if self.branch_state is not None:
            y = self.branch_state.step(x)
            if y is None:  # no finite branch estimate at this reading
                return None, None, bool(self.lo <= x <= self.hi)
        else:
            y = self.memory.step_estimate(w, self.state) if self.memory is not None else y0
        u = None
        if self.uncertainty is not None:
            tab = self.uncertainty
            sig = float(tab.sigma[bisect.bisect_left(tab.edges.tolist(), y if math.isfinite(y) else 0.0),
                                  self.state.direction + 1])
            quant = abs(up - down) / (2 * self._h) * tab.step
            u = math.sqrt(sig * sig + quant * quant / 12.0) if math.isfinite(y) else None
        return y, u, bool(self.lo <= x <= self.hi)

    def run(self, x) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The same as stepping every reading in order, vectorised where the memory allows.

        Parameters
        ----------
        x : array_like
            Readings in row order (NaN: missing).

        Returns
        -------
        estimate, uncertainty : ndarray
            NaN where :meth:`step` gives None. [unit of y]
        in_range : ndarray of bool
        reason : ndarray of int
            0 estimated, 1 no reading, 2 at the floor, 3 beyond the margin or no finite estimate.
        """
        x = np.asarray(x, dtype=float)
        reason = np.where(np.isfinite(x), 0, 1)
        at_floor = np.zeros(x.size, bool)
        if self.floor is not None:
            with np.errstate(invalid="ignore"):
                at_floor = np.isfinite(x) & (self.floor.sign * (x - self.floor.threshold) <= 0)
        reason[at_floor] = 2
        with np.errstate(invalid="ignore", over="ignore"):
            kept = (reason == 0) & (x >= self.kept[0]) & (x <= self.kept[1])
            y0 = np.where(kept, self.base(np.where(kept, x, self.lo)), np.nan)
        kept &= np.isfinite(y0)
        reason[(reason == 0) & ~kept] = 3
        w = np.where(kept, y0 / self.full_scale, np.where(at_floor, 0.0, np.nan))
        p, s, d = causal_features(w, self.state.r, self.state.alphas)
        if self.branches is not None:
            y = np.where(kept, self.branches.predict(np.where(kept, x, np.nan))[0], np.nan)
        elif self.memory is not None:
            y = np.where(kept, self.memory.estimate(np.where(kept, w, 0.0), np.nan_to_num(p), np.nan_to_num(s)), np.nan)
        else:
            y = y0
        u = np.full(x.size, np.nan)
        if self.uncertainty is not None:
            u = np.where(kept, self.uncertainty(y, d, self.slope(np.where(kept, x, self.lo))), np.nan)
        with np.errstate(invalid="ignore"):
            in_range = kept & (x >= self.lo) & (x <= self.hi)
        return y, u, in_range, reason


def live_estimator(cal: Calibration, margin: float | None = None, compensation: bool = True):
    """A causal estimator of a calibration: readings in, estimates out, one at a time.

    Parameters
    ----------
    cal : Calibration or RunCalibration
        From :func:`calibrate_run`, :func:`fsrlab.calibration.heldout_runs.calibrate_runs` or
        :func:`fsrlab.calibration.document.load_calibration`.
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
    if isinstance(cal, RunCalibration):
        return cal.estimator(cal_margin if margin is None else margin, compensation)
    margin = MARGIN if margin is None else margin
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
LiveEstimator = CausalEstimator
