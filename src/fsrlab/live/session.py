"""A live session with a meter: one thread reads the frames, keeps the recent ones for the page, records on request.

The device thread owns the :class:`~fsrlab.acquisition.serial_link.SerialLink`: it identifies the
device, configures and starts it, then reads frames, appends each window to a bounded buffer the pages
read from (:meth:`LiveSession.since`), writes it to a run file while recording (the crash-safe
:class:`~fsrlab.io.runwriter.RunWriter`, the rows ``fsrlab acquire`` writes:
:func:`fsrlab.acquisition.recorder.window_row`), and
carries out the commands the pages send (range, window, start/stop recording) between reads. A device
that vanishes ends the session's reading with a reason on the page; a recording in progress is closed
with everything written so far.
"""

from __future__ import annotations

import math
import queue
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fsrlab.acquisition.stream import WindowStream
from fsrlab.errors import ParameterError

__all__ = ["LiveSession", "LiveStatus", "COLUMNS", "TARE_S"]

#: Time over which a tare from the page collects the load cell's conversions. [s]
TARE_S = 1.0

#: Columns the session keeps for the page (one value per window).
COLUMNS = ("time_s", "seq", "frequency_hz", "duty_cycle", "voltage_v", "range", "missed", "reference",
           "estimate", "uncertainty", "received_s")


@dataclass
class LiveStatus:
    """What the page's status line shows.

    Attributes
    ----------
    state : str
        ``connecting``, ``running``, ``stopped`` or ``disconnected``.
    message : str
        A sentence for the user (the reason, when the device is gone).
    device : str
        Device name, firmware and protocol version, once identified.
    frames : int
        Windows received.
    frames_per_s : float
        Windows in the last second. [1/s]
    dropped, corrupt, missed, stalls : int
        Frames lost on the link, corrupted lines, edges the meter missed, silences longer than the stall time.
    range : int
        C_off switch in force.
    window_ms : int
        Window length in force. [ms]
    recording : str
        The run file being written, or empty.
    recorded : int
        Rows written to it.
    prompt : str
        What the guided known-weight calibration asks for now (empty when none runs).
    weights : str
        Where the guided calibration is (step k/N and its file), or empty.
    events : list of str
        The last 20 notices, each with its time (recording started, device restarted, stall, ...).
    """

    state: str = "connecting"
    message: str = ""
    device: str = ""
    frames: int = 0
    frames_per_s: float = 0.0
    dropped: int = 0
    corrupt: int = 0
    missed: int = 0
    stalls: int = 0
    range: int = 0
    window_ms: int = 100
    recording: str = ""
    recorded: int = 0
    prompt: str = ""
    weights: str = ""
    events: list = field(default_factory=list)


class LiveSession:
    """The device side of ``fsrlab live``.

    Parameters
    ----------
    link : SerialLink
        An open link (not yet identified); the session's thread owns it from :meth:`start` on.
    window_ms : int
        Measurement window. [ms]
    range_ : int
        C_off switch at the start.
    capacity : int
        Windows kept for the pages (the oldest drop out). [1]
    reference : callable, optional
        ``reference(frame) -> stress [Pa]`` known for a window (the virtual device's applied stress).
    loadcell : LoadCellCalibration, optional
        Converts the meter's HX711 counts to ``force_n`` (protocol 2); the page's reference is that force.
    area_m2 : float, optional
        Sensor area, to show a stress-only reference as a force. [m²]
    estimator : callable, optional
        ``estimator(row) -> (estimate [N], uncertainty [N])`` for a window (a calibration), or None.
    health : callable, optional
        ``health() -> None`` or a one-line reason once the device has failed.
    metadata : dict, optional
        Sidecar content of the runs recorded (circuit, sensor, origin).
    stall_s : float
        Silence that counts as a stall. [s]
    scan : Scan, optional
        Several sensors behind the meter's multiplexer (protocol 3): the meter scans these channels, the
        windows carry ``channel`` and ``scan``, :meth:`channels` keeps each channel's latest reading and
        its link health, and a recording is in the long format (``SCAN_COLUMNS``).
    channel_map : list of dict, optional
        The sensors' ids and positions (:func:`fsrlab.acquisition.recorder.channel_map`).
    weights : dict, optional
        The guided known-weight calibration the page offers: ``steps`` (:func:`fsrlab.bench.weights.plan_steps`),
        ``place`` (``place(step) -> time or None``: the virtual bench places the mass), ``x``, ``gravity_m_s2``
        and ``metadata`` for its run's sidecar. None: no guided calibration on the page.
    """

    def __init__(self, link, window_ms: int = 100, range_: int = 0, capacity: int = 20000,
                 reference: Callable | None = None, loadcell=None, area_m2: float | None = None,
                 estimator: Callable | None = None,
                 health: Callable[[], str | None] | None = None, metadata: dict | None = None,
                 stall_s: float = 2.0, weights: dict | None = None, scan=None, channel_map=None) -> None:
        from fsrlab.acquisition.recorder import channel_map as make_map

        self.scan = scan
        self.channel_map = make_map(scan.channels, channel_map) if scan is not None else []
        self._chan: dict[int, dict] = {e["channel"]: {**e, "frequency_hz": math.nan, "estimate": math.nan,
                                                      "readings": 0, "missed": 0, "no_oscillation": 0,
                                                      "time_s": math.nan} for e in self.channel_map}
        self.link = link
        self.reference = reference
        self.loadcell = loadcell
        self.area_m2 = area_m2
        self.estimator = estimator
        self._has_ref = False
        self.weights = weights
        self._proc = None  # the guided calibration in progress (WeightsProcedure)
        self._wwriter = None
        self._answer: str | None = None
        self._tare: list | None = None  # conversions collected for a tare, None when none is going on
        self._tare_until = 0.0
        self.health = health
        self.metadata = dict(metadata or {})
        self.stall_s = float(stall_s)
        self.status = LiveStatus(range=range_, window_ms=window_ms)
        self._lock = threading.Lock()
        self._rows: deque = deque(maxlen=int(capacity))
        self._total = 0
        self._commands: queue.Queue = queue.Queue()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._writer = None
        self._t0 = time.monotonic()
        self._recent: deque = deque()
        self.identity = None
        self._stream: WindowStream | None = None

    # ----------------------------------------------------------------- pages
    def since(self, cursor: int) -> tuple[int, dict[str, list]]:
        """Windows after ``cursor`` (the count a page has seen), as columns, and the new cursor.

        A page that fell behind by more than the buffer gets the buffer (older windows are gone).
        """
        with self._lock:
            total = self._total
            n = min(total - cursor, len(self._rows))
            rows = list(self._rows)[len(self._rows) - n:] if n > 0 else []
        cols = COLUMNS + (("channel",) if self.scan is not None else ())
        return total, {c: [r.get(c) for r in rows] for c in cols}

    def channels(self) -> list[dict]:
        """Each scanned channel's latest reading and health: ``channel``, ``sensor_id``, ``x_m``, ``y_m``,
        ``frequency_hz`` [Hz] and ``estimate`` (NaN without one), ``time_s`` [s], ``readings``, ``missed`` (edges
        missed in all its readings) and ``no_oscillation`` (its readings without a period: an open channel, or
        a sensor out of oscillation). Empty without a scan."""
        with self._lock:
            return [dict(self._chan[k]) for k in sorted(self._chan)]

    def command(self, name: str, value=None) -> None:
        """Queue a command for the device thread: ``range`` (0/1), ``window`` [ms], ``record`` (a path),
        ``stop_recording``, ``tare`` (the load cell's offset from the next :data:`TARE_S` of conversions),
        ``weights`` (start the guided calibration into a path) or ``answer`` (``ok``: the mass is placed; ``skip``)."""
        if name not in ("range", "window", "record", "stop_recording", "tare", "weights", "answer"):
            raise ParameterError(f"unknown live command {name!r}", parameter="name")
        self._commands.put((name, value))

    # ---------------------------------------------------------------- thread
    def start(self) -> LiveSession:
        """Start the device thread."""
        self._thread = threading.Thread(target=self._run, name="fsrlab-live-device", daemon=True)
        self._thread.start()
        return self

    def close(self, timeout_s: float = 3.0) -> None:
        """Stop the thread, close a recording in progress, leave the device stopped."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)

    def _event(self, text: str) -> None:
        with self._lock:
            self.status.events = (self.status.events + [f"{time.strftime('%H:%M:%S')} {text}"])[-20:]

    def _run(self) -> None:
        from fsrlab.acquisition.serial_link import DeviceGone, LinkError

        st = self.status
        try:
            ident = self.link.handshake()
            self.identity = ident
            st.device = f"{ident.name} {ident.firmware_version} (protocol {ident.protocol_version})"
            self._has_ref = ident.protocol_version >= 2
            self.link.stop()
            if self.scan is not None and ident.protocol_version < 3:
                raise LinkError(f"{self.link.port} speaks protocol {ident.protocol_version}: scanning channels needs 3")
            self._stream = WindowStream(self.link, st.window_ms, st.range, self._has_ref, self.stall_s, self.loadcell,
                                        None, self.reference, on_event=self._event, on_gap=self._gap,
                                        on_reset=lambda: self._event("device restarted; its settings sent again"),
                                        scan=self.scan)
            self._stream.configure()
            self._stream.begin()
            st.state, st.message = "running", f"reading {self.link.port}"
            self._loop()
        except DeviceGone as exc:
            reason = self.health() if self.health is not None else None
            st.state, st.message = "disconnected", reason or str(exc)
            self._event(st.message)
        except LinkError as exc:
            st.state, st.message = "disconnected", str(exc)
            self._event(st.message)
        except Exception as exc:  # noqa: BLE001 - the page says what happened; the file keeps its rows
            st.state, st.message = "disconnected", f"{type(exc).__name__}: {exc}"
            self._event(st.message)
        finally:
            self._close_recording("device gone" if st.state == "disconnected" else "stopped")
            if self._proc is not None:
                self._finish_weights("ended early (device gone)" if st.state == "disconnected" else "stopped")
            if st.state == "running":
                try:
                    self.link.stop()
                except Exception:  # noqa: BLE001 - best effort on the way out
                    pass
                st.state, st.message = "stopped", "session closed"

    def _gap(self, now: float) -> None:
        """A gap began or ended on the stream: count the silences longer than the stall time."""
        if self._stream.in_gap:
            self.status.stalls += 1

    def _loop(self) -> None:
        """Read the stream (:class:`~fsrlab.acquisition.stream.WindowStream`, the recorder's loop) until closed."""
        from fsrlab.acquisition.serial_link import DeviceGone

        st = self.status
        parser = self.link.parser
        stream = self._stream
        while not self._stop.is_set():
            if self.health is not None and (reason := self.health()):
                raise DeviceGone(reason)
            self._do_commands()
            for _frame, m, row in stream.windows():
                now = time.monotonic()
                stream.written += 1
                row["reference"] = self._force(row)
                est, unc = self.estimator(row) if self.estimator is not None else (math.nan, math.nan)
                row["estimate"] = est if est is not None else math.nan
                row["uncertainty"] = unc if unc is not None else math.nan
                row["received_s"] = time.time()
                self._write(row)
                self._collect_tare(row, now)
                self._guide(m, row)
                with self._lock:
                    if self.scan is not None and m.channel in self._chan:
                        c = self._chan[m.channel]
                        c.update(frequency_hz=row["frequency_hz"], estimate=row["estimate"], time_s=row["time_s"])
                        c["readings"] += 1
                        c["missed"] += m.missed
                        c["no_oscillation"] += m.periods == 0
                    self._rows.append(row)
                    self._total += 1
                    st.frames += 1
                    st.missed += m.missed
                    st.range = m.range
                self._recent.append(now)
            now = time.monotonic()
            while self._recent and self._recent[0] < now - 1.0:
                self._recent.popleft()
            span = min(now - self._t0, 1.0)
            st.frames_per_s = len(self._recent) / span if span > 0 else 0.0
            st.dropped, st.corrupt = parser.lost, parser.bad_frames

    # ----------------------------------------------------- guided known weights
    def _start_weights(self, path: Path) -> None:
        from fsrlab.acquisition.recorder import COLUMNS as RUN_COLUMNS
        from fsrlab.acquisition.recorder import REFERENCE_COLUMNS
        from fsrlab.bench.weights import WeightsProcedure
        from fsrlab.io.runwriter import RunWriter

        w = self.weights
        if w is None:
            self._event("no guided calibration: start fsrlab live with --masses")
            return
        if self._proc is not None:
            self._event("the guided calibration is already running")
            return
        use_loadcell = self.loadcell is not None and self._has_ref
        self._answer = None
        proc = WeightsProcedure(w["steps"], self._announce, self._take_answer, w.get("place"), None, x=w["x"],
                                gravity_m_s2=w["gravity_m_s2"], use_loadcell=use_loadcell, area_m2=self.area_m2)
        columns = list(RUN_COLUMNS) + (list(REFERENCE_COLUMNS) if self._has_ref else [])
        columns += ["step", "direction", "cycle", "force_nominal_n",
                    "force_n"] + (["stress_pa"] if self.area_m2 else [])
        columns += ["load", "sensor", "reading"]
        columns = list(dict.fromkeys(columns))
        meta = {**self.metadata, **w.get("metadata", {})}
        meta["origin"] = f"fsrlab live (guided known weights) from {self.link.port}"
        meta.setdefault("units", {}).update({"load": "g", "sensor": "1"})
        meta["weights"] = {**meta.get("weights", {}), "force_n": "load cell" if use_loadcell else "nominal (mass × g)"}
        self._wwriter = RunWriter(path, columns, meta, overwrite=False)
        self._proc, self._wpath, self._wt0 = proc, path, None
        self.status.weights = f"guided calibration into {path}"
        self._event(f"guided calibration: {len(w['steps'])} placements into {path}")

    def _announce(self, text: str) -> None:
        self.status.prompt = text.replace("then press Enter (s and Enter skips the step)",
                                          "then click Placed (or Skip step)").replace(
            "press Enter to wait again, or s and Enter to skip the step", "click Placed to wait again, or Skip step")
        self._event(self.status.prompt)

    def _take_answer(self) -> str | None:
        answer, self._answer = self._answer, None
        return answer

    def _guide(self, m, row: dict) -> None:
        """Feed a window to the guided calibration; write its steady windows; finish it at the end of the plan."""
        proc = self._proc
        if proc is None:
            return
        out = proc.on_row(m, dict(row))
        if out is not None:
            if self._wt0 is None:
                self._wt0 = row["time_s"]
            line = {c: out.get(c) for c in self._wwriter.columns}
            line["time_s"] = row["time_s"] - self._wt0
            try:
                self._wwriter.write(line)
            except (OSError, ValueError) as exc:
                self._finish_weights(f"write failed: {exc}")
                return
        k = min(proc.k + 1, len(proc.steps))
        self.status.weights = f"step {k}/{len(proc.steps)} in {self._wpath}"
        if proc.done:
            self._finish_weights("done")

    def _finish_weights(self, why: str) -> None:
        proc, writer, self._proc, self._wwriter = self._proc, self._wwriter, None, None
        if writer is None:
            return
        summary = proc.summary()
        try:
            writer.metadata["weights"] = {**writer.metadata.get("weights", {}), **summary}
            writer.metadata["ended"] = f"guided calibration {why}: {summary['recorded']} placements recorded, " \
                                       f"{summary['skipped']} skipped"
            writer.close()
        except OSError:
            pass
        self.status.prompt = f"guided calibration {why}: {summary['recorded']} recorded, {summary['skipped']} skipped"
        self.status.weights = ""
        self._event(f"{self.status.prompt} ({self._wpath})")

    def _collect_tare(self, row: dict, now: float) -> None:
        """Add a window's conversion to a tare in progress; finish it after :data:`TARE_S`."""
        import dataclasses

        from fsrlab.acquisition.loadcell import LoadCellError, tare_from_readings

        if self._tare is None:
            return
        if row.get("reference_raw") is not None:
            self._tare.append(row["reference_raw"])
        if now < self._tare_until:
            return
        counts, self._tare = self._tare, None
        old = self.loadcell
        try:
            new = tare_from_readings(counts, old.capacity_n, old.scale_counts_per_n)
        except LoadCellError as exc:
            self._event(str(exc))
            return
        self.loadcell = dataclasses.replace(old, offset_counts=new.offset_counts, created=new.created, tare=new.tare)
        if self._stream is not None:  # the rows from now on use the new offset
            self._stream.loadcell = self.loadcell
        self._event(f"tare: offset {old.offset_counts:.0f} → {new.offset_counts:.0f} counts "
                    f"({len(counts)} conversions; in this session only)")

    def _force(self, row: dict) -> float:
        """The page's reference [N]: the load cell's force, else a known stress times the area, else NaN."""
        force = row.get("force_n")
        if force is None and row.get("stress_pa") is not None and self.area_m2:
            force = row["stress_pa"] * self.area_m2
        return float(force) if force is not None and math.isfinite(force) else math.nan

    def _do_commands(self) -> None:
        st = self.status
        while True:
            try:
                name, value = self._commands.get_nowait()
            except queue.Empty:
                return
            try:
                if name == "range":
                    self._stream.set_range(int(value))
                    st.range = int(value)
                    self._event(f"range {int(value)} (C_off {'in' if value else 'out'})")
                elif name == "window":
                    self._stream.set_window(int(value))
                    st.window_ms = int(value)
                    self._event(f"window {int(value)} ms")
                elif name == "record":
                    self._open_recording(Path(value))
                elif name == "stop_recording":
                    self._close_recording("stopped from the page")
                elif name == "weights":
                    self._start_weights(Path(value))
                elif name == "answer":
                    self._answer = str(value)
                elif name == "tare":
                    if self.loadcell is None or not self._has_ref:
                        self._event("tare refused: no load cell (give --loadcell, or a meter with an HX711)")
                    else:
                        self._tare, self._tare_until = [], time.monotonic() + TARE_S
                        self._event(f"tare: keep the load cell unloaded for {TARE_S:g} s")
            except (ValueError, OSError) as exc:
                self._event(f"{name} refused: {exc}")

    # ------------------------------------------------------------- recording
    def _open_recording(self, path: Path) -> None:
        from fsrlab.acquisition.recorder import COLUMNS as RUN_COLUMNS
        from fsrlab.acquisition.recorder import REFERENCE_COLUMNS, SCAN_COLUMNS
        from fsrlab.io.runwriter import RunWriter

        if self._writer is not None:
            self._event(f"already recording to {self.status.recording}")
            return
        columns = list(RUN_COLUMNS if self.scan is None else SCAN_COLUMNS)
        columns += ["stress_pa"] if self.reference is not None else []
        columns += list(REFERENCE_COLUMNS) if self._has_ref else []
        meta = dict(self.metadata)
        meta.setdefault("origin", f"fsrlab live from {self.link.port}")
        if self.loadcell is not None:
            meta["load_cell"] = self.loadcell.to_dict()
        ident = self.identity
        meta["acquisition"] = {"port": self.link.port, "window_ms": self.status.window_ms, "range": self.status.range,
                               "device": ident.name if ident else "",
                               "firmware_version": ident.firmware_version if ident else "",
                               "protocol_version": ident.protocol_version if ident else None}
        if self.scan is not None:
            meta["acquisition"]["scan"] = self.scan.to_dict()
            meta["channels"] = self.channel_map
        self._writer = RunWriter(path, columns, meta, overwrite=False)  # never replaces a run
        self._record_t0 = None
        self.status.recording, self.status.recorded = str(path), 0
        self._event(f"recording to {path}")

    def _write(self, row: dict) -> None:
        if self._writer is None:
            return
        if self._record_t0 is None:
            self._record_t0 = row["time_s"]
        out = {c: row.get(c) for c in self._writer.columns}
        out["time_s"] = row["time_s"] - self._record_t0
        try:
            self._writer.write(out)
            self.status.recorded += 1
        except (OSError, ValueError) as exc:  # the display goes on; the file keeps what it has
            self._close_recording(f"write failed: {exc}")

    def _close_recording(self, why: str) -> None:
        if self._writer is None:
            return
        writer, self._writer = self._writer, None
        try:
            writer.metadata["ended"] = f"{why}; {self.status.recorded} windows kept"
            writer.close()
        except OSError:
            pass
        self._event(f"recording closed ({why}): {self.status.recorded} windows in {self.status.recording}")
        self.status.recording = ""
