"""design(): proposals checked independently with the closed forms on a finer grid (properties)."""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.circuits.design import design
from fsrlab.circuits.lm555 import astable, minimum_n_ratio
from fsrlab.hardware import CAPTURE_MAX_HZ
from fsrlab.hardware import TICK_S as TIMER_TICK_S

SENSOR = dict(r_fsr_range_ohm=(100e3, 2e6), c_fsr_range_farad=(0.5e-9, 1.5e-9))


@pytest.mark.parametrize("band, variant", [((1e3, 20e3), "auto"), ((1e3, 100e3), "auto"),
                                           ((200.0, 40e3), "diode"), ((1e3, 20e3), "no-diode")])
def test_proposal_stays_in_band_with_margin(band, variant):
    d = design(**SENSOR, band_hz=band, variant=variant)
    if variant != "auto":
        assert d.diode == (variant == "diode")
    # Independent check on a 200 × 20 grid of the sensor range (design used 24 × 2 points).
    rf, cf = np.meshgrid(np.geomspace(100e3, 2e6, 200), np.linspace(0.5e-9, 1.5e-9, 20))
    f = astable(d.r_ohm, rf, cf, d.c_off_farad, diode=d.diode).frequency_hz
    assert band[0] <= f.min() and f.max() <= band[1]
    assert f.min() == pytest.approx(d.frequency_range_hz[0], rel=1e-2)
    assert 100e3 / d.r_ohm / minimum_n_ratio() - 1 >= 0.25
    assert d.margin >= 0.25
    # The band's top is lowered to the meter's capture limit (50 kHz): 1–100 kHz designs for 1–50 kHz.
    assert d.band_hz == (band[0], min(band[1], CAPTURE_MAX_HZ)) and f.max() <= CAPTURE_MAX_HZ
    # Uno resolution: one 62.5 ns tick on one period is Δf = f²·q (band ends and the sensor's range).
    assert d.resolution_single_hz[1] == pytest.approx(d.band_hz[1] ** 2 * TIMER_TICK_S, rel=1e-12)
    assert d.range_resolution_single_hz[1] == pytest.approx(d.frequency_range_hz[1] ** 2 * TIMER_TICK_S, rel=1e-12)
    assert d.resolution_window_hz[1] < d.resolution_single_hz[1]


def test_auto_prefers_the_capacitive_variant():
    # Without D1, f hardly depends on R_FSR at large N (|S_R| small); with D1, f ≈ 1/(ln2·R_FSR·C).
    d = design(**SENSOR, band_hz=(1e3, 100e3))
    assert not d.diode
    assert {a["diode"] for a in d.alternatives} <= {False, True}
    assert d.merit == max(a["merit"] for a in d.alternatives)


def test_impossible_band_says_why():
    with pytest.raises(ValueError, match=r"band_hz: no design.*span at least a factor"):
        design(**SENSOR, band_hz=(9e3, 10e3), variant="diode")


@pytest.mark.parametrize("kwargs, name", [
    (dict(band_hz=(2e3, 1e3)), "band_hz"), (dict(band_hz=(1e3, 2e4), variant="x"), "variant"),
    (dict(band_hz=(1e3, 2e4), min_margin=-1), "min_margin"),
    (dict(band_hz=(1e3, 2e4), vcc_v=0.0), "vcc_v"), (dict(band_hz=(1e3, 2e4), diode_drop_v=-1.0), "diode_drop_v"),
    (dict(band_hz=(1e3, 2e4), window_s=float("inf")), "window_s"),
])
def test_validation(kwargs, name):
    with pytest.raises(ValueError, match=name):
        design(**SENSOR, **kwargs)


# The firmware's capture limit. Reference: the measured highest clean frequency in
# docs/performance.md (simavr search of benchmarks/bench_firmware.py) and firmware/README.md "Limits".

def _measured_clean_khz() -> list[float]:
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "performance.md").read_text(encoding="utf-8")
    section = text.split("<!-- bench:bench_firmware -->")[1].split("<!-- /bench:bench_firmware -->")[0]
    return [float(m) for m in re.findall(r"^\| 0\.\d+ \| \*\*([\d.]+)\*\* \|", section, re.MULTILINE)]


def test_capture_limit_is_within_the_measured_clean_frequencies():
    measured = _measured_clean_khz()
    assert len(measured) == 3  # 5, 50 and 95 % duty cycle
    assert CAPTURE_MAX_HZ <= min(measured) * 1e3
    assert CAPTURE_MAX_HZ == 50e3  # the supported range of firmware/README.md, tested in simavr


def test_band_above_the_capture_limit_is_refused():
    # The 1–2 MHz band used to give a 1–1.85 MHz proposal that the meter cannot count.
    with pytest.raises(ValueError, match=r"band_hz: .*beyond what the counter captures.*max_frequency_hz = 50000 Hz"):
        design(**SENSOR, band_hz=(1e6, 2e6))


def test_default_proposal_stays_below_the_capture_limit():
    d = design(**SENSOR, band_hz=(1e3, 10e6))
    assert d.band_hz == (1e3, CAPTURE_MAX_HZ) and d.max_frequency_hz == CAPTURE_MAX_HZ
    rf, cf = np.meshgrid(np.geomspace(100e3, 2e6, 200), np.linspace(0.5e-9, 1.5e-9, 20))
    f = astable(d.r_ohm, rf, cf, d.c_off_farad, diode=d.diode).frequency_hz
    assert 1e3 <= f.min() and f.max() <= CAPTURE_MAX_HZ
    assert d.resolution_single_hz[1] == pytest.approx(CAPTURE_MAX_HZ**2 * TIMER_TICK_S, rel=1e-12)


def test_other_counter_takes_the_band_as_given():
    d = design(**SENSOR, band_hz=(1e6, 2e6), max_frequency_hz=None)
    assert 1e6 <= d.frequency_range_hz[0] and d.frequency_range_hz[1] <= 2e6
    assert d.band_hz == (1e6, 2e6)
    d = design(**SENSOR, band_hz=(1e6, 2e6), max_frequency_hz=5e6)
    assert d.frequency_range_hz[1] <= 2e6


def test_max_frequency_validated():
    with pytest.raises(ValueError, match="max_frequency_hz"):
        design(**SENSOR, band_hz=(1e3, 2e4), max_frequency_hz=0.0)
