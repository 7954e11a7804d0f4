"""The uncertainty of a held-out calibration: by level and direction, from its held-out errors.

**Extension beyond the paper.** :class:`LevelUncertainty` turns the held-out errors of the
calibration :mod:`fsrlab.calibration.selection` chose into a standard uncertainty per estimate:
the :data:`COVERAGE` quantile of |error| in each level and direction cell, plus a relative term for
what changes from one recording to the next (:data:`REPEATABILITY`) and half of any extrapolation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.errors import FileFormatError

__all__ = ["COVERAGE", "REPEATABILITY", "RELATIVE_MAX", "LevelUncertainty"]

#: Quantile of the held-out |error| that ±2u covers in each level and direction cell. [1]
COVERAGE = 0.95
#: Relative standard uncertainty of an estimate from one recording to the next (the sensor re-seated, another
#: loading rate or creep state), added in quadrature; the larger of this and the held-out recordings' (or
#: blocks') gain spread is used, which a few recordings show poorly (docs/calibration.md). [1]
REPEATABILITY = 0.15
#: Largest relative term a calibration holds: an estimate uncertain by nine times itself is no longer a
#: measurement of the reference, only a sign that the calibration does not hold. [1]
RELATIVE_MAX = 9.0


@dataclass
class LevelUncertainty:
    """Standard uncertainty by level (quantile bins of the estimate) and direction, from held-out errors.

    ``2u`` is the :data:`COVERAGE` quantile of the held-out |error| in each cell (a cell with fewer
    than ``least`` errors takes its level's, else all of them), never below the quantile of all the
    held-out errors: the cells sharpen where errors are large, not where few were seen.

    Parameters
    ----------
    edges : ndarray
        Level bin edges (quantiles of the held-out estimates). [unit of the reference]
    table : ndarray, shape (bins, 3)
        u per level bin and direction (−1, 0, +1), without the relative term. [unit of the reference]
    pooled : float
        Half the quantile of all the held-out |errors|. [unit of the reference]
    relative : float
        Relative standard uncertainty between recordings, added in quadrature. [1]
    """

    edges: np.ndarray
    table: np.ndarray  # shape (bins, 3): direction −1, 0, +1
    pooled: float
    relative: float = REPEATABILITY

    @classmethod
    def fit(cls, err, estimate, direction, bins: int = 4, least: int = 20,
            relative: float = REPEATABILITY) -> LevelUncertainty:
        err, estimate, direction = (np.asarray(v) for v in (err, estimate, direction))
        q = COVERAGE
        pooled = float(np.quantile(np.abs(err), q)) / 2
        edges = np.unique(np.quantile(estimate, np.linspace(0, 1, bins + 1)[1:-1]))
        lvl = np.searchsorted(edges, estimate)
        table = np.full((edges.size + 1, 3), pooled)
        for b in range(edges.size + 1):
            mb = lvl == b
            for j, d in enumerate((-1, 0, 1)):
                m = mb & (direction == d)
                pick = m if m.sum() >= least else (mb if mb.sum() >= least else None)
                if pick is not None:
                    table[b, j] = max(pooled, float(np.quantile(np.abs(err[pick]), q)) / 2)
        return cls(edges, table, pooled, float(relative))

    def __call__(self, estimate, direction, extrapolated=None) -> np.ndarray:
        """u of each estimate; ``extrapolated``: how far an estimate went beyond the calibrated curve,
        added in quadrature as half of it (an extrapolation is uncertain by its own size)."""
        estimate = np.asarray(estimate, dtype=float)
        lvl = np.searchsorted(self.edges, np.where(np.isfinite(estimate), estimate, 0.0))
        u = self.table[lvl, np.asarray(direction, dtype=int) + 1]
        u = np.sqrt(u ** 2 + (self.relative * estimate) ** 2)
        if extrapolated is not None:
            u = np.sqrt(u ** 2 + (np.asarray(extrapolated) / 2) ** 2)
        return np.where(np.isfinite(estimate), u, np.nan)

    def to_dict(self) -> dict:
        return {"level_edges": self.edges.tolist(), "u_by_direction": self.table.tolist(), "pooled": self.pooled,
                "relative": self.relative, "coverage": COVERAGE}

    @classmethod
    def from_dict(cls, d: dict) -> LevelUncertainty:
        t = np.asarray(d["u_by_direction"], dtype=float)
        e = np.asarray(d["level_edges"], dtype=float)
        rel = float(d.get("relative", 0.0))
        if t.ndim != 2 or t.shape != (e.size + 1, 3) or np.any(t < 0) or not 0 <= rel <= RELATIVE_MAX:
            raise FileFormatError("uncertainty: one row of 3 non-negative values per level bin, relative in "
                                  f"[0, {RELATIVE_MAX:g}]")
        return cls(e, t, float(d["pooled"]), rel)
