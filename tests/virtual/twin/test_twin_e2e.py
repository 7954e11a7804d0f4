"""The digital twin end to end: the real firmware in simavr, a real pty, the real host commands.

Reference: the exact event-driven transient (fsrlab.circuits.transient.simulate) run once over the
whole run (the source's grid, and the C_off switch at the time the harness reported D4), compared
window by window with what the firmware measured (tests/virtual/twin/twin_windows.py: per-window values and the
quantization bound). simavr (the firmware itself) is the device under test. The twin runs with
--speed max; the simulated time in this file adds up to about 40 s.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest
import twin_windows as win

from fsrlab.acquisition.messages import Measurement
from fsrlab.acquisition.protocol import FrameParser
from fsrlab.virtual.sources import PhysicsSource, StressProfile
from fsrlab.virtual.twin import Twin
from fsrlab.virtual.twin.edges import EdgeStream

FSRLAB = [sys.executable, "-c", "import sys; from fsrlab.cli import main; sys.exit(main())"]


def reference_edges(source, t_end_s: float, switches=()):
    """Rising and falling edges of one transient run over [0, t_end_s) with the C_off switches."""
    stream = EdgeStream(source)
    for t, level in switches:
        stream.switch(t, level, 0, t)  # sets the range series (the edges it returns are not used)
    times = stream.sample_times(0.0, t_end_s)
    r, c = stream.parts(times)
    res = stream.circuit.simulate(r, c, time_s=times)
    return res.rising_s, res.falling_s


def test_acquire_on_triangle_matches_transient(built, tmp_path):
    source = PhysicsSource(StressProfile("triangle", peak_pa=50e3, period_s=2.0))
    out = tmp_path / "run.csv"
    with Twin(source, speed="max") as twin:
        proc = subprocess.run(FSRLAB + ["acquire", "--port", twin.port, "--duration", "3s", "--window", "100ms",
                                        "--out", str(out), "--quiet", "--json"],
                              capture_output=True, text=True, timeout=120)
        t_end = twin.time_s
        assert twin.failure is None
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    assert result["dropped"] == 0
    with open(out, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == result["frames"] >= 20
    seq = np.array([int(r["seq"]) for r in rows])
    assert np.all(np.diff(seq) == 1)  # consecutive windows: none lost
    assert all(int(r["missed"]) == 0 for r in rows)
    periods = np.array([int(r["periods"]) for r in rows])
    f = np.array([float(r["frequency_hz"]) for r in rows])
    duty = np.array([float(r["duty_cycle"]) for r in rows])
    assert f.max() > 2 * f.min()  # the triangle sweeps the 555
    rising, falling = reference_edges(source, t_end + 0.01)
    worst, _ = win.match(win.from_rows(periods, f, duty), rising, falling)
    assert worst <= 1.0, worst


def _collect(ser, parser, frames, pred, timeout_s=60.0):
    """Read frames into ``frames`` (all of them, in order) until ``pred(frames)``."""
    end = time.monotonic() + timeout_s
    while not pred(frames):
        assert time.monotonic() < end, f"timeout; frames: {frames[-3:]}"
        frames.extend(parser.feed(ser.read(4096)))


def _identify(ser, parser, frames, timeout_s=60.0):
    """Ask ``ID`` until the firmware answers (opening a port flushes what came before, such as the
    boot ID frame, and bytes sent before the firmware's UART is up are lost, as on an Uno)."""
    end = time.monotonic() + timeout_s
    asked = False
    t = time.monotonic() + 0.3
    while not any(f.kind == "ID" for f in frames):
        assert time.monotonic() < end, f"no ID frame; frames: {frames[-3:]}"
        if time.monotonic() >= t:
            ser.write(b"ID\n")
            asked, t = True, time.monotonic() + 0.3
        frames.extend(parser.feed(ser.read(4096)))
    if asked:  # the answers to every ID sent: the ID frame, then its ACK
        _collect(ser, parser, frames, lambda fr: fr[-1].kind == "ACK" and fr[-1].fields[0] == "ID", 5.0)


def _m_count(frames):
    return sum(f.kind == "M" for f in frames)


def test_range_switch_mid_run_changes_c_off(built):
    import serial

    source = PhysicsSource(StressProfile("hold", peak_pa=20e3, period_s=1.0))
    with Twin(source, speed="max") as twin, serial.Serial(twin.port, timeout=0.05) as ser:
        parser, frames = FrameParser(), []
        _identify(ser, parser, frames)
        ser.write(b"WINDOW 50\n")
        _collect(ser, parser, frames, lambda fr: fr[-1].kind == "ACK" and fr[-1].fields[0] == "WINDOW")
        ser.write(b"START\n")
        _collect(ser, parser, frames, lambda fr: _m_count(fr) >= 10)
        ser.write(b"RANGE 1\n")
        _collect(ser, parser, frames, lambda fr: sum(f.kind == "M" and f.fields[7] == "1" for f in fr) >= 10)
        ser.write(b"STOP\n")
        t_end = twin.time_s
        switches = list(twin.d4_changes)
        assert twin.failure is None
    assert len(switches) == 1 and switches[0][1] == 1
    ms = [Measurement.from_frame(f) for f in frames if f.kind == "M"]
    ms_before = [m for m in ms if m.range == 0]
    ms_after = [m for m in ms if m.range == 1]
    assert len(ms_before) >= 10 and len(ms_after) >= 10
    assert ms[:len(ms_before)] == ms_before  # range 0, then 1: the frames show the switch once
    assert all(m.missed == 0 for m in ms_before + ms_after)
    # C_off in parallel: a longer period (the frequency falls by (C_FSR + C_off) / C_FSR in the steady state)
    f0 = np.mean([m.frequency_hz for m in ms_before[2:]])
    f1 = np.mean([m.frequency_hz for m in ms_after[2:]])
    assert f1 < 0.8 * f0, (f0, f1)
    # and every window, the one with the switch included, equals the transient with C_off switched in
    # at the time the firmware drove D4
    rising, falling = reference_edges(source, t_end + 0.01, switches)
    seqs = np.array([m.seq for m in ms])
    assert np.all(np.isin(np.diff(seqs), (1, 2)))  # consecutive windows (2: the ACK of RANGE between)
    worst, _ = win.match(win.from_measurements(ms), rising, falling, end_hint_s=ms[0].t_ms / 1000.0)
    assert worst <= 1.0, worst


def test_out_of_oscillation_gap_and_notice(built):
    """A profile past the oscillation limit (N = R_FSR/R < 4, eq. 30; the sensor's R_FSR falls below
    40 kΩ near 100 kPa): the firmware sends windows without periods, as a real one would, the twin
    keeps running and says so; the 555 starts again when the stress falls."""
    import serial

    source = PhysicsSource(StressProfile("triangle", peak_pa=120e3, period_s=1.0))
    with Twin(source, speed="max") as twin, serial.Serial(twin.port, timeout=0.05) as ser:
        parser, frames = FrameParser(), []
        _identify(ser, parser, frames)
        ser.write(b"START\n")
        _collect(ser, parser, frames, lambda fr: _m_count(fr) >= 14 and any("again" in n for n in twin.notices))
        assert twin.failure is None
        notices = list(twin.notices)
    ms = [Measurement.from_frame(f) for f in frames if f.kind == "M"]
    periods = [m.periods for m in ms]
    gap = [i for i, p in enumerate(periods) if p == 0]
    assert gap, periods
    assert any(p > 0 for p in periods[:gap[0]]) and any(p > 0 for p in periods[gap[0]:]), periods
    assert all(m.missed == 0 for m in ms)
    assert any("out of oscillation" in n for n in notices) and any("oscillates again" in n for n in notices)


def test_cli_notice_on_stderr(built):
    proc = subprocess.run(FSRLAB + ["twin", "--profile", "triangle", "--peak", "120k", "--period", "1s",
                                    "--speed", "max", "--duration", "2s", "--no-loadcell"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[0].startswith("/dev/")
    assert "out of oscillation" in proc.stderr and "Traceback" not in proc.stderr


def test_twin_killed_mid_run_ends_acquire_cleanly(built, tmp_path):
    out = tmp_path / "run.csv"
    twin = subprocess.Popen(FSRLAB + ["twin", "--speed", "max", "--json"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    acq = None
    try:
        port = json.loads(twin.stdout.readline())["port"]
        acq = subprocess.Popen(FSRLAB + ["acquire", "--port", port, "--duration", "60s", "--out", str(out),
                                         "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        end = time.monotonic() + 60
        while time.monotonic() < end:
            if out.exists() and len(out.read_text().splitlines()) >= 6:
                break
            time.sleep(0.1)
        twin.kill()  # SIGKILL: no clean-up in the twin at all
        twin.wait(timeout=10)
        stdout, stderr = acq.communicate(timeout=60)
    finally:
        for p in (twin, acq):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
    assert acq.returncode == 1, stderr
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    with open(out, newline="") as fh:
        rows = list(csv.reader(fh))
    header, data = rows[0], rows[1:]
    assert len(data) >= 5
    assert all(len(r) == len(header) for r in data)  # no cut line: the file is intact
    meta = json.loads(out.with_name("run.meta.json").read_text())
    assert meta.get("ended")


def test_no_firmware_one_line_exit_2(tmp_path):
    env = {**os.environ, "FSRLAB_FIRMWARE_BUILD": str(tmp_path / "nothing")}
    proc = subprocess.run(FSRLAB + ["twin", "--duration", "1s"], capture_output=True, text=True, env=env,
                          timeout=60)
    assert proc.returncode == 2
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "make firmware" in lines[0], proc.stderr
    assert proc.stdout == ""


def test_no_firmware_api(tmp_path, monkeypatch):
    from fsrlab.virtual.twin import twin_available

    monkeypatch.setenv("FSRLAB_FIRMWARE_BUILD", str(tmp_path / "nothing"))
    ok, reason = twin_available()
    assert not ok and "make firmware" in reason and "\n" not in reason
    with pytest.raises(RuntimeError, match="make firmware"):
        Twin().open()


@pytest.mark.parametrize("args,option", [(["--speed", "fast"], "--speed"), (["--sensor", "foo"], "--sensor"),
                                         (["--duration", "0"], "--duration"), (["--peak", "-1k"], "--peak"),
                                         (["--hx711-rate", "20"], "--hx711-rate")])
def test_cli_bad_options_one_line_exit_2(args, option):
    from clirun import run_cli

    code, out, err = run_cli(["twin", *args])
    assert code == 2 and out == ""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and option in lines[0], err
