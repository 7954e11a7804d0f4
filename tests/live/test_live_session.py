"""The live session without a browser: what it records, what it hands the pages, and bad options.

References: the load-cell closed form force = (raw − offset) / scale (acquisition.loadcell), the rows
``fsrlab acquire`` writes (acquisition.recorder.window_row, the same function), sequence numbers
(consecutive when nothing is lost), and the CLI's one-line error contract.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.acquisition.recorder import COLUMNS, REFERENCE_COLUMNS
from fsrlab.io.runformat import load_run, sidecar_path
from fsrlab.live.page import Controller


def _virtual_session(tmp_path, capacity=20000, profile="triangle"):
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.cli.acquisition import make_virtual_device
    from fsrlab.live.session import LiveSession

    device, source = make_virtual_device(profile, 50e3, 2.0, 1e-9, 7, 0.0, 0.0, True, 80, None)
    port = device.open()
    cal = device.load_cell.calibration()
    session = LiveSession(SerialLink(port), window_ms=20, capacity=capacity,
                          reference=lambda frame: device.reference(frame.seq), loadcell=cal,
                          area_m2=source.sensor.area_m2).start()
    return session, device, cal


def test_recording_writes_the_rows_acquire_writes_with_the_load_cell_force(tmp_path):
    session, device, cal = _virtual_session(tmp_path)
    out = tmp_path / "rec.csv"
    try:
        deadline = time.monotonic() + 10
        while session.status.frames < 5 and time.monotonic() < deadline:
            time.sleep(0.05)
        session.command("record", str(out))
        time.sleep(1.5)
        session.command("stop_recording")
        time.sleep(0.3)
    finally:
        session.close()
        device.close()
    run = load_run(out)
    assert list(run.columns) == list(COLUMNS) + ["stress_pa"] + list(REFERENCE_COLUMNS)
    assert run.n_rows >= 40  # 1.5 s of 20 ms windows, less start-up jitter
    seq = run["seq"]
    assert np.all(np.diff(seq) == 1)  # nothing lost
    assert run["time_s"][0] == 0 and np.all(np.diff(run["time_s"]) > 0)
    raw, force = run["reference_raw"], run["force_n"]
    have = np.isfinite(raw)
    assert have.sum() > 0.5 * run.n_rows  # 80 conversions/s into 20 ms windows: most windows have one
    np.testing.assert_allclose(force[have], (raw[have] - cal.offset_counts) / cal.scale_counts_per_n, rtol=1e-12)
    assert not np.any(np.isfinite(force[~have]))  # empty, never 0, without a conversion
    meta = __import__("json").loads(sidecar_path(out).read_text())
    assert meta["complete"] and meta["load_cell"]["scale_counts_per_n"] == cal.scale_counts_per_n


def test_pages_get_each_window_once_and_the_buffer_stays_bounded(tmp_path):
    session, device, _ = _virtual_session(tmp_path, capacity=25)
    try:
        deadline = time.monotonic() + 15
        cursor, seen = 0, []
        while len(seen) < 60 and time.monotonic() < deadline:
            cursor, cols = session.since(cursor)
            seen += cols["seq"]
            time.sleep(0.1)
        late_cursor, late = session.since(0)  # a page that saw nothing gets at most the buffer
    finally:
        session.close()
        device.close()
    assert len(seen) >= 60
    assert seen == list(range(seen[0], seen[0] + len(seen)))  # in order, none twice, none skipped
    assert len(late["seq"]) <= 25 and late_cursor >= cursor


def test_next_recording_never_reuses_a_file(tmp_path):
    out = tmp_path / "run.csv"
    c = Controller(out)
    first = c.next_path()
    assert first == out
    first.write_text("x\n")
    (tmp_path / "run-3.meta.json").write_text("{}")  # a sidecar alone also keeps its name taken
    assert c.next_path() == tmp_path / "run-2.csv"
    assert c.next_path() == tmp_path / "run-4.csv"
    assert Controller(None).next_path() is None


def test_one_tab_controls_until_it_closes():
    c = Controller(None)
    a, b = object(), object()
    assert c.claim(a) and not c.claim(b) and c.claim(a)
    c.release(b)
    assert c.owner is a
    c.release(a)
    assert c.claim(b)


@pytest.mark.parametrize("args, option", [
    (["--virtual", "--port", "/dev/null"], "--port"),
    ([], "--port"),
    (["--virtual", "--http-port", "70000"], "--http-port"),
    (["--virtual", "--range", "2"], "--range"),
    (["--virtual", "--window", "5ms"], "--window"),
    (["--virtual", "--duration", "0"], "--duration"),
    (["--virtual", "--cal", "missing.json"], "--cal"),
    (["--virtual", "--unplug-after", "0", "--duration", "1s"], "--unplug-after"),
    (["--virtual", "--host", "nonexistent.invalid", "--duration", "1s"], "--host"),
])
def test_bad_options_end_in_one_line_naming_the_option(args, option, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["live", *args])
    assert code == 2
    assert err.count("\n") == 1 and option in err and "Traceback" not in err


def test_an_existing_output_is_refused_before_anything_starts(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "run.csv").write_text("time_s\n0\n")
    code, _, err = run_cli(["live", "--virtual", "--out", "run.csv", "--duration", "1s"])
    assert code == 2 and "--out" in err and "exists" in err
    assert (tmp_path / "run.csv").read_text() == "time_s\n0\n"


def test_served_for_a_duration_then_stops_with_a_summary(tmp_path, monkeypatch):
    import json

    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["live", "--virtual", "--http-port", "0", "--duration", "1.5s", "--window", "20ms",
                              "--json"])
    assert code == 0, err
    first, last = (json.loads(line) for line in out.strip().splitlines())
    assert first["url"].startswith("http://127.0.0.1:") and first["token"] is None
    assert last["frames"] > 10 and last["recorded"] == 0 and not math.isnan(last["frames"])


def _wait(predicate, timeout_s=15.0):
    deadline = time.monotonic() + timeout_s
    while not predicate() and time.monotonic() < deadline:
        time.sleep(0.05)
    return predicate()


def test_tare_from_the_page_zeroes_a_steady_load_cell(tmp_path):
    # A held load (profile "hold"): the tare takes the mean of 1 s of conversions as the new offset, so
    # the force reads 0 afterwards within the cell's noise (closed form: (raw - offset)/scale).
    session, device, cal = _virtual_session(tmp_path, profile="hold")
    try:
        assert _wait(lambda: session.status.frames > 20)
        before = session.since(0)[1]["reference"][-1]
        session.command("tare")
        assert _wait(lambda: any("tare: offset" in e for e in session.status.events))
        cursor = session.since(0)[0]
        assert _wait(lambda: len(session.since(cursor)[1]["reference"]) > 20)
        after = [f for f in session.since(cursor)[1]["reference"] if not math.isnan(f)]
    finally:
        session.close()
        device.close()
    noise_n = device.load_cell.noise_counts / cal.scale_counts_per_n
    assert before > 100 * noise_n  # a real load was on the cell
    assert abs(np.mean(after)) < 3 * noise_n and session.loadcell.scale_counts_per_n == cal.scale_counts_per_n


def test_tare_while_the_load_moves_is_refused_saying_why(tmp_path):
    session, device, cal = _virtual_session(tmp_path)
    try:
        assert _wait(lambda: session.status.frames > 5)
        session.command("tare")
        assert _wait(lambda: any("tare refused" in e for e in session.status.events))
    finally:
        session.close()
        device.close()
    assert session.loadcell == cal  # unchanged


def test_a_calibration_recorded_on_another_range_is_refused_with_the_reason(tmp_path, monkeypatch):
    from fsrlab.calibration.document import save_calibration
    from fsrlab.calibration.runs import calibrate_runs
    from fsrlab.io.runwriter import write_run
    from fsrlab.virtual.sources import VIRTUAL_CIRCUIT
    from fsrlab.virtual.synthetic import synthetic_run

    monkeypatch.chdir(tmp_path)
    run = synthetic_run(cycles=2, points_per_ramp=60, seed=1)  # recorded on range 0 of the virtual circuit
    write_run(tmp_path / "cal-run.csv", {**run.columns, "range": np.zeros(len(run.columns["time_s"]))},
              {"circuit": VIRTUAL_CIRCUIT.to_dict()})
    cal = calibrate_runs(tmp_path / "cal-run.csv", x="frequency_hz")
    save_calibration(cal, tmp_path / "cal.json")
    code, out, err = run_cli(["live", "--virtual", "--range", "1", "--cal", "cal.json", "--http-port", "0",
                              "--duration", "1s", "--json"])
    # As measure and apply: one line naming --cal (exit 2), before the device or the page starts.
    assert code == 2 and err.count("\n") == 1 and "--cal" in err and out == "", err
    assert "the meter has range 1" in err and "range 0" in err
