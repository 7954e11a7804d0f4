"""The virtual device answers like the real firmware: one command session, played to the firmware
running in simavr (firmware/build/fsrlab_sim, an ATmega328P at 16 MHz) and to the virtual device on
a pty, parsed by the same host parser.

Reference: simavr running the firmware's .elf (firmware/sim/fsrlab_sim.c, protocol v3). Compared: every
non-measurement frame (ID, ACK, ERR: type and fields; the firmware version string aside), and
the measurement frames' window, range, A0 reading and decoded frequency and duty cycle (within
the quantization bound of each: one 62.5 ns tick per timestamp difference for the virtual device,
docs/protocol.md; four in simavr, firmware/sim/simrun.py). The session printed in docs/protocol.md
is checked to be the firmware's.
"""

from __future__ import annotations

import math
import subprocess
import time
from pathlib import Path

import pytest

from fsrlab.acquisition.messages import Measurement
from fsrlab.acquisition.protocol import FrameParser
from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import ConstantSource
from toolcheck import require_file, require_tool

FIRMWARE = Path(__file__).resolve().parents[2] / "firmware"
F_HZ, DUTY, ADC_MV = 5000.0, 0.25, 2000
# Largest error of a difference of two timestamps [ticks]: the virtual device quantizes each edge to
# one tick; in simavr a captured timestamp lies -0.5..+3.5 ticks from the ideal edge (simavr applies
# an edge at the end of the running instruction: firmware/sim/simrun.py, EDGE_ERROR_TICKS).
VIRTUAL_TICKS, SIMAVR_TICKS = 1.0, 4.0

# (time [s], command line) — the same session for both devices.
SESSION = [
    (0.01, "ID"), (0.02, "FOO"), (0.03, "WINDOW 5"), (0.04, "WINDOW 50"), (0.05, "RANGE 1"),
    (0.06, "START"), (0.07, "START"), (0.25, "STOP"), (0.26, ""), (0.27, "STOP 1"),
    (0.28, "X" * 40), (0.29, "RANGE 2"), (0.30, "start"), (0.31, "RANGE 0"),
    (0.32, "SCAN 0"), (0.33, "SCAN 256"), (0.34, "DWELL 0"), (0.35, "SETTLE 101"), (0.36, "SCAN 3"),
    (0.37, "DWELL 5"), (0.38, "SETTLE 1"),
]
END_S = 0.4


@pytest.fixture(scope="module")
def simulator() -> tuple[Path, Path]:
    require_tool("avr-gcc")
    require_tool("make")
    require_file("/usr/include/simavr/sim_avr.h", "libsimavr-dev")
    require_file(FIRMWARE / "Makefile", "the firmware sources")
    build = subprocess.run(["make", "-s", "-C", str(FIRMWARE), "all-sim"], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr[-2000:]
    return FIRMWARE / "build" / "fsrlab_sim", FIRMWARE / "build" / "fsrlab_meter.elf"


def _firmware_frames(simulator) -> list:
    sim, elf = simulator
    args = [str(sim), str(elf), "--time", str(END_S), "--seg", f"0:{F_HZ}:{DUTY}", "--adc-mv", str(ADC_MV)]
    for t, line in SESSION:
        args += ["--cmd", f"{t}:{line}"]
    out = subprocess.run(args, capture_output=True, check=True).stdout
    return FrameParser().feed(out)


def _virtual_frames() -> list:
    source = ConstantSource(F_HZ, DUTY, ADC_MV / 1000.0)
    frames = []
    with VirtualDevice(source, frequency_noise=0.0, jitter_s=0.0, adc_noise_v=0.0, seed=0) as dev, \
            SerialLink(dev.port) as link:
        t0 = time.monotonic()
        for t, line in SESSION + [(END_S, None)]:
            while time.monotonic() - t0 < t:
                frames += link.read_frames()
            if line is not None:
                link.send(line.encode() + b"\n")
        end = time.monotonic() + 0.5  # the last answers (the device was stopped at 0.25 s: no windows)
        while time.monotonic() < end:
            frames += link.read_frames()
    return frames


def _answers(frames) -> list:
    out = []
    for f in frames:
        if f.kind == "M":
            continue
        fields = f.fields
        if f.kind == "ID":
            fields = (fields[0],) + fields[2:]  # firmware version: "1.0.0" vs "1.0.0-virtual"
        out.append((f.kind, fields))
    return out


def test_virtual_device_answers_commands_like_the_firmware(simulator):
    real = _firmware_frames(simulator)
    virtual = _virtual_frames()
    assert real[0].kind == "ID" and real[0].seq == 0  # boot announcement (the host's open flushes it)
    assert _answers(virtual) == _answers(real[1:])


def test_virtual_measurements_agree_with_the_firmware(simulator):
    real = [Measurement.from_frame(f) for f in _firmware_frames(simulator) if f.kind == "M"]
    virtual = [Measurement.from_frame(f) for f in _virtual_frames() if f.kind == "M"]
    assert len(real) == 3 and 2 <= len(virtual) <= 4  # 50 ms windows between START and STOP (OS timing ±1)
    for m, e in [(m, SIMAVR_TICKS) for m in real] + [(m, VIRTUAL_TICKS) for m in virtual]:
        assert (m.window_ms, m.range, m.missed) == (50, 1, 0)
        assert m.adc == math.floor(ADC_MV / 5000 * 1024)
        # the sum of periods telescopes: one timestamp-difference error over the sum
        assert abs(m.frequency_hz - F_HZ) <= F_HZ * e / m.sum_period_ticks + 1e-9
        # each high time is a timestamp difference: at worst e ticks per period over the sum
        assert abs(m.duty_cycle - DUTY) <= e * m.periods / m.sum_period_ticks


def test_the_session_in_the_protocol_document_is_the_firmwares(simulator):
    # docs/protocol.md, "A session", is the firmware's own answer to SESSION in simavr: every frame
    # but the measurements' tick sums (which move by a few ticks between builds) byte for byte
    doc = (FIRMWARE.parent / "docs" / "protocol.md").read_text(encoding="utf-8")
    section = doc.split("### A session", 1)[1].split("```", 2)[1]
    documented = FrameParser().feed("".join(
        line[line.index("$"):] + "\r\n" for line in section.splitlines() if "$" in line).encode())
    real = _firmware_frames(simulator)
    assert len(documented) == len(real)
    for d, r in zip(documented, real, strict=True):
        if r.kind == "M":
            assert len(d.fields) == len(r.fields), (d, r)
            keep = [i for i in range(len(r.fields)) if i not in (3, 4)]  # all but sum_period_ticks, sum_high_ticks
            assert [d.fields[i] for i in keep] == [r.fields[i] for i in keep], (d, r)
        else:
            assert d.encode() == r.encode()
