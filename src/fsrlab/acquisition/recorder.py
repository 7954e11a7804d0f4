"""Record an fsrlab meter into a run file (docs/data-format.md), crash-safe.

:func:`record` identifies the device, sets window and range, starts it and turns every ``M`` frame
into one row written at once through :class:`fsrlab.io.runwriter.RunWriter` (one whole line per
system call, ``fsync`` about every second). Consequences:

- An existing run is never replaced unless asked (``overwrite=True``); the check comes before the
  device is touched.
- Ctrl-C (or SIGTERM through the CLI) stops the device and closes the file: nothing is lost but
  the window in progress. A ``SIGKILL`` leaves every row already written; the file stays readable.
- A device that disappears (unplugged, pty closed) ends the run with ``ended="disconnected"`` and a
  one-line ``message``; the file is closed normally.
- A link that delivers no frame for ``stall_s`` seconds is a *gap*: reported at once through
  ``on_event``, kept in the sidecar (``gaps``), and a failure (``ended="stalled"``) if the device is
  still silent when the run ends.
- A failure of the device's thread (``health``), of the file or of anything else while recording
  ends the run (``ended="failed"``) with the rows so far kept and the reason in the sidecar
  (``ended``); a run without a single valid window is a failure too (``ended="empty"``).
- Corrupted bytes on the link are counted by the parser and never reach the file; lost frames show
  as gaps in ``seq`` and are counted as ``dropped``; a device reset is detected, the settings are
  sent again and recording goes on.

The reference force (protocol version 2, a load cell read by an HX711): each row of a version-2
device gets ``reference_raw`` (the window's mean raw HX711 counts) and ``force_n`` (those counts
through a load-cell calibration, :class:`~fsrlab.acquisition.loadcell.LoadCellCalibration`), both
empty — never 0 — in a window without a conversion (no HX711, or a 10 samples/s one between
conversions) or, for ``force_n``, without a calibration; such windows are counted
(:attr:`RecordResult.no_reference`). With a sensor area, ``stress_pa = force_n / area``. A
version-1 device records as before, without these columns.

Several sensors on one meter (protocol version 3, a multiplexer: docs/multiplexing.md): with ``scan``
(:class:`~fsrlab.acquisition.stream.Scan`) the meter scans those channels and the run is in the long
format, one row per channel reading (:data:`SCAN_COLUMNS`: ``time_s, channel, scan, frequency_hz, ...``,
each reading with its own time), and the sidecar holds the channel map (``channels``: each channel's
``sensor_id`` and position ``x_m``, ``y_m``) and the scan's settings (``acquisition.scan``).
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from fsrlab.acquisition.messages import Identity, Measurement
from fsrlab.acquisition.protocol import WINDOW_MS_DEFAULT, WINDOW_MS_MAX, WINDOW_MS_MIN, Frame, ParserStats
from fsrlab.acquisition.serial_link import DeviceGone, LinkError, SerialLink
from fsrlab.acquisition.stream import CLOCKS, Gap, Scan, WindowStream, window_row

__all__ = ["COLUMNS", "SCAN_COLUMNS", "REFERENCE_COLUMNS", "Scan", "channel_map", "FAILED_ENDINGS", "Gap",
           "RecordStatus", "RecordResult", "default_stall_s", "record",
           "window_row", "result_dict"]

COLUMNS = ("time_s", "frequency_hz", "duty_cycle", "voltage_v", "periods", "missed", "range", "seq")
"""Run columns written for every window (``stress_pa`` is added when a reference is given)."""

SCAN_COLUMNS = ("time_s", "channel", "scan", "frequency_hz", "duty_cycle", "voltage_v", "periods", "missed", "range",
                "seq")
"""Run columns of a multi-channel recording (long format: one row per channel reading)."""

REFERENCE_COLUMNS = ("reference_raw", "force_n")
"""Columns added for a protocol-version-2 device (the load cell's reference)."""

FAILED_ENDINGS = ("disconnected", "error", "failed", "stalled", "empty")
"""Values of :attr:`RecordResult.ended` for a run that did not end as asked (the CLI exits with 1)."""


def channel_map(channels, given=None) -> list[dict]:
    """The sidecar's channel map: per channel its ``sensor_id`` and position (PhysioNet's gait database keeps one).

    Parameters
    ----------
    channels : sequence of int
        The channels recorded.
    given : sequence of dict, optional
        Entries ``{"channel": k, "sensor_id": str, "x_m": float, "y_m": float}`` (any subset of the keys
        but ``channel``); a channel not given gets ``sensor_id`` ``fsr<k>`` and no position.

    Returns
    -------
    list of dict
        One entry per recorded channel, in channel order.
    """
    from fsrlab.errors import ParameterError
    from fsrlab.physics.params import check_int

    if isinstance(channels, (str, bytes)) or not hasattr(channels, "__iter__"):
        raise TypeError(f"channels: must be a sequence of channel numbers, got {type(channels).__name__}")
    channels = [check_int("channels", k, lower=0) for k in channels]
    if given is not None and (isinstance(given, (str, bytes, dict)) or not hasattr(given, "__iter__")):
        raise TypeError(f"given: must be a sequence of channel entries (dicts), got {type(given).__name__}")
    known: dict[int, dict] = {}
    for entry in given or ():
        if not isinstance(entry, dict) or not isinstance(entry.get("channel"), int) or isinstance(entry["channel"],
                bool):
            raise ParameterError(f"every entry needs an integer 'channel', got {entry!r}",
                                 parameter="channel_map")
        unknown = set(entry) - {"channel", "sensor_id", "x_m", "y_m"}
        if unknown:
            raise ParameterError(f"unknown key(s) {', '.join(sorted(unknown))} "
                                 "(known: channel, sensor_id, x_m, y_m)", parameter="channel_map")
        known[entry["channel"]] = entry
    out = []
    for k in channels:
        e = known.get(k, {})
        out.append({"channel": k, "sensor_id": str(e.get("sensor_id", f"fsr{k}")), "x_m": e.get("x_m"),
                    "y_m": e.get("y_m")})
    ids = [e["sensor_id"] for e in out]
    if len(set(ids)) != len(ids):
        raise ParameterError("sensor ids must differ between channels", parameter="channel_map")
    return out


def default_stall_s(window_ms: int) -> float:
    """Silence that counts as a stall by default: 5 windows, at least 2 s.

    Parameters
    ----------
    window_ms : int
        Measurement window. [ms]

    Returns
    -------
    float
        [s]
    """
    from fsrlab.physics.params import check_positive

    check_positive("window_ms", window_ms, "ms", scalar=True)
    return max(5 * window_ms / 1000.0, 2.0)


@dataclass(frozen=True)
class RecordStatus:
    """Progress of a recording, for a live display.

    Attributes
    ----------
    elapsed_s : float
        Time since START on the recording's clock (``record``'s ``clock``). [s]
    frames : int
        Rows written.
    frames_per_s : float
        Rows per second over the last second or so. [1/s]
    frequency_hz, duty_cycle : float
        Last window's values (NaN without signal). [Hz], [1]
    dropped : int
        Frames lost on the link so far (sequence gaps).
    bad_frames : int
        Corrupted lines rejected so far.
    resets : int
        Device restarts seen.
    """

    elapsed_s: float
    frames: int
    frames_per_s: float
    frequency_hz: float
    duty_cycle: float
    dropped: int
    bad_frames: int
    resets: int


@dataclass(frozen=True)
class RecordResult:
    """How a recording went.

    Attributes
    ----------
    frames : int
        Rows written (one per received ``M`` frame).
    dropped : int
        Frames lost on the link during the recording (sequence gaps: never arrived or corrupted).
    duration_s : float
        Time from START to the end on this computer's clock (with ``clock="device"`` the run's own
        length is the sidecar's ``acquisition.run_s``). [s]
    file : Path
        The run file.
    ended : str
        ``"duration"``, ``"interrupted"`` (Ctrl-C), ``"stopped"`` (stop event); or one of
        :data:`FAILED_ENDINGS`: ``"disconnected"`` (device gone), ``"error"`` (device stopped
        answering commands), ``"failed"`` (the device's thread, the file or the recorder failed),
        ``"stalled"`` (no frame at the end for longer than the stall time), ``"empty"`` (no valid
        window at all).
    message : str
        One line describing how it ended (also the sidecar's ``ended``).
    stats : ParserStats
        The link's parser counters (whole session, handshake included).
    identity : Identity
        The device.
    gaps : tuple of Gap
        Silences longer than the stall time, in order.
    reference : bool
        Whether the device sends a reference (protocol version 2: ``reference_raw``, ``force_n``).
    no_reference : int
        Rows written without a load-cell conversion (``reference_raw`` empty): no HX711, a
        disconnected one, or a slow one between conversions.
    run_s : float or None
        With ``clock="device"``: the last window's ``time_s``, the run's length on the device's clock. [s]
    """

    frames: int
    dropped: int
    duration_s: float
    file: Path
    ended: str
    message: str
    stats: ParserStats
    identity: Identity | None
    gaps: tuple[Gap, ...] = ()
    reference: bool = False
    no_reference: int = 0
    run_s: float | None = None

    @property
    def failed(self) -> bool:
        """Whether the run did not end as asked (:data:`FAILED_ENDINGS`)."""
        return self.ended in FAILED_ENDINGS


class _Failure(Exception):
    """Ends the recording loop with ``ended="failed"`` and this message."""


def _empty_reason(ended: str, window_ms: int, duration_s: float, bad: int, lost: int) -> str:
    """Why a run has no valid window, in words."""
    if ended in ("interrupted", "stopped"):
        return "ended before the first window was complete"
    if window_ms / 1000.0 > duration_s:
        return f"each window lasts {window_ms / 1000.0:g} s, longer than the recording"
    if bad:
        return f"{bad} corrupted lines rejected and no intact measurement"
    if lost:
        return f"all {lost} measurements were lost on the link"
    return "the device sent no measurement"


def _ending(ended: str, message: str, frames: int, duration: float, gaps: list, in_gap: bool, empty_reason: str,
            path: Path) -> tuple[str, str]:
    """How a recording ended, in one word and one line: an empty run and a device silent at the end are failures."""
    if ended not in ("disconnected", "error", "failed"):
        if frames == 0:
            message = f"no valid window recorded in {duration:.1f} s: {empty_reason}; {path} has its header only"
            ended = "empty"
        elif in_gap:
            ended = "stalled"
            message = (f"the device sent nothing from {gaps[-1].start_s:.1f} s into the run to the end "
                       f"({gaps[-1].length_s:.1f} s)")
    if not message:
        message = {"duration": f"recorded {frames} windows in {duration:.1f} s",
                   "interrupted": f"interrupted: {frames} windows kept",
                   "stopped": f"stopped: {frames} windows kept"}[ended]
        if gaps:
            message += (f", {len(gaps)} gap{'s' if len(gaps) > 1 else ''} without frames "
                        f"({sum(g.length_s for g in gaps):.1f} s)")
    elif ended != "empty":
        message = f"{message}; {frames} windows kept in {path}"
    return ended, " ".join(message.split())


def record(link: SerialLink, path, duration_s: float, window_ms: int = WINDOW_MS_DEFAULT, range_: int = 0,
           metadata: dict | None = None, reference: Callable[[Frame], float] | None = None,
           on_status: Callable[[RecordStatus], None] | None = None, stop: threading.Event | None = None,
           status_interval_s: float = 0.25, sync_interval_s: float = 1.0,
           handshake_timeout_s: float = 3.0, stall_s: float | None = None,
           on_event: Callable[[str], None] | None = None, health: Callable[[], str | None] | None = None,
           overwrite: bool = False, loadcell=None, area_m2: float | None = None,
           extra_columns: Sequence[str] = (), on_row: Callable[[Measurement, dict], dict | None] | None = None,
           final_metadata: Callable[[], dict] | None = None, clock: str = "host", scan: Scan | None = None,
           channels_meta: list | None = None) -> RecordResult:
    """Record ``duration_s`` seconds of measurement windows into a run file.

    Parameters
    ----------
    link : SerialLink
        An open link (not yet identified).
    path : str or path-like
        The run's CSV (``NAME.csv``; the sidecar ``NAME.meta.json`` is written beside it).
    duration_s : float
        Recording time after START (> 0), on the clock ``clock`` names. [s]
    window_ms : int
        Measurement window, 10..60000. [ms]
    range_ : int
        C_off switch, 0 or 1.
    metadata : dict, optional
        Extra sidecar content (``circuit``, ``sensor``, ``notes``, ...).
    reference : callable, optional
        ``reference(frame) -> stress [Pa]`` for each ``M`` frame, written as ``stress_pa`` (the
        virtual device knows the stress it applied).
    on_status : callable, optional
        Called with a :class:`RecordStatus` about every ``status_interval_s`` seconds.
    stop : threading.Event, optional
        Ends the recording early when set.
    status_interval_s, sync_interval_s : float
        Period of status callbacks and of ``fsync``. [s]
    handshake_timeout_s : float
        Longest wait for the device's identification. [s]
    stall_s : float, optional
        Silence on the link (no valid frame) that counts as a gap; longer than one window.
        Default :func:`default_stall_s`: 5 windows, at least 2 s. [s]
    on_event : callable, optional
        Called with one line of text when a gap begins and when the device comes back.
    health : callable, optional
        ``health() -> None`` while the device is well, or a one-line reason once it has failed
        (e.g. the virtual device's thread); checked on every read.
    overwrite : bool
        Replace an existing run. Without it an existing CSV or sidecar raises
        ``FileExistsError`` before the device is touched.
    loadcell : LoadCellCalibration, optional
        Turns the raw counts into ``force_n`` (:mod:`fsrlab.acquisition.loadcell`); stored in the
        sidecar (``load_cell``). Without one ``force_n`` stays empty.
    area_m2 : float, optional
        Sensor area: ``stress_pa = force_n / area_m2`` when no ``reference`` is given. [m²]
    extra_columns : sequence of str
        More columns, filled by ``on_row``.
    on_row : callable, optional
        ``on_row(measurement, row) -> row or None`` before each row is written: may add the extra
        columns, or return None to leave the window out (e.g. ``fsrlab weights`` keeps the steady
        windows only). It may set ``stop`` to end the recording.
    final_metadata : callable, optional
        ``final_metadata() -> dict`` merged into the sidecar when the run is closed (however it ends).
    clock : {"host", "device"}
        What ``duration_s`` and the progress's ``elapsed_s`` count: ``host``, this computer's clock
        (hardware, or a virtual meter in real time); ``device``, the run's own time axis (``time_s``,
        from the device's ``t_ms``): the run ends with the first window that reaches ``duration_s``,
        for a virtual meter faster than real time. Stalls are wall time either way.
    scan : Scan, optional
        Scan these multiplexer channels (a protocol-3 meter): one row per channel reading, with
        ``channel`` and ``scan`` (:data:`SCAN_COLUMNS`).
    channels_meta : list of dict, optional
        The channel map's entries (:func:`channel_map`); default ``fsr<k>`` without positions.

    Returns
    -------
    RecordResult

    Raises
    ------
    ParameterError
        A parameter out of range (``.parameter`` names it).
    FileExistsError
        The run or its sidecar exists and ``overwrite`` is False.
    LinkError
        The device could not be identified or configured (before anything is recorded).
    OSError
        The run file could not be created (the device is stopped again).
    """
    stall_s = _checked_settings(duration_s, clock, window_ms, range_, stall_s, area_m2, loadcell)
    path = Path(path)
    _refuse_existing(path, overwrite)
    chan_map = _channel_map_of(scan, channels_meta)
    ident = link.handshake(timeout_s=handshake_timeout_s)
    _require_scanning(scan, ident, link)
    link.stop()  # a device left running by a previous session: start from a clean state
    has_ref = ident.protocol_version >= 2
    stress_from_force = reference is None and area_m2 is not None and loadcell is not None and has_ref
    on_device = clock == "device"
    rec = _Recording(link, has_ref, on_device, on_row=on_row, on_status=on_status, stop=stop, health=health,
                     status_interval_s=status_interval_s, sync_interval_s=sync_interval_s)
    rec.stream = WindowStream(link, window_ms, range_, has_ref, stall_s, loadcell,
                              area_m2 if stress_from_force else None, reference, on_event=on_event,
                              on_gap=rec.save_gaps, clock=clock, end_s=duration_s if on_device else None, scan=scan)
    first_seq = rec.stream.configure()
    columns = _run_columns(scan, reference is not None or stress_from_force, has_ref, extra_columns)
    meta = _run_metadata(metadata, link, ident, loadcell, area_m2)
    meta["acquisition"].update({"window_ms": window_ms, "range": range_, "duration_s": duration_s, "clock": clock,
                                "stall_s": stall_s, "first_seq": first_seq})
    _scan_metadata(meta, scan, chan_map)
    meta["gaps"] = []
    rec.writer = _open_run(link, path, columns, meta, overwrite)
    rec.run(duration_s, window_ms, path, final_metadata)
    return RecordResult(rec.frames, rec.dropped, rec.duration_s, path, rec.ended, rec.message, link.parser.stats(),
                        ident, tuple(rec.stream.gaps), has_ref, rec.no_ref, rec.stream.run_s if on_device else None)


def _checked_settings(duration_s, clock, window_ms, range_, stall_s, area_m2, loadcell) -> float:
    """``record``'s settings checked before the device is touched; the stall time (its default filled in). [s]"""
    from fsrlab.errors import ParameterError

    if not duration_s > 0:
        raise ParameterError(f"must be > 0 s, got {duration_s!r}", parameter="duration_s")
    if clock not in CLOCKS:
        raise ParameterError(f"must be host or device, got {clock!r}", parameter="clock")
    if not WINDOW_MS_MIN <= window_ms <= WINDOW_MS_MAX:
        raise ParameterError(f"must be in {WINDOW_MS_MIN}..{WINDOW_MS_MAX} ms, got {window_ms!r}",
                             parameter="window_ms")
    if range_ not in (0, 1):
        raise ParameterError(f"must be 0 or 1, got {range_!r}", parameter="range_")
    stall_s = default_stall_s(window_ms) if stall_s is None else float(stall_s)
    if not stall_s > window_ms / 1000.0:
        raise ParameterError(f"must be longer than one window ({window_ms / 1000.0:g} s), got {stall_s!r}",
                             parameter="stall_s")
    if area_m2 is not None and not (math.isfinite(area_m2) and area_m2 > 0):
        raise ParameterError(f"must be > 0 m², got {area_m2!r}", parameter="area_m2")
    if loadcell is not None and not loadcell.scaled:
        raise ParameterError("the load-cell calibration has a tare but no scale factor; run fsrlab loadcell scale",
                             parameter="loadcell")
    return stall_s


def _refuse_existing(path: Path, overwrite: bool) -> None:
    """An existing run or sidecar is replaced only when asked to (checked before the device is touched)."""
    from fsrlab.io.runformat import sidecar_path

    if not overwrite:
        for existing in (path, sidecar_path(path)):
            if os.path.lexists(existing):
                raise FileExistsError(f"{existing} exists; a run is replaced only when asked to")


def _run_columns(scan: Scan | None, stress: bool, has_ref: bool, extra_columns: Sequence[str]) -> list[str]:
    """The run's columns: the windows' (one channel or a scan's), ``stress_pa``, the load cell's and the extra ones."""
    columns = list(COLUMNS if scan is None else SCAN_COLUMNS)
    columns += ["stress_pa"] if stress else []
    columns += [c for c in (REFERENCE_COLUMNS if has_ref else ()) if c not in columns]
    columns += [c for c in extra_columns if c not in columns]
    return columns


def _run_metadata(metadata: dict | None, link: SerialLink, ident: Identity, loadcell, area_m2: float | None) -> dict:
    """The sidecar at the start: the caller's content, the load cell, the sensor's area and the device."""
    meta = dict(metadata or {})
    if loadcell is not None:
        meta["load_cell"] = loadcell.to_dict()
    if area_m2 is not None:
        meta["sensor"] = {**(meta.get("sensor") or {}), "area_m2": area_m2}
    meta.setdefault("origin", f"fsrlab acquire from {link.port}")
    meta["acquisition"] = {"port": link.port, "baud": link.baud, "device": ident.name,
                           "firmware_version": ident.firmware_version, "protocol_version": ident.protocol_version}
    return meta


def _open_run(link: SerialLink, path: Path, columns: list[str], meta: dict, overwrite: bool):
    """The run file, created with its header and sidecar; if it cannot be, the device is stopped again."""
    from fsrlab.io.runwriter import RunWriter

    try:
        return RunWriter(path, columns, meta, overwrite=overwrite)
    except BaseException:  # e.g. no such directory: do not leave the device running
        try:
            link.command("STOP", timeout_s=0.5)
        except LinkError:
            pass
        raise


class _Recording:
    """One recording: the loop over the stream's windows, each window's row, and the run file kept up to date.

    ``stream`` and ``writer`` are set by :func:`record` once the device is configured and the file is open.
    The counters (``frames``, ``no_ref``, ``dropped``) and the ending (``ended``, ``message``,
    ``duration_s``) are what :class:`RecordResult` reports.
    """

    def __init__(self, link: SerialLink, has_ref: bool, on_device: bool, *, on_row, on_status, stop, health,
                 status_interval_s: float, sync_interval_s: float):
        self.link, self.has_ref, self.on_device = link, has_ref, on_device
        self.on_row, self.on_status, self.stop, self.health = on_row, on_status, stop, health
        self.status_interval_s, self.sync_interval_s = status_interval_s, sync_interval_s
        self.stream: WindowStream | None = None
        self.writer = None
        self.frames, self.no_ref, self.dropped = 0, 0, 0
        self.ended, self.message, self.duration_s = "duration", "", 0.0
        self.last: Measurement | None = None
        self.recent: list[float] = []  # when the last second's rows were written, for the rate shown

    def save_gaps(self, now: float) -> None:
        """The stream's ``on_gap``: the gaps so far into the sidecar, the open one's length so far too, in case
        the process dies during it."""
        stream = self.stream
        shown = stream.gaps + ([stream.open_gap(now)] if stream.in_gap else [])
        try:
            self.writer.update_metadata({"gaps": [g.to_dict() for g in shown]})
        except OSError as exc:
            raise _Failure(str(exc)) from None

    def run(self, duration_s: float, window_ms: int, path: Path, final_metadata) -> None:
        """Record until the duration is over, the stream is complete, ``stop`` is set or something fails; however
        it ends, the device is stopped (if it still answers) and the file closed with every row written."""
        parser = self.link.parser
        lost0, bad0 = parser.lost, parser.bad_frames
        t_start = time.monotonic()
        self.stream.begin(t_start)
        t_end = t_start + duration_s if not self.on_device else math.inf  # on the device clock the stream ends it
        try:
            self._until_ended(t_start, t_end, lost0)
            self.dropped = parser.lost - lost0  # frames sent while recording that never made it
            if self.ended not in ("disconnected", "error", "failed"):
                try:
                    self.link.command("STOP", timeout_s=0.5)
                except (LinkError, KeyboardInterrupt):
                    pass
        finally:
            self.duration_s = time.monotonic() - t_start
            self._close(t_start, window_ms, duration_s, path, final_metadata, lost0, bad0)

    def _until_ended(self, t_start: float, t_end: float, lost0: int) -> None:
        """The loop, and how it ended (``ended``, ``message``): whatever fails, the rows so far stay in the file."""
        try:
            self._loop(t_start, t_end, lost0)
        except KeyboardInterrupt:
            self.ended = "interrupted"
        except DeviceGone as exc:
            reason = self.health() if self.health is not None else None  # a failed device closes its port
            self.ended, self.message = ("failed", reason) if reason else ("disconnected", str(exc))
        except LinkError as exc:  # no answer while re-configuring after a reset
            self.ended, self.message = "error", str(exc)
        except _Failure as exc:
            self.ended, self.message = "failed", str(exc)
        except Exception as exc:  # noqa: BLE001 - whatever it is, the rows so far are kept and the run says why
            self.ended, self.message = "failed", f"recording failed: {type(exc).__name__}: {exc}"

    def _loop(self, t_start: float, t_end: float, lost0: int) -> None:
        """Read windows, write their rows, sync the file and report progress until the run is over."""
        next_status = t_start
        next_sync = t_start + self.sync_interval_s
        while True:
            now = time.monotonic()
            if now >= t_end or self.stream.complete:
                return
            if self.stop is not None and self.stop.is_set():
                self.ended = "stopped"
                return
            if self.health is not None and (reason := self.health()):
                raise _Failure(reason)
            self._write_windows()
            now = time.monotonic()
            if now >= next_sync:
                try:
                    self.writer.sync()
                except OSError as exc:
                    raise _Failure(str(exc)) from None
                next_sync = now + self.sync_interval_s
            if self.on_status is not None and now >= next_status:
                self.on_status(self._status(now, t_start, lost0))
                next_status = now + self.status_interval_s

    def _write_windows(self) -> None:
        """Each window the stream has now: ``on_row`` may complete it or leave it out; its row written at once."""
        for _frame, m, row in self.stream.windows():
            if self.on_row is not None:
                row = self.on_row(m, row)
                if row is None:
                    self.last = m
                    continue
            if self.has_ref and row.get("reference_raw") is None:
                self.no_ref += 1
            try:
                self.writer.write(row)
            except OSError as exc:
                raise _Failure(str(exc)) from None
            self.frames += 1
            self.stream.written = self.frames
            self.last = m
            self.recent.append(time.monotonic())

    def _status(self, now: float, t_start: float, lost0: int) -> RecordStatus:
        """The progress shown: rows and their rate over the last second, the last window, the link's counters."""
        parser, last = self.link.parser, self.last
        self.recent = [t for t in self.recent if t > now - 1.0]
        span = min(now - t_start, 1.0)
        elapsed = self.stream.run_s if self.on_device else now - t_start
        return RecordStatus(elapsed, self.frames, len(self.recent) / span if span > 0 else 0.0,
                            last.frequency_hz if last else math.nan, last.duty_cycle if last else math.nan,
                            parser.lost - lost0, parser.bad_frames, parser.resets)

    def _close(self, t_start: float, window_ms: int, duration_s: float, path: Path, final_metadata,
               lost0: int, bad0: int) -> None:
        """The ending in words, the counters, gaps and ``final_metadata()`` into the sidecar; the file closed."""
        stream, writer, duration = self.stream, self.writer, self.duration_s
        gaps = stream.gaps
        in_gap = stream.in_gap
        if in_gap:
            gaps.append(Gap(stream.silent_since - t_start, t_start + duration - stream.silent_since))
        st = self.link.parser.stats()
        empty_reason = _empty_reason(self.ended, window_ms, duration_s, st.bad_frames - bad0, st.lost - lost0)
        self.ended, self.message = _ending(self.ended, self.message, self.frames, duration, gaps, in_gap,
                                           empty_reason, path)
        acquisition = writer.metadata["acquisition"]
        acquisition.update({"ended": self.ended, "frames": self.frames, "dropped": self.dropped, "resets": st.resets,
                            "bad_checksum": st.bad_checksum, "malformed": st.malformed,
                            "garbage_bytes": st.garbage_bytes, "recorded_s": round(duration, 3)})
        if self.on_device:
            acquisition["run_s"] = round(stream.run_s, 3)
        if self.has_ref:
            acquisition["no_reference"] = self.no_ref
        writer.metadata["gaps"] = [g.to_dict() for g in gaps]
        writer.metadata["ended"] = self.message
        if final_metadata is not None:
            try:
                writer.metadata.update(final_metadata())
            except Exception as exc:  # noqa: BLE001 - the rows are what matters; say what is missing
                writer.metadata["final_metadata_error"] = f"{type(exc).__name__}: {exc}"
        writer.close()


def result_dict(result: RecordResult) -> dict:
    """The command line's JSON summary.

    Parameters
    ----------
    result : RecordResult
        A finished recording.

    Returns
    -------
    dict
        ``frames``, ``dropped``, ``duration_s`` [s] (rounded to ms) and ``file``, in this order; then,
        for a device with a reference (protocol version 2), ``no_reference``: rows without a load-cell
        conversion; for a recording on the device's clock (a virtual bench at ``speed="max"``),
        ``run_s``: the run's length on that clock [s] (``duration_s`` is this computer's).
    """
    out = {"frames": result.frames, "dropped": result.dropped, "duration_s": round(result.duration_s, 3),
           "file": str(result.file)}
    if result.reference:
        out["no_reference"] = result.no_reference
    if result.run_s is not None:
        out["run_s"] = round(result.run_s, 3)
    return out


def _channel_map_of(scan: Scan | None, entries) -> list[dict] | None:
    """The checked channel map of a multi-channel recording (before the device is touched)."""
    if scan is None:
        return None
    if not isinstance(scan, Scan):
        from fsrlab.errors import ParameterError

        raise ParameterError(f"must be a Scan, got {type(scan).__name__}", parameter="scan")
    return channel_map(scan.channels, entries)


def _require_scanning(scan: Scan | None, ident: Identity, link: SerialLink) -> None:
    """A scan needs a version-3 meter."""
    if scan is not None and ident.protocol_version < 3:
        raise LinkError(f"{link.port} speaks protocol version {ident.protocol_version}: scanning channels needs "
                        "version 3 (firmware 3.0.0 or later: fsrlab flash)")


def _scan_metadata(meta: dict, scan: Scan | None, chan_map: list[dict] | None) -> None:
    """The scan's settings (``acquisition.scan``) and the channel map (``channels``, over a bench's own entries)."""
    if scan is None:
        return
    meta["acquisition"]["scan"] = scan.to_dict()
    meta["channels"] = [{**(entry or {}), **m} for m, entry in
                        zip(chan_map, _by_channel(meta.get("channels"), scan.channels), strict=True)]


def _by_channel(entries, channels) -> list[dict | None]:
    """A source's per-channel sidecar entries (``channels`` of a virtual bench) lined up with ``channels``."""
    found = {e.get("channel"): e for e in entries or () if isinstance(e, dict)}
    return [found.get(k) for k in channels]
