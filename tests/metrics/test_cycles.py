"""Branch and cycle detection (fsrlab.metrics.cycles) on constructed stress sequences.

Data: triangle waves of stress (bench-like loading/unloading ramps) built here, with optional
Gaussian noise and dwell plateaus; the expected turning points are known by construction.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.metrics.cycles import split_cycles
from fsrlab.physics.history import branch_directions, turning_points


def triangle(cycles=3, per_ramp=50, peak=10e3, dwell=0):
    up = np.linspace(0, peak, per_ramp + 1)
    one = np.concatenate([up[:-1], np.full(dwell, peak), up[::-1][:-1]])
    return np.concatenate([np.tile(one, cycles), [0.0]])


def test_turning_points_of_clean_triangle():
    x = triangle(3, 50)
    np.testing.assert_array_equal(turning_points(x), [0, 50, 100, 150, 200, 250, 300])


def test_cycles_share_turning_points_and_cover_run():
    x = triangle(3, 50)
    cs = split_cycles(x)
    assert [c.number for c in cs] == [0, 1, 2]
    for k, c in enumerate(cs):
        assert c.load_index[0] == 100 * k and c.load_index[-1] == 100 * k + 50
        assert c.unload_index[0] == 100 * k + 50 and c.unload_index[-1] == 100 * k + 100
        assert np.all(np.diff(x[c.load_index]) > 0) and np.all(np.diff(x[c.unload_index]) < 0)


def test_dwell_goes_to_unloading_and_noise_is_ignored():
    rng = np.random.default_rng(1)
    x = triangle(2, 80, dwell=10) + rng.normal(0, 50.0, 2 * 170 + 1)  # noise 0.5 % of span < 5 % threshold
    cs = split_cycles(x)
    assert len(cs) == 2
    for c in cs:
        assert x[c.load_index[-1]] > 9e3 and x[c.unload_index[-1]] < 1e3


def test_direction_column_overrides_stress():
    x = triangle(2, 10)
    d = np.where(np.diff(x, append=x[-1]) >= 0, 1, -1)  # label by the next move
    d[-1] = -1
    cs = split_cycles(x, direction=d)
    assert len(cs) == 2
    with pytest.raises(ValueError, match="direction"):
        split_cycles(x, direction=np.full(x.size, 2))


def test_cycle_column_groups_rows():
    x = triangle(2, 10)
    cyc = np.repeat([0, 1], [20, x.size - 20])
    cs = split_cycles(x, cycle=cyc)
    assert [c.number for c in cs] == [0, 1]
    assert cs[1].load_index[0] >= 20


def test_start_while_unloading_and_end_while_loading_are_left_out():
    x = np.concatenate([np.linspace(5e3, 0, 26), triangle(1, 50)[1:], np.linspace(0, 5e3, 26)[1:]])
    cs = split_cycles(x)
    assert len(cs) == 1


def test_threshold_validated():
    with pytest.raises(ValueError, match="threshold"):
        turning_points([0, 1, 0], threshold=1.5)


@given(st.integers(1, 6), st.integers(5, 60), st.floats(1e2, 1e6), st.integers(0, 2**31 - 1))
def test_property_cycle_count_and_monotone_labels(n_cycles, per_ramp, peak, seed):
    # Property: noise below half the threshold never creates or hides a cycle.
    rng = np.random.default_rng(seed)
    x = triangle(n_cycles, per_ramp, peak)
    x = x + rng.uniform(-0.02, 0.02, x.size) * peak
    cs = split_cycles(x, threshold=0.1)
    assert len(cs) == n_cycles
    lab = branch_directions(x, threshold=0.1)
    assert set(np.unique(lab)) <= {-1, 1}


# --- hysteresis error from runs (eq. 13 through fsrlab.metrics.hysteresis.hysteresis_error) ---

from fsrlab.metrics.cycles import run_hysteresis  # noqa: E402


def test_run_hysteresis_closed_form():
    # Loading q = σ, unloading q = σ + a σ(σf − σ)/σf²: the largest difference is a/4 at σf/2 and
    # Q(σf) = σf, so eq. (13) gives HE = 100 a / (4 σf) exactly (independent closed form).
    sf, a = 10e3, 2e3
    up = np.linspace(0, sf, 201)
    down = up[::-1]
    x = np.concatenate([up, down[1:], up[1:], down[1:]])
    q = np.where(np.arange(x.size) % 400 < 200, x, x + a * x * (sf - x) / sf**2)
    q[np.arange(x.size) % 400 == 200] = sf
    res = run_hysteresis(x, q)
    assert len(res.cycles) == 2
    for c in res.cycles:
        assert c.percent == pytest.approx(100 * a / (4 * sf), rel=1e-9)
        assert c.stress_at_max_pa == pytest.approx(sf / 2)
    assert res.percent == pytest.approx(5.0, rel=1e-3)  # mean curves on a 201-point grid hold σf/2
    d = res.to_dict()
    assert set(d) == {"hysteresis_error_percent", "stress_at_max_difference_pa", "cycles"}
    assert set(d["cycles"][0]) == {"hysteresis_error_percent", "stress_at_max_difference_pa"}


def test_run_hysteresis_on_synthetic_bench_run_matches_noiseless_model():
    """Data: synthetic_run (VirtualFSR -> lm555.astable, R = 10 kΩ, ideal D1; 0.2 % frequency noise,
    62.5 ns quantization, 100 ms windows). Reference: the same chain without noise and quantization
    sampled finely (eq. 13 on exact branches). Tolerance 1 percentage point: 3 σ of 0.2 % noise on
    a difference of two readings relative to full scale is ≈ 0.85 pp."""
    from fsrlab.circuits.lm555 import astable
    from fsrlab.metrics.hysteresis import hysteresis_error
    from fsrlab.physics.sensor import VirtualFSR
    from fsrlab.virtual.synthetic import synthetic_run, triangle_stress

    run = synthetic_run(cycles=2, peak_pa=50e3, points_per_ramp=100, seed=3)
    c = run.columns
    res = run_hysteresis(c["stress_pa"], c["frequency_hz"])
    s = triangle_stress(1, 50e3, 2000)
    r = VirtualFSR().respond(s)
    f = astable(10e3, r.r_fsr_ohm, r.c_fsr_farad, diode=True).frequency_hz
    ref = hysteresis_error(s[:2001], f[:2001], s[2000:], f[2000:]).percent
    assert 5 < ref < 40  # the virtual sensor is strongly hysteretic, like the paper's Table 3
    for cyc in res.cycles:
        assert cyc.percent == pytest.approx(ref, abs=1.0)
    assert res.percent == pytest.approx(ref, abs=1.0)


def test_run_without_cycle_is_rejected():
    with pytest.raises(ValueError, match="no complete loading-unloading cycle"):
        run_hysteresis(np.linspace(0, 1, 10), np.linspace(1, 2, 10))


def test_rows_without_reference_stress_are_skipped():
    # Acquisition leaves stress_pa empty (NaN) when the reference has no reading: same result without those rows.
    from fsrlab.virtual.synthetic import synthetic_run

    c = synthetic_run(cycles=2, seed=11).columns
    s = c["stress_pa"].copy()
    s[::7] = np.nan
    full = run_hysteresis(c["stress_pa"][~np.isnan(s)], c["frequency_hz"][~np.isnan(s)])
    holes = run_hysteresis(s, c["frequency_hz"])
    assert holes.percent == pytest.approx(full.percent, rel=1e-12)


def test_readout_directions_are_branch_directions_with_gaps_filled():
    # Reference: branch_directions on the valid readings (the one labeller); NaN readings take the
    # previous label, leading NaNs the first one; a flat sequence counts as loading.
    x = triangle(2, 20)
    holes = x.copy()
    holes[[0, 1, 7, 20, 21, 55]] = np.nan
    from fsrlab.metrics.cycles import readout_directions

    lab = readout_directions(holes)
    ok = np.isfinite(holes)
    np.testing.assert_array_equal(lab[ok], branch_directions(holes[ok]))
    assert lab[0] == lab[1] == lab[2] and lab[7] == lab[6] and lab[21] == lab[20] == lab[19]
    np.testing.assert_array_equal(readout_directions(-holes, sign=-1), lab)
    np.testing.assert_array_equal(readout_directions(np.full(5, 3.0)), np.ones(5))


def test_a_readout_that_does_not_respond_has_no_hysteresis_error():
    # Reference: a constant readout (zero span), one that flickers by one quantization step
    # (10-bit ADC, 5 V / 1024), and 0.2 % white noise: none depends on the stress. The synthetic
    # run's own readouts do (HE ≈ 14 %, see above).
    from fsrlab.metrics.hysteresis import check_response
    from fsrlab.virtual.synthetic import synthetic_run

    c = synthetic_run(cycles=3, seed=1).columns
    s, rng = c["stress_pa"], np.random.default_rng(3)
    lsb = 5 / 1024
    for dead in (np.full(s.size, 1300.0), lsb * (200 + rng.integers(0, 2, s.size)),
                 1300 * (1 + 0.002 * rng.standard_normal(s.size))):
        with pytest.raises(ValueError, match="does not respond to the stress"):
            run_hysteresis(s, dead, c["direction"], c["cycle"], name="frequency_hz")
    for q in ("frequency_hz", "duty_cycle", "voltage_v"):
        check_response(s, c[q])
    check_response([0, 1000, 2000, 1000, 0], [3012.5, 3890.1, 4630.7, 3900.2, 3010.0])  # 5 readings suffice
