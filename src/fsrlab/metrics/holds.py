"""Holds of a run: the stretches over which its reference (force or stress) stays steady.

A hold (:func:`find_holds`) is a stretch of at least ``min_hold_s`` over which the reference, after a
running median over 5 of its readings (spikes and HX711 noise), stays within a band of ±``band`` of
full scale (its peak-to-peak spread ≤ 2·band·FS, FS = the largest \\|reference\\| of the run); the
stretches are maximal and found left to right. Empty reference cells (a load cell sampled slower than
the readout) are left out of the test; the hold runs from the first to the last reference reading in
its band. The creep of the readout in each hold is :mod:`fsrlab.metrics.creep`.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_between, check_positive, paired_series

__all__ = ["Hold", "find_holds"]

_SMOOTH = 5  # readings in the running median of the reference


@dataclass(frozen=True)
class Hold:
    """One hold segment of the reference.

    Parameters
    ----------
    start_s, end_s : float
        Times of the first and last reference reading in the band. [s]
    level : float
        Median of the reference readings in the hold. [reference unit]
    first_row, last_row : int
        Their rows (0-based) in the arrays given to :func:`find_holds`.
    n_reference : int
        Reference readings in the hold.
    """

    start_s: float
    end_s: float
    level: float
    first_row: int
    last_row: int
    n_reference: int

    @property
    def duration_s(self) -> float:
        """``end_s − start_s``. [s]"""
        return self.end_s - self.start_s


def _running_median(y: np.ndarray, k: int) -> np.ndarray:
    """Centred running median over ``k`` (odd) readings; the ends use the readings there are."""
    if y.size < 3 or k < 3:
        return y.copy()
    h = k // 2
    padded = np.concatenate([np.full(h, np.nan), y, np.full(h, np.nan)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, k)
    return np.nanmedian(windows, axis=1)  # never an all-NaN window: its centre is a reading


def find_holds(time_s, reference, band: float = 0.02, min_hold_s: float = 5.0,
               full_scale: float | None = None) -> list[Hold]:
    """Hold segments: stretches where the reference stays within ±band of full scale for at least min_hold_s.

    Parameters
    ----------
    time_s : array_like
        Time of each row, non-decreasing. [s]
    reference : array_like
        Reference force or stress per row; NaN where it has no reading (a slower load cell).
        [reference unit]
    band : float
        Half-width of the band, a fraction of full scale in (0, 0.5). [1]
    min_hold_s : float
        Shortest hold reported, > 0. [s]
    full_scale : float, optional
        Full scale [reference unit]; default the largest \\|reference\\|.

    Returns
    -------
    list of Hold
        In time order, not overlapping.

    Raises
    ------
    fsrlab.errors.ParameterError
        A parameter out of range, arrays of different shapes, a reference without any reading or
        that is zero throughout (naming the parameter).
    TypeError
        An argument that is not numbers.

    Notes
    -----
    The reference readings (NaN left out) go through a running median over 5 readings; a stretch
    is a hold when that spans no more than 2·band·full_scale (every reading within ±band·FS of the
    stretch's mid-range) and lasts at least ``min_hold_s``. Stretches are grown left to right, each
    as long as it can be, so a hold is never split while its reference stays in one band.
    """
    t, ref = paired_series("time_s", time_s, "reference", reference)
    check_between("band", band, 0.0, 0.5, "of full scale", lower_open=True, upper_open=True, scalar=True)
    check_positive("min_hold_s", min_hold_s, "s", scalar=True)
    rows = np.flatnonzero(np.isfinite(ref) & np.isfinite(t))
    if rows.size == 0:
        raise ParameterError("no readings (every cell is empty)", parameter="reference")
    if full_scale is None:
        full_scale = float(np.max(np.abs(ref[rows])))
        if full_scale == 0:
            raise ParameterError("zero throughout: a reference that is zero holds no load", parameter="reference")
    check_positive("full_scale", full_scale, scalar=True)
    width = 2 * band * full_scale
    smooth = _running_median(ref[rows], _SMOOTH).tolist()
    times = t[rows].tolist()
    found = _grow(times, smooth, width, min_hold_s)
    holds = []
    for a, b in found:
        r = rows[a:b + 1]
        holds.append(Hold(start_s=times[a], end_s=times[b], level=float(np.median(ref[r])),
                          first_row=int(r[0]), last_row=int(r[-1]), n_reference=int(r.size)))
    return holds


def _grow(times: list, values: list, width: float, min_hold_s: float) -> list[tuple[int, int]]:
    """Maximal stretches [a, b] (inclusive) with max − min ≤ width and times[b] − times[a] ≥ min_hold_s.

    Two pointers with monotonic deques of the window's maximum and minimum: O(n).
    """
    n = len(values)
    out: list[tuple[int, int]] = []
    hi: deque = deque()
    lo: deque = deque()
    i = j = 0  # the window is [i, j)
    while i < n:
        while j < n:
            v = values[j]
            top = max(values[hi[0]], v) if hi else v
            bottom = min(values[lo[0]], v) if lo else v
            if top - bottom > width:
                break
            while hi and values[hi[-1]] <= v:
                hi.pop()
            hi.append(j)
            while lo and values[lo[-1]] >= v:
                lo.pop()
            lo.append(j)
            j += 1
        if times[j - 1] - times[i] >= min_hold_s:
            out.append((i, j - 1))
            i = j
            hi.clear()
            lo.clear()
        else:
            if hi and hi[0] == i:
                hi.popleft()
            if lo and lo[0] == i:
                lo.popleft()
            i += 1
            if j < i:
                j = i
    return out
