"""Helpers of the recording tests: the command line in a child process, and polling a growing run."""

from __future__ import annotations

import sys
import time
from pathlib import Path

CLI = [sys.executable, "-c", "import sys; from fsrlab.cli import main; main(sys.argv[1:])"]
"""``fsrlab`` in a child process (``CLI + [command, ...]``)."""


def rows(path: Path) -> int:
    """Data rows written so far to a run file (0 before it exists)."""
    try:
        return max(path.read_text().count("\n") - 1, 0)
    except FileNotFoundError:
        return 0


def wait(predicate, limit_s: float = 30.0) -> None:
    """Poll until ``predicate()``; the limit only guards against a hang."""
    end = time.monotonic() + limit_s
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError("condition not reached")
        time.sleep(0.02)
