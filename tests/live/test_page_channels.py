"""The multi-sensor live page's pieces without a browser (src/fsrlab/live/page_channels.py).

References: the channel map's positions as given (metres) or, without them, a grid of four columns; the
scan order of the meter (channels read in increasing order, a scan after a scan: docs/protocol.md,
``SCAN``), which makes one row per scan; 1-2-5 steps by their definition.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from fsrlab.acquisition.stream import Scan
from fsrlab.live.page_channels import ChannelPlots, map_columns, nice_step


def _chan(k, f=1000.0 * (1 + 0.1), x=None, y=None, readings=1):
    return {"channel": k, "sensor_id": f"fsr{k}", "x_m": x, "y_m": y, "frequency_hz": f, "estimate": math.nan,
            "readings": readings, "missed": 0, "no_oscillation": 0 if math.isfinite(f) else readings}


def test_map_positions_are_the_channel_maps_or_a_grid():
    grid = map_columns([_chan(k) for k in range(6)], estimated=False)
    assert list(zip(grid["x"], grid["y"], strict=True)) == [(0, 0), (1, 0), (2, 0), (3, 0), (0, -1), (1, -1)]
    placed = map_columns([_chan(0, x=0.01, y=0.02), _chan(1, f=math.nan, x=0.03, y=0.0)], estimated=False)
    assert (placed["x"], placed["y"]) == ([0.01, 0.03], [0.02, 0.0])
    assert placed["value"][0] == pytest.approx(1.1) and math.isnan(placed["value"][1])  # no oscillation: grey


def test_readings_become_one_row_per_scan():
    chans = [_chan(k) for k in range(3)]
    session = SimpleNamespace(scan=Scan((0, 1, 2)), estimator=None, channel_map=chans,
                              channels=lambda: [dict(c) for c in chans])
    plots = ChannelPlots(session)
    plots.add({"time_s": [0.0, 0.1, 0.2, 0.3, 0.4], "frequency_hz": [1e3, 2e3, 3e3, 1.5e3, float("nan")],
               "channel": [0, 1, 2, 0, 1]})
    plots.flush()  # the first scan is complete; the second is still being read
    assert plots.source.data["t0"] == [0.0] and plots.source.data["f2"] == [3.0]
    plots.add({"time_s": [0.5, 0.6], "frequency_hz": [3.5e3, 1.6e3], "channel": [2, 0]})
    plots.flush()
    assert plots.source.data["t0"] == [0.0, 0.3] and plots.source.data["f2"] == [3.0, 3.5]
    assert math.isnan(plots.source.data["f1"][1])


@pytest.mark.parametrize("x, step", [(0.3, 0.5), (1.0, 1.0), (1.2, 2.0), (3.0, 5.0), (7.0, 10.0), (1.6e3, 2e3)])
def test_nice_step(x, step):
    assert nice_step(x) == pytest.approx(step)
