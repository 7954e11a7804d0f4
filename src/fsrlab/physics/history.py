"""Turning points, loading/unloading directions and cycle numbers of a stress (or readout) history.

A turning point is confirmed once the history has moved back from its running extremum by more than a
threshold (a fraction of its span), which ignores noise smaller than the threshold. These pure array
functions label a history; the virtual bench's generators label the runs they make with them, and the
metrics (:mod:`fsrlab.metrics.cycles`) and the calibration split real runs with them.
"""

from __future__ import annotations

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_finite, float_array

__all__ = ["turning_points", "branch_directions", "cycle_numbers"]


def _check_threshold(threshold: float) -> float:
    check_finite("threshold", threshold)
    if np.ndim(threshold) or not (0 < threshold < 1):
        raise ParameterError(f"must be a fraction of the stress span in (0, 1), got {threshold!r}",
                             parameter="threshold")
    return float(threshold)


def _history(stress_pa) -> np.ndarray:
    x = float_array("stress_pa", stress_pa)
    if x.ndim > 1:
        raise ParameterError(f"must be one-dimensional (a history in time order), got shape {x.shape}",
                             parameter="stress_pa")
    return x.ravel()


def _confirmed(x: np.ndarray, cand: list[int], thr: float) -> list[int]:
    """0, the candidates (local extrema) confirmed as turning points by a move back of more than ``thr``,
    and the last index."""
    n = x.size
    pivots = [0]
    trend = 0  # 0: not yet moved beyond the threshold; +1 rising; -1 falling
    hi_i = lo_i = ext_i = 0
    for i in cand[1:]:
        xi = x[i]
        if trend == 0:
            if xi > x[hi_i]:
                hi_i = i
            if xi < x[lo_i]:
                lo_i = i
            if x[hi_i] - x[lo_i] > thr:
                # The first excursion beyond the threshold sets the direction (from index 0).
                trend = 1 if hi_i > lo_i else -1
                ext_i = hi_i if trend == 1 else lo_i
        elif trend == 1:
            if xi > x[ext_i]:
                ext_i = i
            elif x[ext_i] - xi > thr:
                pivots.append(ext_i)
                trend, ext_i = -1, i
        else:
            if xi < x[ext_i]:
                ext_i = i
            elif xi - x[ext_i] > thr:
                pivots.append(ext_i)
                trend, ext_i = 1, i
    if pivots[-1] != n - 1:
        pivots.append(n - 1)
    return pivots


def turning_points(stress_pa, threshold: float = 0.05) -> np.ndarray:
    """Indices of the confirmed turning points of a stress sequence, with its first and last index.

    Parameters
    ----------
    stress_pa : array_like, shape (n,)
        Reference stress in time order. [Pa]
    threshold : float
        A reversal counts once the stress has come back from its running extremum by more than
        ``threshold`` times the span ``max - min`` (noise below that is ignored). [1]

    Returns
    -------
    ndarray of int
        Increasing indices: 0, the turning points (first reading at each extremum), n - 1.
    """
    x = _history(stress_pa)
    threshold = _check_threshold(threshold)
    n = x.size
    if n < 2:
        return np.arange(n)
    if not np.all(np.isfinite(x)):
        raise ParameterError("must be finite (drop rows without a reference stress first)", parameter="stress_pa")
    span = float(x.max() - x.min())
    if span == 0:
        return np.array([0, n - 1])
    thr = threshold * span
    # Only local extrema can be turning points: reduce to them first (vectorised), then scan.
    d = np.sign(np.diff(x))
    nz = np.flatnonzero(d)
    if nz.size == 0:
        return np.array([0, n - 1])
    cand = [0]
    ds = d[nz]
    change = np.flatnonzero(ds[1:] != ds[:-1])
    # the extremum is the first reading after the last move in the old direction
    cand.extend((nz[change] + 1).tolist())
    cand.append(n - 1)
    return np.array(sorted(set(_confirmed(x, cand, thr))))


def branch_directions(stress_pa, threshold: float = 0.05) -> np.ndarray:
    """Label each reading +1 (loading) or -1 (unloading) from the stress sequence.

    Parameters
    ----------
    stress_pa : array_like, shape (n,)
        Reference stress in time order. [Pa]
    threshold : float
        See :func:`turning_points`. [1]

    Returns
    -------
    ndarray of int, shape (n,)
        +1 on rising segments, -1 on falling ones, 0 where the stress never moves beyond the
        threshold. A turning-point reading carries the label of the segment it ends.
    """
    x = _history(stress_pa)
    piv = turning_points(x, threshold)
    out = np.zeros(x.size, dtype=int)
    for a, b in zip(piv[:-1], piv[1:], strict=True):
        out[a + 1:b + 1] = int(np.sign(x[b] - x[a]))
    if x.size > 1:
        out[0] = out[1]
    return out


def cycle_numbers(direction) -> np.ndarray:
    """Number the cycles of a labelled run: a new cycle starts where loading follows unloading.

    Parameters
    ----------
    direction : array_like, shape (n,)
        +1 loading, -1 unloading, 0 hold (NaN is taken as 0); holds between branches are skipped.

    Returns
    -------
    ndarray of int, shape (n,)
        0 for the first cycle, then 1, 2, ... from each reading that starts a loading branch after
        an unloading one.
    """
    lab = np.nan_to_num(float_array("direction", direction).ravel()).astype(int)
    nz = np.flatnonzero(lab != 0)
    starts = np.zeros(lab.size, dtype=int)
    if nz.size > 1:
        starts[nz[1:][(lab[nz[1:]] == 1) & (lab[nz[:-1]] == -1)]] = 1
    return np.cumsum(starts)
