"""The LM555's output edges for the digital twin, computed in chunks as the firmware needs them.

:class:`EdgeStream` runs the exact event-driven transient (:func:`fsrlab.circuits.transient.simulate`)
of the virtual sensor (:class:`fsrlab.virtual.sources.PhysicsSource`: stress profile →
R_FSR(t), C_FSR(t)) piece by piece, so that an hour-long run never holds more than a short stretch
of edges. The parts are held constant between the samples of the source's grid (zero-order hold,
``source.dt_s``), and the timing capacitance is C_FSR(t) + C_off · range(t), where range(t) is the
C_off switch the firmware drives on D4 (a change becomes one more sample time; the charge is
conserved across the step, the transient's default).

Continuity (the property tested in tests/virtual/twin/test_edges.py: chunks joined = one run of
``simulate`` over the whole time series): a chunk is cut where the transient's state is known
exactly, so the next one starts from it:

- at the chunk's last rising edge (C at the lower threshold, output just gone high: the transient's
  default start, which records that rising edge again: it is emitted by the next chunk only);
- with no rising edge, if the output is high at the chunk's end: there, with the capacitor voltage
  carried over (a start voltage below the upper threshold starts high); the end lies in the middle
  of a grid interval, where the parts do not step;
- with no rising edge and the output low: at the last falling edge (C at the upper threshold starts
  low); a chunk that has neither is extended.

A switch of C_off at time t_s recomputes from the last cut at or before t_s with the new range
series; the edges before t_s come out the same and are skipped by their index.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

__all__ = ["EdgeChunk", "EdgeStream"]


@dataclass(frozen=True)
class EdgeChunk:
    """Edges of D8 in time order.

    Attributes
    ----------
    t_s : ndarray
        Edge times. [s]
    level : ndarray of int8
        Level after each edge: 1 rising, 0 falling.
    first_index : int
        Index of the first edge in the whole stream (rising and falling edges counted from 0).
    done_s : float
        Every edge before this time has been emitted. [s]
    """

    t_s: np.ndarray
    level: np.ndarray
    first_index: int
    done_s: float


@dataclass(frozen=True)
class _Cut:
    t: float       # [s]
    mode: str      # "rising", "high" (voltage v), "low" (C at the upper threshold)
    v: float       # [V]
    index: int     # stream index of the first edge emitted after the cut


class EdgeStream:
    """The 555 output of a :class:`~fsrlab.virtual.sources.PhysicsSource`, chunk by chunk.

    Parameters
    ----------
    source : PhysicsSource
        Stress profile, sensor and circuit (its ``c_off_farad`` is what range 1 switches in).
    range0 : int
        C_off switch at time 0 (the firmware boots with range 0).

    Notes
    -----
    :meth:`advance` emits the edges up to a time; :meth:`switch` changes the range and recomputes;
    :meth:`forget_before` bounds the memory (cuts older than the consumer's progress).
    """

    def __init__(self, source, range0: int = 0) -> None:
        self.source = source
        self.circuit = source.circuit.replace(c_off_farad=0.0)  # C_off enters as part of C(t)
        self.c_off_farad = float(source.circuit.c_off_farad)
        self.dt_s = float(source.dt_s)
        self.v_high = self.circuit.upper_fraction * self.circuit.vcc_v
        self._range_t = [0.0]
        self._range_v = [int(range0)]
        self._cut = _Cut(0.0, "rising", math.nan, 0)
        self._cuts: deque[_Cut] = deque([self._cut])
        self.done_s = 0.0

    # ------------------------------------------------------------ parts
    def range_at(self, t_s) -> np.ndarray:
        """C_off switch state at times ``t_s`` [s] (0 or 1)."""
        i = np.searchsorted(np.asarray(self._range_t), np.asarray(t_s, dtype=float), side="right") - 1
        return np.asarray(self._range_v)[np.maximum(i, 0)]

    def parts(self, t_s):
        """R_FSR [Ω] and the timing capacitance C_FSR + C_off·range [F] at times ``t_s`` [s]."""
        r, c, _ = self.source.parts(t_s)
        return r, c + self.c_off_farad * self.range_at(t_s)

    def sample_times(self, t0_s: float, t1_s: float) -> np.ndarray:
        """Times where the parts may change in ``(t0_s, t1_s)``, with both ends. [s]"""
        k0 = math.floor(t0_s / self.dt_s) + 1
        k1 = math.ceil(t1_s / self.dt_s)
        grid = np.arange(k0, k1 + 1) * self.dt_s
        sw = np.asarray(self._range_t[1:])
        inner = np.union1d(grid, sw)
        inner = inner[(inner > t0_s) & (inner < t1_s)]
        return np.concatenate([[t0_s], inner, [t1_s]])

    def _mid(self, t_s: float) -> float:
        """A time near ``t_s`` in the middle of a grid interval (where the parts do not step). [s]"""
        return (math.floor(t_s / self.dt_s) + 0.5) * self.dt_s

    # ------------------------------------------------------------ chunks
    def _chunk(self, cut: _Cut, t1: float):
        times = self.sample_times(cut.t, t1)
        r, c = self.parts(times)
        v0 = None if cut.mode == "rising" else (cut.v if cut.mode == "high" else self.v_high)
        return self.circuit.simulate(r, c, time_s=times, v_initial_v=v0)

    def advance(self, t_target_s: float) -> EdgeChunk:
        """Emit the edges from where the stream stands up to at least ``t_target_s`` [s]."""
        ts: list[np.ndarray] = []
        lv: list[np.ndarray] = []
        first = self._cut.index
        while self.done_s < t_target_s:
            cut = self._cut
            span = max(t_target_s - cut.t, 2 * self.dt_s)
            while True:
                t1 = self._mid(cut.t + span)
                if t1 <= cut.t:
                    t1 += self.dt_s
                res = self._chunk(cut, t1)
                rising, falling = res.rising_s, res.falling_s
                later = rising[rising > cut.t]
                if later.size:
                    end, new = later[-1], _Cut(float(later[-1]), "rising", math.nan, 0)
                    keep_r, keep_f = rising < end, falling < end
                elif res.high_end:
                    end, new = t1, _Cut(t1, "high", float(res.v_end_v), 0)
                    keep_r, keep_f = rising < end, falling < end
                else:
                    lf = falling[falling > cut.t] if cut.mode == "low" else falling
                    if not lf.size:
                        span *= 2  # a long low phase: look further
                        continue
                    end, new = float(lf[-1]), _Cut(float(lf[-1]), "low", math.nan, 0)
                    keep_r, keep_f = rising < end, falling <= end
                break
            t = np.concatenate([rising[keep_r], falling[keep_f]])
            level = np.concatenate([np.ones(int(keep_r.sum()), np.int8), np.zeros(int(keep_f.sum()), np.int8)])
            order = np.argsort(t, kind="stable")
            ts.append(t[order])
            lv.append(level[order])
            n = t.size
            self._cut = _Cut(new.t, new.mode, new.v, cut.index + n)
            self._cuts.append(self._cut)
            self.done_s = float(end)
        t = np.concatenate(ts) if ts else np.empty(0)
        level = np.concatenate(lv) if lv else np.empty(0, np.int8)
        return EdgeChunk(t, level, first, self.done_s)

    def switch(self, t_s: float, range_: int, consumed: int, t_target_s: float) -> EdgeChunk:
        """The C_off switch changes to ``range_`` at ``t_s`` [s]: recompute the edges from there.

        Parameters
        ----------
        t_s : float
            Time of the change. [s]
        range_ : int
            New switch state, 0 or 1.
        consumed : int
            Edges the consumer has already applied (they are not emitted again).
        t_target_s : float
            Emit up to at least this time. [s]

        Returns
        -------
        EdgeChunk
            The edges from stream index ``consumed`` on.
        """
        keep = [i for i, t in enumerate(self._range_t) if t < t_s or i == 0]
        self._range_t = [self._range_t[i] for i in keep] + [float(t_s)]
        self._range_v = [self._range_v[i] for i in keep] + [int(range_)]
        while len(self._cuts) > 1 and self._cuts[-1].t > t_s:
            self._cuts.pop()
        self._cut = self._cuts[-1]
        self.done_s = self._cut.t
        chunk = self.advance(max(t_target_s, t_s))
        skip = max(0, consumed - chunk.first_index)
        return EdgeChunk(chunk.t_s[skip:], chunk.level[skip:], chunk.first_index + skip, chunk.done_s)

    def forget_before(self, t_s: float) -> None:
        """Drop what a switch at or after ``t_s`` [s] can no longer need (bounded memory)."""
        while len(self._cuts) > 1 and self._cuts[1].t <= t_s:
            self._cuts.popleft()
        t0 = self._cuts[0].t
        while len(self._range_t) > 1 and self._range_t[1] <= t0:
            del self._range_t[0], self._range_v[0]
