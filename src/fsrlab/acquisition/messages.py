"""The device's frames in physical units: measurement windows, identity, acknowledgements, errors.

A frame of :mod:`fsrlab.acquisition.protocol` (its framing, checked fields and constants) becomes one
of these values: an ``M`` frame a :class:`Measurement` (frequency and duty cycle from the window's
tick sums, :func:`decode_sums`; the A0 voltage), ``ID`` an :class:`Identity`, ``ACK`` an :class:`Ack`,
``ERR`` a :class:`DeviceError`. ``docs/protocol.md`` is the normative description.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fsrlab.acquisition.protocol import M_FIELDS_V2, M_FIELDS_V3, Frame, ProtocolError, check_fields
from fsrlab.hardware import ADC_V_PER_COUNT, F_CPU

__all__ = ["decode_sums", "Measurement", "Identity", "Ack", "DeviceError"]


def decode_sums(periods, sum_period_ticks, sum_high_ticks):
    """Frequency and duty cycle from a window's sums, as the host decodes an ``M`` frame.

    Parameters
    ----------
    periods : int or array_like
        Complete periods in the window (0: no signal).
    sum_period_ticks, sum_high_ticks : int or array_like
        Sums of the periods and of the high times over those periods. [ticks of :data:`TICK_S`]

    Returns
    -------
    (frequency_hz, duty_cycle) : floats, or ndarrays for array input
        ``f = periods · F_CPU / sum_period_ticks`` [Hz] and ``duty = sum_high_ticks / sum_period_ticks``
        [1]; NaN where ``periods == 0``.
    """
    import numpy as np

    from fsrlab.physics.params import float_array

    n, p, h = (float_array(name, x) for name, x in
               (("periods", periods), ("sum_period_ticks", sum_period_ticks), ("sum_high_ticks", sum_high_ticks)))
    try:
        n, p, h = np.broadcast_arrays(n, p, h)
    except ValueError:
        from fsrlab.errors import ParameterError

        raise ParameterError(f"must have the shape of periods {n.shape} and sum_period_ticks {p.shape}, got {h.shape}",
                             parameter="sum_high_ticks") from None
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.where(n > 0, n * F_CPU / p, math.nan)
        duty = np.where(n > 0, h / p, math.nan)
    return (float(f), float(duty)) if f.ndim == 0 else (f, duty)


@dataclass(frozen=True, slots=True)
class Measurement:
    """One measurement window (an ``M`` frame) in physical units.

    Attributes
    ----------
    seq : int
        Sequence number of the frame.
    t_ms : int
        Device time at the end of the window. [ms]
    window_ms : int
        Window length. [ms]
    periods : int
        Complete periods of the 555 output in the window.
    sum_period_ticks, sum_high_ticks : int
        Sums over those periods of the period and of the high time, in 62.5 ns ticks.
    missed : int
        Edges missed or rejected by the firmware in the window.
    adc : int
        Mean A0 reading, 0..1023 (op-amp output, traditional readout).
    range : int
        State of the C_off switch (1 = C_off connected).
    frequency_hz : float
        ``periods · F_CPU / sum_period_ticks``; NaN when ``periods == 0`` (no signal). [Hz]
    duty_cycle : float
        ``sum_high_ticks / sum_period_ticks``, 0..1; NaN when ``periods == 0``.
    ref_ok : int or None
        Protocol v2: 1 when the load cell's HX711 answers (a conversion completed in the last second),
        0 when none is connected or it stopped answering; None for a version-1 frame (no reference input).
    ref_n : int
        HX711 conversions that completed in the window (0 for version 1, with no HX711, or when a slow
        HX711 finished none in this window).
    ref_mean : float
        Mean of those conversions, raw 24-bit two's-complement counts as the firmware rounds it
        (``floor(sum/n + 1/2)``); NaN when ``ref_n == 0``, never 0 in its place. [count]
    channel : int
        Protocol v3: the multiplexer channel the window measured (0..7); 0 for versions 1 and 2.
    scan : int or None
        Protocol v3: the scan the reading belongs to (a single channel: the window's number since
        ``START``), modulo 65536; None for versions 1 and 2.
    """

    seq: int
    t_ms: int
    window_ms: int
    periods: int
    sum_period_ticks: int
    sum_high_ticks: int
    missed: int
    adc: int
    range: int
    frequency_hz: float
    duty_cycle: float
    ref_ok: int | None = None
    ref_n: int = 0
    ref_mean: float = math.nan
    channel: int = 0
    scan: int | None = None

    @classmethod
    def from_frame(cls, frame: Frame) -> Measurement:
        """Decode an ``M`` frame.

        Parameters
        ----------
        frame : Frame
            A frame of kind ``M`` (as returned by :class:`FrameParser`).

        Returns
        -------
        Measurement

        Raises
        ------
        ProtocolError
            When the frame is not a valid ``M`` frame.
        """
        if frame.kind != "M":
            raise ProtocolError(f"frame kind must be 'M' for a measurement, got {frame.kind!r}")
        check_fields("M", frame.fields)
        t_ms, window, periods, sum_p, sum_h, missed, adc, rng = (int(f) for f in frame.fields[:8])
        f, duty = decode_sums(periods, sum_p, sum_h)
        if len(frame.fields) >= M_FIELDS_V2:
            ref_ok, ref_n, ref_mean = (int(x) for x in frame.fields[8:11])
            channel, scan = (int(frame.fields[11]), int(frame.fields[12])) if len(frame.fields) == M_FIELDS_V3 \
                else (0, None)
            return cls(frame.seq, t_ms, window, periods, sum_p, sum_h, missed, adc, rng, f, duty,
                       ref_ok, ref_n, float(ref_mean) if ref_n > 0 else math.nan, channel, scan)
        return cls(frame.seq, t_ms, window, periods, sum_p, sum_h, missed, adc, rng, f, duty)

    @property
    def adc_v(self) -> float:
        """A0 voltage for the Uno's 5 V reference (``adc · ADC_V_PER_COUNT``). [V]"""
        return self.adc * ADC_V_PER_COUNT


@dataclass(frozen=True, slots=True)
class Identity:
    """The device's answer to ``ID`` (also sent once at boot).

    Attributes
    ----------
    seq : int
        Sequence number of the frame.
    name : str
        Device name (``fsrlab-meter``).
    firmware_version : str
        Firmware version, e.g. ``1.0.0``.
    protocol_version : int
        Protocol version (2; version-1 devices send 1).
    f_cpu_hz : int
        Device clock. [Hz]
    """

    seq: int
    name: str
    firmware_version: str
    protocol_version: int
    f_cpu_hz: int

    @classmethod
    def from_frame(cls, frame: Frame) -> Identity:
        """Decode an ``ID`` frame; raises :class:`ProtocolError` for any other kind."""
        if frame.kind != "ID":
            raise ProtocolError(f"frame kind must be 'ID', got {frame.kind!r}")
        check_fields("ID", frame.fields)
        name, fw, proto, fcpu = frame.fields
        return cls(frame.seq, name, fw, int(proto), int(fcpu))


@dataclass(frozen=True, slots=True)
class Ack:
    """``$ACK``: the device accepted a command.

    Attributes
    ----------
    seq : int
        Sequence number of the frame.
    command : str
        The command word.
    value : int or None
        The value in force for ``WINDOW`` [ms] and ``RANGE``; None for the others.
    """

    seq: int
    command: str
    value: int | None

    @classmethod
    def from_frame(cls, frame: Frame) -> Ack:
        """Decode an ``ACK`` frame; raises :class:`ProtocolError` for any other kind."""
        if frame.kind != "ACK":
            raise ProtocolError(f"frame kind must be 'ACK', got {frame.kind!r}")
        check_fields("ACK", frame.fields)
        return cls(frame.seq, frame.fields[0], int(frame.fields[1]) if len(frame.fields) == 2 else None)


@dataclass(frozen=True, slots=True)
class DeviceError:
    """``$ERR``: the device rejected a command.

    Attributes
    ----------
    seq : int
        Sequence number of the frame.
    code : int
        1 unknown command, 2 bad value, 3 line too long.
    token : str
        The command word as the device read it (``LINE`` for code 3, ``?`` when empty).
    """

    seq: int
    code: int
    token: str

    @classmethod
    def from_frame(cls, frame: Frame) -> DeviceError:
        """Decode an ``ERR`` frame; raises :class:`ProtocolError` for any other kind."""
        if frame.kind != "ERR":
            raise ProtocolError(f"frame kind must be 'ERR', got {frame.kind!r}")
        check_fields("ERR", frame.fields)
        return cls(frame.seq, int(frame.fields[0]), frame.fields[1])
