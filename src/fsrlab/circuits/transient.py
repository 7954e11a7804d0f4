"""Exact event-driven transient of the FSR-timed LM555 astable.

Between events the timing capacitor follows a closed-form RC exponential, so the simulation jumps
from one threshold crossing to the next without a time step: each crossing time is solved exactly,
``Δt = τ·ln((V − V∞)/(V_th − V∞))``. The circuit model is the one of :mod:`fsrlab.circuits.lm555`
(ideal comparators, constant-drop diode D1 in series with R_B, optional discharge on-resistance), and
each phase's source and resistance are the Thevenin equivalents of :func:`fsrlab.circuits.phases.thevenin`.

Parts that change in time (the sensor under a changing force) are given as samples
``time_s``, ``r_fsr_ohm``, ``c_fsr_farad`` and held constant from one sample to the next (zero-order
hold), which makes every piece an exact RC segment. When the capacitance steps, the charge
``Q = C·V`` is conserved by default (a capacitor whose plates move at fixed charge; the continuous
limit of ``i = d(C·v)/dt``); ``capacitance_step="voltage"`` keeps the voltage instead
(quasi-static). A step can cross a threshold, which then switches the output at the sample time.

With constant parts the period repeats after the start: the loop runs to the second rising edge
and the remaining edges follow as an arithmetic sequence (``method="events"`` keeps the loop).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5 (eqs. 20–26, 33–34).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsrlab.circuits.checks import check_lm555, check_single
from fsrlab.circuits.phases import thevenin
from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_finite, check_int, check_positive, float_array

__all__ = ["TransientResult", "simulate"]


@dataclass(frozen=True)
class TransientResult:
    """Output edges (and optionally the capacitor waveform) of a transient run.

    Attributes
    ----------
    rising_s : ndarray
        Times the output goes high (start of a charge). [s]
    falling_s : ndarray
        Times the output goes low (start of a discharge). [s]
    t_s : ndarray or None
        Waveform sample times (``waveform=True``). [s]
    v_cap_v : ndarray or None
        Capacitor voltage at ``t_s``. [V]
    output_high : ndarray or None
        Output state at ``t_s`` (True = high).
    t_end_s : float
        Time the run stopped. [s]
    v_end_v : float
        Capacitor voltage at ``t_end_s`` (to continue a run). [V]
    high_end : bool
        Output state at ``t_end_s``.
    """

    rising_s: np.ndarray
    falling_s: np.ndarray
    t_s: np.ndarray | None
    v_cap_v: np.ndarray | None
    output_high: np.ndarray | None
    t_end_s: float
    v_end_v: float
    high_end: bool

    def _complete(self):
        """Rising edges r[i], the falling edge inside each complete period, and r[i+1]."""
        r, f = self.rising_s, self.falling_s
        if r.size < 2:
            return r[:0], f[:0], r[:0]
        starts, ends = r[:-1], r[1:]
        idx = np.searchsorted(f, starts, side="left")
        valid = idx < f.size
        falls = np.full(starts.shape, np.nan)
        falls[valid] = f[idx[valid]]
        ok = valid & (falls < ends)
        return starts[ok], falls[ok], ends[ok]

    @property
    def periods_s(self) -> np.ndarray:
        """Duration of each complete period (rising edge to rising edge). [s]"""
        s, _, e = self._complete()
        return e - s

    @property
    def high_times_s(self) -> np.ndarray:
        """Output-high time of each complete period. [s]"""
        s, f, _ = self._complete()
        return f - s

    @property
    def frequency_hz(self) -> float:
        """Mean frequency over the complete periods (as a counter would average them). [Hz]"""
        p = self.periods_s
        return float(p.size / p.sum()) if p.size else math.nan

    @property
    def duty_cycle(self) -> float:
        """Mean duty cycle, total high time over total period time. [1]"""
        p = self.periods_s
        return float(self.high_times_s.sum() / p.sum()) if p.size else math.nan


def _as_series(name, value, n):
    a = float_array(name, value)
    if a.ndim == 0:
        return np.full(n, float(a))
    if a.shape != (n,):
        raise ParameterError(f"must be a scalar or have the shape of time_s ({n},), got {a.shape}", parameter=name)
    return a


def simulate(r_ohm: float, r_fsr_ohm, c_fsr_farad, c_off_farad: float = 0.0, diode: bool = False,
             diode_drop_v: float = 0.0, vcc_v: float = 5.0, lower_fraction: float = 1 / 3,
             upper_fraction: float = 2 / 3, *, periods: int | None = None, t_stop_s: float | None = None,
             time_s=None, v_initial_v: float | None = None, waveform: bool = False,
             points_per_segment: int = 16, capacitance_step: str = "charge",
             discharge_ohm: float = 0.0, method: str = "auto") -> TransientResult:
    """Simulate the astable event by event with closed-form RC segments.

    Parameters
    ----------
    r_ohm : float
        R_A = R_B = R. [Ω]
    r_fsr_ohm : float or array_like
        FSR resistance; an array gives its value at each ``time_s`` sample (``inf`` allowed). [Ω]
    c_fsr_farad : float or array_like
        FSR capacitance, scalar or per ``time_s`` sample. [F]
    c_off_farad : float
        Offset capacitor in parallel. [F]
    diode : bool
        D1 in series with R_B.
    diode_drop_v : float
        Constant forward drop of D1 (needs ``diode=True``). [V]
    vcc_v : float
        Supply. [V]
    lower_fraction, upper_fraction : float
        Comparator thresholds as fractions of Vcc. [1]
    periods : int, optional
        Constant parts only: stop after this many complete periods.
    t_stop_s : float, optional
        Stop time (constant parts; default for time series: ``time_s[-1]``). [s]
    time_s : array_like, optional
        Sample times of the part values, strictly increasing; each sample holds until the next. [s]
    v_initial_v : float, optional
        Capacitor voltage at the start. Default: the lower threshold with the output just gone
        high (steady state; a rising edge is recorded at the start time). A value at or below the
        lower threshold starts high (power-up: 0), at or above the upper one low, in between high. [V]
    waveform : bool
        Also return the capacitor voltage, ``points_per_segment`` points per RC segment.
    points_per_segment : int
        Waveform points per segment (≥ 2), segment ends included.
    capacitance_step : {"charge", "voltage"}
        What is conserved when the capacitance steps between samples.
    discharge_ohm : float
        Discharge-transistor on-resistance (0: ideal switch, as in the paper); see
        :func:`fsrlab.circuits.lm555.astable`. [Ω]
    method : {"auto", "events"}
        ``"auto"``: constant parts without a waveform take the closed-form path (the loop runs to
        the second rising edge, the remaining edges are an arithmetic sequence of the steady
        period); ``"events"``: every edge from the event loop (the reference for that path).

    Returns
    -------
    TransientResult

    Raises
    ------
    ParameterError
        Parameters out of range, or neither/both of ``periods`` and a stop time for constant parts.

    Notes
    -----
    Charge (output high): ``V∞ = (Vcc − V_D)·R_FSR/(2R + R_FSR)``, ``τ = C·(2R ∥ R_FSR)`` (eq. 21);
    if the capacitor sits above ``Vcc − V_D`` D1 is off and C decays through R_FSR until it
    conducts again. Discharge (output low): ``V∞ = 0``, ``τ = C·(R ∥ R_FSR)`` without D1 (eq. 24)
    or ``τ = C·R_FSR`` with D1 (eq. 33); with a discharge on-resistance R_d and no D1, the discharge
    heads for ``V_T·R_FSR/(R + R_T + R_FSR)`` through ``(R + R_T) ∥ R_FSR`` (``V_T = Vcc·R_d/(R + R_d)``,
    ``R_T = R ∥ R_d``). A circuit that does not oscillate simply produces no more
    edges (the capacitor settles below the upper threshold).

    With constant parts (``method="auto"``, no waveform) the loop stops at the second rising edge:
    the first rising edge leaves C at the lower threshold, so every later period repeats that one,
    and the edges are ``r_0 + i·T`` (falling edges ``+ T_high``), with ``T`` and ``T_high`` taken
    from the loop's first steady period; after a ``t_stop_s`` the loop runs again for the last, cut
    period. The loop accumulates ``t += Δt`` one event at a time, so the two agree to the rounding of
    that sum (≈ 3e-11 relative after 10^6 periods); an edge within that rounding of ``t_stop_s``
    may fall on either side of it.
    """
    check_single(("r_ohm", r_ohm), ("c_off_farad", c_off_farad), ("discharge_ohm", discharge_ohm),
                 ("v_initial_v", v_initial_v))
    check_lm555(r_ohm, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, discharge_ohm)
    if not isinstance(capacitance_step, str) or capacitance_step not in ("charge", "voltage"):
        raise ParameterError(f"must be 'charge' or 'voltage', got {capacitance_step!r}", parameter="capacitance_step")
    if not isinstance(method, str) or method not in ("auto", "events"):
        raise ParameterError(f"must be 'auto' or 'events', got {method!r}", parameter="method")
    points_per_segment = check_int("points_per_segment", points_per_segment, 2)
    times, rf, cap = _sampled_parts(r_fsr_ohm, c_fsr_farad, c_off_farad, periods, t_stop_s, time_s)
    loop = _EventLoop(r_ohm, rf, cap, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction,
                      discharge_ohm, capacitance_step, int(points_per_segment) if waveform else 0)
    max_rising = None if periods is None else int(periods) + 1
    t = float(times[0])
    if v_initial_v is None:
        v, high = loop.v_lo, True
        loop.rising.append(t)
    else:
        check_finite("v_initial_v", v_initial_v)
        v = float(v_initial_v)
        high = v < loop.v_hi
    if method == "auto" and time_s is None and not waveform:
        fast = _steady_edges(loop, times, t, v, high, max_rising)
        if fast is not None:
            return fast
    else:
        t, v, high = loop.run(times, t, v, high, max_rising)

    def as_arr(parts):
        return np.concatenate(parts) if parts else np.empty(0)

    return TransientResult(
        rising_s=np.asarray(loop.rising), falling_s=np.asarray(loop.falling),
        t_s=as_arr(loop.wt) if waveform else None, v_cap_v=as_arr(loop.wv) if waveform else None,
        output_high=as_arr(loop.wh).astype(bool) if waveform else None,
        t_end_s=loop.t_end_s, v_end_v=loop.v_end_v, high_end=loop.high_end,
    )


def _sampled_parts(r_fsr_ohm, c_fsr_farad, c_off_farad, periods, t_stop_s, time_s):
    """The sample times and the FSR's resistance and timing capacitance at each, checked. [s, Ω, F]"""
    if time_s is None:
        if np.ndim(r_fsr_ohm) or np.ndim(c_fsr_farad):
            raise ParameterError("an array of values needs its sample times time_s",
                                 parameter="r_fsr_ohm" if np.ndim(r_fsr_ohm) else "c_fsr_farad")
        if (periods is None) == (t_stop_s is None):
            raise ParameterError("give exactly one of periods and t_stop_s for constant parts",
                                 parameter="periods" if periods is None else "t_stop_s")
        if periods is not None:
            check_int("periods", periods, 1)
        else:
            check_positive("t_stop_s", t_stop_s, "s")
        times = np.array([0.0, math.inf if t_stop_s is None else float(t_stop_s)])
        rf = np.full(2, float(float_array("r_fsr_ohm", r_fsr_ohm)))
        cf = np.full(2, float(float_array("c_fsr_farad", c_fsr_farad)))
    else:
        times = float_array("time_s", time_s)
        if times.ndim != 1 or times.size < 2 or not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
            raise ParameterError("must be a 1-D array of at least 2 finite, strictly increasing times",
                                 parameter="time_s")
        rf = _as_series("r_fsr_ohm", r_fsr_ohm, times.size)
        cf = _as_series("c_fsr_farad", c_fsr_farad, times.size)
        if t_stop_s is not None:
            check_finite("t_stop_s", t_stop_s)
            if np.ndim(t_stop_s) or not t_stop_s > times[0]:
                raise ParameterError("must be after time_s[0]", parameter="t_stop_s")
            keep = times < t_stop_s
            times = np.append(times[keep], float(t_stop_s))
            rf, cf = np.append(rf[keep], rf[keep][-1]), np.append(cf[keep], cf[keep][-1])
    if np.any(np.isnan(rf)) or np.any(rf <= 0):
        raise ParameterError("must be > 0 Ω (inf allowed)", parameter="r_fsr_ohm")
    if np.any(~np.isfinite(cf)) or np.any(cf < 0):
        raise ParameterError("must be finite and >= 0 F", parameter="c_fsr_farad")
    cap = cf + c_off_farad
    if np.any(cap <= 0):
        raise ParameterError("the timing capacitance C_FSR + C_off must be > 0 F", parameter="c_fsr_farad")
    return times, rf, cap


class _EventLoop:
    """The astable's event loop: closed-form RC segments from one threshold crossing to the next.

    ``rising`` and ``falling`` collect the edges, ``wt``/``wv``/``wh`` the waveform when
    ``points_per_segment`` > 0; ``run`` also leaves its end state in ``t_end_s``, ``v_end_v``, ``high_end``.
    """

    def __init__(self, r_ohm, rf, cap, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction,
                 discharge_ohm, capacitance_step, points_per_segment):
        # What C sees in each phase, per sample (eqs. 21, 24, 33), as Python floats for the loop.
        charge, discharge = thevenin(float(r_ohm), rf, diode, diode_drop_v, vcc_v, float(discharge_ohm))
        self.charge_vinfs, self.charge_rs = charge.source_v.tolist(), charge.resistance_ohm.tolist()
        self.dis_vinfs, self.dis_rs = discharge.source_v.tolist(), discharge.resistance_ohm.tolist()
        self.rf, self.cap = rf, cap
        self.diode, self.vs = diode, vcc_v - diode_drop_v
        self.v_lo, self.v_hi = lower_fraction * vcc_v, upper_fraction * vcc_v
        self.charge_step = capacitance_step == "charge"
        self.npts = points_per_segment
        self.rising: list[float] = []
        self.falling: list[float] = []
        self.wt: list[np.ndarray] = []
        self.wv: list[np.ndarray] = []
        self.wh: list[np.ndarray] = []
        self.t_end_s = self.v_end_v = math.nan
        self.high_end = False

    def record(self, t0, dt, v0, vinf, tau, state):
        """One RC segment of the waveform, ``npts`` points, its ends included."""
        frac = np.linspace(0.0, 1.0, self.npts)
        ts = t0 + frac * dt
        if math.isinf(tau):
            vs_ = np.full(self.npts, v0)
        else:
            vs_ = vinf + (v0 - vinf) * np.exp(-(frac * dt) / tau)
        self.wt.append(ts)
        self.wv.append(vs_)
        self.wh.append(np.full(self.npts, state))

    def run(self, times, t, v, high, max_rising):
        """The event loop over the sample intervals of ``times``; appends edges, returns the end state."""
        rf, cap = self.rf, self.cap
        for k in range(times.size - 1):
            t_end = float(times[k + 1])
            ck = float(cap[k])
            if k > 0 and self.charge_step and ck != float(cap[k - 1]):
                v *= float(cap[k - 1]) / ck  # Q = C·V conserved across the step
            segment = (self.charge_vinfs[k], self.charge_rs[k] * ck, self.dis_vinfs[k], self.dis_rs[k] * ck,
                       float(rf[k]) * ck)  # D1 off: C decays through R_FSR alone
            t, v, high, done = self._interval(t, v, high, t_end, segment, max_rising)
            if done:
                break
        self.t_end_s, self.v_end_v, self.high_end = t, v, high
        return t, v, high

    def _phase(self, v, high, segment):
        """The RC segment the capacitor follows from ``v``: ``(v_inf, tau, target, edge, dt)``, where ``dt``
        is the time to reach ``target`` (``inf`` when it never does) and ``edge`` whether the output
        switches there."""
        charge_vinf, charge_tau, dis_vinf, dis_tau, leak_tau = segment
        if not high:
            vinf, tau, target, edge = dis_vinf, dis_tau, self.v_lo, True
        elif self.diode and v > self.vs:
            # D1 reverse biased: C decays through R_FSR until it reaches Vcc − V_D.
            vinf, tau, target, edge = 0.0, leak_tau, self.vs, False
        else:
            vinf, tau, target, edge = charge_vinf, charge_tau, self.v_hi, True
        if math.isinf(tau):
            return vinf, tau, target, edge, math.inf
        ratio = (target - vinf) / (v - vinf) if v != vinf else -1.0
        return vinf, tau, target, edge, (tau * math.log(1.0 / ratio) if 0.0 < ratio <= 1.0 else math.inf)

    def _interval(self, t, v, high, t_end, segment, max_rising):
        """Edges within one sample interval up to ``t_end``; returns ``(t, v, high, done)``."""
        v_lo, v_hi = self.v_lo, self.v_hi
        rising, falling, waveform = self.rising, self.falling, self.npts > 0
        while True:
            # A step of C (or the start) may already sit beyond a threshold: switch now.
            if high and v >= v_hi:
                falling.append(t)
                high = False
            elif not high and v <= v_lo:
                rising.append(t)
                high = True
                if max_rising is not None and len(rising) >= max_rising:
                    return t, v, high, True
            vinf, tau, target, edge, dt = self._phase(v, high, segment)
            if t + dt < t_end:
                if waveform:
                    self.record(t, dt, v, vinf, tau, high)
                t += dt
                v = target
                if edge:
                    if high:
                        falling.append(t)
                        high = False
                    else:
                        rising.append(t)
                        high = True
                        if max_rising is not None and len(rising) >= max_rising:
                            return t, v, high, True
                continue
            # No event before the end of this sample interval.
            if math.isinf(t_end):
                return t, v, high, True  # constant parts that stopped oscillating: nothing more will happen
            span = t_end - t
            if waveform:
                self.record(t, span, v, vinf, tau, high)
            if not math.isinf(tau):
                v = vinf + (v - vinf) * math.exp(-span / tau)
            return t_end, v, high, False


def _steady_edges(loop: _EventLoop, times, t, v, high, max_rising) -> TransientResult | None:
    """Constant parts: the loop up to the second rising edge, the rest as an arithmetic sequence.

    ``rising[0]`` always starts a steady period (the default start sits at the lower threshold, and
    any other start reaches it at its first rising edge, with v = v_lo exactly), so every later period
    repeats the one from ``rising[0]`` to ``rising[1]``. None when the loop alone already finished (the
    circuit stopped oscillating, or at most two rising edges were asked for); ``loop`` then holds the edges.
    """
    rising, falling = loop.rising, loop.falling
    t, v, high = loop.run(times, t, v, high, 2 if max_rising is None else min(2, max_rising))
    if not (len(rising) == 2 and (max_rising is None or max_rising > 2)):
        return None
    r0, period = rising[0], rising[1] - rising[0]
    f0 = next(f for f in falling if f > r0)
    high_time = f0 - r0
    startup_falls = [f for f in falling if f < r0]
    t_end = float(times[-1])
    if max_rising is not None:
        count = max_rising  # rising edges in all, as the loop would record them
    else:
        # Rising edges strictly before t_stop (the loop records an edge only if t + dt < t_end).
        count = max(2, math.ceil((t_end - r0) / period) + 2)
        while count > 2 and r0 + (count - 1) * period >= t_end:
            count -= 1
    edges = np.arange(count, dtype=float)  # in place: two passes over 10^6 edges, no temporaries
    edges *= period
    edges += r0
    rising_arr = edges
    falling_arr = np.empty(len(startup_falls) + count - 1)
    falling_arr[:len(startup_falls)] = startup_falls
    np.add(edges[:-1], high_time, out=falling_arr[len(startup_falls):])
    t, v, high = float(edges[-1]), loop.v_lo, True
    if max_rising is None:
        # The last period may be cut by t_stop: run the loop for it from the last rising edge.
        rising.clear()
        falling.clear()
        t, v, high = loop.run(np.array([t, t_end]), t, v, high, None)
        rising_arr = np.concatenate([rising_arr, rising])  # empty unless rounding moved an edge
        falling_arr = np.concatenate([falling_arr, falling])
    return TransientResult(rising_s=rising_arr, falling_s=falling_arr, t_s=None, v_cap_v=None,
                           output_high=None, t_end_s=t, v_end_v=v, high_end=high)
