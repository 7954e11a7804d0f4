"""Nothing lost, nothing silently wrong, when recording: existing runs, units on the command line,
a stalled device, a failing device or file, runs without a valid window, and the help.

References: the command line's contract (exit 2 with one line naming the option or file for bad
input, before the device is touched; exit 1 with one line and the rows so far kept when a run
fails), the run format's sidecar (docs/data-format.md: ``complete``, ``rows``, ``ended``,
``gaps``), the protocol's window limits (10..60000 ms, docs/protocol.md) and the quantity parsers
of the command line (fsrlab.cli.options). Devices are the virtual meter on a real pty, in this
process or in another one (``fsrlab virtual-device``), stopped and resumed with SIGSTOP/SIGCONT.
"""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.acquisition.recorder import record
from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.io.runformat import load_run, sidecar_path
from fsrlab.io.runwriter import RunWriter
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import ConstantSource
from recording import CLI
from recording import rows as _rows
from recording import wait as _wait


def _existing_run(path: Path, rows: int = 600) -> dict:
    with RunWriter(path, ["time_s", "frequency_hz"], {"origin": "an earlier bench run"}) as w:
        for i in range(rows):
            w.write({"time_s": i * 0.1, "frequency_hz": 5000.0 + i})
    return {p: p.read_bytes() for p in (path, sidecar_path(path)) if p.exists()}


def _files(path: Path) -> dict:
    return {p: p.read_bytes() for p in (path, sidecar_path(path)) if p.exists()}


# ---------------------------------------------------------------- an existing run is kept
@pytest.mark.parametrize("which", ["csv", "sidecar"])
def test_an_existing_run_is_never_replaced_without_overwrite(tmp_path, which):
    out = tmp_path / "bench.csv"
    _existing_run(out)
    if which == "sidecar":
        out.unlink()
    before = _files(out)
    named = out if which == "csv" else sidecar_path(out)
    with VirtualDevice(ConstantSource(), seed=1) as dev:
        sent = dev.frames_sent  # the boot ID frame
        code, _, stderr = run_cli(["acquire", "--port", dev.port, "--duration", "1", "--out", out])
        assert dev.frames_sent == sent  # the device was never asked anything
    assert code == 2 and stderr.count("\n") == 1
    assert "--out" in stderr and str(named) in stderr and "--overwrite" in stderr
    assert _files(out) == before


def test_overwrite_replaces_an_existing_run(tmp_path):
    out = tmp_path / "bench.csv"
    _existing_run(out)
    code, stdout, stderr = run_cli(["acquire", "--virtual", "--duration", "0.5", "--window", "20ms", "--out", out,
                                    "--overwrite", "--quiet", "--json"])
    assert code == 0, stderr
    run = load_run(out)
    assert run.n_rows == json.loads(stdout)["frames"] > 0 and "acquisition" in run.metadata


def test_record_refuses_an_existing_run_before_the_handshake(tmp_path):
    out = tmp_path / "run.csv"
    before = _existing_run(out, rows=3)
    with VirtualDevice(ConstantSource(), seed=2) as dev, SerialLink(dev.port) as link:
        sent = dev.frames_sent
        with pytest.raises(FileExistsError, match="run.csv"):
            record(link, out, 1.0, window_ms=10)
        assert dev.frames_sent == sent and link.identity is None
    assert _files(out) == before


# ---------------------------------------------------------------- units on the command line
@pytest.mark.parametrize("argv, field, words", [
    (["--duration", "1m"], "--duration", "minutes or milliseconds"),
    (["--window", "1k"], "--window", "as a duration"),
    (["--window", "2min"], "--window", "10 ms to 60 s"),
    (["--window", "5ms"], "--window", "10 ms to 60 s"),
    (["--window", "12.5ms"], "--window", "whole milliseconds"),
    (["--window", "20ms", "--stall", "10ms"], "--stall", "longer than one window"),
    (["--corrupt", "5"], "--corrupt", "5%"),
    (["--drop", "2"], "--drop", "2%"),
    (["--peak", "10kF"], "--peak", "Pa"),
    (["--peak", "-5k"], "--peak", "> 0 Pa"),
    (["--peak", "999k"], "--peak", "smaller peak"),
    (["--period", "-1"], "--period", "> 0 s"),
    (["--c-off", "1m"], "--c-off", "ambiguous"),
    (["--seed", "-1"], "--seed", ">= 0"),
])
def test_acquire_options_take_units_and_blame_the_right_option(tmp_path, argv, field, words):
    out = tmp_path / "x.csv"
    code, _, stderr = run_cli(["acquire", "--virtual", "--out", out] + argv)
    assert code == 2 and stderr.count("\n") == 1, stderr
    assert f"Invalid value for {field}:" in stderr and words in stderr
    for internal in ("r_fsr_ohm", "array(", "np.float64", "peak_pa", "period_s", "Traceback"):
        assert internal not in stderr
    assert not out.exists() and not sidecar_path(out).exists()


@pytest.mark.parametrize("argv, field", [
    (["--period", "-1"], "--period"),
    (["--peak", "0"], "--peak"),
    (["--peak", "999k"], "--peak"),
    (["--c-off", "-1n"], "--c-off"),
    (["--duration", "2m"], "--duration"),
    (["--drop", "150%"], "--drop"),
    (["--seed", "-3"], "--seed"),
])
def test_virtual_device_options_blame_the_right_option(argv, field):
    code, stdout, stderr = run_cli(["virtual-device"] + argv)
    assert code == 2 and stdout == "" and stderr.count("\n") == 1
    assert f"Invalid value for {field}:" in stderr and "r_fsr_ohm" not in stderr and "array(" not in stderr


def test_options_in_their_units_reach_the_device_and_the_sidecar(tmp_path):
    out = tmp_path / "run.csv"
    code, _, stderr = run_cli(["acquire", "--virtual", "--duration", "500ms", "--window", "0.02", "--period", "1.5s",
                               "--peak", "60kPa", "--c-off", "2.2nF", "--corrupt", "0%", "--drop", "0%",
                               "--out", out, "--quiet"])
    assert code == 0, stderr
    run = load_run(out)
    acq = run.metadata["acquisition"]
    assert acq["window_ms"] == 20 and acq["duration_s"] == 0.5 and acq["stall_s"] == 2.0  # 5 windows < 2 s
    assert run.circuits()[0].c_off_farad == pytest.approx(2.2e-9)
    assert "peak 60000 Pa, period 1.5 s" in run.metadata["notes"]


# ---------------------------------------------------------------- a stalled device
@pytest.fixture
def device_process():
    """``fsrlab virtual-device`` in its own process; yields (process, port)."""
    proc = subprocess.Popen(CLI + ["virtual-device", "--duration", "120"], stdout=subprocess.PIPE, text=True)
    try:
        port = proc.stdout.readline().strip()
        assert port.startswith("/dev/")
        yield proc, port
    finally:
        proc.kill()
        proc.wait()


def _pause(proc, out: Path, resume_after_s: float | None) -> threading.Thread:
    """SIGSTOP the device once the run has rows; SIGCONT after ``resume_after_s`` (never if None)."""
    def pause():
        _wait(lambda: _rows(out) >= 5)
        os.kill(proc.pid, signal.SIGSTOP)
        if resume_after_s is not None:
            time.sleep(resume_after_s)
            os.kill(proc.pid, signal.SIGCONT)

    thread = threading.Thread(target=pause, daemon=True)
    thread.start()
    return thread


def test_a_stall_the_device_recovers_from_is_reported_and_kept_as_a_gap(tmp_path, device_process):
    proc, port = device_process
    out = tmp_path / "run.csv"
    pauser = _pause(proc, out, resume_after_s=1.5)
    code, stdout, stderr = run_cli(["acquire", "--port", port, "--duration", "4", "--window", "20ms", "--stall", "0.5",
                                    "--out", out, "--quiet", "--json"])
    pauser.join()
    assert code == 0, stderr
    lines = stderr.splitlines()
    assert len(lines) == 2 and "no frame from the device" in lines[0] and "device back after" in lines[1]
    run = load_run(out)
    gaps = run.metadata["gaps"]
    assert len(gaps) == 1 and set(gaps[0]) == {"start_s", "length_s"}
    assert gaps[0]["length_s"] >= 0.5 and 0 < gaps[0]["start_s"] < 4
    assert run.n_rows == json.loads(stdout)["frames"] and run.metadata["complete"]
    assert run.metadata["acquisition"]["ended"] == "duration" and "1 gap without frames" in run.metadata["ended"]


def test_a_device_that_never_comes_back_fails_the_run(tmp_path, device_process):
    proc, port = device_process
    out = tmp_path / "run.csv"
    pauser = _pause(proc, out, resume_after_s=None)
    code, stdout, stderr = run_cli(["acquire", "--port", port, "--duration", "2", "--window", "20ms", "--stall", "0.5",
                                    "--out", out, "--quiet", "--json"])
    pauser.join()
    assert code == 1
    lines = stderr.splitlines()
    assert len(lines) == 2 and "no frame from the device" in lines[0]
    assert "sent nothing" in lines[1] and "to the end" in lines[1] and str(out) in lines[1]
    run = load_run(out)
    assert run.n_rows == json.loads(stdout)["frames"] >= 5  # the rows before the stall are kept
    gap = run.metadata["gaps"][-1]
    assert gap["start_s"] + gap["length_s"] >= 2.0 - 0.05  # open until the end (ms rounding, timer slack)
    assert run.metadata["acquisition"]["ended"] == "stalled" and run.metadata["ended"] == lines[1][len("fsrlab: "):]


def test_stall_defaults_to_five_windows_and_at_least_2_s(tmp_path):
    with VirtualDevice(ConstantSource(), seed=3) as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "a.csv", 0.3, window_ms=500)
    assert load_run(tmp_path / "a.csv").metadata["acquisition"]["stall_s"] == 2.5
    assert result.ended == "empty"  # 500 ms windows in 0.3 s: none complete
    with VirtualDevice(ConstantSource(), seed=3) as dev, SerialLink(dev.port) as link:
        record(link, tmp_path / "b.csv", 0.3, window_ms=20)
    assert load_run(tmp_path / "b.csv").metadata["acquisition"]["stall_s"] == 2.0


# ---------------------------------------------------------------- a failing device or file
class _FailingSource(ConstantSource):
    """A signal source that breaks after a few windows, as a bug in a model would."""

    def __init__(self, after: int) -> None:
        super().__init__()
        object.__setattr__(self, "calls", 0)
        object.__setattr__(self, "after", after)

    def window(self, t0_s, t1_s, range_):
        object.__setattr__(self, "calls", self.calls + 1)
        if self.calls > self.after:
            raise RuntimeError("model blew up at 12.5 kPa")
        return super().window(t0_s, t1_s, range_)


def test_a_failing_device_thread_ends_the_run_with_one_line_and_the_rows_kept(tmp_path, monkeypatch):
    import fsrlab.cli.acquisition as cli_acq

    original = cli_acq.make_virtual_device

    def failing(*args, **kwargs):
        device, source = original(*args, **kwargs)
        device.source = _FailingSource(after=10)
        return device, source

    monkeypatch.setattr(cli_acq, "make_virtual_device", failing)
    out = tmp_path / "run.csv"
    code, stdout, stderr = run_cli(["acquire", "--virtual", "--duration", "30", "--window", "20ms", "--out", out,
                                    "--quiet", "--json"])
    assert code == 1
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert "device thread failed: RuntimeError: model blew up at 12.5 kPa" in stderr and str(out) in stderr
    run = load_run(out)
    assert run.n_rows == json.loads(stdout)["frames"] == 10
    assert run.metadata["complete"] and run.metadata["rows"] == 10
    assert run.metadata["acquisition"]["ended"] == "failed"
    assert run.metadata["ended"].startswith("device thread failed: RuntimeError: model blew up")


def test_a_failing_virtual_device_command_says_why_in_one_line(monkeypatch):
    import fsrlab.cli.acquisition as cli_acq

    original = cli_acq.make_virtual_device
    ports: list[str] = []

    def failing(*args, **kwargs):
        device, source = original(*args, **kwargs)
        device.source = _FailingSource(after=2)
        opened = device.open

        def open_(thread=True):
            ports.append(opened(thread=thread))
            return ports[-1]

        device.open = open_
        return device, source

    monkeypatch.setattr(cli_acq, "make_virtual_device", failing)

    def host():  # a program that opens the port and starts the meter
        _wait(lambda: bool(ports))
        with SerialLink(ports[0]) as link:
            link.handshake()
            link.set_window(10)
            link.start()
            try:
                while True:
                    link.read_frames()
            except OSError:
                pass  # the device closed its port

    thread = threading.Thread(target=host, daemon=True)
    thread.start()
    code, stdout, stderr = run_cli(["virtual-device", "--duration", "30"])
    thread.join(timeout=30)
    assert code == 1 and stdout.strip() == ports[0]
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert "virtual device failed: RuntimeError: model blew up" in stderr


def test_a_failing_writer_ends_the_run_with_one_line_and_whole_rows(tmp_path):
    """The run file hits the file-size limit (EFBIG): exit 1, one line naming the run, the sidecar says
    why, and the file holds whole rows only."""
    out = tmp_path / "run.csv"
    script = ("import resource, signal, sys; signal.signal(signal.SIGXFSZ, signal.SIG_IGN); "
              "resource.setrlimit(resource.RLIMIT_FSIZE, (8000, 8000)); "
              "from fsrlab.cli import main; main(sys.argv[1:])")
    proc = subprocess.run([sys.executable, "-c", script, "acquire", "--virtual", "--duration", "60", "--window", "10ms",
                           "--out", str(out), "--quiet", "--json"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert f"cannot write '{out}': File too large" in proc.stderr
    run = load_run(out)
    assert out.read_text().endswith("\n")
    assert run.n_rows == run.metadata["rows"] == json.loads(proc.stdout)["frames"] > 0
    assert run.metadata["acquisition"]["ended"] == "failed" and "File too large" in run.metadata["ended"]


# ---------------------------------------------------------------- no valid window
@pytest.mark.parametrize("argv, words", [
    (["--drop", "1", "--duration", "1"], "lost on the link"),
    (["--corrupt", "1", "--duration", "1"], "corrupted lines rejected"),
    (["--window", "5", "--duration", "2"], "each window lasts 5 s, longer than the recording"),
])
def test_a_run_without_a_valid_window_is_an_error(tmp_path, argv, words):
    out = tmp_path / "run.csv"
    code, stdout, stderr = run_cli(["acquire", "--virtual", "--window", "20ms", "--out", out, "--quiet", "--json"]
                                   + argv)
    assert code == 1
    assert stderr.count("\n") == 1 and "no valid window recorded" in stderr and words in stderr
    assert json.loads(stdout)["frames"] == 0
    run = load_run(out)  # the empty run stays, and its sidecar says what happened
    assert run.n_rows == 0 and run.metadata["rows"] == 0
    assert run.metadata["acquisition"]["ended"] == "empty" and words in run.metadata["ended"]


# ---------------------------------------------------------------- output paths
def test_output_errors_name_the_users_path(tmp_path):
    code, _, stderr = run_cli(["acquire", "--virtual", "--duration", "1", "--out", tmp_path / "missing" / "x.csv"])
    assert code == 2 and stderr.count("\n") == 1 and "--out" in stderr and "missing" in stderr
    (tmp_path / "y.meta.json").mkdir()  # the sidecar's place is taken by a directory
    code, _, stderr = run_cli(["acquire", "--virtual", "--duration", "1", "--out", tmp_path / "y.csv", "--overwrite",
                               "--quiet"])
    assert code == 2 and stderr.count("\n") == 1
    assert str(tmp_path / "y.meta.json") in stderr and ".tmp" not in stderr
    code, _, stderr = run_cli(["acquire", "--virtual", "--duration", "1", "--out", tmp_path])
    assert code == 2 and "is a directory" in stderr and "--out" in stderr


# ---------------------------------------------------------------- help
@pytest.mark.parametrize("command, units", [
    ("acquire", {"--duration": "[s]", "--window": "[s]", "--stall": "[s]", "--peak": "[Pa]", "--period": "[s]",
                 "--c-off": "[F]", "--corrupt": "[1]", "--drop": "[1]", "--baud": "[bit/s]"}),
    ("virtual-device", {"--duration": "[s]", "--peak": "[Pa]", "--period": "[s]", "--c-off": "[F]",
                        "--corrupt": "[1]", "--drop": "[1]"}),
])
def test_help_shows_units_and_ends_with_examples_that_run(tmp_path, command, units):
    code, out, _ = run_cli([command, "--help"])
    assert code == 0
    text = " " + " ".join(out.split("Options:")[1].split()) + " --"
    for option, unit in units.items():
        start = text.index(f" {option} ")
        assert unit in text[start:text.index(" --", start + len(option) + 2)], option
    examples = out.split("Examples:")[1].split("Options:")[0].strip().splitlines()
    assert 1 <= len(examples) <= 2 and all(e.strip().startswith(f"fsrlab {command} ") for e in examples)
    for example in examples:  # each one is valid: run it briefly (virtual devices only)
        argv = shlex.split(example)[1:]
        if "--port" in argv:
            continue
        if "--out" in argv:
            argv[argv.index("--out") + 1] = str(tmp_path / "example.csv")
            argv += ["--quiet", "--overwrite"]
        if "--duration" in argv:
            argv[argv.index("--duration") + 1] = "0.3s"
        else:
            argv += ["--duration", "0.3s"]
        code, _, stderr = run_cli(argv)
        assert code in (0, 1) and "Invalid value" not in stderr, (example, stderr)


def test_a_load_cell_without_its_calibration_is_said_not_left_silent(tmp_path):
    """A meter with an HX711 (protocol 2) recorded without --loadcell: the counts are kept in reference_raw,
    force_n is empty in every row -- and the command says so, instead of only counting the rows."""
    out = tmp_path / "run.csv"
    with VirtualDevice(ConstantSource(), seed=1) as dev:
        code, stdout, stderr = run_cli(["acquire", "--port", dev.port, "--duration", "0.5", "--window", "20ms",
                                        "--out", out, "--quiet"])
    assert code == 0, stderr
    run = load_run(out)
    assert run.n_rows > 0 and np.isnan(run["force_n"]).all() and np.isfinite(run["reference_raw"]).any()
    assert "force_n is empty" in stderr and "--loadcell" in stderr
