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

With a :class:`~fsrlab.virtual.sources.MuxSource` (several sensors behind the multiplexer) the parts are
the selected channel's (an open channel: no FSR, R_FSR infinite and only the node's capacitance), and a
change of channel at t_s (:meth:`EdgeStream.switch` with ``channel``) is a cut: the old channel's
transient runs to t_s exactly; the sensor it leaves keeps its voltage and decays through its own
R_FSR·C_FSR while disconnected; the sensor connected shares its charge with the node
(:func:`fsrlab.circuits.mux.shared_voltage`). The 555 then goes on from that voltage: high (a rising edge
at t_s if it was low) when it is at or below the lower threshold or the output was high; otherwise it
keeps discharging, and the next rising edge comes when the voltage reaches the lower threshold
(the decay of the parts at t_s, eq. 33 with D1, eq. 24 without).
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
    mode: str      # "rising", "high" (voltage v), "low" (C at the upper threshold),
                   # "wait" (low, discharging from v after a change of channel, until `until`)
    v: float       # [V]
    index: int     # stream index of the first edge emitted after the cut
    until: float = math.nan  # "wait": the next rising edge [s]


class EdgeStream:
    """The 555 output of a :class:`~fsrlab.virtual.sources.PhysicsSource`, chunk by chunk.

    Parameters
    ----------
    source : PhysicsSource
        Stress profile, sensor and circuit (its ``c_off_farad`` is what range 1 switches in).
    range0 : int
        C_off switch at time 0 (the firmware boots with range 0).
    channel0 : int
        Multiplexer channel selected at time 0 (the firmware boots with channel 0; a
        :class:`~fsrlab.virtual.sources.MuxSource` only).

    Notes
    -----
    :meth:`advance` emits the edges up to a time; :meth:`switch` changes the range and recomputes;
    :meth:`forget_before` bounds the memory (cuts older than the consumer's progress).
    """

    def __init__(self, source, range0: int = 0, channel0: int = 0) -> None:
        self.source = source
        self.mux = getattr(source, "mux", None) if hasattr(source, "channel") else None
        self._chan_t = [0.0]
        self._chan_v = [int(channel0)]
        self._left: dict[int, tuple[float, float]] = {}  # channel -> (time, voltage) when it was disconnected
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

    def channel_at(self, t_s) -> np.ndarray:
        """Multiplexer channel selected at times ``t_s`` [s]."""
        i = np.searchsorted(np.asarray(self._chan_t), np.asarray(t_s, dtype=float), side="right") - 1
        return np.asarray(self._chan_v)[np.maximum(i, 0)]

    def _channel_parts(self, k: int, t_s):
        """R_FSR and C of channel k at ``t_s`` (an open channel: infinite R, the node's C)."""
        t = np.asarray(t_s, dtype=float)
        src = self.source.channel(int(k))
        if src is None:
            return np.full(t.shape, np.inf), np.full(t.shape, self.mux.c_node_farad if self.mux else 1e-12)
        r, c, _ = src.parts(t)
        return r, c

    def parts(self, t_s):
        """R_FSR [Ω] and the timing capacitance C_FSR + C_off·range [F] at times ``t_s`` [s]."""
        if self.mux is None and not hasattr(self.source, "channel"):
            r, c, _ = self.source.parts(t_s)
        else:
            t = np.atleast_1d(np.asarray(t_s, dtype=float))
            ch = self.channel_at(t)
            r, c = np.empty(t.shape), np.empty(t.shape)
            for k in np.unique(ch):
                sel = ch == k
                r[sel], c[sel] = self._channel_parts(int(k), t[sel])
            if np.ndim(t_s) == 0:
                r, c = r[0], c[0]
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
            if cut.mode == "wait":  # nothing until the rising edge that ends the discharge
                self._cut = _Cut(cut.until, "rising", math.nan, cut.index)
                self._cuts.append(self._cut)
                self.done_s = cut.until
                continue
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
                    if not lf.size and span > 1.0 and self._parts_at(t1)[0] == np.inf:
                        # an open channel: low at the upper threshold for good (nothing discharges it)
                        end, new = t1, _Cut(t1, "low", math.nan, 0)
                        keep_r, keep_f = rising < end, falling <= end
                        break
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

    def _discharge_ohm(self, r_fsr: float) -> float:
        """Resistance the timing capacitor discharges through: R_FSR with D1 (eq. 33), R ∥ R_FSR without (eq. 24)."""
        if self.circuit.diode or not math.isfinite(r_fsr):
            return r_fsr
        return 1.0 / (1.0 / r_fsr + 1.0 / self.circuit.r_ohm)

    def _parts_at(self, t_s: float):
        r, c = self.parts(np.array([t_s]))
        return float(r[0]), float(c[0])

    def switch(self, t_s: float, range_: int, consumed: int, t_target_s: float,
               channel: int | None = None) -> EdgeChunk:
        """The C_off switch (``range_``) or the channel changes at ``t_s`` [s]: recompute the edges from there.

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
        channel : int, optional
            The multiplexer channel selected from ``t_s`` on (a :class:`MuxSource`); None: unchanged.

        Returns
        -------
        EdgeChunk
            The edges from stream index ``consumed`` on.
        """
        while len(self._cuts) > 1 and self._cuts[-1].t > t_s:
            self._cuts.pop()
        self._cut = self._cuts[-1]
        self.done_s = self._cut.t
        old_channel = int(self.channel_at(t_s))
        if int(range_) != int(self.range_at(t_s)) or channel is None or channel == old_channel:
            keep = [i for i, t in enumerate(self._range_t) if t < t_s or i == 0]
            self._range_t = [self._range_t[i] for i in keep] + [float(t_s)]
            self._range_v = [self._range_v[i] for i in keep] + [int(range_)]
        head = None
        if channel is not None and channel != old_channel:
            head = self._reconnect(t_s, int(channel), old_channel)
        chunk = self.advance(max(t_target_s, t_s))
        if head is not None:
            chunk = EdgeChunk(np.concatenate([head.t_s, chunk.t_s]), np.concatenate([head.level, chunk.level]),
                              head.first_index, chunk.done_s)
        skip = max(0, consumed - chunk.first_index)
        return EdgeChunk(chunk.t_s[skip:], chunk.level[skip:], chunk.first_index + skip, chunk.done_s)

    def _reconnect(self, t_s: float, channel: int, old: int) -> EdgeChunk:
        """Run the old channel to ``t_s``, connect ``channel`` (charge sharing), cut there; its edges."""
        from fsrlab.circuits.mux import disconnected_voltage, shared_voltage

        cut = self._cut
        res = self._chunk(cut, t_s) if t_s > cut.t and cut.mode != "wait" else None
        if cut.mode == "wait":  # still discharging from cut.v
            r_c, c_c = self._parts_at(cut.t)
            v_end = cut.v * math.exp(-(t_s - cut.t) / (c_c * self._discharge_ohm(r_c)))
            high, t, level = False, np.empty(0), np.empty(0, np.int8)
        elif res is None:  # switched at the cut itself: its state
            v_end = self.circuit.lower_fraction * self.circuit.vcc_v if cut.mode == "rising" else (
                cut.v if cut.mode == "high" else self.v_high)
            high, t, level = cut.mode != "low", np.empty(0), np.empty(0, np.int8)
        else:
            v_end, high = float(res.v_end_v), bool(res.high_end)
            keep_r, keep_f = res.rising_s < t_s, res.falling_s < t_s
            if cut.mode == "low":
                keep_f &= res.falling_s > cut.t
            t = np.concatenate([res.rising_s[keep_r], res.falling_s[keep_f]])
            level = np.concatenate([np.ones(int(keep_r.sum()), np.int8), np.zeros(int(keep_f.sum()), np.int8)])
            order = np.argsort(t, kind="stable")
            t, level = t[order], level[order]
        self._left[old] = (t_s, v_end)
        keep = [i for i, tc in enumerate(self._chan_t) if tc < t_s or i == 0]
        self._chan_t = [self._chan_t[i] for i in keep] + [float(t_s)]
        self._chan_v = [self._chan_v[i] for i in keep] + [channel]
        c_node = (self.mux.c_node_farad if self.mux else 0.0) + self.c_off_farad * int(self.range_at(t_s))
        r_k, c_k = self._parts_at(t_s)
        c_fsr = max(c_k - c_node, 0.0)
        t_off, v_off = self._left.get(channel, (0.0, 0.0))  # never connected yet: at rest
        r_own = r_k - (self.mux.r_on_ohm if self.mux else 0.0)
        v_k = float(disconnected_voltage(v_off, t_s - t_off, r_own, c_fsr)) if c_fsr > 0 else 0.0
        v = shared_voltage(v_end, c_node, v_k, c_fsr) if c_node + c_fsr > 0 else v_end
        v_low = self.circuit.lower_fraction * self.circuit.vcc_v
        index = cut.index + t.size
        if v <= v_low and not high:  # the trigger fires: the output goes high at the switch
            t, level = np.append(t, t_s), np.append(level, np.int8(1))
            index += 1
        if high or v <= v_low:
            new = _Cut(t_s, "high", v, index)
        else:  # low, discharging from v: the next rising edge when it reaches the lower threshold
            r_d = self._discharge_ohm(r_k)
            if not math.isfinite(r_d):
                new = _Cut(t_s, "low", math.nan, index)  # (an open channel: low for good)
            else:
                new = _Cut(t_s, "wait", v, index, t_s + c_k * r_d * math.log(v / v_low))
        self._cut = new
        self._cuts.append(new)
        self.done_s = new.t
        return EdgeChunk(t, level.astype(np.int8), cut.index, new.t)

    def forget_before(self, t_s: float) -> None:
        """Drop what a switch at or after ``t_s`` [s] can no longer need (bounded memory)."""
        while len(self._cuts) > 1 and self._cuts[1].t <= t_s:
            self._cuts.popleft()
        t0 = self._cuts[0].t
        while len(self._range_t) > 1 and self._range_t[1] <= t0:
            del self._range_t[0], self._range_v[0]
        while len(self._chan_t) > 1 and self._chan_t[1] <= t0:
            del self._chan_t[0], self._chan_v[0]
