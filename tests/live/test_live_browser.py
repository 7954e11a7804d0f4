"""``fsrlab live`` in a real headless Chromium (Debian's chromium + chromium-driver, Selenium).

Reference: the run file the same session recorded (rows written by the crash-safe writer), read back
with fsrlab's run reader; and HTTP status codes for the access rules. The virtual device feeds the
page (a triangle stress profile through the physics, circuit and meter models, over a pty).
"""

from __future__ import annotations

import urllib.error
import urllib.request

import pytest

from browser import (
    ARTIFACTS,
    LIGHT,
    LiveServer,
    button_disabled,
    chromium,
    click_button,
    model_length,
    text,
    texts,
    wait_for,
)
from clirun import run_cli
from fsrlab.io.runformat import load_run, sidecar_path


@pytest.fixture
def driver():
    d = chromium()
    yield d
    d.quit()


def test_page_shows_the_windows_the_recorder_wrote_and_the_loop_grows(driver, tmp_path):
    out = tmp_path / "live.csv"
    server = LiveServer("--virtual", "--seed", "3", "--out", str(out), "--window", "50ms", *LIGHT)
    try:
        driver.get(server.url)
        assert wait_for(lambda: text(driver, "#latest-seq"))
        assert click_button(driver, "Start recording")
        assert wait_for(lambda: text(driver, "#recording")) == str(out)
        n1 = wait_for(lambda: model_length(driver, "windows", "seq"))
        seen = []
        keys = ("#latest-seq", "#latest-frequency", "#latest-duty", "#latest-voltage")
        for _ in range(15):  # values as the page shows them, window after window (each read in one step)
            shown = texts(driver, keys)
            seen.append(tuple(shown[k] for k in keys))
            wait_for(lambda s=seen[-1][0]: text(driver, "#latest-seq") != s, timeout_s=2)
        n2 = model_length(driver, "windows", "seq")
        assert n2 > n1 > 0  # the loop plot's source grows
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        driver.save_screenshot(str(ARTIFACTS / "live-page.png"))
        assert click_button(driver, "Stop recording")
        assert wait_for(lambda: text(driver, "#recording") is None)
    finally:
        summary, err = server.stop()
    run = load_run(out)
    assert run.n_rows > 10
    rows = {int(s): i for i, s in enumerate(run["seq"])}
    compared = 0
    for seq, f, duty, volts in seen:
        if seq is None or int(seq) not in rows:
            continue  # shown before the recording started
        i = rows[int(seq)]
        assert f == f"{run['frequency_hz'][i]:.2f}"
        assert duty == f"{run['duty_cycle'][i]:.6f}"
        assert volts == f"{run['voltage_v'][i]:.4f}"
        compared += 1
    assert compared >= 10
    assert summary is not None and summary["recorded"] == run.n_rows


def test_unplugged_device_shows_on_the_page_and_the_file_keeps_its_rows(driver, tmp_path):
    out = tmp_path / "unplug.csv"
    # unplugged after 3000 windows (60 s): time for a loaded machine to start Chromium, load the page and
    # start the recording first (after 500 windows a busy CI run once saw the device gone before that; with
    # one other busy process on this 2-core machine the page took 20 s to take its first click)
    server = LiveServer("--virtual", "--out", str(out), "--window", "20ms", "--unplug-after", "3000", *LIGHT)
    try:
        driver.get(server.url)
        assert wait_for(lambda: text(driver, "#latest-seq"))
        assert click_button(driver, "Start recording")
        assert wait_for(lambda: text(driver, "#recording"))
        page = wait_for(lambda: "disconnected" in (driver.execute_script("return document.body.innerText") or "")
                        or _shadow_text_has(driver, "disconnected"))
        assert page
    finally:
        server.stop()
    run = load_run(out)
    assert run.n_rows > 0
    seq = list(run["seq"])
    assert seq == list(range(int(seq[0]), int(seq[0]) + len(seq)))  # nothing lost before the unplug
    assert "device gone" in __import__("json").loads(sidecar_path(out).read_text())["ended"]


def _shadow_text_has(driver, word: str) -> bool:
    return bool(driver.execute_script("""
      function all(root, acc) {
        for (const n of (root.querySelectorAll ? root.querySelectorAll('*') : [])) {
          if (n.shadowRoot) { acc.push(n.shadowRoot.textContent || ''); all(n.shadowRoot, acc); }
        }
        return acc;
      }
      return all(document, []).some(t => t.includes(arguments[0]));""", word))


def test_second_tab_watches_and_cannot_control(driver, tmp_path):
    server = LiveServer("--virtual", "--out", str(tmp_path / "two.csv"), *LIGHT)
    try:
        driver.get(server.url)
        assert wait_for(lambda: text(driver, "#latest-seq"))
        assert button_disabled(driver, "Start recording") is False
        driver.switch_to.new_window("tab")
        driver.get(server.url)
        assert wait_for(lambda: text(driver, "#latest-seq"))  # the second tab shows the data too
        assert button_disabled(driver, "Start recording") is True
        assert _shadow_text_has(driver, "view only")
    finally:
        server.stop()


def test_another_interface_needs_the_token():
    server = LiveServer("--virtual", "--host", "127.0.0.2")
    try:
        url, token = server.url, server.info["token"]
        assert token and f"token={token}" in url and len(token) >= 16
        bare = url.split("?")[0]
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(bare, timeout=10)
        assert refused.value.code == 403
        with pytest.raises(urllib.error.HTTPError) as wrong:
            urllib.request.urlopen(bare + "?token=not-the-token", timeout=10)
        assert wrong.value.code == 403
        with urllib.request.urlopen(url, timeout=10) as ok:
            assert ok.status == 200 and b"Bokeh" in ok.read()
    finally:
        server.stop()


def test_local_page_needs_no_token_and_serves_nothing_else():
    server = LiveServer("--virtual")
    try:
        assert server.info["token"] is None and server.url.startswith("http://127.0.0.1:")
        with urllib.request.urlopen(server.url, timeout=10) as ok:
            assert ok.status == 200
        for path in ("etc/passwd", "../pyproject.toml", "run.csv"):
            with pytest.raises(urllib.error.HTTPError) as missing:
                urllib.request.urlopen(server.url + path, timeout=10)
            assert missing.value.code == 404
    finally:
        server.stop()


def test_guided_known_weights_from_the_page_write_a_run_calibrate_accepts(driver, tmp_path):
    # The virtual bench places each mass when the page's Placed is clicked; the procedure waits for a
    # steady readout and keeps 1 s of windows per placement (bench.weights). Reference: the plan
    # (mass × g per step, loading then unloading) and fsrlab calibrate reading the run back.
    out = tmp_path / "w.csv"
    server = LiveServer("--virtual", "--seed", "2", "--window", "20ms", "--out", str(out), *LIGHT,
                        "--masses", "0,100g,200g", "--unload")
    try:
        driver.get(server.url)
        assert wait_for(lambda: text(driver, "#latest-seq"))
        assert click_button(driver, "Start guided calibration")
        for step in range(1, 6):  # 0, 100 g, 200 g, then 100 g, 0 back down
            assert wait_for(lambda s=step: (text(driver, "#prompt") or "").startswith(f"step {s}/5"), interval_s=0.5)
            assert click_button(driver, "Placed")
        assert wait_for(lambda: "guided calibration done" in (text(driver, "#prompt") or ""), interval_s=0.5)
    finally:
        server.stop()
    weights = tmp_path / "w-weights.csv"
    run = load_run(weights)
    steps = sorted(set(int(s) for s in run["step"]))
    assert steps == [0, 1, 2, 3, 4]
    g = 9.80665
    for s, mass, direction in zip(steps, (0.0, 0.1, 0.2, 0.1, 0.0), (1, 1, 1, -1, -1), strict=True):
        rows = run["step"] == s
        assert rows.sum() >= 20  # ~1 s of 20 ms windows held per placement
        assert set(run["force_nominal_n"][rows]) == {mass * g}
        assert set(run["direction"][rows]) == {direction}
    code, out_json, err = run_cli(["calibrate", str(weights), "--x", "frequency_hz",
                                   "--reference", "force_n", "--json"])
    assert code == 0, err
