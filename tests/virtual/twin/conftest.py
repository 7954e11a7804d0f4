"""The digital twin for the tests of this folder: firmware and harnesses built once (``make -C firmware``).

Outside CI a missing tool (avr-gcc, make, simavr headers, Debian's Arduino core) skips with a reason;
with ``CI=true`` it fails (:mod:`toolcheck`).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from toolcheck import require_file, require_tool

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "firmware" / "sim"))
sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture(scope="session")
def built():
    """The firmware ELF and the twin's harness, built (incremental ``make -C firmware``)."""
    require_tool("avr-gcc")
    require_tool("make")
    require_file("/usr/include/simavr/sim_avr.h", "libsimavr-dev (simavr headers)")
    require_file("/usr/share/arduino/hardware/arduino/avr/cores/arduino/Arduino.h", "arduino-core-avr")
    subprocess.run(["make", "-s", "-C", str(ROOT / "firmware")], check=True, capture_output=True, text=True)
    from fsrlab.virtual.twin import twin_available

    ok, reason = twin_available()
    assert ok, reason
    return ROOT
