"""The demo (``make demo`` = ``fsrlab demo``) with very short recordings: the whole chain runs and links its reports.

References: the chain the module's docstring lists (fsrlab/bench/demo.py, fsrlab/reports/demo.py) and the files
each step must leave; the demo's numbers are checked against the measurement report it wrote (report.json), and
the hysteresis error of the compensated estimate against the raw frequency's (the compensation's
purpose). The virtual bench runs faster than real time (the default ``speed="max"``).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.bench.demo import DEMO_SENSOR, DemoSettings, demo_sensor
from fsrlab.reports.demo import run_demo

SHORT = DemoSettings(cycles=2, period_s=1.5, repeat=2, settle_hold_s=0.1)


@pytest.mark.slow
def test_demo_runs_the_chain_and_links_both_reports(tmp_path):
    lines = []
    res = run_demo(tmp_path / "demo", SHORT, device="virtual", paper=False, progress=lines.append)
    assert res.device == "virtual" and res.index.is_file()
    for name in ("calibration-run.csv", "test-run.csv", "weights-run.csv", "calibration", "estimate",
                 "measurement report"):
        assert res.files[name].is_file(), name
    page = res.index.read_text()
    assert "measurement/index.html" in page and "Python virtual device" in page
    # Step by step, numbered, each with its time.
    numbered = [ln for ln in lines if ln.startswith("[")]
    assert [ln.split("]")[0] for ln in numbered] == [f"[{k}/7" for k in range(1, 8)]
    assert "Python virtual device" in numbered[0]
    saved = json.loads((tmp_path / "demo" / "measurement" / "report.json").read_text())
    he = {h["quantity"]: h["hysteresis_error_percent"] for h in saved["hysteresis"]}
    assert res.numbers["he_frequency_percent"] == he["frequency_hz"]
    assert res.numbers["he_estimate_percent"] < he["frequency_hz"]
    assert {p["load_g"] for p in res.numbers["repeatability"]} == {200.0, 400.0}
    # The recordings' time axes are the simulated clocks: whole runs of 2 × 1.5 s of 20 ms windows.
    from fsrlab.io.runformat import load_run

    for name in ("calibration-run.csv", "test-run.csv"):
        run = load_run(res.files[name])
        assert run.n_rows == 150 and run.metadata["acquisition"]["run_s"] == 3.0, name
    # Several sensors: 8 channels from one scan, each calibrated, and the 8×8 cross-talk matrix. References: the
    # issue's rate (20 readings/s per channel at the default dwell), the physics (channel k at 50 kPa·(k+1)/8: an
    # FSR's frequency rises with its stress, paper §5 Fig. 19a), the matrix's definition (diagonal 1) and
    # the run file the step wrote.
    assert "several sensors on one meter" in numbered[5]
    ch = res.numbers["channels"]
    assert [c["sensor_id"] for c in ch["sensors"]] == [f"fsr{k}" for k in range(8)]
    assert all(c["readings_per_s"] >= 20 for c in ch["sensors"])
    peaks = [c["peak_hz"] for c in ch["sensors"]]
    assert all(a < b for a, b in zip(peaks, peaks[1:], strict=False))
    multi = load_run(res.files["multi-channel run"])
    assert max(multi["frequency_hz"][multi["channel"] == 7]) == peaks[7]
    assert sorted(json.loads(res.files["per-channel calibration"].read_text())["sensors"]) == \
        [f"fsr{k}" for k in range(8)]
    matrix = np.asarray(ch["crosstalk"]["matrix"])
    assert matrix.shape == (8, 8) and np.allclose(np.diag(matrix), 1.0)
    assert "Several sensors on one meter" in page


def test_demo_sensor_is_chosen_in_one_place():
    sensor, text = demo_sensor()
    # The demo runs on the first sensor fitted to the paper's §6 (fsrlab.physics.paper_sensor).
    assert DEMO_SENSOR == "paper-a201-1" and hasattr(sensor, "respond") and getattr(sensor, "name", "") == DEMO_SENSOR
    assert DEMO_SENSOR in text
    with pytest.raises(ValueError, match="sensor"):
        demo_sensor("no-such-sensor")


@pytest.mark.parametrize("args, option", [
    (["demo", "--device", "spice"], "--device"),
    (["demo", "--cycles", "0"], "--cycles"),
    (["demo", "--repeat", "1"], "--repeat"),
    (["demo", "--speed", "fast"], "--speed"),
    (["demo", "--sensor", "paper-9x"], "--sensor"),
])
def test_demo_bad_input_is_one_line(args, option, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and option in err
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_demo_falls_back_to_the_python_device_when_the_twin_fails(tmp_path, monkeypatch):
    import sys
    import types

    class BrokenTwin:
        def __init__(self, source, speed="realtime", seed=0, loadcell=None):
            pass

        def open(self):
            raise RuntimeError("simavr exited")

        def close(self):
            pass

    twin = types.ModuleType("fsrlab.virtual.twin")
    twin.Twin, twin.twin_available = BrokenTwin, lambda: (True, "")
    monkeypatch.setitem(sys.modules, "fsrlab.virtual.twin", twin)
    lines = []
    res = run_demo(tmp_path / "demo", DemoSettings(cycles=1, period_s=1.0, repeat=2, settle_hold_s=0.1),
                   paper=False, progress=lines.append)
    # The calibration step names the model; a plain curve comes with the one line saying why.
    model = next(ln.split(",")[0].strip() for ln in lines if ln.strip().startswith("monotone-"))
    assert "+" in model or any(ln.strip().startswith("memory not kept:") for ln in lines)
    assert "digital twin" in lines[0]  # auto: the twin first, as it says it can run
    assert any("the digital twin failed (RuntimeError: simavr exited); using the Python virtual device" in ln
               for ln in lines)
    assert res.device == "virtual" and "Python virtual device" in res.index.read_text()


@pytest.mark.slow
def test_demo_command_prints_steps_and_ends_with_the_index(tmp_path):
    code, out, err = run_cli(["demo", "--out", tmp_path / "d", "--device", "virtual", "--cycles", "2", "--period",
                              "1.5s", "--repeat", "2", "--no-paper", "--json"])
    assert code == 0, err
    info = json.loads(out)
    assert info["index"] == str(tmp_path / "d" / "index.html") and info["device"] == "virtual"
    assert [s["step"] for s in info["steps"]][:3] == ["spring runs", "dead weights", "calibration"]
    assert info["total_s"] == pytest.approx(sum(s["seconds"] for s in info["steps"]))
    assert info["numbers"]["calibration"]["reference"] == "force_n"  # the emulated load cell
    assert err.splitlines()[0].startswith("fsrlab demo: [1/7]")
    assert [s["step"] for s in info["steps"]][-2:] == ["several sensors", "index"]


def test_an_interrupted_demo_leaves_the_old_runs_whole(tmp_path, monkeypatch):
    # Reference: the output policy (fsrlab.io.outputs; README "Files written"): an interrupted write never leaves
    # half a file under its final name. Here the first recording is cut after a header and a row (a stand-in for
    # the bench, stopped by Ctrl-C): the demo directory's files are byte for byte the old ones, and the folder
    # the runs are recorded in is gone.
    import hashlib

    from fsrlab.bench import protocols
    from fsrlab.bench.demo import run_chain

    out = tmp_path / "demo"
    out.mkdir()
    (out / "calibration-run.csv").write_text("time_s,frequency_hz\n0.1,5000\n")
    (out / "calibration-run.meta.json").write_text('{"format": "fsrlab-run"}\n')

    def cut_recording(plan, path, **kwargs):
        path.write_text("time_s,frequency_hz\n0.02,51")
        raise KeyboardInterrupt

    monkeypatch.setattr(protocols, "run_protocol", cut_recording)

    def tree():
        return {str(p.relative_to(out)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "dir"
                for p in sorted(out.rglob("*"))}

    before = tree()
    with pytest.raises(KeyboardInterrupt):
        run_chain(out, DemoSettings(cycles=1, period_s=1.0, repeat=2, speed="realtime"), device="virtual")
    assert tree() == before


@pytest.mark.slow
def test_demo_draws_the_reproduction_report_while_the_dead_weights_are_recorded(tmp_path, monkeypatch):
    # The report starts in its own process once the spring runs are in (before the dead weights end) and is
    # linked from the index; a chain that fails after that start leaves no report process running.
    import fsrlab.reports.paper as paper

    started = []
    real = paper.start_report

    def spy(outdir, nice=0, **kwargs):
        started.append(real(outdir, nice, **kwargs))
        return started[-1]

    monkeypatch.setattr(paper, "start_report", spy)
    lines = []
    res = run_demo(tmp_path / "demo", SHORT, device="virtual", progress=lines.append)
    assert len(started) == 1 and (tmp_path / "demo" / "paper" / "paper.json").is_file()
    assert "paper/index.html" in res.index.read_text()
    numbered = [ln for ln in lines if ln.startswith("[")]
    assert [ln.split("]")[0] for ln in numbered] == [f"[{k}/8" for k in range(1, 9)]
    assert "drawn while the dead weights were recorded" in numbered[5]

    import fsrlab.reports.run_report as run_report

    def broken(*args, **kwargs):
        raise RuntimeError("measurement report: cannot")

    monkeypatch.setattr(run_report, "write_run_report", broken)
    with pytest.raises(RuntimeError, match="cannot"):
        run_demo(tmp_path / "again", SHORT, device="virtual")
    assert len(started) == 2 and started[-1]._proc.poll() is not None


def test_a_killed_demos_hidden_folder_is_removed_and_does_not_block_the_next(tmp_path, monkeypatch):
    """A demo killed outright (``kill -9``) cannot remove the hidden folder it records in: the next demo
    removes it when its process is gone (not one whose process still runs) and does not take the
    directory for one holding results."""
    import os
    import subprocess
    import sys

    from fsrlab.bench import demo as demo_mod

    out = tmp_path / "d"
    out.mkdir()
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    stale = out / f"{demo_mod.STAGING_PREFIX}{int(ended.stdout)}-abc"
    stale.mkdir()
    (stale / "calibration-run.csv").write_text("time_s,frequency_hz\n0.02,51")
    running = out / f"{demo_mod.STAGING_PREFIX}{os.getpid()}-def"
    running.mkdir()
    assert demo_mod.remove_stale_staging(out) == [stale]
    assert not stale.exists() and running.exists()
    running.rmdir()
    stale.mkdir()
    reached = []

    def fake_run_demo(out_dir, *args, **kwargs):
        reached.append(out_dir)
        raise SystemExit(0)

    from fsrlab.reports import demo as reports_demo

    monkeypatch.setattr(reports_demo, "run_demo", fake_run_demo)
    code, _, err = run_cli(["demo", "--out", out, "--device", "virtual", "--no-paper"])
    assert code == 0 and reached and not stale.exists() and "removed" in err, err
