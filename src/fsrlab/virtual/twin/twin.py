"""The digital twin: the real firmware in simavr, driven by the sensor and 555 models, on a pty.

:class:`Twin` starts the harness (:mod:`fsrlab.virtual.twin.process`) with the master side of a
pseudo-terminal it opens (``os.openpty``, raw mode, as
:class:`~fsrlab.virtual.device.VirtualDevice` does), so the firmware's UART is the pty
and any serial program (``fsrlab acquire --port``, ``fsrlab live --port``, a serial monitor) talks to
the real firmware unchanged. Two threads feed the harness:

- the *feeder* computes the LM555's edges (:class:`~fsrlab.virtual.twin.edges.EdgeStream`: the exact
  transient of the virtual sensor's R_FSR(t), C_FSR(t)) a short look-ahead (:attr:`Twin.LOOKAHEAD_S`)
  ahead of the simulation, the A0 voltage of the op-amp readout (eq. 38) on the source's grid and,
  with a load cell, the HX711's raw value of each conversion (``LoadCellModel.raw`` of the applied
  force, mean over the conversion approximated at its middle), and confirms how far the stream is
  complete; the harness never runs past that point;
- the *reader* follows the harness's progress and its reports of D4 (the C_off switch): at a change
  the harness drops the edges it holds and waits, and the feeder recomputes from the change with the
  new capacitance (a new epoch, so edges still in the pipe for the old one are ignored).

Memory stays bounded for any run length: a look-ahead of edges, and the transient's state at the
chunk cuts since the harness's position.

With ``speed="realtime"`` the harness holds simulated time to the wall clock; ``"max"`` runs as fast
as simavr goes (``benchmarks/bench_twin.py``). The profile's clock starts at the firmware's reset
(the twin's start), not at ``START``.
"""

from __future__ import annotations

import math
import os
import subprocess
import threading
import tty
from collections import deque

from fsrlab.errors import ParameterError
from fsrlab.virtual.twin.process import F_CPU_HZ, elf_path, harness_path, pack_records, twin_available

__all__ = ["Twin", "SPEEDS"]

SPEEDS = ("realtime", "max")
"""Pacing of the simulated time: ``realtime`` (wall clock) or ``max`` (as fast as simavr goes)."""


class Twin:
    """The fsrlab meter's real firmware in simavr, driven by a physics source, on a pseudo-terminal.

    Parameters
    ----------
    source : PhysicsSource, optional
        Stress profile, virtual sensor, LM555 circuit (its C_off is what ``RANGE 1`` switches in) and
        op-amp readout; default ``PhysicsSource()``.
    speed : {"realtime", "max"}
        Pacing of simulated time.
    seed : int
        Seed of the load cell's noise. [1]
    loadcell : LoadCellModel, optional
        The load cell and HX711 under the sensor (D2/D3); None: no HX711 (``ref_ok`` 0).

    Notes
    -----
    :meth:`open` returns the pty path; :meth:`close` ends the harness; use as a context manager.
    A failure of the harness or of the feeder ends the twin as a pulled cable (the pty closes);
    :attr:`failure` then says why in one line. :attr:`notices` collects what the twin reports
    (a sensor driven out of oscillation), also passed to ``on_notice`` when set.
    """

    LOOKAHEAD_S = 0.05
    """Edges computed ahead of the simulation. [s]"""
    CHUNK_S = 0.025
    """Time computed per feeder step. [s]"""
    NO_OSCILLATION_S = 0.1
    """A stretch without a rising edge this long is reported as out of oscillation. [s]"""

    def __init__(self, source=None, *, speed: str = "realtime", seed: int = 0, loadcell=None) -> None:
        from fsrlab.acquisition.loadcell import LoadCellModel
        from fsrlab.virtual.sources import PhysicsSource

        if speed not in SPEEDS:
            raise ParameterError(f"must be one of {', '.join(SPEEDS)}, got {speed!r}", parameter="speed")
        if source is not None and not all(hasattr(source, a) for a in ("parts", "dt_s", "force_n", "circuit",
                                                                          "metadata")):
            raise ParameterError(f"must be a PhysicsSource or BenchSource (parts, dt_s, force_n, circuit, "
                             f"metadata), got {type(source).__name__}", parameter="source")
        if loadcell is not None and not isinstance(loadcell, LoadCellModel):
            raise ParameterError("must be a LoadCellModel or None, got "
                    f"{type(loadcell).__name__}", parameter="loadcell")
        self.source = source if source is not None else PhysicsSource()
        self.speed, self.seed, self.loadcell = speed, int(seed), loadcell
        self.port: str | None = None
        self.on_notice = None
        self.notices: deque[str] = deque(maxlen=100)
        self.d4_changes: list[tuple[float, int]] = []
        self.channel_changes: deque[tuple[float, int]] = deque(maxlen=100000)
        self.multiplexed = hasattr(self.source, "channel")
        self._d4_level = self._channel = 0  # the firmware's boot state
        self.edges_sent = 0
        self._proc: subprocess.Popen | None = None
        self._slave: int | None = None
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._progress = 0  # harness cycle
        self._events: list[tuple[int, int, int, int]] = []
        self._stderr_tail: deque[str] = deque(maxlen=5)
        self._error: str | None = None
        self._threads: list[threading.Thread] = []

    # ------------------------------------------------------------ lifecycle
    def open(self) -> str:
        """Start the harness on a new pseudo-terminal.

        Returns
        -------
        str
            Path of the pty slave (``/dev/pts/N``) for ``--port``.

        Raises
        ------
        RuntimeError
            The twin cannot run here (:func:`~fsrlab.virtual.twin.process.twin_available`'s reason).
        """
        ok, reason = twin_available()
        if not ok:
            raise RuntimeError(reason)
        from fsrlab.virtual.twin.edges import EdgeStream

        master, slave = os.openpty()
        tty.setraw(slave)  # no echo, no newline translation: bytes pass as on a UART
        tty.setraw(master)
        args = [str(harness_path()), str(elf_path()), "--uart-fd", str(master), "--speed", self.speed]
        if self.loadcell is not None:
            args += ["--hx", f"{self.loadcell.rate_sps}:{self.loadcell.phase_s!r}"]
        try:
            self._proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.PIPE, pass_fds=(master,), bufsize=0)
        finally:
            os.close(master)  # the harness holds the master: when it ends, the pty hangs up
        self._slave = slave
        self.port = os.ttyname(slave)
        self._stream = EdgeStream(self.source)
        reader = threading.Thread(target=self._read, name="fsrlab-twin-reader", daemon=True)
        feeder = threading.Thread(target=self._feed, name="fsrlab-twin-feeder", daemon=True)
        self._threads = [reader, feeder]
        reader.start()
        feeder.start()
        return self.port

    def close(self) -> None:
        """Stop the harness (its pty closes) and the threads."""
        self._stop.set()
        with self._cond:
            self._cond.notify_all()
        proc = self._proc
        if proc is not None:
            if proc.poll() is None:
                proc.terminate()  # nothing to save in the harness; its pty hangs up
            try:
                proc.wait(timeout=3)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        for t in self._threads:
            if t is not threading.current_thread():
                t.join(timeout=3)
        if proc is not None:
            try:
                proc.stdin.close()  # after the feeder has stopped writing to it
            except OSError:
                pass
            proc.stderr.close()
        if self._slave is not None:
            try:
                os.close(self._slave)
            except OSError:
                pass
            self._slave = None

    def __enter__(self) -> Twin:
        if self.port is None:
            self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def failure(self) -> str | None:
        """None while the twin runs or after :meth:`close`; one line saying why it failed otherwise."""
        return self._error

    @property
    def running(self) -> bool:
        """True while the harness runs."""
        return self._proc is not None and self._proc.poll() is None

    @property
    def time_s(self) -> float:
        """Simulated time the firmware has reached since its reset. [s]"""
        return self._progress / F_CPU_HZ

    def time_since_start(self) -> float:
        """The source's clock: simulated time since the firmware's reset (as :attr:`time_s`). [s]"""
        return self.time_s

    @property
    def load_cell(self):
        """The load cell under the sensor (``LoadCellModel``) or None: the name the Python virtual device uses."""
        return self.loadcell

    def metadata(self) -> dict:
        """Sidecar content of a run recorded from the twin: the source's, the firmware's, the twin's."""
        meta = self.source.metadata()
        profile = getattr(self.source, "profile", None)  # a BenchSource places masses instead
        meta["origin"] = ("fsrlab twin (VirtualFSR -> exact LM555 transient -> D8, op-amp -> A0, "
                          "load cell -> HX711 model; the real firmware in simavr over a pty)")
        meta["twin"] = {"firmware": str(elf_path()), "harness": str(harness_path()), "speed": self.speed,
                        "seed": self.seed, "profile": None if profile is None else {
                            "kind": profile.kind, "peak_pa": profile.peak_pa, "period_s": profile.period_s,
                            "base_pa": profile.base_pa},
                        "loadcell": None if self.loadcell is None else {
                            "rate_sps": self.loadcell.rate_sps, "offset_counts": self.loadcell.offset_counts,
                            "scale_counts_per_n": self.loadcell.scale_counts_per_n,
                            "noise_counts": self.loadcell.noise_counts}}
        return meta

    # ------------------------------------------------------------ threads
    def _fail(self, message: str) -> None:
        if self._error is None and not self._stop.is_set():
            self._error = " ".join(message.split())
        self._stop.set()
        with self._cond:
            self._cond.notify_all()
        proc = self._proc
        if proc is not None and proc.poll() is None:
            proc.kill()  # the pty hangs up: the host sees a pulled cable

    def _notice(self, text: str) -> None:
        self.notices.append(text)
        callback = self.on_notice
        if callback is not None:
            callback(text)

    def _read(self) -> None:
        proc = self._proc
        for raw in proc.stderr:
            line = raw.decode("ascii", "replace").strip()
            if not line:
                continue
            parts = line.split()
            if parts[0] == "#T":
                with self._cond:
                    self._progress = int(parts[1])
                    self._cond.notify_all()
            elif parts[0] == "#SW":
                cycle, level, channel, epoch, consumed = (int(x) for x in parts[1:6])
                with self._cond:
                    self._events.append((cycle, level, channel, epoch, consumed))
                    self._progress = max(self._progress, cycle)
                    if level != self._d4_level:
                        self.d4_changes.append((cycle / F_CPU_HZ, level))
                        self._d4_level = level
                    if channel != self._channel:
                        self.channel_changes.append((cycle / F_CPU_HZ, channel))
                        self._channel = channel
                    self._cond.notify_all()
            elif not parts[0].startswith("#HX") and parts[0] != "#READY":
                self._stderr_tail.append(line)
        rc = proc.wait()
        if not self._stop.is_set():
            last = self._stderr_tail[-1] if self._stderr_tail else "no message"
            self._fail(f"the twin's simavr harness ended (exit code {rc}): {last}")

    def _write(self, data: bytes) -> None:
        fd = self._proc.stdin.fileno()
        view = memoryview(data)
        while view:
            n = os.write(fd, view)
            view = view[n:]

    def _feed(self) -> None:
        try:
            self._feed_loop()
        except (BrokenPipeError, ValueError, OSError):
            if not self._stop.is_set():
                self._fail("the twin's simavr harness stopped reading its input")
        except Exception as exc:  # noqa: BLE001 - any failure ends the twin, as a pulled cable; see failure
            self._fail(f"twin feeder failed: {type(exc).__name__}: {exc}")

    def _feed_loop(self) -> None:
        import numpy as np

        stream = self._stream
        rng = np.random.default_rng([self.seed, 711])
        self._aux_done = 0.0
        self._last_rise = 0.0
        self._silent = False
        self._write(pack_records("P", 0, 0))
        while not self._stop.is_set():
            with self._cond:
                while (not self._stop.is_set() and not self._events
                       and stream.done_s - self._progress / F_CPU_HZ >= self.LOOKAHEAD_S):
                    self._cond.wait(0.2)
                events, self._events = self._events, []
                progress_s = self._progress / F_CPU_HZ
            if self._stop.is_set():
                return
            target = max(progress_s + self.LOOKAHEAD_S, stream.done_s + self.CHUNK_S)
            parts = []
            if events:
                for cycle, level, channel, epoch, consumed in events:
                    # a look-ahead from the switch (the stream's end before it is void: with a switch every
                    # few ms, as a scan makes, a target from it would run away)
                    t_sw = cycle / F_CPU_HZ
                    chunk = stream.switch(t_sw, level, consumed, max(progress_s, t_sw) + self.LOOKAHEAD_S,
                                          channel if self.multiplexed else None)
                    parts = [pack_records("P", epoch, 0)]  # earlier epochs' edges are void
                    self.edges_sent = consumed
            else:
                chunk = stream.advance(target)
            parts.append(self._edges(chunk))
            parts.append(self._aux(chunk.done_s, rng))
            parts.append(pack_records("L", 0, max(0, math.floor(chunk.done_s * F_CPU_HZ) - 64)))
            self._write(b"".join(parts))
            self._watch_oscillation(chunk)
            stream.forget_before(progress_s - 0.01)

    def _edges(self, chunk) -> bytes:
        import numpy as np

        self.edges_sent += chunk.t_s.size
        if not chunk.t_s.size:
            return b""
        return pack_records("E", chunk.level, np.rint(chunk.t_s * F_CPU_HZ).astype(np.int64))

    def _aux(self, t_end: float, rng) -> bytes:
        """A0 on the source's grid and the HX711's conversions in ``[aux_done, t_end)``."""
        import numpy as np

        t0 = self._aux_done
        if t_end <= t0:
            return b""
        dt = self.source.dt_s
        k = np.arange(math.ceil(t0 / dt - 1e-9), math.ceil(t_end / dt - 1e-9))
        out = []
        if k.size:
            t = k * dt
            mv = np.clip(np.rint(self.source.parts(t)[2] * 1000.0), 0, 5000).astype(np.int64)
            out.append(pack_records("A", mv, np.rint(t * F_CPU_HZ).astype(np.int64)))
        cell = self.loadcell
        if cell is not None:
            tc = cell.conversion_times(t0, t_end)
            if tc.size:
                force = self.source.force_n(np.maximum(tc - 0.5 * cell.period_s, 0.0))
                raw = cell.raw(force, tc, rng=rng).astype(np.int64)
                out.append(pack_records("H", raw, np.rint(tc * F_CPU_HZ).astype(np.int64) - 16))
        self._aux_done = t_end
        return b"".join(out)

    def _watch_oscillation(self, chunk) -> None:
        rises = chunk.t_s[chunk.level == 1]
        if rises.size:
            if self._silent:
                self._notice(f"t = {rises[0]:.3f} s: the 555 oscillates again")
                self._silent = False
            self._last_rise = float(rises[-1])
        elif not self._silent and chunk.done_s - self._last_rise > self.NO_OSCILLATION_S:
            self._silent = True
            self._notice(f"t = {self._last_rise:.3f} s: the sensor drives the 555 out of oscillation "
                         "(R_FSR too low for the capacitor to reach 2/3 Vcc: N = R_FSR/R below 4, eq. 30); "
                         "the firmware sends windows without periods")
