"""Branch and cycle detection (fsrlab.analysis.cycles) on constructed stress sequences.

Data: triangle waves of stress (bench-like loading/unloading ramps) built here, with optional
Gaussian noise and dwell plateaus; the expected turning points are known by construction.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, strategies as st

from fsrlab.analysis.cycles import branch_directions, split_cycles, turning_points


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
