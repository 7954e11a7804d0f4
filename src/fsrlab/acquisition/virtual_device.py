"""A virtual fsrlab meter: the firmware's protocol over a real pseudo-terminal, fed by the models.

:class:`VirtualDevice` opens a pseudo-terminal pair (``os.openpty``, raw mode), keeps the master
side and offers the slave's path (``/dev/pts/N``) to any program that opens serial ports. It answers
``ID``/``START``/``STOP``/``WINDOW``/``RANGE`` as docs/protocol.md prescribes and, while started,
sends one ``M`` frame per window, in real time.

What the 555 does during a window comes from a *signal source* (:class:`SignalSource`), injectable
for tests. :class:`PhysicsSource` is the default: a stress profile (:class:`StressProfile`) drives
:class:`fsrlab.physics.sensor.VirtualFSR` (stress → R_FSR, C_FSR with hysteresis memory), an
:class:`~fsrlab.circuits.circuit.LM555Circuit` (→ frequency, duty cycle) and an
:class:`~fsrlab.circuits.circuit.OpAmpReadout` on A0 (paper eq. 38). The device then measures with
the meter's model, :func:`fsrlab.acquisition.meter.measure`, window by window (the same model makes
the synthetic runs): rising edges on a continuous phase, edge times with jitter quantized to
62.5 ns Timer1 ticks, whole periods per window, the high times summed with their quantization
noise, the 10-bit A0 conversion. The load cell under the sensor and its HX711
(:mod:`fsrlab.acquisition.loadcell`, :class:`~fsrlab.acquisition.loadcell.LoadCellModel`) see the
applied force, stress × the sensor's area, and fill the ``M`` frame's reference (protocol version 2:
``ref_ok``, ``ref_n``, ``ref_mean``) with their own conversion times, noise and lag; ``load_cell=None``
emulates a meter without an HX711 (``ref_ok`` 0). Optional faults (:class:`Faults`) corrupt, drop or add bytes,
reset the device or unplug it, for tests.

References
----------
.. [1] Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901 (§5 Figs. 13–16, §6 eq. 38).
"""

from __future__ import annotations

import errno
import math
import os
import select
import threading
import time
import tty
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from fsrlab.acquisition.loadcell import LoadCellModel, window_reference
from fsrlab.acquisition.meter import MeterState, measure
from fsrlab.acquisition.protocol import (
    DEVICE_NAME, F_CPU, MAX_COMMAND, PROTOCOL_VERSION, SEQ_MODULO, UINT32_MODULO, WINDOW_MS_DEFAULT, CommandError,
    encode_frame, parse_command,
)
from fsrlab.circuits.circuit import LM555Circuit, OpAmpReadout
from fsrlab.physics.params import PAPER_CIRCUIT, PAPER_OPAMP
from fsrlab.physics.sensor import A201_AREA_M2

__all__ = ["FIRMWARE_VERSION", "Signal", "SignalSource", "ConstantSource", "StressProfile", "PhysicsSource",
           "sensor_metadata", "Faults", "VirtualDevice", "PROFILE_KINDS", "VIRTUAL_CIRCUIT"]

FIRMWARE_VERSION = "1.0.0-virtual"
"""Firmware version the virtual device reports in its ``ID`` frame."""
PROFILE_KINDS = ("triangle", "sine", "steps", "hold")
"""Shapes of :class:`StressProfile`."""


@dataclass(frozen=True)
class Signal:
    """What the meter's inputs carry during one window.

    Attributes
    ----------
    frequency_hz : float
        Frequency of the 555 output; NaN or 0 when it does not oscillate. [Hz]
    duty_cycle : float
        High time over period, 0..1. [1]
    voltage_v : float
        Op-amp output on A0. [V]
    stress_pa : float
        The applied stress (reference, not sent on the link; NaN if unknown). [Pa]
    """

    frequency_hz: float
    duty_cycle: float
    voltage_v: float = 0.0
    stress_pa: float = math.nan


class SignalSource(Protocol):
    """Anything that says what the 555 and the op-amp do during a window.

    An object with a method ``window(t0_s, t1_s, range_) -> Signal``; see :class:`ConstantSource`
    and :class:`PhysicsSource`.
    """

    def window(self, t0_s: float, t1_s: float, range_: int) -> Signal:
        """Signal averaged over ``[t0_s, t1_s)`` (time since START [s]) with the C_off switch at ``range_``."""
        ...


@dataclass(frozen=True)
class ConstantSource:
    """A fixed square wave (for protocol tests).

    Parameters
    ----------
    frequency_hz : float
        Frequency of the wave. [Hz]
    duty_cycle : float
        High time over period. [1]
    voltage_v : float
        Voltage on A0. [V]
    stress_pa : float
        Reference stress reported by :meth:`VirtualDevice.reference`. [Pa]
    area_m2 : float
        Sensor area, for the force on the load cell (stress × area; NaN stress: no force). [m²]
    """

    frequency_hz: float = 5000.0
    duty_cycle: float = 0.5
    voltage_v: float = 1.0
    stress_pa: float = math.nan
    area_m2: float = A201_AREA_M2

    def window(self, t0_s: float, t1_s: float, range_: int) -> Signal:
        """The same :class:`Signal` for every window."""
        return Signal(self.frequency_hz, self.duty_cycle, self.voltage_v, self.stress_pa)

    def force_n(self, t_s) -> np.ndarray:
        """Force on the load cell at times ``t_s`` [s]: stress × area, 0 when the stress is unknown. [N]"""
        f = self.stress_pa * self.area_m2 if math.isfinite(self.stress_pa) else 0.0
        return np.full(np.shape(t_s), f)


@dataclass(frozen=True)
class StressProfile:
    """A periodic stress profile σ(t), like the paper's stepper-motor bench (§6.1).

    Parameters
    ----------
    kind : str
        ``triangle`` (linear load and unload), ``sine`` (raised cosine), ``steps`` (5 stairs up, 5
        down) or ``hold`` (constant ``peak_pa``).
    peak_pa : float
        Largest stress (> base_pa). [Pa]
    period_s : float
        Duration of one loading-unloading cycle (> 0). [s]
    base_pa : float
        Smallest stress (≥ 0). [Pa]
    """

    kind: str = "triangle"
    peak_pa: float = 50e3
    period_s: float = 4.0
    base_pa: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in PROFILE_KINDS:
            raise ValueError(f"profile kind must be one of {', '.join(PROFILE_KINDS)}, got {self.kind!r}")
        if not self.period_s > 0:
            raise ValueError(f"period_s must be > 0 s, got {self.period_s!r}")
        if not self.peak_pa > self.base_pa >= 0:
            raise ValueError(f"peak_pa must exceed base_pa >= 0 Pa, got {self.peak_pa!r} and {self.base_pa!r}")

    def stress(self, t_s) -> np.ndarray:
        """Stress at time ``t_s`` [s] since START; returns [Pa], same shape."""
        t = np.asarray(t_s, dtype=float)
        x = np.mod(t / self.period_s, 1.0)
        if self.kind == "triangle":
            u = 1.0 - np.abs(2.0 * x - 1.0)
        elif self.kind == "sine":
            u = 0.5 - 0.5 * np.cos(2.0 * np.pi * x)
        elif self.kind == "steps":
            u = np.minimum(np.floor((1.0 - np.abs(2.0 * x - 1.0)) * 5.0 + 1e-9), 5.0) / 5.0
        else:
            u = np.ones_like(x)
        return self.base_pa + (self.peak_pa - self.base_pa) * u


VIRTUAL_CIRCUIT = PAPER_CIRCUIT.replace(c_off_farad=1e-9)
"""The virtual device's 555: the paper's circuit (:data:`~fsrlab.physics.params.PAPER_CIRCUIT`) with a
1 nF C_off that ``RANGE 1`` switches in."""


def sensor_metadata(sensor) -> dict:
    """What a run's sidecar says about a virtual sensor.

    Parameters
    ----------
    sensor : object
        A virtual sensor with ``respond`` and ``area_m2`` (``VirtualFSR``, a paper sensor).

    Returns
    -------
    dict
        ``model`` (class and module; the VirtualFSR is FlexiForce A201-like), ``name`` (when the
        sensor has one, e.g. ``paper-a201-1``) and ``area_m2`` [m²].
    """
    cls = type(sensor)
    model = f"{cls.__name__} ({cls.__module__})"
    if cls.__name__ == "VirtualFSR":
        model = "VirtualFSR (FlexiForce A201-like, fsrlab.physics.sensor)"
    name = getattr(sensor, "name", None)
    return {"model": model, **({"name": name} if isinstance(name, str) else {}), "area_m2": float(sensor.area_m2)}


class PhysicsSource:
    """Signal from a stress profile through the virtual FSR, the LM555 astable and the op-amp.

    Parameters
    ----------
    profile : StressProfile
        σ(t).
    sensor : VirtualFSR, optional
        Default ``fsrlab.physics.sensor.VirtualFSR()``.
    circuit : LM555Circuit
        The 555 readout; its C_off is in circuit on ``RANGE 1`` only (:meth:`LM555Circuit.on_range`).
        R_FSR is taken at Vcc/2, the middle of the capacitor's swing.
    opamp : OpAmpReadout
        The traditional readout on A0 (eq. 38), with R_FSR taken at its |Vcc|
        (:attr:`OpAmpReadout.fsr_voltage_v`).
    dt_s : float
        Time step on which the stress history is sampled. [s]

    Notes
    -----
    The hysteresis memory needs the whole stress history, so R_FSR and C_FSR are computed once for
    two periods of the profile; from the second period on the response repeats (a periodic
    profile reaches its steady loop after the first cycle), and later times map into it.
    """

    def __init__(self, profile: StressProfile | None = None, sensor=None, circuit: LM555Circuit = VIRTUAL_CIRCUIT,
                 opamp: OpAmpReadout = PAPER_OPAMP, dt_s: float = 0.005) -> None:
        from fsrlab.physics.sensor import VirtualFSR

        if not dt_s > 0:
            raise ValueError(f"dt_s must be > 0, got {dt_s!r}")
        for name, obj, cls in (("circuit", circuit, LM555Circuit), ("opamp", opamp, OpAmpReadout)):
            if not isinstance(obj, cls):
                raise ValueError(f"{name} must be an {cls.__name__}, got {type(obj).__name__}")
        self.profile = profile or StressProfile()
        self.sensor = sensor if sensor is not None else VirtualFSR()
        self.circuit, self.opamp = circuit, opamp
        period = self.profile.period_s
        self.dt_s = min(dt_s, period / 20)
        self._t = np.arange(0.0, 2 * period + self.dt_s, self.dt_s)
        stress = self.profile.stress(self._t)
        resp = self.sensor.respond(stress, voltage_v=circuit.fsr_voltage_v)
        self._stress = np.asarray(resp.stress_pa, dtype=float)
        self._r = np.asarray(resp.r_fsr_ohm, dtype=float)
        self._c = np.asarray(resp.c_fsr_farad, dtype=float)
        r_opamp = self.sensor.respond(stress, voltage_v=opamp.fsr_voltage_v).r_fsr_ohm
        self._v = np.asarray(opamp.output_v(r_opamp), dtype=float)  # Eq. (38)

    def metadata(self) -> dict:
        """Sidecar content of a run recorded from this source: ``circuit``, ``opamp``, ``sensor``."""
        return {"circuit": self.circuit.to_dict(), "opamp": self.opamp.to_dict(),
                "sensor": sensor_metadata(self.sensor)}

    def force_n(self, t_s) -> np.ndarray:
        """Applied force at times ``t_s`` since START [s]: the profile's stress × the sensor's area. [N]"""
        return self.profile.stress(t_s) * self.sensor.area_m2

    def parts(self, t_s):
        """Sensor state at times ``t_s``: the source's own samples (grid ``k·dt_s``, hysteresis memory
        included) held from one sample to the next (zero-order hold).

        Parameters
        ----------
        t_s : array_like
            Times since the start of the profile (≥ 0). [s]

        Returns
        -------
        r_fsr_ohm : ndarray
            R_FSR at the 555's voltage. [Ω]
        c_fsr_farad : ndarray
            C_FSR. [F]
        a0_v : ndarray
            Op-amp output (eq. 38). [V]
        """
        t = np.asarray(t_s, dtype=float)
        idx = self._index(np.floor(t / self.dt_s + 1e-9) * self.dt_s)  # the grid :meth:`window` samples
        return self._r[idx], self._c[idx], self._v[idx]

    def _index(self, t_s: np.ndarray) -> np.ndarray:
        period = self.profile.period_s
        t = np.where(t_s < 2 * period, t_s, period + np.mod(t_s - period, period))
        return np.clip(np.round(t / self.dt_s).astype(int), 0, self._t.size - 1)

    def window(self, t0_s: float, t1_s: float, range_: int) -> Signal:
        """Mean signal over the window (see :class:`SignalSource`)."""
        n = max(2, int(math.ceil((t1_s - t0_s) / self.dt_s)) + 1)
        idx = self._index(np.linspace(max(t0_s, 0.0), max(t1_s, 0.0), n))
        osc = self.circuit.on_range(range_).astable(self._r[idx], self._c[idx], check=False)
        period = np.asarray(osc.tau_high_s) + np.asarray(osc.tau_low_s)
        if not np.all(np.isfinite(period)):
            f = duty = math.nan
        else:
            # The meter measures whole periods: mean frequency = 1/mean period, duty = ΣτH/ΣT.
            f = 1.0 / float(np.mean(period))
            duty = float(np.mean(osc.tau_high_s) / np.mean(period))
        return Signal(f, duty, float(np.mean(self._v[idx])), float(np.mean(self._stress[idx])))


@dataclass
class Faults:
    """Faults the virtual device injects (all off by default).

    Parameters
    ----------
    corrupt : float
        Probability that a frame gets one bit flipped. [1]
    drop : float
        Probability that a frame is not sent (its sequence number is used). [1]
    garbage : float
        Probability of 1–20 random bytes before a frame. [1]
    reset_after : int, optional
        Restart the device (mid-frame) after this many ``M`` frames: the host sees a cut line, the
        boot ``ID`` with sequence 0, and a stopped device.
    unplug_after : int, optional
        Close the pseudo-terminal after this many ``M`` frames (a pulled USB cable).
    """

    corrupt: float = 0.0
    drop: float = 0.0
    garbage: float = 0.0
    reset_after: int | None = None
    unplug_after: int | None = None

    def __post_init__(self) -> None:
        for name in ("corrupt", "drop", "garbage"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be in 0..1, got {v!r}")
        for name in ("reset_after", "unplug_after"):
            v = getattr(self, name)
            if v is not None and v < 0:
                raise ValueError(f"{name} must be >= 0 frames, got {v!r}")


@dataclass
class _State:
    seq: int = 0
    started: bool = False
    window_ms: int = WINDOW_MS_DEFAULT
    current_ms: int = WINDOW_MS_DEFAULT  # length of the window in progress (WINDOW acts on the next one)
    range_: int = 0
    window_start: float = 0.0  # device time [s]
    start_time: float = 0.0
    meter: MeterState = field(default_factory=MeterState)  # the 555's phase and the last captured edge
    m_frames: int = 0
    resets_done: int = 0
    line: bytearray = field(default_factory=bytearray)
    overflow: bool = False


class VirtualDevice:
    """The fsrlab meter's protocol on a pseudo-terminal, driven by a signal source.

    Parameters
    ----------
    source : SignalSource, optional
        What the 555 does; default :class:`PhysicsSource` with the default triangle profile.
    frequency_noise : float
        Relative standard deviation of the frequency per window (sensor and circuit noise). [1]
    jitter_s : float
        Standard deviation of each captured edge time (555 and comparator jitter). [s]
    adc_noise_v : float
        Standard deviation of the A0 voltage before 10-bit quantization. [V]
    faults : Faults, optional
        Fault injection for tests.
    seed : int, optional
        Random seed (noise and faults).
    load_cell : LoadCellModel or None
        The load cell and HX711 under the sensor (default :class:`LoadCellModel()`: 80 samples/s);
        None: no HX711 (``ref_ok`` 0 in every frame). Its noise has a random stream of its own, so
        the 555's and A0's numbers for a seed do not depend on it.

    Notes
    -----
    Use as a context manager, or call :meth:`open` (returns the pty path and runs the device in a
    thread) and :meth:`close`; :meth:`serve` runs it in the calling thread instead. Times: the
    device clock starts at :meth:`open` (``t_ms``), the profile's clock at ``START``.

    An exception inside the device (a signal source that raises, say) ends it without a traceback:
    the pseudo-terminal closes, as a pulled cable, and :attr:`failure` says why.
    """

    def __init__(self, source: SignalSource | None = None, frequency_noise: float = 1e-3, jitter_s: float = 20e-9,
                 adc_noise_v: float = 2e-3, faults: Faults | None = None, seed: int | None = None,
                 load_cell: LoadCellModel | None = LoadCellModel()) -> None:
        for name, v in (("frequency_noise", frequency_noise), ("jitter_s", jitter_s), ("adc_noise_v", adc_noise_v)):
            if not v >= 0:
                raise ValueError(f"{name} must be >= 0, got {v!r}")
        self.source = source if source is not None else PhysicsSource()
        self.frequency_noise, self.jitter_s, self.adc_noise_v = frequency_noise, jitter_s, adc_noise_v
        self.faults = faults or Faults()
        self._rng = np.random.default_rng(seed)
        if load_cell is not None and not isinstance(load_cell, LoadCellModel):
            raise ValueError(f"load_cell must be a LoadCellModel or None, got {type(load_cell).__name__}")
        self.load_cell = load_cell
        self._cell_rng = np.random.default_rng(None if seed is None else [seed, 711])
        self._master: int | None = None
        self._slave: int | None = None
        self.port: str | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._t0 = 0.0
        self._st = _State()
        self._truth: OrderedDict[int, float] = OrderedDict()
        self.frames_sent = 0
        self.frames_overflowed = 0
        self.unplugged = False
        self.error: Exception | None = None

    # ------------------------------------------------------------ lifecycle
    def open(self, thread: bool = True) -> str:
        """Create the pseudo-terminal, send the boot ``ID`` and (by default) run in a daemon thread.

        Returns
        -------
        str
            Path of the pty slave for ``serial_for_url``.
        """
        master, slave = os.openpty()
        tty.setraw(slave)  # no echo, no newline translation: bytes pass as on a UART
        os.set_blocking(master, False)
        self._master, self._slave = master, slave
        self.port = os.ttyname(slave)
        self._t0 = time.monotonic()
        self._boot()
        if thread:
            self._thread = threading.Thread(target=self._loop, name="fsrlab-virtual-device", daemon=True)
            self._thread.start()
        return self.port

    def serve(self, duration_s: float | None = None) -> None:
        """Run in the calling thread until :meth:`close`, Ctrl-C, or ``duration_s`` seconds."""
        if self._master is None:
            self.open(thread=False)
        self._loop(None if duration_s is None else time.monotonic() + duration_s)

    def close(self) -> None:
        """Stop the device and close the pseudo-terminal."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        self._close_fds()

    def unplug(self) -> None:
        """Close the pseudo-terminal now, as a pulled cable: the host's next read fails."""
        self.unplugged = True
        self._stop.set()
        self._close_fds()

    def _close_fds(self) -> None:
        for name in ("_master", "_slave"):
            fd = getattr(self, name)
            if fd is not None:
                setattr(self, name, None)
                try:
                    os.close(fd)
                except OSError:
                    pass

    def __enter__(self) -> "VirtualDevice":
        if self._master is None:
            self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def failure(self) -> str | None:
        """None while the device runs or after a normal end; one line saying why it failed otherwise."""
        if self.error is None:
            return None
        return " ".join(f"device thread failed: {type(self.error).__name__}: {self.error}".split())

    def time_since_start(self) -> float:
        """Time since ``START`` on the device's clock, the signal source's time (NaN when stopped). [s]"""
        st = self._st
        return self._now() - st.start_time if st.started else math.nan

    def _force_at(self, sig: Signal):
        source_force = getattr(self.source, "force_n", None)
        if callable(source_force):
            return source_force
        f = sig.stress_pa * A201_AREA_M2 if math.isfinite(sig.stress_pa) else 0.0  # a source without a force
        return lambda t: np.full(np.shape(t), f)

    def reference(self, seq: int) -> float:
        """Stress [Pa] the device applied during the window sent with sequence number ``seq`` (NaN if unknown)."""
        return self._truth.get(seq, math.nan)

    # ------------------------------------------------------------ device
    def _now(self) -> float:
        return time.monotonic() - self._t0

    def _boot(self) -> None:
        self._st = _State(resets_done=self._st.resets_done, m_frames=self._st.m_frames)
        self._send_frame("ID", (DEVICE_NAME, FIRMWARE_VERSION, PROTOCOL_VERSION, F_CPU), faults=False)

    def _send_frame(self, kind: str, fields, faults: bool = True) -> int:
        st = self._st
        seq = st.seq
        st.seq = (st.seq + 1) % SEQ_MODULO
        data = encode_frame(kind, seq, fields)
        f, rng = self.faults, self._rng
        if faults and f.drop and rng.random() < f.drop:
            return seq
        if faults and f.corrupt and rng.random() < f.corrupt:
            b = bytearray(data)
            b[int(rng.integers(len(b)))] ^= 1 << int(rng.integers(8))
            data = bytes(b)
        if faults and f.garbage and rng.random() < f.garbage:
            data = rng.integers(0, 256, int(rng.integers(1, 21)), dtype=np.uint8).tobytes() + data
        self._write(data)
        return seq

    def _write(self, data: bytes) -> None:
        if self._master is None:
            return
        try:
            os.write(self._master, data)
            self.frames_sent += 1
        except BlockingIOError:
            self.frames_overflowed += 1  # the host does not read: bytes are lost, as on a UART
        except OSError as exc:
            if exc.errno not in (errno.EIO, errno.EBADF):
                raise

    def _handle_line(self, raw: bytes) -> None:
        st = self._st
        try:
            name, value = parse_command(raw)
        except CommandError as err:
            self._send_frame("ERR", (err.code, err.token), faults=False)
            return
        if name == "ID":  # the ID frame, then the ACK, as the firmware does
            self._send_frame("ID", (DEVICE_NAME, FIRMWARE_VERSION, PROTOCOL_VERSION, F_CPU), faults=False)
        elif name == "START" and not st.started:
            st.started = True
            st.window_start = st.start_time = self._now()
            st.current_ms = st.window_ms
            st.meter = MeterState.started(self._rng)
        elif name == "STOP":
            st.started = False
        elif name == "WINDOW":
            st.window_ms = int(value)
            if st.started:  # as the firmware: the window in progress restarts with the new length
                st.window_start = self._now()
                st.current_ms = st.window_ms
                st.meter = st.meter.restarted()
        elif name == "RANGE":
            st.range_ = int(value)
        self._send_frame("ACK", (name,) if value is None else (name, value), faults=False)

    def _feed_commands(self, data: bytes) -> None:
        st = self._st
        for byte in data:
            if byte == 0x0A:
                if st.overflow:
                    self._send_frame("ERR", (3, "LINE"), faults=False)
                else:
                    self._handle_line(bytes(st.line))
                st.line.clear()
                st.overflow = False
            elif not st.overflow:
                st.line.append(byte)
                if len(st.line) > MAX_COMMAND - 1 + st.line.count(b"\r"):
                    st.overflow = True
                    st.line.clear()

    def _measure(self, t_end: float) -> None:
        """Close the current window at device time ``t_end`` and send its ``M`` frame."""
        st = self._st
        t0, t1 = st.window_start, t_end
        sig = self.source.window(t0 - st.start_time, t1 - st.start_time, st.range_)
        m, st.meter = measure(sig.frequency_hz, sig.duty_cycle, sig.voltage_v, t1 - t0, state=st.meter,
                              rng=self._rng, start_s=t0, frequency_noise=self.frequency_noise,
                              jitter_s=self.jitter_s, adc_noise_v=self.adc_noise_v)
        u32 = UINT32_MODULO - 1
        ref = window_reference(self.load_cell, self._force_at(sig), t0 - st.start_time, t1 - st.start_time,
                               rng=self._cell_rng)
        fields = (int(t1 * 1000) % UINT32_MODULO, st.current_ms, int(m.periods[0]), min(int(m.sum_period_ticks[0]), u32),
                  min(int(m.sum_high_ticks[0]), u32), 0, int(m.adc[0]), st.range_, ref.ref_ok, ref.ref_n, ref.ref_mean)
        fault = self.faults
        st.m_frames += 1
        if fault.reset_after is not None and st.m_frames > fault.reset_after and st.resets_done == 0:
            st.resets_done = 1
            self._write(encode_frame("M", st.seq, fields)[:17])  # cut mid-line by the reset
            self._boot()
            return
        self._truth[st.seq] = sig.stress_pa  # before sending: the host may look it up at once
        self._send_frame("M", fields)
        while len(self._truth) > 8192:
            self._truth.popitem(last=False)
        if fault.unplug_after is not None and st.m_frames >= fault.unplug_after:
            self.unplug()

    def _loop(self, deadline: float | None = None) -> None:
        try:
            while not self._stop.is_set():
                if deadline is not None and time.monotonic() >= deadline:
                    return
                st = self._st
                now = self._now()
                wait = 0.05
                if st.started:
                    t_end = st.window_start + st.current_ms / 1000.0
                    if now >= t_end:
                        self._measure(t_end)
                        st = self._st
                        if st.started:
                            st.window_start = t_end
                            st.current_ms = st.window_ms
                        continue
                    wait = min(wait, t_end - now)
                master = self._master
                if master is None:
                    return
                try:
                    ready, _, _ = select.select([master], [], [], max(wait, 0.0))
                except (OSError, ValueError):
                    return
                if ready:
                    try:
                        data = os.read(master, 1024)
                    except BlockingIOError:
                        continue
                    except OSError:
                        return
                    self._feed_commands(data)
        except KeyboardInterrupt:
            return
        except Exception as exc:  # noqa: BLE001 - any failure ends the device, as a pulled cable; see failure
            self.error = exc
            self._stop.set()
            self._close_fds()
