"""The virtual device's signal and its meter: eq. (38) on A0, and the same statistics as a synthetic run.

References: the paper's eq. (38), |V_out| = R_F/R_FSR·|Vcc| with R_F = 20 kΩ and |Vcc| = 5 V,
evaluated by hand on the sensor model's R_FSR at 5 V; the synthetic run (fsrlab.virtual.synthetic)
as a second, vectorised path through the meter's model, compared statistically (bounds from the
sampling spread of n windows, stated at each assertion).
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from fsrlab.acquisition.messages import Measurement
from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.hardware import ADC_V_PER_COUNT
from fsrlab.physics.sensor import VirtualFSR
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import VIRTUAL_CIRCUIT, PhysicsSource, StressProfile
from fsrlab.virtual.synthetic import synthetic_run

SIGMA = 30e3  # Pa


def _measurements(device: VirtualDevice, n: int, window_ms: int, range_: int) -> list[Measurement]:
    """The first ``n`` windows after START (the limit only guards against a hang)."""
    out, end = [], time.monotonic() + 30.0
    with SerialLink(device.port) as link:
        link.handshake()
        link.set_window(window_ms)
        link.set_range(range_)
        link.start()
        while len(out) < n and time.monotonic() < end:
            out += [Measurement.from_frame(f) for f in link.read_frames() if f.kind == "M"]
        link.stop()
    return out[:n]


def test_opamp_voltage_is_eq38_at_5_v():
    r5 = VirtualFSR().respond(np.array([SIGMA]), voltage_v=5.0).r_fsr_ohm[0]
    r25 = VirtualFSR().respond(np.array([SIGMA]), voltage_v=2.5).r_fsr_ohm[0]
    expected = 20e3 / r5 * 5.0  # Eq. (38) by hand: R_F = 20 kΩ, |Vcc| = 5 V across the FSR
    src = PhysicsSource(StressProfile("hold", peak_pa=SIGMA, period_s=1.0))
    assert src.window(0.0, 0.1, 0).voltage_v == pytest.approx(expected, rel=1e-12)
    assert src.window(0.0, 0.1, 1).voltage_v == pytest.approx(expected, rel=1e-12)  # C_off does not touch A0
    # The FSR's resistance depends on its voltage, so this test tells 5 V from the 555's 2.5 V.
    assert abs(20e3 / r25 * 5.0 / expected - 1) > 1e-4
    with VirtualDevice(src, frequency_noise=0.0, jitter_s=0.0, adc_noise_v=0.0, seed=2) as dev:
        ms = _measurements(dev, 3, 10, 0)
    assert [m.adc for m in ms] == [math.floor(expected * 1024 / 5.0)] * 3


@pytest.mark.parametrize("range_", [0, 1])
def test_virtual_device_and_synthetic_run_agree(range_):
    """The same constant signal (the sensor held at 30 kPa, 10 ms windows, the same noise settings)
    through the virtual device window by window and through synthetic_run all at once. The first
    window after START (it only opens a period) is left out; the device runs on its simulated clock
    (``speed="max"``). Bounds for n ≈ 150 windows: means
    within 4 standard errors of their difference; standard deviations within a factor 1.4 (the
    ratio of two sample deviations of 150 normal values stays within exp(±3.3/√149) = 0.76..1.31
    with probability 0.999)."""
    n, noise = 151, dict(frequency_noise=1e-3, jitter_s=20e-9)
    src = PhysicsSource(StressProfile("hold", peak_pa=SIGMA, period_s=1.0))
    with VirtualDevice(src, adc_noise_v=2e-3, seed=3, speed="max", **noise) as dev:
        ms = _measurements(dev, n, 10, range_)[1:]
    syn = synthetic_run(stress_pa=np.full(n, SIGMA), window_s=0.01, voltage_noise_v=2e-3, seed=3,
                        circuit=VIRTUAL_CIRCUIT.on_range(range_), **noise).columns
    dev_cols = {"frequency_hz": np.array([m.frequency_hz for m in ms]),
                "duty_cycle": np.array([m.duty_cycle for m in ms]),
                "voltage_v": np.array([m.adc_v for m in ms]),
                "periods": np.array([m.periods for m in ms], dtype=float)}
    assert len(ms) == n - 1
    for name, a in dev_cols.items():
        b = syn[name][1:]
        se = math.sqrt(np.var(a, ddof=1) / a.size + np.var(b, ddof=1) / b.size)
        assert abs(a.mean() - b.mean()) <= 4 * se + 1e-12 * abs(b.mean()), name
        if name in ("frequency_hz", "duty_cycle"):
            assert 1 / 1.4 < np.std(a) / np.std(b) < 1.4, name
    # Both read the same A0 codes (2 mV of noise on a fixed voltage: two or three adjacent codes).
    codes = np.unique(np.concatenate([dev_cols["voltage_v"], syn["voltage_v"]]) / ADC_V_PER_COUNT)
    assert codes.size <= 4 and np.ptp(codes) <= 3


def test_max_speed_waits_for_the_host_and_keeps_the_time_axis():
    """``speed="max"``: frames come one window apart on the device's clock (t_ms: whole windows from
    START, no drift), none is lost while the host does not read, and the device never has more than
    MAX_UNREAD bytes plus one frame (the protocol's longest line, MAX_LINE) waiting for the host."""
    from fsrlab.acquisition.protocol import MAX_LINE

    with VirtualDevice(PhysicsSource(), seed=4, speed="max") as dev, SerialLink(dev.port) as link:
        link.handshake()
        link.set_window(10)
        start = link.start()
        time.sleep(0.3)  # the host reads nothing meanwhile
        assert dev._unread() <= VirtualDevice.MAX_UNREAD + MAX_LINE
        frames, end = [], time.monotonic() + 30.0
        while len(frames) < 300 and time.monotonic() < end:  # the limit only guards against a hang
            frames += [f for f in link.read_frames() if f.kind == "M"]
        link.stop()
    ms = [Measurement.from_frame(f) for f in frames[:300]]
    assert [f.seq for f in frames[:300]] == list(range(start.seq + 1, start.seq + 301))
    t = np.array([m.t_ms for m in ms])
    assert np.all(np.diff(t) == 10) and all(m.window_ms == 10 for m in ms)
