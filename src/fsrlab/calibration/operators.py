"""Memory of a readout: play operators (rate-independent hysteresis) and exponential averages (creep).

**Extension beyond the paper.** Both run forward in time on a normalised level ``u`` (the static
estimate as a fraction of full scale), one reading at a time, so the same numbers come out of a whole
recording (:func:`memory_features`) and of a live stream (:class:`MemoryState`).

A play (backlash) operator of threshold r holds a state p that follows u only when u leaves the band
``[p − r, p + r]``::

    p_t = max(u_t − r, min(u_t + r, p_{t−1}))

so ``p − u`` lies in ``[−r, r]``: −r while loading, +r after an unloading of more than 2r, and it
remembers every reversal larger than 2r (Prandtl–Ishlinskii; the wiping-out property of Preisach
models). An exponential average of time constant τ gives the creep feature ``u − ū_τ``: the whole
step right after a change of load, decaying as the load is held; a set of time constants spread over
decades approximates the logarithmic creep of FSRs with a time scale the fit chooses.

References
----------
M. Brokate, J. Sprekels, *Hysteresis and Phase Transitions*, Springer 1996, ch. 2.
"""

from __future__ import annotations

import math

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_between, float_array

__all__ = ["PLAY_THRESHOLDS", "CREEP_TIME_CONSTANTS_S", "CREEP_START", "DIRECTION_THRESHOLD", "memory_features",
           "directions", "MemoryState"]

#: Play-operator thresholds, fractions of full scale. [1]
PLAY_THRESHOLDS = (0.02, 0.05, 0.1, 0.2, 0.4)
#: Time constants of the creep features, two per decade from 0.5 s to 32 s; not longer, for recordings of
#: a few minutes (docs/calibration.md, "Why the constants are what they are"). [s]
CREEP_TIME_CONSTANTS_S = (0.5, 2.0, 8.0, 32.0)
#: The creep averages of a calibration at a recording's first reading, a fraction of its level: what came
#: before a recording that starts under load is unknown -- held for ever (1) or just loaded (0) -- and the
#: middle halves the worst case (docs/calibration.md). Recordings that start at rest do not depend on it. [1]
CREEP_START = 0.5
#: Threshold of the play operator that tells the direction (loading, unloading, still). [1]
DIRECTION_THRESHOLD = 0.01


def _play(u: np.ndarray, r: float) -> np.ndarray:
    """Play operator of threshold r along u (finite), from rest: as if loaded from 0 to the first level.

    Each reading clamps the state to ``[u_t − r, u_t + r]``; clamps compose into clamps,
    ``(lo₁, hi₁) then (lo₂, hi₂) = (min(max(lo₁, lo₂), hi₂), max(min(hi₁, hi₂), lo₂))``, an
    associative rule, so the states of all readings come from a prefix scan in log₂(n) vectorised
    passes -- the same numbers as the loop, which only takes minima and maxima.
    """
    lo = u - r
    hi = u + r
    k = 1
    n = u.size
    while k < n:
        new_lo = np.maximum(lo[:-k], lo[k:])
        np.minimum(new_lo, hi[k:], out=new_lo)
        new_hi = np.minimum(hi[:-k], hi[k:])
        np.maximum(new_hi, lo[k:], out=new_hi)
        lo[k:] = new_lo
        hi[k:] = new_hi
        k *= 2
    p0 = max(float(u[0]) - r, 0.0)
    return np.minimum(np.maximum(p0, lo), hi)


def _ema(u: np.ndarray, dt: np.ndarray, tau: float, start: float = 1.0) -> np.ndarray:
    """Exponential average of ``u`` with steps ``dt``, ``start`` times the first level at the first reading."""
    from scipy.signal import lfilter

    if start != 1.0:
        out = np.empty(u.size)
        out[0] = start * u[0]
        if u.size > 1:
            a = 1.0 - np.exp(-dt[1:] / tau)
            if np.allclose(a, a[0]):
                out[1:], _ = lfilter([a[0]], [1.0, a[0] - 1.0], u[1:], zi=[(1.0 - a[0]) * out[0]])
            else:
                q = float(out[0])
                for i, (ai, ui) in enumerate(zip(a.tolist(), u[1:].tolist(), strict=True), start=1):
                    q = q + ai * (ui - q)
                    out[i] = q
        return out
    if np.allclose(dt, dt[0]):
        a = 1.0 - math.exp(-dt[0] / tau)
        out, _ = lfilter([a], [1.0, a - 1.0], u, zi=[(1.0 - a) * u[0]])
        return out
    a = (1.0 - np.exp(-dt / tau)).tolist()
    out = []
    q = float(u[0])
    for ai, ui in zip(a, u.tolist(), strict=True):
        q = q + ai * (ui - q)
        out.append(q)
    return np.asarray(out)


def _steps(t: np.ndarray) -> np.ndarray:
    """Time step before each reading; the first and any non-positive step take the median step. [s]"""
    dt = np.diff(t, prepend=np.nan)
    good = dt[np.isfinite(dt) & (dt > 0)]
    med = float(np.median(good)) if good.size else 1.0
    return np.where(np.isfinite(dt) & (dt > 0), dt, med)


def _series(name: str, value) -> np.ndarray:
    """``value`` as a one-dimensional float array, or an error naming ``name``."""
    v = float_array(name, value)
    if v.ndim != 1:
        raise ParameterError(f"must be a sequence of numbers in time order, got shape {v.shape}", parameter=name)
    return v


def _constants(name: str, value, upper: float = math.inf) -> tuple:
    """``value`` as a tuple of numbers above zero (below ``upper``), or an error naming ``name``."""
    v = float_array(name, value)
    if v.ndim != 1 or not np.all(np.isfinite(v)) or np.any(v <= 0) or np.any(v >= upper):
        raise ParameterError("must be a sequence of numbers above "
                f"0{f' and below {upper:g}' if upper < math.inf else ''}"
                             f", got {value!r}", parameter=name)
    return tuple(v.tolist())


def memory_features(u, t, thresholds=PLAY_THRESHOLDS, time_constants=CREEP_TIME_CONSTANTS_S,
                    scaled: bool = False, creep_start: float = 1.0) -> np.ndarray:
    """Hysteresis and creep features of a level sequence, in time order.

    Parameters
    ----------
    u : array_like
        Level, a fraction of full scale, in time order; NaN readings are skipped (the memory is
        kept across them) and give NaN rows. [1]
    t : array_like
        Time of each reading. [s]
    thresholds : sequence of float
        Play-operator thresholds, fractions of full scale. [1]
    time_constants : sequence of float
        Creep time constants. [s]
    scaled : bool
        Multiply the features by the level: a loop whose width, and a creep whose size, grow with
        the load, as an FSR's hysteresis and creep stated in % of the reading give.
    creep_start : float
        The creep averages at the first reading, a fraction of its level: 1 as if it had been held
        there for ever, 0 as if just loaded from rest (as the play operators start), 0.5 between
        (:data:`CREEP_START`). It matters only for a recording that starts under load. [1]

    Returns
    -------
    ndarray, shape (n, len(thresholds) + len(time_constants))
        ``p_r − u`` for each threshold, then ``u − ū_τ`` for each time constant. [1]
    """
    u, t = _series("u", u), _series("t", t)
    thresholds, time_constants = _constants("thresholds", thresholds, 1.0), _constants("time_constants", time_constants)
    check_between("creep_start", creep_start, 0.0, 1.0, scalar=True)
    out = np.full((u.size, len(thresholds) + len(time_constants)), np.nan)
    rows = np.flatnonzero(np.isfinite(u))
    if rows.size == 0:
        return out
    ul = u[rows]
    for j, r in enumerate(thresholds):
        out[rows, j] = (_play(ul, float(r)) - ul) * (np.maximum(ul, 0.0) if scaled else 1.0)
    dt = _steps(t[rows]) if t.size == u.size else np.ones(rows.size)
    for m, tau in enumerate(time_constants):
        ema = _ema(ul, dt, float(tau), float(creep_start))
        out[rows, len(thresholds) + m] = (ul - ema) * (np.maximum(ul, 0.0) if scaled else 1.0)
    return out


def directions(u) -> np.ndarray:
    """+1 loading, −1 unloading, 0 still or missing: the movement of a play operator of
    :data:`DIRECTION_THRESHOLD` (noise smaller than it is no reversal).

    Parameters
    ----------
    u : array_like
        Level, a fraction of full scale, in time order (NaN: missing). [1]
    """
    u = _series("u", u)
    d = np.zeros(u.size, dtype=int)
    rows = np.flatnonzero(np.isfinite(u))
    if rows.size < 2:
        return d
    p = _play(u[rows], DIRECTION_THRESHOLD)
    step = np.sign(np.diff(p)).astype(int)
    d[rows[1:]] = step
    return d


class MemoryState:
    """The same memory one reading at a time (live estimation).

    Parameters
    ----------
    thresholds, time_constants : sequence of float
        As for :func:`memory_features`.
    scaled : bool
        As for :func:`memory_features`.
    creep_start : float
        As for :func:`memory_features`. [1]
    """

    def __init__(self, thresholds=PLAY_THRESHOLDS, time_constants=CREEP_TIME_CONSTANTS_S, scaled: bool = False,
                 creep_start: float = 1.0):
        self.scaled = bool(scaled)
        self.start = float(creep_start)
        self.r = [float(v) for v in thresholds]
        self.tau = [float(v) for v in time_constants]
        self.p: list[float] | None = None
        self.s: list[float] = []
        self.pd = 0.0
        self.t: float | None = None
        self.dt_default = 1.0

    def advance(self, u: float, t: float | None = None) -> tuple[list[float], int]:
        """Take one finite level ``u`` at time ``t`` [s]; return its features and its direction."""
        if self.p is None:
            self.p = [u - r if u - r > 0.0 else 0.0 for r in self.r]
            self.s = [self.start * u for _ in self.tau]
            self.pd = u - DIRECTION_THRESHOLD if u - DIRECTION_THRESHOLD > 0.0 else 0.0
            self.t = t
            for j, r in enumerate(self.r):
                lo, hi = u - r, u + r
                q = self.p[j]
                self.p[j] = lo if lo > q else (hi if hi < q else q)
            k = max(u, 0.0) if self.scaled else 1.0
            return [(p - u) * k for p in self.p] + [(u - s) * k for s in self.s], 0
        for j, r in enumerate(self.r):
            lo, hi = u - r, u + r
            q = self.p[j]
            self.p[j] = lo if lo > q else (hi if hi < q else q)
        dt = (t - self.t) if (t is not None and self.t is not None and t > self.t) else self.dt_default
        self.t = t if t is not None else self.t
        for m, tau in enumerate(self.tau):
            self.s[m] += (1.0 - math.exp(-dt / tau)) * (u - self.s[m])
        lo, hi = u - DIRECTION_THRESHOLD, u + DIRECTION_THRESHOLD
        d = 0
        if lo > self.pd:
            self.pd, d = lo, 1
        elif hi < self.pd:
            self.pd, d = hi, -1
        k = max(u, 0.0) if self.scaled else 1.0
        return [(p - u) * k for p in self.p] + [(u - s) * k for s in self.s], d
