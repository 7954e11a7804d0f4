"""The reference's delay: the readout as it was a fraction of a reading earlier.

**Extension beyond the paper.** A load-cell amplifier does not report the force of the instant it is
read: an HX711 at 10 samples/s integrates over its whole conversion (100 ms) and hands over the
previous conversion, so the reference it logs beside an ``analogRead`` of an FSR describes, on
average, an instant half a reading or more before the row it sits in. A calibration that estimates
the reference *as recorded* (fsrlab's default) then estimates best from the readout as it was that
much earlier. The delay is causal (only past readings are used), so :class:`DelayLine` gives the
same estimates one reading at a time, and ``0`` is the default hypothesis
(:mod:`fsrlab.calibration.heldout_model` keeps a delay only where it wins on held-out data).
"""

from __future__ import annotations

from collections import deque

import numpy as np

__all__ = ["delayed", "DelayLine"]


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
    x = np.asarray(x, dtype=float)
    if not delay_s > 0 or x.size == 0:
        return x
    t = np.asarray(t, dtype=float)
    back = np.flatnonzero(np.diff(t) < 0) + 1  # where the time goes back: each stretch on its own
    if back.size:
        return np.concatenate([delayed(tt, xx, delay_s) for tt, xx in zip(np.split(t, back), np.split(x, back))])
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
