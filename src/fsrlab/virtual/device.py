"""A virtual fsrlab meter: the firmware's protocol over a real pseudo-terminal, fed by the models.

:class:`VirtualDevice` opens a pseudo-terminal pair (``os.openpty``, raw mode), keeps the master
side and offers the slave's path (``/dev/pts/N``) to any program that opens serial ports. It answers
``ID``/``START``/``STOP``/``WINDOW``/``RANGE``/``SCAN``/``DWELL``/``SETTLE`` as docs/protocol.md prescribes
and, while started, sends one ``M`` frame per window (per channel reading in a scan): in real time
(``speed="realtime"``), or as fast as the host reads
them (``speed="max"``: the device's clock is simulated and moves one window at a time, each frame
written once the host has read all but a few of the ones before, so nothing is lost and the
windows' times are the same simulated time axis).

What the 555 does during a window comes from a *signal source*
(:class:`~fsrlab.virtual.sources.SignalSource`, :mod:`fsrlab.virtual.sources`), injectable for tests.
:class:`~fsrlab.virtual.sources.PhysicsSource` is the default: a stress profile (:class:`StressProfile`) drives
:class:`fsrlab.physics.sensor.VirtualFSR` (stress → R_FSR, C_FSR with hysteresis memory), an
:class:`~fsrlab.circuits.circuit.LM555Circuit` (→ frequency, duty cycle) and an
:class:`~fsrlab.circuits.circuit.OpAmpReadout` on A0 (paper eq. 38). The device then measures with
the meter's model, :func:`fsrlab.virtual.meter.measure`, window by window (the same model makes
the synthetic runs): rising edges on a continuous phase, edge times with jitter quantized to
62.5 ns Timer1 ticks, whole periods per window, the high times summed with their quantization
noise, the 10-bit A0 conversion. The load cell under the sensor and its HX711
(:mod:`fsrlab.acquisition.loadcell`, :class:`~fsrlab.acquisition.loadcell.LoadCellModel`) see the
applied force, stress × the sensor's area, and fill the ``M`` frame's reference (protocol version 2:
``ref_ok``, ``ref_n``, ``ref_mean``) with their own conversion times, noise and lag; ``load_cell=None``
emulates a meter without an HX711 (``ref_ok`` 0). With a :class:`~fsrlab.virtual.sources.MuxSource` the
device has a multiplexer: a scan of more than one channel measures each for ``DWELL`` ms after the time the
firmware spends settling (the first edge after the switch and ``SETTLE`` periods), an open channel
gives readings without periods; A0 and the load cell follow the source's reference channel.
A plain source is channel 0, the other channels are open. Optional faults (:class:`Faults`) corrupt, drop or add bytes,
reset the device or unplug it, for tests.

References
----------
.. [1] Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901 (§5 Figs. 13–16, §6 eq. 38).
"""

from __future__ import annotations

import errno
import fcntl
import math
import os
import select
import termios
import threading
import time
import tty
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from fsrlab.acquisition.loadcell import LoadCellModel, window_reference
from fsrlab.acquisition.protocol import (
    DEVICE_NAME,
    DWELL_MS_DEFAULT,
    MAX_COMMAND,
    PROTOCOL_VERSION,
    SEQ_MODULO,
    SETTLE_DEFAULT,
    UINT32_MODULO,
    WINDOW_MS_DEFAULT,
    CommandError,
    encode_frame,
    mask_channels,
    parse_command,
)
from fsrlab.errors import ParameterError
from fsrlab.hardware import F_CPU
from fsrlab.physics.params import check_at_least, check_between, check_int
from fsrlab.physics.sensor import A201_AREA_M2
from fsrlab.virtual.meter import MeterState, measure
from fsrlab.virtual.sources import PhysicsSource, Signal, SignalSource

__all__ = ["FIRMWARE_VERSION", "SPEEDS", "Faults", "VirtualDevice"]

SPEEDS = ("realtime", "max")
"""Pacing of the device's clock: ``realtime`` (the wall clock) or ``max`` (simulated, as fast as the host reads)."""

FIRMWARE_VERSION = "3.0.0-virtual"
"""Firmware version the virtual device reports in its ``ID`` frame."""


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
            check_between(name, getattr(self, name), 0.0, 1.0, scalar=True)
        for name in ("reset_after", "unplug_after"):
            if getattr(self, name) is not None:
                check_int(name, getattr(self, name), 0)


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
    scan_mask: int = 1
    dwell_ms: int = DWELL_MS_DEFAULT
    settle: int = SETTLE_DEFAULT
    channel: int = 0
    scan_no: int = 0
    scan_set: bool = False  # a SCAN was accepted since boot: M frames carry channel and scan

    @property
    def scanning(self) -> bool:
        """More than one channel in the mask: readings of DWELL ms with a settling time between them."""
        return self.scan_mask & (self.scan_mask - 1) != 0


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
    speed : {"realtime", "max"}
        ``realtime``: one window per window length of wall time. ``max``: the device's clock is
        simulated; the next window is measured and sent as soon as the host has read the frames
        before it (at most :attr:`MAX_UNREAD` bytes left unread), so a recording takes as long as
        the host needs. Either way the frames' times (``t_ms``) and the signal are the device's clock.

    Notes
    -----
    Use as a context manager, or call :meth:`open` (returns the pty path and runs the device in a
    thread) and :meth:`close`; :meth:`serve` runs it in the calling thread instead. Times: the
    device clock starts at :meth:`open` (``t_ms``), the profile's clock at ``START``.

    An exception inside the device (a signal source that raises, say) ends it without a traceback:
    the pseudo-terminal closes, as a pulled cable, and :attr:`failure` says why.
    """

    MAX_UNREAD = 256
    """``speed="max"``: the next window waits while the host has more bytes than this unread (a few frames). [B]"""

    def __init__(self, source: SignalSource | None = None, frequency_noise: float = 1e-3, jitter_s: float = 20e-9,
                 adc_noise_v: float = 2e-3, faults: Faults | None = None, seed: int | None = None,
                 load_cell: LoadCellModel | None = LoadCellModel(), speed: str = "realtime") -> None:
        if not isinstance(speed, str) or speed not in SPEEDS:
            raise ParameterError(f"must be one of {', '.join(SPEEDS)}, got {speed!r}", parameter="speed")
        self.speed = speed
        self._sim_s = 0.0  # the device's clock with speed="max" [s]
        for name, v in (("frequency_noise", frequency_noise), ("jitter_s", jitter_s), ("adc_noise_v", adc_noise_v)):
            check_at_least(name, v, 0.0, scalar=True)
        self.source = source if source is not None else PhysicsSource()
        self.frequency_noise, self.jitter_s, self.adc_noise_v = frequency_noise, jitter_s, adc_noise_v
        self.faults = faults or Faults()
        if seed is not None:
            check_int("seed", seed, 0)
        self._rng = np.random.default_rng(seed)
        if load_cell is not None and not isinstance(load_cell, LoadCellModel):
            raise ParameterError(f"must be a LoadCellModel or None, got {type(load_cell).__name__}",
                                 parameter="load_cell")
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

    def __enter__(self) -> VirtualDevice:
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
        if self.speed == "max":
            return self._sim_s
        return time.monotonic() - self._t0

    def _unread(self) -> int:
        """Bytes written to the pty that the host has not read yet."""
        try:
            return int.from_bytes(fcntl.ioctl(self._slave, termios.FIONREAD, b"\0\0\0\0"), "little")
        except (OSError, TypeError):
            return 0

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
        before = self._unread() if self.speed == "max" else 0
        try:
            os.write(self._master, data)
            self.frames_sent += 1
            if self.speed == "max":
                self._await_delivery(before, len(data))
        except BlockingIOError:
            self.frames_overflowed += 1  # the host does not read: bytes are lost, as on a UART
        except OSError as exc:
            if exc.errno not in (errno.EIO, errno.EBADF):
                raise

    def _await_delivery(self, before: int, n: int, limit_s: float = 1.0) -> None:
        """Wait until the kernel has passed the ``n`` bytes just written to the host's side of the pty.

        Linux hands bytes written to a pty master to the slave in deferred work: until that work runs,
        FIONREAD on the slave does not count them, and on a busy machine it can lag by many frames. The
        backpressure of ``speed="max"`` (:attr:`MAX_UNREAD`) reads FIONREAD, so without this wait the
        device would write past its bound. A poll of the slave runs the deferred work when the slave has
        nothing to read (``before == 0``); otherwise the count grows by ``n`` once delivered, or falls
        below ``before`` when the host reads. ``limit_s`` only guards against a hang.
        """
        slave = self._slave
        if slave is None:
            return
        if before == 0:
            try:
                select.select([slave], [], [], 0)  # runs the pending delivery when nothing is readable
            except (OSError, ValueError):
                return
            return
        end = time.monotonic() + limit_s
        while not self._stop.is_set() and time.monotonic() < end:
            now = self._unread()
            if now >= before + n or now < before:
                return
            time.sleep(0.0002)

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
            st.start_time = self._now()
            st.scan_no = 0
            self._restart_measuring(st.start_time)
        elif name == "STOP":
            st.started = False
        elif name == "SCAN":
            st.scan_mask = int(value)
            st.scan_set = True
            st.channel = mask_channels(st.scan_mask)[0]
            if st.started:  # as the firmware: the scan restarts from the mask's first channel
                self._restart_measuring(self._now())
        elif name == "DWELL":
            st.dwell_ms = int(value)
        elif name == "SETTLE":
            st.settle = int(value)
        elif name == "WINDOW":
            st.window_ms = int(value)
            if st.started and not st.scanning:  # as the firmware: the window in progress restarts
                st.window_start = self._now()
                st.current_ms = st.window_ms
                st.meter = st.meter.restarted()
        elif name == "RANGE":
            st.range_ = int(value)
        self._send_frame("ACK", (name,) if value is None else (name, value), faults=False)

    def _restart_measuring(self, now: float) -> None:
        """START, or a new mask while started: the first channel of the mask, a new window or reading."""
        st = self._st
        st.channel = mask_channels(st.scan_mask)[0]
        st.meter = MeterState.started(self._rng)
        if st.scanning:
            st.window_start = now + self._settle_s(now)
            st.current_ms = st.dwell_ms
        else:
            st.window_start = now
            st.current_ms = st.window_ms

    def _channel_signal(self, t0: float, t1: float) -> Signal:
        """The selected channel's signal (a plain source is channel 0; the others are open)."""
        st = self._st
        if hasattr(self.source, "channel"):
            return self.source.window(t0, t1, st.range_, channel=st.channel)
        if st.channel == 0:
            return self.source.window(t0, t1, st.range_)
        return Signal(math.nan, math.nan, 0.0, math.nan)

    def _settle_s(self, now: float) -> float:
        """Time the firmware spends after a switch before it counts: the first edge and SETTLE periods;
        an open channel waits one dwell and the 2 ms after which the firmware stops waiting for an edge. [s]"""
        st = self._st
        t = now - st.start_time
        f = self._channel_signal(t, t + 1e-3).frequency_hz
        if not (math.isfinite(f) and f > 0):
            return st.dwell_ms / 1000.0 + 0.004
        return (st.settle + 1.0) / f

    def _next_reading(self, t_end: float) -> None:
        """After a window: the next one follows at once; in a scan, the next channel after its settling."""
        st = self._st
        if not st.scanning:
            st.window_start = t_end
            st.current_ms = st.window_ms
            st.scan_no = (st.scan_no + 1) % SEQ_MODULO
            return
        chans = mask_channels(st.scan_mask)
        later = [c for c in chans if c > st.channel]
        if not later:
            st.scan_no = (st.scan_no + 1) % SEQ_MODULO
        st.channel = later[0] if later else chans[0]
        st.meter = st.meter.restarted()
        st.window_start = t_end + self._settle_s(t_end)
        st.current_ms = st.dwell_ms

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
        sig = self._channel_signal(t0 - st.start_time, t1 - st.start_time)
        if hasattr(self.source, "channel"):  # A0 and the load cell: the reference channel's
            ref_sig = self.source.window(t0 - st.start_time, t1 - st.start_time, st.range_)
            sig = Signal(sig.frequency_hz, sig.duty_cycle, ref_sig.voltage_v, sig.stress_pa)
        m, st.meter = measure(sig.frequency_hz, sig.duty_cycle, sig.voltage_v, t1 - t0, state=st.meter,
                              rng=self._rng, start_s=t0, frequency_noise=self.frequency_noise,
                              jitter_s=self.jitter_s, adc_noise_v=self.adc_noise_v)
        u32 = UINT32_MODULO - 1
        ref = window_reference(self.load_cell, self._force_at(sig), t0 - st.start_time, t1 - st.start_time,
                               rng=self._cell_rng)
        t_ms = round(t1 * 1000) if self.speed == "max" else int(t1 * 1000)  # (max: whole ms already)
        fields = (t_ms % UINT32_MODULO, st.current_ms, int(m.periods[0]), min(int(m.sum_period_ticks[0]), u32),
                  min(int(m.sum_high_ticks[0]), u32), 0, int(m.adc[0]), st.range_, ref.ref_ok, ref.ref_n, ref.ref_mean)
        if st.scan_set:  # as the firmware: version 2's fields until a SCAN
            fields += (st.channel, st.scan_no)
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
        """The device's thread: measure the windows as they end and answer the host's commands."""
        try:
            while not self._stop.is_set():
                if deadline is not None and time.monotonic() >= deadline:
                    return
                wait = self._measure_due()
                if wait is None:
                    continue
                if not self._read_commands(wait):
                    return
        except KeyboardInterrupt:
            return
        except Exception as exc:  # noqa: BLE001 - any failure ends the device, as a pulled cable; see failure
            self.error = exc
            self._stop.set()
            self._close_fds()

    def _measure_due(self) -> float | None:
        """Send the window that has ended, if one has; return how long to wait for a command [s], or None to
        look again at once (real time: right after a window)."""
        st = self._st
        now = self._now()
        wait = 0.05
        if not st.started:
            return wait
        t_end = st.window_start + st.current_ms / 1000.0
        if self.speed == "max":
            t_end = round(t_end * 1000.0) / 1000.0  # whole ms, as the firmware's clock: no drift
            if self._unread() <= self.MAX_UNREAD:
                # The clock moves to the window's end first: a mass placed while this window is
                # measured (time_since_start) counts from its end, as in real time.
                self._sim_s = now = max(now, t_end)
                wait = 0.0  # commands first (non-blocking), then this window
            else:
                wait = 0.0005  # the host is reading: look again soon
        if now >= t_end:
            self._measure(t_end)
            if self._st.started:
                self._next_reading(t_end)
            if self.speed != "max":
                return None
        return min(wait, max(t_end - now, 0.0))

    def _read_commands(self, wait: float) -> bool:
        """Wait up to ``wait`` seconds for the host's bytes and act on them; False once the pty is gone. [s]"""
        master = self._master
        if master is None:
            return False
        try:
            ready, _, _ = select.select([master], [], [], max(wait, 0.0))
        except (OSError, ValueError):
            return False
        if ready:
            try:
                data = os.read(master, 1024)
            except BlockingIOError:
                return True
            except OSError:
                return False
            self._feed_commands(data)
        return True
