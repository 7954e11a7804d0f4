"""The fsrlab meter as a model: what the Arduino Uno reports for a 555 signal and an op-amp voltage.

One model serves the synthetic runs (:func:`fsrlab.virtual.synthetic.synthetic_run`, many windows
at once) and the virtual device (:class:`fsrlab.virtual.device.VirtualDevice`, one
window at a time, carrying a :class:`MeterState` from window to window). Given, per window, the
555's frequency and duty cycle and the op-amp's output voltage, :func:`measure` returns the fields
of the window's ``M`` frame (docs/protocol.md): complete periods, their summed length and summed
high time in Timer1 ticks, and the A0 reading. Every constant comes from
:mod:`fsrlab.acquisition.protocol`.

The 555 output is a square wave on a continuous phase: rising edges where the phase (cycles since
START) is a whole number. A window counts the periods that end in it (rising edge to rising edge)
and sums their length as the difference of two captured timestamps (the window's last rising edge
and the one before the window's first period), each the floor of the edge time in ticks, so the
summed length telescopes and carries one quantization error for the whole window. The first rising
edge after START (or after a restarted window) only opens a period. The high times are summed with
the quantization noise of fsrlab's decoding model (:func:`fsrlab.circuits.decode.decode`): each
edge uniform within ±½ tick (σ = q/√12), independently, so the sum of n high times has variance
n·2σ² = n/6 tick². The A0 reading is the Uno's 10-bit conversion of the window's mean voltage.

References
----------
.. [1] Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901 (§5: the 555 read by a
   microcontroller's timer; §6: the op-amp readout on an analog input).
.. [2] ATmega328P datasheet, section "ADC Conversion Result": ADC = V_IN·1024/V_REF, 0x3FF standing for
   V_REF minus one LSB (a truncating conversion).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.acquisition.messages import decode_sums
from fsrlab.errors import ParameterError
from fsrlab.hardware import ADC_COUNTS, ADC_V_PER_COUNT, TICK_S
from fsrlab.physics.params import check_at_least, check_finite, float_array
from fsrlab.virtual.arguments import random_generator

__all__ = ["NOISE_DRAWS", "MeterState", "MeterReadings", "adc_code", "measure"]

NOISE_DRAWS = 5
"""Standard normal draws :func:`measure` takes per window, as one array of shape (NOISE_DRAWS, n) with
rows: frequency, the window's last rising edge, the edge that opens the first period, the high-time
sum, the A0 voltage (drawn whatever the noise levels, so a seed gives the same noise for any settings)."""


def adc_code(voltage_v):
    """The Uno's 10-bit conversion, ``code = floor(V·1024/Vref)`` clipped to 0..1023.

    Parameters
    ----------
    voltage_v : float or array_like
        Voltage on A0 (finite or ±inf; out-of-range values clip). [V]

    Returns
    -------
    int or ndarray of int
        The ADC code, 0..:data:`~fsrlab.hardware.ADC_COUNTS` − 1.

    Raises
    ------
    ValueError
        A NaN voltage.

    Notes
    -----
    The ATmega328P's successive approximation truncates: ``ADC = V_IN·1024/V_REF`` rounded down [2]_,
    with the Uno's AVcc reference of 5 V; the code's voltage is ``code · Vref/1024``, ½ LSB below the
    middle of the interval it stands for.
    """
    v = float_array("voltage_v", voltage_v)
    if np.any(np.isnan(v)):
        raise ParameterError(f"must not be NaN, got {voltage_v!r}", parameter="voltage_v")
    code = np.clip(np.floor(v / ADC_V_PER_COUNT), 0, ADC_COUNTS - 1).astype(np.int64)
    return int(code) if code.ndim == 0 else code


@dataclass(frozen=True)
class MeterState:
    """What the meter carries from one window to the next.

    Parameters
    ----------
    phase : float
        555 cycles since START; the output rises where the phase is a whole number. [1]
    last_edge_ticks : float or None
        Time of the last captured rising edge, in ticks since the device clock started (its
        timestamp is the floor); None after START or a restarted window, when the next rising edge
        only opens a period. [ticks]
    """

    phase: float = 0.0
    last_edge_ticks: float | None = None

    @classmethod
    def started(cls, rng: np.random.Generator) -> MeterState:
        """State at START: a random phase of the 555 (one uniform draw), no edge captured yet.

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the phase.
        """
        return cls(phase=float(rng.random()))

    def restarted(self) -> MeterState:
        """State when a window restarts (``WINDOW`` while started): same phase, no edge captured."""
        return MeterState(self.phase)


@dataclass(frozen=True)
class MeterReadings:
    """The fields of the ``M`` frames of consecutive windows (arrays of one length).

    Parameters
    ----------
    periods : ndarray of int
        Complete periods that ended in each window.
    sum_period_ticks : ndarray of int
        Their summed length. [ticks]
    sum_high_ticks : ndarray of int
        Their summed high time. [ticks]
    adc : ndarray of int
        A0 reading, 0..1023.
    """

    periods: np.ndarray
    sum_period_ticks: np.ndarray
    sum_high_ticks: np.ndarray
    adc: np.ndarray

    @property
    def frequency_hz(self) -> np.ndarray:
        """Frequency as the host decodes it (:func:`~fsrlab.acquisition.messages.decode_sums`); NaN without
        periods. [Hz]"""
        return decode_sums(self.periods, self.sum_period_ticks, self.sum_high_ticks)[0]

    @property
    def duty_cycle(self) -> np.ndarray:
        """Duty cycle as the host decodes it; NaN without periods. [1]"""
        return decode_sums(self.periods, self.sum_period_ticks, self.sum_high_ticks)[1]

    @property
    def voltage_v(self) -> np.ndarray:
        """A0 voltage of the reading, ``adc · Vref/1024``. [V]"""
        return self.adc * ADC_V_PER_COUNT


def _nonnegative(**values) -> None:
    for name, v in values.items():
        check_at_least(name, v, 0.0, scalar=True)


def measure(frequency_hz, duty_cycle, voltage_v, window_s, state: MeterState | None = None,
            rng: np.random.Generator | int | None = None, start_s: float = 0.0, frequency_noise: float = 0.0,
            jitter_s: float = 0.0, adc_noise_v: float = 0.0) -> tuple[MeterReadings, MeterState]:
    """What the meter reports for consecutive windows of a 555 signal and an op-amp voltage.

    Parameters
    ----------
    frequency_hz : float or array_like, shape (n,)
        555 frequency in each window; NaN or ≤ 0 where it does not oscillate (no edges). [Hz]
    duty_cycle : float or array_like, shape (n,)
        555 high time over period in each window (clipped to 0..1). [1]
    voltage_v : float or array_like, shape (n,)
        Op-amp output on A0, mean over each window. [V]
    window_s : float or array_like, shape (n,)
        Length of each window (> 0); window i starts where window i − 1 ends. [s]
    state : MeterState, optional
        The state after the previous window; default a START (:meth:`MeterState.started`, its
        phase drawn from ``rng`` after the noise).
    rng : numpy.random.Generator or int, optional
        Source of the noise (a seed is turned into a generator); :data:`NOISE_DRAWS` standard
        normals per window.
    start_s : float
        Device time at which the first window starts. [s]
    frequency_noise : float
        Relative standard deviation of the frequency per window (sensor and circuit noise). [1]
    jitter_s : float
        Standard deviation of each captured rising edge's time (555 and comparator jitter). [s]
    adc_noise_v : float
        Standard deviation of the A0 voltage before conversion. [V]

    Returns
    -------
    (MeterReadings, MeterState)
        The windows' frame fields and the state after the last window.

    Notes
    -----
    With φ the phase at the window's start, the periods ending in the window are
    ``floor(φ + f·w) − floor(φ)`` (one fewer in the window that opens the first period). The last
    edge's time ``t = t0 + (floor(φ + f·w) − φ)/f`` [+ jitter] is captured as ``floor(t/q)`` with
    q = :data:`~fsrlab.hardware.TICK_S`; ``sum_period_ticks`` is the difference of the
    window's and the previous window's captures (≥ 1), within one tick of the true length. The high
    times: ``round(D·T/q + √(n/6)·z)`` with T the true summed length and n the periods, clipped to
    0..``sum_period_ticks``; the final rounding to whole ticks adds at most ½ tick. ADC:
    :func:`adc_code` of the voltage plus noise. The frequency noise moves the phase too, so the
    periods a window counts follow the noisy frequency.
    """
    named = {"frequency_hz": frequency_hz, "duty_cycle": duty_cycle, "voltage_v": voltage_v, "window_s": window_s}
    arrays = {name: np.atleast_1d(float_array(name, x)) for name, x in named.items()}
    shape = arrays["frequency_hz"].shape
    for name, a in arrays.items():
        try:
            shape = np.broadcast_shapes(shape, a.shape)
        except ValueError:
            raise ParameterError(f"must have the shape of frequency_hz {arrays['frequency_hz'].shape} or be one "
                                 f"number, got {a.shape}", parameter=name) from None
    f, duty, volts, w = np.broadcast_arrays(*arrays.values())
    if f.ndim != 1:
        raise ParameterError(f"frequency_hz, duty_cycle, voltage_v, window_s: need one dimension, got shape {f.shape}",
                             parameter="frequency_hz")
    if np.any(~(w > 0)) or np.any(~np.isfinite(w)):
        raise ParameterError(f"must be finite and > 0 s, got {window_s!r}", parameter="window_s")
    _nonnegative(frequency_noise=frequency_noise, jitter_s=jitter_s, adc_noise_v=adc_noise_v)
    check_finite("start_s", start_s, scalar=True)
    if state is not None and not isinstance(state, MeterState):
        raise TypeError(f"state: must be a MeterState (the one measure returned), got {type(state).__name__}")
    rng = random_generator("rng", rng)
    n = f.size
    z = rng.standard_normal((NOISE_DRAWS, n))
    state = state if state is not None else MeterState.started(rng)
    if n == 0:
        empty = np.zeros(0, dtype=np.int64)
        return MeterReadings(empty, empty, empty, empty), state

    fn = f * (1.0 + frequency_noise * z[0])
    osc = np.isfinite(fn) & (fn > 0)
    fn = np.where(osc, fn, 1.0)  # placeholder where nothing oscillates (no edges there)
    phi1 = state.phase + np.cumsum(np.where(osc, fn * w, 0.0))
    phi0 = np.concatenate([[state.phase], phi1[:-1]])
    last_k = np.floor(phi1)
    edges = np.where(osc, last_k - np.floor(phi0), 0).astype(np.int64)
    t0 = start_s + np.concatenate([[0.0], np.cumsum(w)[:-1]])
    last = (t0 + (last_k - phi0) / fn + jitter_s * z[1]) / TICK_S  # the window's last rising edge [ticks]

    has = edges > 0
    periods = edges.copy()
    before = np.maximum.accumulate(np.where(has, np.arange(n), -1))  # last window with an edge, up to i
    prev_idx = np.concatenate([[-1], before[:-1]])
    prev = np.where(prev_idx >= 0, last[np.maximum(prev_idx, 0)],
                    np.nan if state.last_edge_ticks is None else state.last_edge_ticks)
    if state.last_edge_ticks is None and np.any(has):
        i = int(np.argmax(has))  # the window whose first rising edge opens the first period
        if edges[i] > 1:
            prev[i] = (t0[i] + (np.floor(phi0[i]) + 1 - phi0[i]) / fn[i] + jitter_s * z[2, i]) / TICK_S
        else:
            prev[i] = last[i]
        periods[i] -= 1
    counted = periods > 0
    with np.errstate(invalid="ignore"):
        sum_p = np.where(counted, np.maximum(np.floor(last) - np.floor(prev), 1), 0).astype(np.int64)
        span = np.where(counted, last - prev, 0.0)
        high = np.rint(np.clip(duty, 0.0, 1.0) * span + np.sqrt(np.maximum(periods, 0) / 6.0) * z[3])
    sum_h = np.where(counted, np.clip(np.nan_to_num(high), 0, sum_p), 0).astype(np.int64)
    adc = np.atleast_1d(adc_code(volts + adc_noise_v * z[4]))

    last_edge = state.last_edge_ticks
    if np.any(has):
        last_edge = float(last[np.flatnonzero(has)[-1]])
    new_state = MeterState(phase=float(phi1[-1]), last_edge_ticks=last_edge)
    return MeterReadings(periods=periods, sum_period_ticks=sum_p, sum_high_ticks=sum_h, adc=adc), new_state
