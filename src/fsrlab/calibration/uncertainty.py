"""The uncertainty table of a calibration's estimate: by level and direction, plus quantization.

Uncertainty: out-of-fold residuals, grouped by level (quintiles of the estimate) and direction
(the movement of a 1 % play operator: loading, unloading, still), give a standard deviation per
cell; the readout's quantization adds ``(dŷ/dx·q)²/12``.

The table is fitted on the out-of-fold residuals of :func:`fsrlab.calibration.play.fit_memory` (or of the
plain model) by :func:`fsrlab.calibration.fit.calibrate_run`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Uncertainty", "fit_uncertainty"]


@dataclass(frozen=True)
class Uncertainty:
    """Standard uncertainty of an estimate by level and direction, plus quantization.

    Parameters
    ----------
    edges : ndarray
        Inner bin edges of the estimate's level (the quintiles). [unit of y]
    sigma : ndarray, shape (bins, 3)
        RMS out-of-fold residual per level bin and direction (columns: unloading, still,
        loading). [unit of y]
    step : float
        The readout's resolution q. [unit of x]
    """

    edges: np.ndarray
    sigma: np.ndarray
    step: float

    def __call__(self, y, direction, slope) -> np.ndarray:
        """Standard uncertainty [unit of y] for estimates ``y``, directions, and ``dŷ/dx`` [unit of y / unit of x]."""
        y = np.asarray(y, dtype=float)
        i = np.searchsorted(self.edges, np.where(np.isfinite(y), y, 0.0))
        j = np.asarray(direction, dtype=int) + 1
        sig = self.sigma[i, j]
        quant = np.asarray(slope, dtype=float) * self.step
        return np.where(np.isfinite(y), np.sqrt(sig * sig + quant * quant / 12.0), np.nan)

    def to_dict(self) -> dict:
        """JSON form."""
        return {"level_edges": self.edges.tolist(), "sigma": self.sigma.tolist(), "readout_step": self.step,
                "directions": ["unloading", "still", "loading"]}

    @classmethod
    def from_dict(cls, d: dict) -> "Uncertainty":
        """Inverse of :meth:`to_dict`."""
        edges = np.asarray(d["level_edges"], float)
        sigma = np.asarray(d["sigma"], float)
        step = float(d["readout_step"])
        if sigma.ndim != 2 or sigma.shape != (edges.size + 1, 3) or not np.all(np.isfinite(sigma)) \
                or not np.all(np.isfinite(edges)) or not step >= 0:
            raise ValueError("uncertainty: sigma must be (level bins) x 3 finite numbers and readout_step >= 0")
        return cls(edges, sigma, step)


def fit_uncertainty(estimate, reference, direction, step: float, bins: int = 5, least: int = 10) -> Uncertainty:
    """The uncertainty table from out-of-fold estimates.

    Parameters
    ----------
    estimate, reference : array_like
        Out-of-fold estimate and reference (NaN rows ignored). [unit of y]
    direction : array_like of int
        −1, 0, +1 per row.
    step : float
        Readout resolution. [unit of x]
    bins : int
        Level bins (quantiles of the estimate).
    least : int
        A cell with fewer residuals takes its level's RMS (and a level with fewer, the overall RMS).

    Returns
    -------
    Uncertainty
    """
    e = np.asarray(estimate, float)
    r = np.asarray(reference, float)
    d = np.asarray(direction, int)
    ok = np.isfinite(e) & np.isfinite(r)
    e, r, d = e[ok], r[ok], d[ok]
    res2 = (e - r) ** 2
    overall = float(np.sqrt(res2.mean()))
    edges = np.quantile(e, np.linspace(0, 1, bins + 1)[1:-1])
    lev = np.searchsorted(edges, e)
    sigma = np.full((bins, 3), overall)
    for i in range(bins):
        m = lev == i
        level = float(np.sqrt(res2[m].mean())) if m.sum() >= least else overall
        for j in range(3):
            c = m & (d == j - 1)
            sigma[i, j] = float(np.sqrt(res2[c].mean())) if c.sum() >= least else level
    return Uncertainty(edges=edges, sigma=sigma, step=float(step))
