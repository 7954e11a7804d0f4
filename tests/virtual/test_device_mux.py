"""The Python virtual device with several sensors behind a multiplexer (issue 39), recorded through the
real pty and the host's recording loop.

References: properties the scan must have (docs/protocol.md, "A scan"): readings in channel order with
one scan number per pass and their own time; an open channel's readings have no periods; each channel's
frequency is its own sensor's (channel k under the profile at peak × (k+1)/n, so its peak frequency rises
strictly with k: the sensor's frequency rises with stress, paper §5 Fig. 19a); the rate the firmware's
timing gives (DWELL plus SETTLE + 1 periods of the channel, ≥ 20 readings/s each for 8 channels at the
defaults, as in the twin).
"""

from __future__ import annotations

import numpy as np

from fsrlab.acquisition.recorder import Scan, record
from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.io.runformat import load_run
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import MuxSource, StressProfile


def _run(tmp_path, source, channels, duration_s=2.0):
    with VirtualDevice(source, seed=3, speed="max") as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", duration_s, scan=Scan(channels), clock="device",
                        metadata=source.metadata(), reference=lambda f: dev.reference(f.seq))
    assert result.ended == "duration" and result.dropped == 0, result.message
    return load_run(tmp_path / "run.csv")


def test_eight_channels_in_order_each_its_own_sensor(tmp_path):
    source = MuxSource.scaled(8, StressProfile("triangle", 50e3, 4.0))
    run = _run(tmp_path, source, tuple(range(8)), duration_s=3.0)
    ch = np.asarray(run["channel"], dtype=int)
    assert np.array_equal(ch, np.arange(ch.size) % 8)
    assert np.array_equal(np.asarray(run["scan"], dtype=int), np.arange(ch.size) // 8)
    assert np.all(np.diff(np.asarray(run["time_s"])) > 0)
    assert np.all(np.bincount(ch) / 3.0 >= 20.0)
    f = np.asarray(run["frequency_hz"])
    assert np.all(np.diff([f[ch == k].max() for k in range(8)]) > 0)
    stress = np.asarray(run["stress_pa"])
    assert np.all(np.diff([stress[ch == k].max() for k in range(8)]) > 0)  # each reading: its channel's stress
    assert run.metadata["channels"][3]["sensor_id"] == "fsr3"


def test_an_open_channel_gives_readings_without_periods(tmp_path):
    full = MuxSource.scaled(3, StressProfile("hold", 20e3, 1.0))
    source = MuxSource([full.sources[0], None, full.sources[2]])
    run = _run(tmp_path, source, (0, 1, 2), duration_s=1.0)
    ch = np.asarray(run["channel"], dtype=int)
    periods = np.asarray(run["periods"])
    assert np.all(periods[ch == 1] == 0) and np.all(periods[ch != 1] > 0)
    assert np.all(np.isnan(np.asarray(run["frequency_hz"])[ch == 1]))
    assert run.metadata["channels"][1]["open"] is True
