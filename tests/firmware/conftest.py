"""The firmware in simavr for the tests of this folder: the harness built once (``firmware/sim``).

Outside CI a missing tool (avr-gcc, make, simavr headers, Debian's Arduino core) skips with a reason;
with ``CI=true`` it fails (:mod:`toolcheck`).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from toolcheck import require_file, require_tool

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "firmware" / "sim"))


@pytest.fixture(scope="session")
def fw():
    """The :mod:`simrun` module with the sketch and the harness built (``make -C firmware``)."""
    import simrun

    require_tool("avr-gcc")
    require_tool("make")
    require_file("/usr/include/simavr/sim_avr.h", "libsimavr-dev (simavr headers)")
    require_file("/usr/share/arduino/hardware/arduino/avr/cores/arduino/Arduino.h", "arduino-core-avr")
    simrun.build()
    return simrun
