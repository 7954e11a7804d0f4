"""Recording through a real pty: the run file, corruption, resets, unplugging, Ctrl-C, SIGKILL, the CLI.

References: the run format (fsrlab.io.runformat.load_run, docs/data-format.md), the protocol's
sequence numbers (every lost frame is a gap in ``seq``), and the command line's contract (the JSON
summary, one-line errors with exit code 2, exit code 1 when the device disappears).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.acquisition.recorder import COLUMNS, record
from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.circuits.circuit import PAPER_CIRCUIT, PAPER_OPAMP
from fsrlab.io.runformat import load_run
from fsrlab.virtual.device import Faults, VirtualDevice
from fsrlab.virtual.sources import ConstantSource
from recording import CLI
from recording import rows as _rows
from recording import wait as _wait


def test_recording_writes_a_valid_run(tmp_path):
    with VirtualDevice(seed=1) as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", 0.6, window_ms=20, reference=lambda f: dev.reference(f.seq))
    run = load_run(tmp_path / "run.csv")
    assert result.ended == "duration" and result.dropped == 0
    assert run.n_rows == result.frames > 0
    # A protocol-3 device (2 and later): the load cell's columns follow (empty force_n: no load-cell calibration given).
    assert list(run.columns) == list(COLUMNS) + ["stress_pa", "reference_raw", "force_n"]
    assert np.all(np.isfinite(run["reference_raw"])) and np.all(np.isnan(run["force_n"]))
    assert np.all(np.diff(run["time_s"]) > 0) and np.all(np.diff(run["seq"]) == 1)
    assert np.all(run["frequency_hz"] > 0) and np.all((run["duty_cycle"] > 0) & (run["duty_cycle"] < 1))
    assert np.all(np.isfinite(run["stress_pa"]))  # every window has its reference stress
    # The triangle profile loads from 0: stress rises, and so does the frequency (paper §5, Fig. 19a).
    assert np.all(np.diff(run["stress_pa"]) > 0)
    assert np.corrcoef(run["stress_pa"], run["frequency_hz"])[0, 1] > 0.9
    meta = run.metadata
    assert meta["complete"] and meta["rows"] == run.n_rows
    assert meta["acquisition"]["window_ms"] == 20 and meta["acquisition"]["protocol_version"] == 3


def test_device_clock_recording_is_exact_and_loses_nothing(tmp_path):
    """A virtual device at ``speed="max"`` recorded with ``clock="device"``: 2 s of 20 ms windows on
    the device's clock are exactly 100 rows ending at 2 s, none lost, whatever the host's speed."""
    with VirtualDevice(seed=1, speed="max") as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", 2.0, window_ms=20, reference=lambda f: dev.reference(f.seq),
                        clock="device")
    run = load_run(tmp_path / "run.csv")
    assert result.ended == "duration" and result.dropped == 0 and result.run_s == 2.0
    assert run.n_rows == result.frames == 100 and np.all(np.diff(run["seq"]) == 1)
    assert run["time_s"] == pytest.approx(0.02 * np.arange(1, 101), abs=1e-12)
    acq = run.metadata["acquisition"]
    assert acq["clock"] == "device" and acq["run_s"] == 2.0
    assert np.all(np.isfinite(run["stress_pa"]))


def test_device_clock_continues_through_a_device_reset(tmp_path):
    """On the device's clock the windows after a reset continue the run's time axis from the last one
    (the host's clock plays no part): a device restarting after 20 windows still gives 1 s of 20 ms
    windows as exactly 50 rows, 0.02 s apart, the settings sent again once."""
    with VirtualDevice(ConstantSource(), faults=Faults(reset_after=20), seed=2, speed="max") as dev, \
            SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", 1.0, window_ms=20, clock="device")
    run = load_run(tmp_path / "run.csv")
    assert result.ended == "duration" and result.stats.resets == 1 and result.run_s == 1.0
    assert run.n_rows == result.frames == 50
    assert run["time_s"] == pytest.approx(0.02 * np.arange(1, 51), abs=1e-12)
    assert run["seq"][20] < run["seq"][19]  # the device's sequence restarted


def test_corrupted_link_is_counted_and_never_reaches_the_file(tmp_path):
    """Bit flips, dropped frames and garbage on the link: every row in the file is a valid window,
    and the gaps in ``seq`` add up exactly to the frames the recorder reports as dropped."""
    faults = Faults(corrupt=0.2, drop=0.1, garbage=0.2)
    with VirtualDevice(ConstantSource(4000.0, 0.4), faults=faults, seed=7) as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", 1.0, window_ms=10)
    run = load_run(tmp_path / "run.csv")
    seq = run["seq"].astype(int)
    assert run.n_rows == result.frames > 20
    assert result.stats.bad_frames > 0 and result.stats.garbage_bytes > 0 and result.dropped > 0
    first = run.metadata["acquisition"]["first_seq"]  # what the first window after START carries
    assert (seq[0] - first) + int(np.sum(np.diff(seq) - 1)) == result.dropped
    assert np.allclose(run["frequency_hz"], 4000.0, rtol=5e-3)  # 1e-3 noise, 5σ
    assert np.allclose(run["duty_cycle"], 0.4, rtol=5e-3)


def test_device_reset_mid_run_is_recovered(tmp_path):
    with VirtualDevice(ConstantSource(), faults=Faults(reset_after=10), seed=2) as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", 0.8, window_ms=20)
    run = load_run(tmp_path / "run.csv")
    assert result.stats.resets == 1 and result.ended == "duration"
    assert run.n_rows > 12  # recording went on after the reset
    assert np.all(np.diff(run["time_s"]) > 0)
    assert np.any(np.diff(run["seq"]) < 0)  # sequence restarted


def test_unplug_mid_run_ends_cleanly_with_the_file_intact(tmp_path):
    with VirtualDevice(ConstantSource(), faults=Faults(unplug_after=8), seed=3) as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", 30.0, window_ms=10)
    assert result.ended == "disconnected"
    assert "disconnected" in result.message and "\n" not in result.message
    run = load_run(tmp_path / "run.csv")
    # Bytes still in the pty when it closes are lost, as on a pulled cable: at most the 8 frames sent.
    assert 0 < run.n_rows == result.frames <= 8
    assert run.metadata["complete"] and run.metadata["acquisition"]["ended"] == "disconnected"


def test_device_process_killed_mid_run(tmp_path):
    """``fsrlab virtual-device`` in another process, killed while we record: a pulled cable."""
    proc = subprocess.Popen(CLI + ["virtual-device", "--profile", "sine", "--duration", "60"],
                            stdout=subprocess.PIPE, text=True)
    try:
        port = proc.stdout.readline().strip()
        assert port.startswith("/dev/")
        with SerialLink(port) as link:
            import threading

            killer = threading.Timer(0.5, proc.kill)
            killer.start()
            result = record(link, tmp_path / "run.csv", 30.0, window_ms=20)
            killer.cancel()
    finally:
        proc.kill()
        proc.wait()
    assert result.ended == "disconnected"
    run = load_run(tmp_path / "run.csv")
    assert run.n_rows == result.frames > 0 and run.metadata["complete"]


def _start_recording(out: Path) -> subprocess.Popen:
    # Ctrl-C restored in the child: a test runner started in the background (a shell's `&`) passes SIGINT on
    # as ignored, and the interrupt this file sends would then never arrive.
    return subprocess.Popen(CLI + ["acquire", "--virtual", "--duration", "60", "--window", "20ms", "--out", str(out),
                                   "--quiet", "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def test_sigkill_of_a_recording_leaves_a_readable_file(tmp_path):
    out = tmp_path / "run.csv"
    proc = _start_recording(out)
    try:
        _wait(lambda: _rows(out) >= 10 or proc.poll() is not None)
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    run = load_run(out)
    assert run.n_rows >= 10
    assert np.all(np.isfinite(run["frequency_hz"])) and np.all(np.diff(run["seq"]) == 1)
    assert run.metadata["complete"] is False  # the sidecar says the run was not closed


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupt_of_a_recording_closes_the_file(tmp_path, sig):
    out = tmp_path / "run.csv"
    proc = _start_recording(out)
    try:
        _wait(lambda: _rows(out) >= 5 or proc.poll() is not None)
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 0, stderr
    summary = json.loads(stdout)
    run = load_run(out)
    assert run.n_rows == summary["frames"] >= 5
    assert run.metadata["complete"] and run.metadata["acquisition"]["ended"] == "interrupted"
    assert run.metadata["ended"] == f"interrupted: {run.n_rows} windows kept" and stderr == ""


def test_cli_json_contract(tmp_path):
    out = tmp_path / "run.csv"
    code, stdout, stderr = run_cli(["acquire", "--virtual", "--duration", "2", "--out", str(out), "--json"])
    assert code == 0, stderr
    summary = json.loads(stdout)
    assert list(summary) == ["frames", "dropped", "duration_s", "file", "no_reference"]
    assert summary["file"] == str(out) and summary["dropped"] == 0
    assert summary["duration_s"] >= 2.0
    run = load_run(out)
    assert run.n_rows == summary["frames"] >= 10  # 100 ms windows over 2 s
    for col in ("time_s", "frequency_hz", "duty_cycle", "stress_pa"):
        assert col in run.columns and np.all(np.isfinite(run[col]))
    # The sidecar names the virtual circuits (docs/data-format.md): the paper's 555 with the 1 nF C_off
    # of --c-off's default, and the paper's op-amp.
    assert run.circuits() == (PAPER_CIRCUIT.replace(c_off_farad=1e-9), PAPER_OPAMP)


@pytest.mark.parametrize("argv, field", [
    (["acquire", "--duration", "1"], "--port"),
    (["acquire", "--virtual", "--port", "/dev/null", "--duration", "1"], "--port"),
    (["acquire", "--virtual", "--window", "5ms"], "--window"),
    (["acquire", "--virtual", "--range", "2"], "--range"),
    (["acquire", "--virtual", "--duration", "0"], "--duration"),
    (["acquire", "--virtual", "--profile", "zigzag"], "--profile"),
    (["acquire", "--port", "/dev/does-not-exist", "--duration", "1"], "/dev/does-not-exist"),
    (["virtual-device", "--corrupt", "2"], "--corrupt"),
])
def test_cli_bad_input_is_one_line_and_exit_2(tmp_path, argv, field):
    code, stdout, stderr = run_cli(argv + ["--out", str(tmp_path / "x.csv")] if argv[0] == "acquire" else argv)
    assert code == 2
    assert stderr.count("\n") == 1 and field in stderr


def test_cli_unplugged_device_exit_1_with_one_line(tmp_path):
    proc = subprocess.Popen(CLI + ["virtual-device", "--duration", "1"], stdout=subprocess.PIPE, text=True)
    try:
        port = proc.stdout.readline().strip()
        code, stdout, stderr = run_cli(["acquire", "--port", port, "--duration", "30", "--window", "20ms",
                                     "--out", str(tmp_path / "run.csv"), "--json"])
    finally:
        proc.kill()
        proc.wait()
    assert code == 1
    assert stderr.count("\n") == 1 and "disconnected" in stderr
    assert load_run(tmp_path / "run.csv").n_rows == json.loads(stdout)["frames"] > 0


def test_windows_of_a_device_left_running_are_not_recorded(tmp_path):
    with VirtualDevice(ConstantSource(), seed=4) as dev, SerialLink(dev.port) as link:
        link.send(b"WINDOW 10\nRANGE 1\nSTART\n")  # someone left it running at range 1 ...
        time.sleep(0.15)  # ... and its windows wait unread in the port
        result = record(link, tmp_path / "run.csv", 0.3, window_ms=10, range_=0)
    run = load_run(tmp_path / "run.csv")
    assert run.n_rows == result.frames > 0
    assert np.all(run["range"] == 0)
    assert run["seq"][0] >= run.metadata["acquisition"]["first_seq"]


def test_unwritable_output_is_one_line_exit_2_and_the_device_is_stopped(tmp_path):
    with VirtualDevice(ConstantSource(), seed=5) as dev, SerialLink(dev.port) as link:
        with pytest.raises(OSError):
            record(link, tmp_path / "missing" / "run.csv", 1.0, window_ms=10)
        time.sleep(0.05)
        assert not dev._st.started
    code, _, stderr = run_cli(["acquire", "--virtual", "--duration", "1", "--out", str(tmp_path / "missing" / "x.csv")])
    assert code == 2 and stderr.count("\n") == 1 and "missing" in stderr


def test_a_virtual_recording_is_analysable(tmp_path):
    """Contract with the analysis capability: two loading-unloading cycles recorded from the virtual
    device give a hysteresis error per cycle through ``fsrlab hysteresis`` (property: HE > 0 for
    the hysteretic sensor model, and the two steady cycles agree within 2 percentage points)."""
    out = tmp_path / "run.csv"
    code, _, err = run_cli(["acquire", "--virtual", "--duration", "2.05", "--period", "1", "--window", "20ms",
                         "--out", str(out), "--quiet", "--seed", "1", "--c-off", "2.2n"])
    assert code == 0, err
    circuit = load_run(out).circuits()[0]  # --c-off builds the circuit
    assert circuit.c_off_farad == pytest.approx(2.2e-9) and circuit.replace(c_off_farad=0.0) == PAPER_CIRCUIT
    code, stdout, err = run_cli(["hysteresis", str(out), "--json"])
    assert code == 0, err
    result = json.loads(stdout)
    per_cycle = [c["hysteresis_error_percent"] for c in result["cycles"]]
    assert len(per_cycle) == 2 and all(he > 0 for he in per_cycle)
    assert abs(per_cycle[0] - per_cycle[1]) < 2.0
