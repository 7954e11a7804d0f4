"""A device reset in the middle of a session: ``fsrlab acquire`` and ``fsrlab live`` both go on.

Both read the meter through the same loop (:class:`fsrlab.acquisition.stream.WindowStream`), which sends the
settings and START again when the device restarts. Reference: the virtual device's fault injection
(``Faults(reset_after=N)``: a cut line, the boot ``ID`` with sequence 0 and a stopped device after N
windows) and the number of 20 ms windows in the time the device is read.
"""

from __future__ import annotations

import time

import numpy as np

from fsrlab.acquisition.recorder import record
from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.io.runformat import load_run
from fsrlab.live.session import LiveSession
from fsrlab.virtual.device import Faults, VirtualDevice
from fsrlab.virtual.sources import ConstantSource

RESET_AFTER = 20
"""Windows before the device restarts."""
READ_S = 3.0
"""How long each command reads the device: 150 windows of 20 ms. [s]"""


def test_acquire_and_live_both_go_on_after_the_same_device_reset(tmp_path):
    with VirtualDevice(ConstantSource(), faults=Faults(reset_after=RESET_AFTER), seed=2) as dev, \
            SerialLink(dev.port) as link:
        result = record(link, tmp_path / "acquire.csv", READ_S, window_ms=20)
    run = load_run(tmp_path / "acquire.csv")
    assert result.stats.resets == 1 and result.ended == "duration"
    assert run.n_rows > 3 * RESET_AFTER  # the recording went on after the reset
    assert np.all(np.diff(run["time_s"]) > 0)  # one time axis through the reset

    with VirtualDevice(ConstantSource(), faults=Faults(reset_after=RESET_AFTER), seed=2) as dev:
        session = LiveSession(SerialLink(dev.port), window_ms=20, stall_s=1.0).start()
        recording = tmp_path / "live.csv"
        try:
            time.sleep(0.2)
            session.command("record", str(recording))
            time.sleep(READ_S)
            session.command("stop_recording")
            time.sleep(0.2)
            status = session.status
            parser = session.link.parser
        finally:
            session.close()
    assert parser.resets == 1
    assert status.frames > 3 * RESET_AFTER, status.events  # the page kept getting windows
    assert status.stalls == 0 and status.state in ("running", "stopped")
    assert any("device restarted" in e for e in status.events)
    live = load_run(recording)
    assert live.n_rows > 2 * RESET_AFTER and np.all(np.diff(live["time_s"]) > 0)
