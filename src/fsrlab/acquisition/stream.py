"""The one loop over a meter's frames, shared by every recording and by the live view.

:class:`WindowStream` owns what happens between the serial link and a run's rows: it sends the
settings and START (:meth:`WindowStream.configure`), reads the frames the link has
(:meth:`WindowStream.windows`), turns each ``M`` frame into the row ``fsrlab acquire`` writes
(:func:`window_row`) on one time axis, notices a link that stays silent for
longer than the stall time (a *gap*: reported when it begins and when the device comes back), and, when
the device restarts (a reset frame: the boot ``ID`` with sequence 0), sends the settings in force and
START again, so that recording goes on. :func:`fsrlab.acquisition.recorder.record` (``acquire``,
``measure``, ``bench``, ``weights``) and :class:`fsrlab.live.session.LiveSession` (``live``) both read
through it: a reset, a stall and an unplugged device behave the same everywhere.

The time axis follows one of two clocks (:data:`CLOCKS`). On the ``host`` clock (hardware, or a
virtual meter in real time) a run's length is this computer's time, and the windows after a reset
continue from it. On the ``device`` clock (a virtual meter faster than real time, ``speed="max"``)
the run's own time axis is the only one: the windows after a reset continue from the last one, and
with ``end_s`` the stream yields no window after the first that reaches it (:attr:`WindowStream.complete`).
Stalls are wall time on either clock.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from fsrlab.acquisition.messages import Measurement
from fsrlab.acquisition.protocol import SEQ_MODULO, UINT32_MODULO, Frame

__all__ = ["CLOCKS", "Gap", "Scan", "WindowStream", "configure", "window_row"]

CLOCKS = ("host", "device")
"""What a run's time axis and length count: this computer's clock, or the device's own (its ``t_ms``)."""

_END_TOL_S = 1e-9  # a window's time_s is a sum of milliseconds: reaching end_s allows for rounding


@dataclass(frozen=True)
class Gap:
    """A stretch of the run in which the link delivered no frame for longer than the stall time.

    Attributes
    ----------
    start_s : float
        When the last frame before the silence arrived (or START, if none had), host clock since
        START. [s]
    length_s : float
        From ``start_s`` to the next frame, or to the end of the run if none came. [s]
    """

    start_s: float
    length_s: float

    def to_dict(self) -> dict:
        """``{"start_s", "length_s"}`` rounded to ms, as the sidecar's ``gaps`` holds them."""
        return {"start_s": round(self.start_s, 3), "length_s": round(self.length_s, 3)}


@dataclass(frozen=True)
class Scan:
    """What a multi-channel recording asks of a version-3 meter (docs/protocol.md, ``SCAN``).

    Attributes
    ----------
    channels : tuple of int
        Multiplexer channels, each 0..7, in scan order (ascending).
    dwell_ms : int
        Counting time per channel (used when more than one channel is scanned). [ms]
    settle : int
        Periods discarded after the first edge that follows a switch.
    """

    channels: tuple[int, ...]
    dwell_ms: int = 3
    settle: int = 2

    def __post_init__(self) -> None:
        from fsrlab.acquisition.protocol import (
            DWELL_MS_MAX,
            DWELL_MS_MIN,
            SETTLE_MAX,
            channel_mask,
            mask_channels,
        )
        from fsrlab.errors import ParameterError

        object.__setattr__(self, "channels", mask_channels(channel_mask(self.channels)))
        if isinstance(self.dwell_ms, bool) or not isinstance(self.dwell_ms, int) \
                or not DWELL_MS_MIN <= self.dwell_ms <= DWELL_MS_MAX:
            raise ParameterError(f"must be an integer {DWELL_MS_MIN}..{DWELL_MS_MAX} ms, got {self.dwell_ms!r}",
                                 parameter="dwell_ms")
        if isinstance(self.settle, bool) or not isinstance(self.settle, int) or not 0 <= self.settle <= SETTLE_MAX:
            raise ParameterError(f"must be an integer 0..{SETTLE_MAX} periods, got {self.settle!r}",
                                 parameter="settle")

    @property
    def mask(self) -> int:
        """The ``SCAN`` mask."""
        from fsrlab.acquisition.protocol import channel_mask

        return channel_mask(self.channels)

    def to_dict(self) -> dict:
        """``{"channels", "dwell_ms", "settle"}`` as the sidecar's ``acquisition.scan`` keeps it."""
        return {"channels": list(self.channels), "dwell_ms": self.dwell_ms, "settle": self.settle}


def window_row(m: Measurement, time_s: float, has_ref: bool, loadcell=None, area_m2: float | None = None,
               stress_pa: float | None = None) -> dict:
    """One run row for a measurement window (what ``record`` writes, before ``on_row``).

    Parameters
    ----------
    m : Measurement
        The window.
    time_s : float
        Its time in the run. [s]
    has_ref : bool
        The device sends a reference (protocol 2): ``reference_raw`` and ``force_n`` are filled, empty
        (None, never 0) for a window without an HX711 conversion.
    loadcell : LoadCellCalibration, optional
        Converts raw counts to ``force_n``; without it ``force_n`` stays empty.
    area_m2 : float, optional
        Sensor area: ``stress_pa = force_n / area``. [m²]
    stress_pa : float, optional
        A known reference stress (the virtual device's); written as ``stress_pa`` when given. [Pa]

    Returns
    -------
    dict
        Column → value (None: an empty cell).
    """
    row = {"time_s": time_s, "frequency_hz": m.frequency_hz, "duty_cycle": m.duty_cycle, "voltage_v": m.adc_v,
           "periods": m.periods, "missed": m.missed, "range": m.range, "seq": m.seq}
    if stress_pa is not None:
        row["stress_pa"] = stress_pa if math.isfinite(stress_pa) else None
    if has_ref:
        raw = m.ref_mean if m.ref_n > 0 else None  # empty, never 0, without a conversion
        force = loadcell.force(raw) if raw is not None and loadcell is not None else None
        row["reference_raw"], row["force_n"] = raw, force
        if area_m2 is not None:
            row["stress_pa"] = force / area_m2 if force is not None else None
    return row


def configure(link, window_ms: int, range_: int, scan: Scan | None = None) -> int:
    """Send the window and the range (and a scan's mask, dwell, settle), then START; return the sequence
    number the first window will carry.

    Parameters
    ----------
    link : SerialLink
        An identified link.
    window_ms : int
        Measurement window. [ms]
    range_ : int
        C_off switch, 0 or 1.
    scan : Scan, optional
        The channels to scan (a version-3 meter).

    Returns
    -------
    int
    """
    if scan is not None:
        link.command("SCAN", scan.mask)
        link.command("DWELL", scan.dwell_ms)
        link.command("SETTLE", scan.settle)
    link.set_window(window_ms)
    link.set_range(range_)
    return (link.start().seq + 1) % SEQ_MODULO


class WindowStream:
    """A meter's windows as run rows, on one time axis, through resets and silences.

    Parameters
    ----------
    link : SerialLink
        An identified link.
    window_ms : int
        Measurement window in force (sent again after a reset). [ms]
    range_ : int
        C_off switch in force (sent again after a reset).
    has_ref : bool
        The device sends a reference (protocol version 2).
    stall_s : float
        Silence on the link that counts as a gap. [s]
    loadcell : LoadCellCalibration, optional
        Turns raw counts into ``force_n``.
    area_m2 : float, optional
        Sensor area: ``stress_pa = force_n / area_m2``. [m²]
    reference : callable, optional
        ``reference(frame) -> stress [Pa]`` known for a window (the virtual device's).
    on_event : callable, optional
        ``on_event(line)``: a gap begins or ends, the load cell goes or comes back.
    on_gap : callable, optional
        ``on_gap(now)`` each time a gap begins or ends (e.g. to store the gaps in the sidecar at once).
    on_reset : callable, optional
        ``on_reset()`` when the device has restarted and its settings have been sent again.
    clock : {"host", "device"}
        The time axis (:data:`CLOCKS`): after a reset, the windows continue from the host clock's time
        since START (``host``) or from the last window's ``time_s`` (``device``).
    end_s : float, optional
        On the ``device`` clock: the run's length; the first window whose ``time_s`` reaches it is the
        last one yielded. [s]
    scan : Scan, optional
        Channels scanned (sent again after a reset); the rows then carry ``channel`` and ``scan``
        (the scan number unwrapped past 65535, counted from the run's first).

    Attributes
    ----------
    gaps : list of Gap
        The gaps that ended, in order.
    in_gap : bool
        Whether the link is silent for longer than the stall time now.
    silent_since : float
        Arrival of the last frame (``time.monotonic()``), START before the first one. [s]
    written : int
        Rows the caller kept so far (it counts them): the time axis of the windows after a reset
        continues (from the clock's time) once a row has been kept.
    run_s : float
        The last window's ``time_s`` (0 before the first). [s]
    complete : bool
        On the ``device`` clock with ``end_s``: a window has reached ``end_s``, the run is complete.
    """

    def __init__(self, link, window_ms: int, range_: int, has_ref: bool, stall_s: float, loadcell=None,
                 area_m2: float | None = None, reference: Callable[[Frame], float] | None = None,
                 on_event: Callable[[str], None] | None = None, on_gap: Callable[[float], None] | None = None,
                 on_reset: Callable[[], None] | None = None, clock: str = "host",
                 end_s: float | None = None, scan: Scan | None = None) -> None:
        from fsrlab.errors import ParameterError

        if clock not in CLOCKS:
            raise ParameterError(f"must be host or device, got {clock!r}", parameter="clock")
        if end_s is not None and clock != "device":
            raise ParameterError("a run ends on its own time axis only on the device clock", parameter="end_s")
        self.link = link
        self.clock, self.end_s = clock, end_s
        self.window_ms, self.range = int(window_ms), int(range_)
        self.has_ref, self.stall_s = has_ref, float(stall_s)
        self.loadcell, self.area_m2, self.reference = loadcell, area_m2, reference
        self.on_event, self.on_gap, self.on_reset = on_event, on_gap, on_reset
        self.gaps: list[Gap] = []
        self.in_gap = False
        self.t_start = self.silent_since = time.monotonic()
        self.written = 0
        self.run_s = 0.0
        self._anchor_ms: int | None = None  # device t_ms at START (start of the first window after it)
        self._offset_s = 0.0
        self._cell_ok: int | None = None  # the HX711's last state (ref_ok), to say when it goes or comes back
        self.scan = scan
        self._scan_last: int | None = None  # the device's last scan number (mod 65536)
        self._scan_total = -1  # the run's scan count of that frame

    def configure(self) -> int:
        """Send the settings in force and START; return the first window's sequence number."""
        return configure(self.link, self.window_ms, self.range, self.scan)

    def begin(self, t_start: float | None = None) -> None:
        """Start the time axis and the silence clock (at START; default now)."""
        self.t_start = self.silent_since = time.monotonic() if t_start is None else t_start

    def set_window(self, window_ms: int) -> None:
        """Change the window on the device and for later resets. [ms]"""
        self.link.set_window(int(window_ms))
        self.window_ms = int(window_ms)

    def set_range(self, range_: int) -> None:
        """Change the C_off switch on the device and for later resets."""
        self.link.set_range(int(range_))
        self.range = int(range_)

    def open_gap(self, now: float) -> Gap | None:
        """The gap in progress, its length so far (None when the link is not silent)."""
        return Gap(self.silent_since - self.t_start, now - self.silent_since) if self.in_gap else None

    @property
    def complete(self) -> bool:
        """Whether a window has reached ``end_s`` (never on the host clock)."""
        return self.end_s is not None and self.run_s >= self.end_s - _END_TOL_S

    def _event(self, text: str) -> None:
        if self.on_event is not None:
            self.on_event(text)

    def windows(self) -> Iterator[tuple[Frame, Measurement, dict]]:
        """Read what the link has; yield each ``M`` frame, its measurement and its run row.

        The row is :func:`window_row`'s, ``time_s`` on the stream's time
        axis. After the last window of a read that held a reset, the settings are sent again. Once the
        run is :attr:`complete`, the windows still read are left out.

        Yields
        ------
        (Frame, Measurement, dict)
        """
        batch = self._read()
        restart = False
        for frame in batch:
            if self.complete:
                return  # the device clock reached the run's end: the windows after it are not part of it
            if frame.reset:
                restart = True
                self._anchor_ms = None
                self._scan_last = None
            if frame.kind != "M":
                continue
            m = Measurement.from_frame(frame)
            self.run_s = self._window_time(m)
            row = window_row(m, self.run_s, self.has_ref, self.loadcell, self.area_m2,
                             self.reference(frame) if self.reference is not None else None)
            if self.scan is not None:
                row["channel"], row["scan"] = m.channel, self._unwrap_scan(m.scan)
            if self.has_ref and m.ref_ok != self._cell_ok:
                self._load_cell_changed(m.ref_ok, row["time_s"])
            yield frame, m, row
        if restart:
            self.configure()
            if self.on_reset is not None:
                self.on_reset()

    def _read(self) -> list[Frame]:
        """The frames the link has now; a silence longer than the stall time opens a gap, a frame closes it."""
        now = time.monotonic()
        batch = self.link.read_frames()
        if batch:
            now = time.monotonic()
            if self.in_gap:
                self.in_gap = False
                self.gaps.append(Gap(self.silent_since - self.t_start, now - self.silent_since))
                if self.on_gap is not None:
                    self.on_gap(now)
                self._event(f"device back after {now - self.silent_since:.1f} s without a frame")
            self.silent_since = now
        elif not self.in_gap and now - self.silent_since >= self.stall_s:
            self.in_gap = True
            if self.on_gap is not None:
                self.on_gap(now)
            self._event(f"no frame from the device for {now - self.silent_since:.1f} s "
                        f"(since {self.silent_since - self.t_start:.1f} s into the run)")
        return batch

    def _window_time(self, m: Measurement) -> float:
        """The window's ``time_s`` on the stream's axis: the device's ``t_ms`` since START; after a reset it
        continues from the last window (device clock) or from the host's time since START (host clock). [s]"""
        if self._anchor_ms is None:
            self._anchor_ms = (m.t_ms - m.window_ms) % UINT32_MODULO
            if not self.written:
                self._offset_s = 0.0
            elif self.clock == "device":
                self._offset_s = self.run_s
            else:
                self._offset_s = max(time.monotonic() - self.t_start - m.window_ms / 1000.0, 0.0)
        return self._offset_s + ((m.t_ms - self._anchor_ms) % UINT32_MODULO) / 1000.0

    def _load_cell_changed(self, ref_ok: int, time_s: float) -> None:
        """Say when the meter's HX711 stops answering (``ref_ok`` 0) and when it answers again."""
        if ref_ok == 0:
            self._event(f"no load cell: the meter reports no HX711 (ref_ok 0) from {time_s:.1f} s "
                        "into the run; reference_raw and force_n stay empty")
        elif self._cell_ok == 0:
            self._event(f"load cell answering again from {time_s:.1f} s into the run")
        self._cell_ok = ref_ok

    def _unwrap_scan(self, scan: int | None) -> int:
        """The run's scan number: the device's counts on (mod 65536), a restart of it (reset) moves on by one."""
        if scan is None:
            return 0
        if self._scan_last is None:
            self._scan_total += 1
        else:
            d = (scan - self._scan_last) % SEQ_MODULO
            self._scan_total += d if d < SEQ_MODULO // 2 else 1
        self._scan_last = scan
        return self._scan_total
