"""``fsrlab live --channels 0-7`` in a real headless Chromium: the sensor map updates, at a bounded rate.

Reference: the run file the same session recorded (the host's recording loop, read back with fsrlab's run
reader): every value the page's sensor map shows is a reading of that channel in the file. The ordering
of the channels is the physics': channel k is held under the triangle at peak · (k + 1)/8, and an FSR's
frequency rises with its stress (paper §5, Fig. 19a). The rate bound is the page's own contract
(the map is patched with the status line, at most every :data:`fsrlab.live.page.STATUS_S`), counted by BokehJS's
``patching`` signal in the browser.
"""

from __future__ import annotations

import numpy as np
import pytest

from browser import ARTIFACTS, LIGHT, LiveServer, chromium, click_button, model_length, text, wait_for
from fsrlab.io.runformat import load_run
from fsrlab.live.page import STATUS_S

MAP_JS = """
  if (!window.Bokeh || !Bokeh.documents || !Bokeh.documents.length) return null;
  const src = Bokeh.documents[0].get_model_by_name('sensor_map');
  if (!src) return null;
  if (window.__mapPatches === undefined) {
    window.__mapPatches = 0;
    src.patching.connect(() => { window.__mapPatches += 1; });
  }
  const d = src.data, get = (k) => Array.from((d instanceof Map) ? d.get(k) : d[k]);
  return {channel: get('channel'), f: get('frequency_khz'), readings: get('readings'),
          missed: get('missed'), patches: window.__mapPatches, t: performance.now()};
"""


@pytest.fixture
def driver():
    d = chromium()
    yield d
    d.quit()


def _map(driver):
    return driver.execute_script(MAP_JS)


def test_sensor_map_updates_with_each_channels_readings(driver, tmp_path):
    out = tmp_path / "eight.csv"
    server = LiveServer("--virtual", "--channels", "0-7", "--seed", "5", "--out", str(out), "--period", "4s", *LIGHT)
    try:
        driver.get(server.url)
        assert wait_for(lambda: (m := _map(driver)) is not None and min(m["readings"]) > 0)
        assert click_button(driver, "Start recording")
        assert wait_for(lambda: text(driver, "#recording")) == str(out)
        first = _map(driver)
        shown = []
        end = first["t"] + 5000.0  # 5 s of the page's clock: more than one period of the profile
        while (m := _map(driver))["t"] < end:
            if not shown or m["readings"] != shown[-1]["readings"]:
                shown.append(m)
            wait_for(lambda r=m["readings"]: _map(driver)["readings"] != r, timeout_s=2, interval_s=0.02)
        last = _map(driver)
        lengths = [model_length(driver, "channels", f"t{k}") for k in range(8)]
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        driver.save_screenshot(str(ARTIFACTS / "live-channels.png"))
        assert click_button(driver, "Stop recording")
        assert wait_for(lambda: text(driver, "#recording") is None)
    finally:
        server.stop()
    assert first["channel"] == list(range(8))
    # updating: every channel read again and again, the map sent as patches no faster than one per STATUS_S
    assert len(shown) >= 10
    assert all(b > a for a, b in zip(first["readings"], last["readings"], strict=True))
    seconds = (last["t"] - first["t"]) / 1000.0
    patches = last["patches"] - first["patches"]
    assert 5 <= patches <= seconds / STATUS_S * 1.2 + 2, (patches, seconds)
    assert min(lengths) > 0  # the frequency plot has every channel's readings
    assert all(m == 0 for m in last["missed"])
    # every frequency the map showed while recording is a reading of that channel in the run
    run = load_run(out)
    channel, f_khz = np.asarray(run["channel"], dtype=int), np.asarray(run["frequency_hz"]) / 1e3
    compared = 0
    for m in shown:
        for k, f in zip(m["channel"], m["f"], strict=True):
            if f is not None and np.isclose(f_khz[channel == k], f, rtol=1e-12, atol=0).any():
                compared += 1
    assert compared >= 8 * (len(shown) - 2)  # (the first and last maps may be from outside the recording)
    # near the profile's peak the map is ordered by stress: the map where channel 7 is highest
    top = max(shown, key=lambda m: m["f"][7])
    assert all(a < b for a, b in zip(top["f"], top["f"][1:], strict=False)), top["f"]
