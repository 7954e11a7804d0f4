"""Tests that need a real tool (ngspice, avr-gcc, simavr) call :func:`require_tool`.

Outside CI a missing tool skips the test with a reason; with ``CI=true`` it fails, so CI always
proves the real thing.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

IN_CI = os.environ.get("CI", "").lower() in {"1", "true", "yes"}


def missing_column(what: str, hint: str) -> None:
    message = f"{what} is not installed ({hint}; `make sysdeps` installs it)"
    if IN_CI:
        pytest.fail(f"CI=true: {message}")
    pytest.skip(message)


def require_tool(name: str) -> str:
    """Return the path of executable ``name``, or skip (fail in CI) when it is missing."""
    path = shutil.which(name)
    if path is None:
        missing_column(f"`{name}`", "needed by this test")
    return path


def require_file(path: str | os.PathLike, hint: str) -> Path:
    """Return ``path`` when it exists, or skip (fail in CI) naming ``hint``."""
    p = Path(path)
    if not p.exists():
        missing_column(str(p), hint)
    return p
