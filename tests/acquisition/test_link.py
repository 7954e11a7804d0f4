"""The serial link and the virtual device, through real pseudo-terminals (and pyserial's loop://).

References: docs/protocol.md (commands, answers, error codes), the protocol's decoding formula
f = periods·16 MHz/Σticks with its 62.5 ns quantization, and the lm555 closed form.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from fsrlab.acquisition import protocol as P
from fsrlab.acquisition.messages import DeviceError, Measurement
from fsrlab.acquisition.protocol import encode_frame
from fsrlab.acquisition.serial_link import (
    CommandRejected,
    HandshakeError,
    LinkError,
    SerialLink,
    UsbPort,
    find_uno,
)
from fsrlab.circuits.circuit import PAPER_CIRCUIT
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import ConstantSource, PhysicsSource, StressProfile


def _collect(link: SerialLink, n: int, kinds=("M",), limit_s: float = 10.0):
    """Read until ``n`` frames of ``kinds`` arrived (the limit only guards against a hang)."""
    out, end = [], time.monotonic() + limit_s
    while len(out) < n and time.monotonic() < end:
        out += [f for f in link.read_frames() if f.kind in kinds]
    return out


@pytest.fixture
def square():
    """A virtual device with a clean 5 kHz, 25 % square wave (no noise, no jitter)."""
    with VirtualDevice(ConstantSource(5000.0, 0.25, 2.0), frequency_noise=0.0, jitter_s=0.0,
                       adc_noise_v=0.0, seed=1) as dev:
        with SerialLink(dev.port) as link:
            yield dev, link


def test_handshake_over_a_pty(square):
    dev, link = square
    ident = link.handshake()
    assert (ident.name, ident.protocol_version, ident.f_cpu_hz) == ("fsrlab-meter", P.PROTOCOL_VERSION, 16_000_000)
    assert link.identity == ident


def test_commands_are_acknowledged_like_the_firmware(square):
    _, link = square
    link.handshake()
    assert (link.set_window(20).command, link.set_window(20).value) == ("WINDOW", 20)
    assert link.set_range(1).value == 1
    assert link.start().command == "START"
    assert link.start().command == "START"  # START while started: accepted, nothing changes
    frames = _collect(link, 3)
    ms = [Measurement.from_frame(f) for f in frames]
    assert all(m.window_ms == 20 and m.range == 1 for m in ms)
    assert link.stop().command == "STOP"


@pytest.mark.parametrize("line, code, token", [
    (b"FOO\n", P.ERR_UNKNOWN_COMMAND, "FOO"), (b"\n", P.ERR_UNKNOWN_COMMAND, "?"),
    (b"WINDOW 5\n", P.ERR_BAD_VALUE, "WINDOW"), (b"RANGE 2\r\n", P.ERR_BAD_VALUE, "RANGE"),
    (b"X" * 40 + b"\n", P.ERR_LINE_TOO_LONG, "LINE"),
])
def test_rejected_commands_answer_err(square, line, code, token):
    _, link = square
    link.handshake()
    link.send(line)
    (err,) = _collect(link, 1, kinds=("ERR",))
    e = DeviceError.from_frame(err)
    assert (e.code, e.token) == (code, token)


def test_host_validates_commands_before_sending(square):
    _, link = square
    link.handshake()
    with pytest.raises(ValueError, match="10..60000"):
        link.command("WINDOW", 5)
    assert link.set_window(10).value == 10


def test_err_answer_raises_command_rejected():
    # loop:// hands back what is written: an ERR frame queued before the command is its answer.
    with SerialLink("loop://") as link:
        link.serial.write(encode_frame("ERR", 9, (2, "START")))
        with pytest.raises(CommandRejected, match="error 2"):
            link.command("START", timeout_s=0.5)
    with SerialLink("loop://") as link:
        with pytest.raises(LinkError, match="no answer"):
            link.command("STOP", timeout_s=0.2)


def test_measurements_decode_within_the_quantization_bound(square):
    """A 5 kHz, 25 % wave: f = periods·16e6/Σticks within one 62.5 ns tick over Σticks (the edge
    timestamps are quantized, the frequency itself is exact), periods = f·window ± 1, and the duty
    cycle within 6σ of the per-period high-time quantization (σ = √(periods/6) ticks)."""
    _, link = square
    link.handshake()
    link.set_window(50)
    link.start()
    ms = [Measurement.from_frame(f) for f in _collect(link, 6)]
    link.stop()
    for m in ms:
        assert abs(m.periods - 5000 * 0.05) <= 1
        assert abs(m.frequency_hz - 5000.0) <= 5000.0 * 1.0 / m.sum_period_ticks + 1e-9
        assert abs(m.duty_cycle - 0.25) <= 6 * math.sqrt(m.periods / 6) / m.sum_period_ticks
        assert m.adc == int(2.0 / 5 * 1024)  # ideal ADC: floor(V·1024/5 V)


def test_physics_source_matches_the_closed_forms_at_constant_stress():
    """'hold' profile at 30 kPa: the recorded frequency equals lm555.astable(VirtualFSR at 30 kPa)
    within 4σ of the frequency noise (1e-3 per window, averaged over n windows) plus one tick."""
    from fsrlab.circuits.lm555 import astable
    from fsrlab.physics.sensor import VirtualFSR

    sigma = 30e3
    resp = VirtualFSR().respond(np.array([sigma]), voltage_v=2.5)
    expected = astable(10e3, resp.r_fsr_ohm[0], resp.c_fsr_farad[0], diode=True)
    src = PhysicsSource(StressProfile("hold", peak_pa=sigma, period_s=1.0))
    with VirtualDevice(src, frequency_noise=1e-3, seed=3) as dev, SerialLink(dev.port) as link:
        link.handshake()
        link.set_window(20)
        link.start()
        frames = _collect(link, 10)
    ms = [Measurement.from_frame(f) for f in frames]
    f_mean = np.mean([m.frequency_hz for m in ms])
    duty = np.mean([m.duty_cycle for m in ms])
    assert f_mean == pytest.approx(float(expected.frequency_hz), rel=4e-3 / math.sqrt(len(ms)) + 1e-4)
    assert duty == pytest.approx(float(expected.duty_cycle), rel=1e-2)
    assert all(dev.reference(f.seq) == pytest.approx(sigma) for f in frames)


def test_range_switch_adds_c_off_and_lowers_the_frequency():
    # Closed form: more timing capacitance C = C_FSR + C_off, lower frequency (f ∝ 1/C at fixed N).
    src = PhysicsSource(StressProfile("hold", peak_pa=20e3, period_s=1.0),
                        circuit=PAPER_CIRCUIT.replace(c_off_farad=1e-9))
    with VirtualDevice(src, seed=4) as dev, SerialLink(dev.port) as link:
        link.handshake()
        link.set_window(20)
        link.start()
        f0 = Measurement.from_frame(_collect(link, 2)[-1]).frequency_hz
        link.set_range(1)
        frames = _collect(link, 3)
    f1 = Measurement.from_frame(frames[-1]).frequency_hz
    c = src._c[src._index(np.array([0.5]))][0]
    assert f1 / f0 == pytest.approx(c / (c + 1e-9), rel=0.01)  # 1 % covers the 1e-3 frequency noise


def test_handshake_refuses_another_protocol_version():
    with SerialLink("loop://") as link:
        link.serial.write(encode_frame("ID", 0, ("fsrlab-meter", "4.0.0", 4, 16000000)))
        with pytest.raises(HandshakeError, match="protocol version 4"):
            link.handshake(timeout_s=1.0)


def test_handshake_without_frames_hints_at_the_baud_rate():
    with SerialLink("loop://") as link:
        link.serial.write(bytes(range(256)) * 4)  # what a receiver at the wrong rate sees
        with pytest.raises(HandshakeError, match="baud"):
            link.handshake(timeout_s=0.6, retry_s=0.2)


def test_opening_a_missing_port_is_a_one_line_link_error():
    with pytest.raises(LinkError, match="cannot open /dev/does-not-exist"):
        SerialLink("/dev/does-not-exist")


def test_find_uno_by_usb_identity():
    uno = UsbPort("/dev/ttyACM0", 0x2341, 0x0043, "Arduino Uno")
    clone = UsbPort("/dev/ttyUSB0", 0x1A86, 0x7523, "USB2.0-Serial")
    other = UsbPort("/dev/ttyUSB1", 0x0403, 0x6001, "FT232R")
    assert find_uno([other, uno]) == "/dev/ttyACM0"
    assert find_uno([clone]) == "/dev/ttyUSB0"
    with pytest.raises(LinkError, match="found no Arduino Uno.*ttyUSB1"):
        find_uno([other])
    with pytest.raises(LinkError, match="several.*ttyACM0.*ttyUSB0"):
        find_uno([uno, clone])


def test_device_reset_is_detected_and_counted():
    from fsrlab.virtual.device import Faults

    with VirtualDevice(ConstantSource(), faults=Faults(reset_after=3), seed=5) as dev, SerialLink(dev.port) as link:
        link.handshake()
        link.set_window(10)
        link.start()
        frames = _collect(link, 1, kinds=("ID",))
    assert frames[0].reset and frames[0].seq == 0
    assert link.parser.resets == 1 and link.parser.malformed == 1 and link.parser.lost == 0


def test_unplugged_device_raises_device_gone(square):
    from fsrlab.acquisition.serial_link import DeviceGone

    dev, link = square
    link.handshake()
    dev.unplug()
    with pytest.raises(DeviceGone, match="disconnected"):
        for _ in range(100):
            link.read_frames()


def test_frames_after_the_answer_in_the_same_read_are_kept():
    with SerialLink("loop://") as link:
        stale = encode_frame("M", 3, (1, 100, 0, 0, 0, 0, 0, 1))
        ack = encode_frame("ACK", 4, ("START",))
        fresh = encode_frame("M", 5, (2, 100, 0, 0, 0, 0, 0, 0))
        link.serial.write(stale + ack + fresh)
        assert link.start().seq == 4
        assert [f.seq for f in link.read_frames()] == [5]  # the stale window is dropped, the fresh kept
        link.serial.write(stale + encode_frame("ACK", 4, ("RANGE", 1)) + fresh)
        assert link.set_range(1).value == 1
        assert [f.seq for f in link.read_frames()] == [3, 5]  # other commands keep every window
