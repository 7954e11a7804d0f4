"""The load cell and HX711 model, and the load-cell calibration (tare, scale, file).

References: the closed forms of fsrlab.acquisition.loadcell's docstring — raw = offset + scale·F
(rounded, clipped to the HX711's 24-bit two's complement, datasheet), F = (raw − offset)/scale
(the HX711 libraries' get_units()), one conversion every 1/rate s, a conversion averaging the force
over its own period (so a force ramp F = k·t is read k·p/2 late) —, and the model's known parameters.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.acquisition.loadcell import (
    STANDARD_GRAVITY,
    LoadCellCalibration,
    LoadCellError,
    LoadCellModel,
    WindowReference,
    load_loadcell,
    raw_to_force,
    scale_from_readings,
    tare_from_readings,
    window_reference,
)
from fsrlab.acquisition.protocol import HX711_MAX, HX711_MIN

QUIET = LoadCellModel(noise_counts=0.0)


@given(st.floats(-50.0, 50.0))
def test_force_from_raw_inverts_the_model(force):
    # Noiseless: the only error is the rounding to whole counts, half a count = 0.5/scale N.
    raw = QUIET.raw(force)
    assert raw_to_force(raw, QUIET.offset_counts, QUIET.scale_counts_per_n) == pytest.approx(
        force, abs=0.5 / QUIET.scale_counts_per_n + 1e-12)


def test_raw_saturates_at_24_bits():
    assert QUIET.raw(1e6) == HX711_MAX and QUIET.raw(-1e6) == HX711_MIN


@pytest.mark.parametrize("rate, window_s, per_window", [(80, 0.05, {4}), (10, 0.05, {0, 1}), (10, 0.1, {1})])
def test_conversions_per_window(rate, window_s, per_window):
    cell = LoadCellModel(rate_sps=rate, noise_counts=0.0, phase_s=0.0037)
    counts = [window_reference(cell, lambda t: 0 * t, k * window_s, (k + 1) * window_s).ref_n for k in range(40)]
    assert set(counts) == per_window
    assert sum(counts) == pytest.approx(40 * window_s * rate, abs=1)  # rate × time, ±1 at the ends


def test_constant_force_window_mean_and_no_hx711():
    ref = window_reference(QUIET, lambda t: np.full(np.shape(t), 2.0), 0.0, 0.1)
    assert (ref.ref_ok, ref.ref_n) == (1, 8)
    assert ref.ref_mean == round(QUIET.offset_counts + QUIET.scale_counts_per_n * 2.0)
    assert window_reference(None, lambda t: t, 0.0, 0.1) == WindowReference(0, 0, 0)  # no HX711


@pytest.mark.parametrize("rate", [10, 80])
def test_a_ramp_is_read_half_a_conversion_late(rate):
    # F = k·t averaged over [t − p, t] is k·(t − p/2): the lag is p/2 = 1/(2·rate).
    cell = LoadCellModel(rate_sps=rate, noise_counts=0.0, scale_counts_per_n=1e5, phase_s=0.0)
    k = 1.0  # N/s
    times = cell.conversion_times(1.0, 2.0)
    ref = window_reference(cell, lambda t: k * t, 1.0, 2.0, substeps=64)
    expected = cell.offset_counts + cell.scale_counts_per_n * k * np.mean(times - cell.lag_s)
    assert cell.lag_s == 0.5 / rate
    assert ref.ref_mean == pytest.approx(expected, abs=1.0)


def test_tare_of_steady_readings_is_their_mean():
    rng = np.random.default_rng(1)
    counts = 8192 + rng.normal(0, 40, 50)
    cal = tare_from_readings(counts, capacity_n=49.0)
    assert cal.offset_counts == pytest.approx(np.mean(counts))
    assert cal.tare["noise_counts"] == pytest.approx(np.std(counts, ddof=1)) and cal.tare["n"] == 50
    assert not cal.scaled


def test_tare_of_drifting_readings_is_refused_saying_why():
    counts = 8192 + np.linspace(0, 2000, 50) + np.random.default_rng(2).normal(0, 40, 50)  # something settling
    with pytest.raises(LoadCellError, match="unstable"):
        tare_from_readings(counts)
    with pytest.raises(LoadCellError, match="at least 5"):
        tare_from_readings([8192.0, 8190.0])


def test_scale_from_a_known_mass_and_the_5_percent_warning():
    rng = np.random.default_rng(3)
    cell = LoadCellModel()
    tare = tare_from_readings(cell.raw(np.zeros(40), rng=rng), capacity_n=cell.capacity_n)
    cal, warning = scale_from_readings(tare, cell.raw(np.full(40, 0.5 * STANDARD_GRAVITY), rng=rng), 0.5)
    # Bound: the two means' noise, 40 counts/sqrt(40) each, over the 0.5 kg signal (~4.3e5 counts).
    assert cal.scale_counts_per_n == pytest.approx(cell.scale_counts_per_n, rel=5 * 40 * math.sqrt(2 / 40) / 4.3e5)
    assert warning is None and cal.scale["gravity_m_s2"] == STANDARD_GRAVITY and cal.scale["mass_kg"] == 0.5
    _, warning = scale_from_readings(tare, cell.raw(np.full(40, 0.1 * STANDARD_GRAVITY), rng=rng), 0.1)
    assert "below 5 %" in warning  # 0.98 N < 5 % of 49 N
    with pytest.raises(LoadCellError, match="is the mass on the cell"):
        scale_from_readings(tare, cell.raw(np.zeros(40), rng=rng), 0.5)


def test_file_round_trip_and_bad_files(tmp_path):
    cal, _ = scale_from_readings(tare_from_readings([100.0, 101, 99, 100, 100, 101]),
                                 [1100.0, 1101, 1099, 1100, 1100], 0.01)
    cal.save(tmp_path / "lc.json")
    back = load_loadcell(tmp_path / "lc.json")
    assert back == cal and back.force(1100.0) == pytest.approx(0.01 * STANDARD_GRAVITY, rel=1e-3)
    d = json.loads((tmp_path / "lc.json").read_text())
    for key, value, said in (("scale_counts_per_n", -1, "scale_counts_per_n"), ("format", "x", "format"),
                             ("offset_counts", "abc", "offset_counts")):
        (tmp_path / "bad.json").write_text(json.dumps({**d, key: value}))
        with pytest.raises(LoadCellError, match=said):
            load_loadcell(tmp_path / "bad.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(LoadCellError, match="not JSON"):
        load_loadcell(tmp_path / "bad.json")
    with pytest.raises(LoadCellError, match="no scale factor"):
        LoadCellCalibration(0.0).force(1.0)


def test_a_drifting_offset_is_an_unstable_tare():
    # 5 s of window means from a cell whose offset drifts 200 counts/s (a bridge warming up):
    # the halves differ by ~500 counts, far beyond 4 standard errors of 40/√8-count means.
    cell = LoadCellModel(drift_counts_per_s=200.0)
    t = np.arange(50) * 0.1
    means = [window_reference(cell, lambda s: 0 * s, a, a + 0.1, rng=np.random.default_rng(k)).ref_mean
             for k, a in enumerate(t)]
    with pytest.raises(LoadCellError, match="unstable"):
        tare_from_readings(means)
    steady = [window_reference(LoadCellModel(), lambda s: 0 * s, a, a + 0.1, rng=np.random.default_rng(k)).ref_mean
              for k, a in enumerate(t)]
    assert tare_from_readings(steady).offset_counts == pytest.approx(8192, abs=5 * 40 / np.sqrt(400))
