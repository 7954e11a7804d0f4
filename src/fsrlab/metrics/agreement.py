"""How a calibrated run's estimate agrees with the reference recorded in the same run.

**Extension beyond the paper.** A calibration's own held-out error says how it did on the data it
was chosen on; a run recorded later with its reference (a validation run) says how it holds where
it is used. :func:`agreement` compares the estimate that :func:`fsrlab.calibration.apply.apply_calibration`
wrote with that reference, over the loaded rows, as ``benchmarks/bench_realdata.py`` scores real
recordings: the RMSE (also in % of the run's reference span), the mean error, the straight line
that takes the estimate to the reference (a gain that moved between recordings shows as a slope away
from 1), and the share of errors within ±2u. On third parties' recordings (docs/calibration.md) ±2u
covered fewer than 90 % of the errors exactly where the sensor read differently from the
calibration's runs, so :meth:`Agreement.warning` says so below :data:`COVERAGE_AIM`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.errors import ParameterError

__all__ = ["LOADED", "COVERAGE_AIM", "MIN_ROWS", "Agreement", "agreement"]

#: Rows whose reference is above this share of the run's largest count as loaded. [1]
LOADED = 0.05
#: Below this share of loaded errors within ±2u, :meth:`Agreement.warning` speaks. [1]
COVERAGE_AIM = 0.90
#: Fewest loaded rows with an estimate for an agreement to be stated. [1]
MIN_ROWS = 10


@dataclass(frozen=True)
class Agreement:
    """The estimate against the run's reference over its loaded rows.

    Parameters
    ----------
    loaded : int
        Rows whose reference is above :data:`LOADED` of its largest. [1]
    estimated : int
        Of those, the rows with an estimate (the statistics are over these). [1]
    rmse : float
        Root mean square of estimate − reference. [unit of the reference]
    span : float
        The run's reference span (largest − smallest). [unit of the reference]
    bias : float
        Mean of estimate − reference. [unit of the reference]
    slope, intercept : float
        Least-squares line reference ≈ slope · estimate + intercept. [1], [unit of the reference]
    coverage : float or None
        Share of the errors within ±2u (None when the run has no uncertainty). [1]
    """

    loaded: int
    estimated: int
    rmse: float
    span: float
    bias: float
    slope: float
    intercept: float
    coverage: float | None

    @property
    def rmse_percent_span(self) -> float:
        """The RMSE in % of the run's reference span. [%]"""
        return 100.0 * self.rmse / self.span if self.span > 0 else float("nan")

    def to_dict(self) -> dict:
        return {"loaded_rows": self.loaded, "estimated_rows": self.estimated, "rmse": self.rmse,
                "rmse_percent_span": self.rmse_percent_span, "span": self.span, "bias": self.bias,
                "slope": self.slope, "intercept": self.intercept,
                "coverage_percent": None if self.coverage is None else 100.0 * self.coverage}

    def rows(self) -> str:
        """``N loaded rows``, or ``the N estimated of its M loaded rows`` when some have no estimate."""
        return (f"{self.estimated} loaded rows" if self.estimated == self.loaded
                else f"the {self.estimated} estimated of its {self.loaded} loaded rows")

    def line(self, unit: str = "") -> str:
        """``reference ≈ slope × estimate ± intercept [unit]``, or a note when the estimate did not vary."""
        if not np.isfinite(self.slope):
            return "the estimate did not vary"
        return (f"reference ≈ {self.slope:.3g} × estimate {'+' if self.intercept >= 0 else '−'} "
                f"{abs(self.intercept):.3g}" + (f" {unit}" if unit else ""))

    def warning(self, unit: str = "") -> str | None:
        """One line when ±2u covers fewer than :data:`COVERAGE_AIM` of the errors, else None."""
        if self.coverage is None or self.coverage >= COVERAGE_AIM:
            return None
        return (f"±2u covers only {100 * self.coverage:.0f} % of this run's errors (the calibration aims at 95 %): "
                f"the sensor reads differently here than in the calibration's runs ({self.line(unit)}); "
                "calibrate from this run too, or from several runs so that their spread is measured")


def agreement(reference, estimate, uncertainty=None) -> Agreement | None:
    """The estimate against the reference of the same run, over its loaded rows.

    Parameters
    ----------
    reference : array_like
        The reference recorded in the run (NaN where missing). [N or Pa]
    estimate : array_like
        The calibrated estimate of each row (NaN where none). [unit of the reference]
    uncertainty : array_like, optional
        The standard uncertainty of each estimate (NaN where none). [unit of the reference]

    Returns
    -------
    Agreement or None
        None when the reference does not rise above zero or fewer than :data:`MIN_ROWS` loaded rows
        have an estimate.

    Raises
    ------
    ParameterError
        An argument that is not numbers; ``estimate`` or ``uncertainty`` not one value per reference row;
        an uncertainty below zero or infinite (NaN: no uncertainty for that row).
    """
    y = _values(reference, "reference")
    est = _values(estimate, "estimate")
    if y.shape != est.shape:
        raise ParameterError(f"one value per reference row, got {est.shape} for {y.shape}", parameter="estimate")
    u = None if uncertainty is None else _values(uncertainty, "uncertainty")
    if u is not None:
        if u.shape != y.shape:
            raise ParameterError(f"one value per reference row, got {u.shape} for {y.shape}", parameter="uncertainty")
        bad = np.isinf(u) | (u < 0)  # NaN compares False: a row without an uncertainty
        if bad.any():
            raise ParameterError(f"a standard uncertainty is >= 0 and finite (NaN where none), got "
                                 f"{u[bad][0]!r} at row {int(np.flatnonzero(bad)[0])}", parameter="uncertainty")
    finite = np.isfinite(y)
    if not finite.any() or not np.nanmax(y) > 0:
        return None
    loaded = finite & (y > LOADED * np.nanmax(y))
    got = loaded & np.isfinite(est)
    if int(got.sum()) < MIN_ROWS:
        return None
    e = est[got] - y[got]
    if np.ptp(est[got]) > 0:
        slope, intercept = np.polyfit(est[got], y[got], 1)
    else:
        slope, intercept = float("nan"), float("nan")
    coverage = None
    if u is not None:
        has_u = np.isfinite(u[got])
        if has_u.any():
            coverage = float(np.mean(np.abs(e[has_u]) <= 2.0 * u[got][has_u]))
    return Agreement(loaded=int(loaded.sum()), estimated=int(got.sum()), rmse=float(np.sqrt(np.mean(e ** 2))),
                     span=float(np.nanmax(y) - np.nanmin(y)), bias=float(np.mean(e)), slope=float(slope),
                     intercept=float(intercept), coverage=coverage)


def _values(values, parameter: str) -> np.ndarray:
    """``values`` as a float array, or a :class:`ParameterError` naming ``parameter`` (not numbers)."""
    if isinstance(values, (str, bytes, dict)):
        raise ParameterError(f"must be an array of numbers, got {type(values).__name__}", parameter=parameter)
    try:
        with np.errstate(all="ignore"):
            return np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"must be an array of numbers ({exc})", parameter=parameter) from None
