"""What fsrlab shows and reads on the terminal: the one rendering boundary (:class:`EscapedStream`,
:func:`escaped_output`: everything a command prints passes :func:`fsrlab.io.shown.printable`), the live table of a
recording (:class:`LiveView`), a person's answers typed on stdin (:class:`Keyboard`), and SIGTERM taken as Ctrl-C.
Re-exported by :mod:`fsrlab.cli.options`, where the command modules take them from."""

from __future__ import annotations

import math
import queue
import signal
import sys
import threading
from contextlib import contextmanager


class EscapedStream:
    """A text stream that writes what it is given through :func:`fsrlab.io.shown.printable`: a control character
    in a table cell, a title, a column name, a file name or a message is printed as its escape (``\\x1b``), never
    sent to the terminal.

    It says it is not a terminal, so rich tables and click print plain text through it (their own styling escapes
    would be escaped too); :attr:`raw` is the stream underneath, for the one writer that draws on the terminal
    itself (:class:`LiveView`, whose content it escapes).

    Parameters
    ----------
    raw : text stream
        ``sys.stdout`` or ``sys.stderr`` as they were.
    """

    def __init__(self, raw) -> None:
        self.raw = raw

    def write(self, text: str) -> int:
        if not isinstance(text, str):
            raise TypeError(f"write() argument must be str, not {type(text).__name__}")
        from fsrlab.io.shown import printable

        self.raw.write(printable(text))
        return len(text)

    def writelines(self, lines) -> None:
        for line in lines:
            self.write(line)

    def isatty(self) -> bool:
        return False

    def __getattr__(self, name):  # flush, fileno, encoding, errors, buffer, ...
        return getattr(self.raw, name)


@contextmanager
def escaped_output():
    """``sys.stdout`` and ``sys.stderr`` as :class:`EscapedStream` for the duration of a command."""
    saved = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = (s if isinstance(s, EscapedStream) else EscapedStream(s) for s in saved)
    try:
        yield
    finally:
        sys.stdout, sys.stderr = saved


def raw_stream(stream):
    """The stream under an :class:`EscapedStream` (``stream`` itself otherwise)."""
    return stream.raw if isinstance(stream, EscapedStream) else stream


def fmt_value(value: float, spec: str) -> str:
    return "—" if value is None or not math.isfinite(value) else format(value, spec)


class LiveView:
    """Rich live table of the recording on stderr (frames/s, frequency, duty cycle, dropped), and notices."""

    def __init__(self, enabled: bool, title: str) -> None:
        from rich.console import Console

        from fsrlab.io.shown import printable

        # The terminal itself (the live table moves the cursor); what it shows is escaped here.
        self.console = Console(file=raw_stream(sys.stderr))
        self.enabled = enabled and self.console.is_terminal
        self.title = printable(title, keep="")
        self.live = None

    def __enter__(self) -> LiveView:
        if self.enabled:
            from rich.live import Live

            self.live = Live(self._render(None), console=self.console, transient=True, refresh_per_second=8)
            self.live.__enter__()
        return self

    def _render(self, st):
        from rich.table import Table

        table = Table(title=self.title, show_header=True, header_style="bold")
        for col in ("time (s)", "frames", "frames/s", "frequency (Hz)", "duty cycle "
                "(%)", "dropped", "corrupt", "resets"):
            table.add_column(col, justify="right")
        if st is not None:
            table.add_row(f"{st.elapsed_s:.1f}", str(st.frames), f"{st.frames_per_s:.1f}",
                          fmt_value(st.frequency_hz, ".1f"),
                          fmt_value(st.duty_cycle * 100 if st.duty_cycle == st.duty_cycle else math.nan, ".2f"),
                          str(st.dropped), str(st.bad_frames), str(st.resets))
        return table

    def update(self, st) -> None:
        if self.live is not None:
            self.live.update(self._render(st))

    def notice(self, text: str) -> None:
        """One line on stderr, above the live table when there is one (shown even with --quiet)."""
        if self.live is not None:
            from fsrlab.io.shown import printable

            self.console.print(f"fsrlab: {printable(text, keep='')}", markup=False, highlight=False)
        else:
            print(f"fsrlab: {text}", file=sys.stderr, flush=True)

    def __exit__(self, *exc) -> None:
        if self.live is not None:
            self.live.__exit__(*exc)


class Keyboard:
    """The user's answers: lines typed on stdin, read by a daemon thread (the recording never waits on them)."""

    def __init__(self) -> None:
        self._lines: queue.Queue = queue.Queue()
        self._eof_said = False
        threading.Thread(target=self._read, name="fsrlab-weights-stdin", daemon=True).start()

    def _read(self) -> None:
        try:
            for line in sys.stdin:
                self._lines.put(line)
        except (OSError, ValueError):  # no usable stdin (closed, or a test's captured one)
            pass
        self._lines.put(None)  # end of input: every later question is answered "ok"

    def drain(self) -> None:
        """Forget what was typed before the question."""
        while True:
            try:
                if self._lines.get_nowait() is None:
                    self._lines.put(None)
                    return
            except queue.Empty:
                return

    def answer(self) -> str | None:
        """None (nothing typed yet), "skip" (s) or "ok" (anything else, or the end of the input)."""
        try:
            line = self._lines.get_nowait()
        except queue.Empty:
            return None
        if line is None:
            self._lines.put(None)
            if not self._eof_said:
                self._eof_said = True
                print("fsrlab: standard input closed: every later step goes on without waiting for Enter",
                      file=sys.stderr, flush=True)
            return "ok"
        return "skip" if line.strip().lower() in ("s", "skip") else "ok"


@contextmanager
def sigterm_as_interrupt():
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
