"""Record an fsrlab meter into a run file (docs/data-format.md), crash-safe.

:func:`record` identifies the device, sets window and range, starts it and turns every ``M`` frame
into one row written at once through :class:`fsrlab.runformat.RunWriter` (one whole line per
system call, ``fsync`` about every second). Consequences:

- Ctrl-C (or SIGTERM through the CLI) stops the device and closes the file: nothing is lost but
  the window in progress. A ``SIGKILL`` leaves every row already written; the file stays readable.
- A device that disappears (unplugged, pty closed) ends the run with ``ended="disconnected"`` and a
  one-line ``message``; the file is closed normally.
- Corrupted bytes on the link are counted by the parser and never reach the file; lost frames show
  as gaps in ``seq`` and are counted as ``dropped``; a device reset is detected, the settings are
  sent again and recording goes on.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

from fsrlab.acquisition.messages import Identity, Measurement
from fsrlab.acquisition.protocol import (
    SEQ_MODULO, UINT32_MODULO, WINDOW_MS_DEFAULT, WINDOW_MS_MAX, WINDOW_MS_MIN, Frame, ParserStats,
)
from fsrlab.acquisition.serial_link import DeviceGone, LinkError, SerialLink

__all__ = ["COLUMNS", "RecordStatus", "RecordResult", "record", "result_dict", "stats_dict"]

COLUMNS = ("time_s", "frequency_hz", "duty_cycle", "voltage_v", "periods", "missed", "range", "seq")
"""Run columns written for every window (``stress_pa`` is added when a reference is given)."""


@dataclass(frozen=True)
class RecordStatus:
    """Progress of a recording, for a live display.

    Attributes
    ----------
    elapsed_s : float
        Time since START. [s]
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
        Time from START to the end. [s]
    file : Path
        The run file.
    ended : str
        ``"duration"``, ``"interrupted"`` (Ctrl-C), ``"stopped"`` (stop event), ``"disconnected"``
        (device gone) or ``"error"`` (device stopped answering commands).
    message : str
        One line describing how it ended.
    stats : ParserStats
        The link's parser counters (whole session, handshake included).
    identity : Identity
        The device.
    """

    frames: int
    dropped: int
    duration_s: float
    file: Path
    ended: str
    message: str
    stats: ParserStats
    identity: Identity | None


def _configure(link: SerialLink, window_ms: int, range_: int) -> int:
    """Send the settings and START; return the sequence number the first window will carry."""
    link.set_window(window_ms)
    link.set_range(range_)
    return (link.start().seq + 1) % SEQ_MODULO


def record(link: SerialLink, path, duration_s: float, window_ms: int = WINDOW_MS_DEFAULT, range_: int = 0,
           metadata: dict | None = None, reference: Callable[[Frame], float] | None = None,
           on_status: Callable[[RecordStatus], None] | None = None, stop: threading.Event | None = None,
           status_interval_s: float = 0.25, sync_interval_s: float = 1.0,
           handshake_timeout_s: float = 3.0) -> RecordResult:
    """Record ``duration_s`` seconds of measurement windows into a run file.

    Parameters
    ----------
    link : SerialLink
        An open link (not yet identified).
    path : str or path-like
        The run's CSV (``NAME.csv``; the sidecar ``NAME.meta.json`` is written beside it).
    duration_s : float
        Recording time after START (> 0). [s]
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

    Returns
    -------
    RecordResult

    Raises
    ------
    ValueError
        A parameter out of range.
    LinkError
        The device could not be identified or configured (before anything is recorded).
    """
    from fsrlab.runformat import RunWriter

    if not duration_s > 0:
        raise ValueError(f"duration_s must be > 0 s, got {duration_s!r}")
    if not WINDOW_MS_MIN <= window_ms <= WINDOW_MS_MAX:
        raise ValueError(f"window_ms must be in {WINDOW_MS_MIN}..{WINDOW_MS_MAX} ms, got {window_ms!r}")
    if range_ not in (0, 1):
        raise ValueError(f"range must be 0 or 1, got {range_!r}")
    path = Path(path)
    ident = link.handshake(timeout_s=handshake_timeout_s)
    link.stop()  # a device left running by a previous session: start from a clean state
    first_seq = _configure(link, window_ms, range_)
    columns = list(COLUMNS) + (["stress_pa"] if reference is not None else [])
    meta = dict(metadata or {})
    meta.setdefault("origin", f"fsrlab acquire from {link.port}")
    meta["acquisition"] = {"port": link.port, "baud": link.baud, "device": ident.name,
                           "firmware_version": ident.firmware_version, "protocol_version": ident.protocol_version,
                           "window_ms": window_ms, "range": range_, "duration_s": duration_s,
                           "first_seq": first_seq}
    parser = link.parser
    lost0 = parser.lost
    t_start = time.monotonic()
    t_end = t_start + duration_s
    frames, ended, message, dropped = 0, "duration", "", 0
    anchor_ms: int | None = None  # device t_ms at START (start of the first window after it)
    offset_s = 0.0
    last: Measurement | None = None
    recent: list[float] = []
    next_status = t_start
    next_sync = t_start + sync_interval_s
    try:
        writer = RunWriter(path, columns, meta)
    except BaseException:  # e.g. no such directory: do not leave the device running
        try:
            link.command("STOP", timeout_s=0.5)
        except LinkError:
            pass
        raise
    try:
        try:
            while True:
                now = time.monotonic()
                if now >= t_end:
                    break
                if stop is not None and stop.is_set():
                    ended = "stopped"
                    break
                restart = False
                for frame in link.read_frames():
                    if frame.reset:
                        restart = True
                        anchor_ms = None
                    if frame.kind != "M":
                        continue
                    m = Measurement.from_frame(frame)
                    if anchor_ms is None:
                        anchor_ms = (m.t_ms - m.window_ms) % UINT32_MODULO
                        offset_s = max(time.monotonic() - t_start - m.window_ms / 1000.0, 0.0) if frames else 0.0
                    row = {
                        "time_s": offset_s + ((m.t_ms - anchor_ms) % UINT32_MODULO) / 1000.0,
                        "frequency_hz": m.frequency_hz, "duty_cycle": m.duty_cycle,
                        "voltage_v": m.adc_v, "periods": m.periods, "missed": m.missed,
                        "range": m.range, "seq": m.seq,
                    }
                    if reference is not None:
                        value = reference(frame)
                        row["stress_pa"] = value if value is not None and math.isfinite(value) else None
                    writer.write(row)
                    frames += 1
                    last = m
                    recent.append(time.monotonic())
                if restart:
                    _configure(link, window_ms, range_)
                now = time.monotonic()
                if now >= next_sync:
                    writer.sync()
                    next_sync = now + sync_interval_s
                if on_status is not None and now >= next_status:
                    recent = [t for t in recent if t > now - 1.0]
                    span = min(now - t_start, 1.0)
                    on_status(RecordStatus(now - t_start, frames, len(recent) / span if span > 0 else 0.0,
                                           last.frequency_hz if last else math.nan,
                                           last.duty_cycle if last else math.nan,
                                           parser.lost - lost0, parser.bad_frames, parser.resets))
                    next_status = now + status_interval_s
        except KeyboardInterrupt:
            ended = "interrupted"
        except DeviceGone as exc:
            ended, message = "disconnected", str(exc)
        except LinkError as exc:  # no answer while re-configuring after a reset
            ended, message = "error", str(exc)
        dropped = parser.lost - lost0  # frames sent while recording that never made it
        if ended not in ("disconnected", "error"):
            try:
                link.command("STOP", timeout_s=0.5)
            except (LinkError, KeyboardInterrupt):
                pass
    finally:
        duration = time.monotonic() - t_start
        st = parser.stats()
        writer.metadata["acquisition"].update(
            {"ended": ended, "frames": frames, "dropped": dropped, "resets": st.resets,
             "bad_checksum": st.bad_checksum, "malformed": st.malformed, "garbage_bytes": st.garbage_bytes,
             "recorded_s": round(duration, 3)})
        writer.close()
    if not message:
        message = {"duration": f"recorded {frames} windows in {duration:.1f} s",
                   "interrupted": f"interrupted: {frames} windows kept",
                   "stopped": f"stopped: {frames} windows kept"}[ended]
    else:
        message = f"{message}; {frames} windows kept in {path}"
    return RecordResult(frames, dropped, duration, path, ended, message, parser.stats(), ident)


def result_dict(result: RecordResult) -> dict:
    """The command line's JSON summary.

    Parameters
    ----------
    result : RecordResult
        A finished recording.

    Returns
    -------
    dict
        ``frames``, ``dropped``, ``duration_s`` [s] (rounded to ms) and ``file``, in this order.
    """
    return {"frames": result.frames, "dropped": result.dropped, "duration_s": round(result.duration_s, 3),
            "file": str(result.file)}


def stats_dict(stats: ParserStats) -> dict:
    """Parser counters as a plain dict.

    Parameters
    ----------
    stats : ParserStats
        Counters of a :class:`~fsrlab.acquisition.protocol.FrameParser`.

    Returns
    -------
    dict
    """
    return asdict(stats)
