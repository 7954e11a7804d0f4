"""The reference's delay: the readout as it was a fraction of a reading, or many readings, earlier.

**Extension beyond the paper.** A load-cell amplifier does not report the force of the instant it is
read: an HX711 at 10 samples/s integrates over its whole conversion (100 ms) and hands over the
previous conversion, so the reference it logs beside an ``analogRead`` of an FSR describes, on
average, an instant half a reading or more before the row it sits in. A calibration that estimates
the reference *as recorded* (fsrlab's default) then estimates best from the readout as it was that
much earlier. The delay is causal (only past readings are used), so :class:`DelayLine` gives the
same estimates one reading at a time, and ``0`` is the default hypothesis
(:mod:`fsrlab.calibration.selection` keeps a delay only where it wins on held-out data). A
reference logged by another device and joined by its time stamps, or filtered, can be many readings
late: :func:`delay_trials` lists the delays the calibration tries.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_at_least, check_positive, float_array

__all__ = ["DELAY_ROWS", "DELAY_MAX_S", "delay_trials", "delayed", "DelayLine"]

#: Delays of the reference tried first, in readings: fractions of one (a load-cell amplifier's conversion
#: window), then longer (a reference logged by another device, or filtered); then doubling up to
#: :data:`DELAY_MAX_S`, with finer steps around the best (:func:`delay_trials`). [1]
DELAY_ROWS = (0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)
#: The delays tried go on doubling beyond :data:`DELAY_ROWS` until they reach this much time. [s]
DELAY_MAX_S = 0.5


def delay_trials(row_s: float, best: float | None = None) -> list[float]:
    """The delays tried, in readings: :data:`DELAY_ROWS` and their doublings up to :data:`DELAY_MAX_S`;
    with ``best``, the quarter, half and three-quarter points between it and each neighbour, in quarter
    readings, not already among them.

    Parameters
    ----------
    row_s : float
        The time of one reading. [s]
    best : float, optional
        One of the delays tried first, the one to refine around. [1]
    """
    check_positive("row_s", row_s, "s", scalar=True)  # finite too
    grid = list(DELAY_ROWS)
    while grid and grid[-1] * row_s < DELAY_MAX_S:
        grid.append(2.0 * grid[-1])
    if best is None:
        return grid
    if isinstance(best, bool) or not isinstance(best, (int, float, np.number)) or best not in grid:
        raise ParameterError(f"must be one of the delays tried first, {grid}, got {best!r}", parameter="best")
    i = grid.index(best)
    finer = {round(4.0 * (best + (n - best) * f)) / 4.0 for n in grid[max(i - 1, 0):i + 2] if n != best
             for f in (0.25, 0.5, 0.75)}
    return sorted(d for d in finer if d > 0 and d not in grid)


def delayed(t, x, delay_s: float) -> np.ndarray:
    """The readings ``x`` as they were ``delay_s`` earlier, linear between readings.

    Before the first reading, the first reading; a missing reading (NaN) stays missing, and its
    neighbours interpolate across it. Where the time goes back (two logs one after the other), the
    delay starts again as at the first reading.

    Parameters
    ----------
    t : array_like
        Time of each reading, in order. [s]
    x : array_like
        Readings (NaN where missing). [unit of the readout]
    delay_s : float
        The delay (>= 0). [s]
    """
    x = float_array("x", x)
    if x.ndim != 1:
        raise ParameterError(f"must be a sequence of readings, got shape {x.shape}", parameter="x")
    check_at_least("delay_s", delay_s, 0.0, "s", scalar=True)  # finite too
    if not delay_s > 0 or x.size == 0:
        return x
    t = float_array("t", t)
    if t.shape != x.shape:
        raise ParameterError(f"must have one time per reading ({x.shape}), got shape {t.shape}", parameter="t")
    back = np.flatnonzero(np.diff(t) < 0) + 1  # where the time goes back: each stretch on its own
    if back.size:
        return np.concatenate([delayed(tt, xx, delay_s) for tt, xx in zip(np.split(t, back), np.split(x, back),
                                                                          strict=True)])
    ok = np.isfinite(x) & np.isfinite(t)
    if not ok.any():
        return x
    out = np.interp(t - delay_s, t[ok], x[ok])
    out[~np.isfinite(x)] = np.nan
    return out


class DelayLine:
    """:func:`delayed` one reading at a time: ``push(t, x)`` returns the reading ``delay_s`` before ``t``.

    Parameters
    ----------
    delay_s : float
        The delay (>= 0). [s]
    """

    def __init__(self, delay_s: float):
        self.delay_s = float(delay_s)
        self._past: deque = deque()  # (t, x) of finite readings, oldest first

    def push(self, t: float, x: float) -> float:
        if not self.delay_s > 0:
            return x
        past = self._past
        if past and t < past[-1][0]:  # the time went back: start again, as at the first reading
            past.clear()
        past.append((t, x))
        when = t - self.delay_s
        while len(past) > 2 and past[1][0] <= when:  # keep one reading at or before the instant asked for
            past.popleft()
        t0, x0 = past[0]
        if when <= t0:
            return x0
        for t1, x1 in list(past)[1:]:
            if t1 >= when:
                return x0 + (x1 - x0) * (when - t0) / (t1 - t0) if t1 > t0 else x1
            t0, x0 = t1, x1
        return x0
