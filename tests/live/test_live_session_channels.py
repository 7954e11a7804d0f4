"""The live session with several sensors (issue 39): each channel's latest reading and link health.

Reference: the virtual device's sensors (channel k held at 50 kPa · (k + 1)/8: its frequency rises with
k, paper §5 Fig. 19a; channel 2 open: no sensor, so no oscillation) read through the host's recording
loop; the session's counters against the rows it kept.
"""

from __future__ import annotations

import math
import time

from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.acquisition.stream import Scan
from fsrlab.live.session import LiveSession
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import MuxSource, StressProfile


def test_channels_keep_their_latest_reading_and_health():
    full = MuxSource.scaled(4, StressProfile("hold", peak_pa=50e3, period_s=1.0))
    source = MuxSource([full.sources[0], full.sources[1], None, full.sources[3]])
    with VirtualDevice(source, seed=2, speed="max") as dev, SerialLink(dev.port) as link:
        session = LiveSession(link, scan=Scan((0, 1, 2, 3))).start()
        try:
            end = time.monotonic() + 60
            while time.monotonic() < end and min(c["readings"] for c in session.channels()) < 10:
                time.sleep(0.05)
            chans = session.channels()
            total, cols = session.since(0)
        finally:
            session.close()
    assert [c["sensor_id"] for c in chans] == ["fsr0", "fsr1", "fsr2", "fsr3"]
    assert all(c["readings"] >= 10 for c in chans)
    f = [c["frequency_hz"] for c in chans]
    assert f[0] < f[1] < f[3] and math.isnan(f[2])
    assert chans[2]["no_oscillation"] == chans[2]["readings"] and chans[0]["no_oscillation"] == 0
    assert all(c["missed"] == 0 for c in chans)
    assert set(cols["channel"]) == {0, 1, 2, 3}
