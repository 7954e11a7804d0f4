"""``fsrlab acquire`` and ``fsrlab virtual-device``: record an fsrlab meter, or emulate one on a pty."""

from __future__ import annotations

import math
import signal
import sys
from contextlib import contextmanager
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli._common import emit_json, eng, fail

_PROFILE_HELP = "Virtual stress profile: triangle, sine, steps or hold."


@contextmanager
def _sigterm_as_interrupt():
    """Let SIGTERM end a recording like Ctrl-C (file closed, device stopped)."""
    def handler(signum, frame):  # noqa: ARG001
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread (e.g. called from a test thread): leave it
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _virtual_device(profile: str, peak: float, period: float, c_off: float, seed: int | None,
                    corrupt: float, drop: float):
    from fsrlab.acquisition.virtual_device import VIRTUAL_CIRCUIT, Faults, PhysicsSource, StressProfile, VirtualDevice

    prof = StressProfile(kind=profile, peak_pa=peak, period_s=period)
    source = PhysicsSource(prof, circuit=VIRTUAL_CIRCUIT.replace(c_off_farad=c_off))
    return VirtualDevice(source, faults=Faults(corrupt=corrupt, drop=drop), seed=seed), source


def _fmt(value: float, spec: str) -> str:
    return "—" if value is None or not math.isfinite(value) else format(value, spec)


class _LiveView:
    """Rich live table of the recording on stderr (frames/s, frequency, duty cycle, dropped)."""

    def __init__(self, enabled: bool, title: str) -> None:
        from rich.console import Console

        self.console = Console(stderr=True)
        self.enabled = enabled and self.console.is_terminal
        self.title = title
        self.live = None

    def __enter__(self) -> "_LiveView":
        if self.enabled:
            from rich.live import Live

            self.live = Live(self._render(None), console=self.console, transient=True, refresh_per_second=8)
            self.live.__enter__()
        return self

    def _render(self, st):
        from rich.table import Table

        table = Table(title=self.title, show_header=True, header_style="bold")
        for col in ("time (s)", "frames", "frames/s", "frequency (Hz)", "duty cycle (%)", "dropped", "corrupt", "resets"):
            table.add_column(col, justify="right")
        if st is not None:
            table.add_row(f"{st.elapsed_s:.1f}", str(st.frames), f"{st.frames_per_s:.1f}", _fmt(st.frequency_hz, ".1f"),
                          _fmt(st.duty_cycle * 100 if st.duty_cycle == st.duty_cycle else math.nan, ".2f"),
                          str(st.dropped), str(st.bad_frames), str(st.resets))
        return table

    def update(self, st) -> None:
        if self.live is not None:
            self.live.update(self._render(st))

    def __exit__(self, *exc) -> None:
        if self.live is not None:
            self.live.__exit__(*exc)


@app.command("acquire")
def acquire(
    port: str = typer.Option(None, "--port", help="Serial port (/dev/ttyACM0, COM3, a pty) or 'auto' to find an Uno by USB id."),
    virtual: bool = typer.Option(False, "--virtual", help="Record from a virtual device (pty, physics and 555 models) instead of hardware."),
    duration: float = typer.Option(60.0, "--duration", parser=eng, help="Recording time (s)."),
    out: Path = typer.Option(Path("run.csv"), "--out", "-o", help="Run file (CSV + NAME.meta.json sidecar, docs/data-format.md)."),
    window: int = typer.Option(100, "--window", help="Measurement window (ms), 10..60000."),
    range_: int = typer.Option(0, "--range", help="C_off range switch: 0 (off) or 1 (C_off connected)."),
    baud: int = typer.Option(115200, "--baud", help="Line rate (bit/s; protocol v1: 115200)."),
    profile: str = typer.Option("triangle", "--profile", help=_PROFILE_HELP),
    peak: float = typer.Option(50e3, "--peak", parser=eng, help="Virtual profile: peak stress [Pa], e.g. 50k."),
    period: float = typer.Option(4.0, "--period", parser=eng, help="Virtual profile: cycle time (s)."),
    c_off: float = typer.Option(1e-9, "--c-off", parser=eng, help="Virtual circuit: C_off switched in by --range 1 [F], e.g. 1n."),
    seed: int = typer.Option(None, "--seed", help="Virtual device: random seed."),
    corrupt: float = typer.Option(0.0, "--corrupt", parser=eng, help="Virtual device: probability that a frame is corrupted (tests)."),
    drop: float = typer.Option(0.0, "--drop", parser=eng, help="Virtual device: probability that a frame is lost (tests)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No live display."),
    json_out: bool = typer.Option(False, "--json", help='Print {"frames", "dropped", "duration_s", "file"} as JSON.'),
) -> None:
    """Record measurement windows (frequency, duty cycle, A0 voltage) from an fsrlab meter into a run file.

    Written row by row: Ctrl-C or a kill loses at most the window in progress. A device unplugged
    mid-run ends the run with the file intact, a one-line message and exit code 1.
    """
    from fsrlab.acquisition.protocol import WINDOW_MS_MAX, WINDOW_MS_MIN
    from fsrlab.acquisition.recorder import record, result_dict
    from fsrlab.acquisition.serial_link import SerialLink

    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    if not duration > 0:
        fail(f"must be > 0 s, got {duration:g}", "--duration")
    if not WINDOW_MS_MIN <= window <= WINDOW_MS_MAX:
        fail(f"must be in {WINDOW_MS_MIN}..{WINDOW_MS_MAX} ms, got {window}", "--window")
    if range_ not in (0, 1):
        fail(f"must be 0 or 1, got {range_}", "--range")
    if not baud > 0:
        fail(f"must be > 0, got {baud}", "--baud")
    for name, v in (("--corrupt", corrupt), ("--drop", drop)):
        if not 0 <= v <= 1:
            fail(f"must be in 0..1, got {v:g}", name)
    device = None
    metadata: dict = {}
    reference = None
    if virtual:
        from fsrlab.acquisition.virtual_device import PROFILE_KINDS

        if profile not in PROFILE_KINDS:
            fail(f"must be one of {', '.join(PROFILE_KINDS)}, got {profile!r}", "--profile")
        if not peak > 0:
            fail(f"must be > 0 Pa, got {peak:g}", "--peak")
        if not period > 0:
            fail(f"must be > 0 s, got {period:g}", "--period")
        if not c_off >= 0:
            fail(f"must be >= 0 F, got {c_off:g}", "--c-off")
        device, source = _virtual_device(profile, peak, period, c_off, seed, corrupt, drop)
        port = device.open()
        metadata = {"origin": "fsrlab acquire --virtual (VirtualFSR -> LM555 astable and op-amp -> meter model "
                              "fsrlab.acquisition.meter -> emulated firmware over a pty)",
                    **source.metadata(),
                    "notes": f"virtual stress profile {profile}, peak {peak:g} Pa, period {period:g} s; "
                             "stress_pa is the applied (reference) stress"}
        reference = lambda frame: device.reference(frame.seq)  # noqa: E731
    try:
        with SerialLink(port, baud=baud) as link, _sigterm_as_interrupt(), \
                _LiveView(not quiet, f"fsrlab acquire {link.port} -> {out}") as view:
            result = record(link, out, duration, window_ms=window, range_=range_, metadata=metadata,
                            reference=reference, on_status=view.update)
    finally:
        if device is not None:
            device.close()
    if json_out:
        emit_json(result_dict(result))
    else:
        typer.echo(f"{out}: {result.frames} windows, {result.dropped} dropped, {result.duration_s:.1f} s "
                   f"({result.stats.bad_frames} corrupt lines, {result.stats.resets} device resets)")
    if result.ended in ("disconnected", "error"):
        print(f"fsrlab: {result.message}", file=sys.stderr)
        raise typer.Exit(1)


@app.command("virtual-device")
def virtual_device(
    duration: float = typer.Option(None, "--duration", parser=eng, help="Run this long (s); default until Ctrl-C."),
    profile: str = typer.Option("triangle", "--profile", help=_PROFILE_HELP),
    peak: float = typer.Option(50e3, "--peak", parser=eng, help="Peak stress [Pa], e.g. 50k."),
    period: float = typer.Option(4.0, "--period", parser=eng, help="Cycle time of the profile (s)."),
    c_off: float = typer.Option(1e-9, "--c-off", parser=eng, help="C_off switched in by RANGE 1 [F], e.g. 1n."),
    seed: int = typer.Option(None, "--seed", help="Random seed."),
    corrupt: float = typer.Option(0.0, "--corrupt", parser=eng, help="Probability that a frame is corrupted."),
    drop: float = typer.Option(0.0, "--drop", parser=eng, help="Probability that a frame is lost."),
    json_out: bool = typer.Option(False, "--json", help='Print {"port": PATH} as JSON (one line) instead of the bare path.'),
) -> None:
    """Emulate an fsrlab meter on a pseudo-terminal; prints its path (open it with --port PATH or any serial tool)."""
    import json

    from fsrlab.acquisition.virtual_device import PROFILE_KINDS

    if duration is not None and not duration > 0:
        fail(f"must be > 0 s, got {duration:g}", "--duration")
    if profile not in PROFILE_KINDS:
        fail(f"must be one of {', '.join(PROFILE_KINDS)}, got {profile!r}", "--profile")
    for name, v in (("--corrupt", corrupt), ("--drop", drop)):
        if not 0 <= v <= 1:
            fail(f"must be in 0..1, got {v:g}", name)
    if not (peak > 0 and period > 0 and c_off >= 0):
        fail("--peak and --period must be > 0 and --c-off >= 0", "--peak")
    device, _ = _virtual_device(profile, peak, period, c_off, seed, corrupt, drop)
    path = device.open(thread=False)
    typer.echo(json.dumps({"port": path}) if json_out else path)
    sys.stdout.flush()
    try:
        with _sigterm_as_interrupt():
            device.serve(duration)
    except KeyboardInterrupt:
        pass
    finally:
        device.close()
