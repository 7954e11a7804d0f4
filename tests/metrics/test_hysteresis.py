"""Hysteresis error (eq. 13) on sampled data."""

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from fsrlab.metrics.hysteresis import hysteresis_error, hysteresis_error_curves


def test_linear_branches_with_known_gap():
    # Closed form: Q_l = σ, Q_u = σ + 0.1·σf·(1 − (2σ/σf − 1)²) peaks at σf/2 with gap 0.1·σf;
    # Q(σf) = σf, so HE = 10 %. Branches are sampled at different stresses.
    sf = 100e3
    xl = np.linspace(0, sf, 11)
    xu = np.linspace(0, sf, 17)
    ql = xl
    qu = xu + 0.1 * sf * (1 - (2 * xu / sf - 1) ** 2)
    r = hysteresis_error(xl, ql, xu, qu)
    assert r.percent == pytest.approx(10.0, rel=1e-12)
    assert r.stress_at_max_pa == pytest.approx(sf / 2)
    assert "interpolation" in r.method


def test_order_and_repeats_do_not_matter():
    sf = 10.0
    xl = np.array([0, 2.5, 5, 7.5, 10.0])
    xu = np.array([10.0, 6, 3, 0])
    ql, qu = 2 * xl + 1, 2 * xu + 1 + xu * (10 - xu) / 10
    a = hysteresis_error(xl, ql, xu, qu)
    perm = np.array([3, 0, 4, 1, 2])
    b = hysteresis_error(xl[perm], ql[perm], np.r_[xu, xu[1]], np.r_[qu, qu[1]])
    assert a.percent == pytest.approx(b.percent, rel=1e-12)
    assert a.sigma_f_pa == sf


finite = st.floats(-1e3, 1e3, allow_nan=False)


@given(ql=arrays(float, 8, elements=finite), qu=arrays(float, 6, elements=finite), scale=st.floats(1e-3, 1e3))
def test_properties(ql, qu, scale):
    # Properties: HE ≥ 0, identical branches give 0, HE does not change when Q is scaled.
    xl = np.linspace(0, 1e4, 8)
    xu = np.linspace(0, 1e4, 6)
    if ql[-1] == 0:
        with pytest.raises(ValueError, match="q_load"):
            hysteresis_error(xl, ql, xu, qu)
        return
    assume(scale * ql[-1] != 0)  # a subnormal Q(σf) times a small scale underflows to 0
    r = hysteresis_error(xl, ql, xu, qu)
    assert r.percent >= 0
    assert hysteresis_error(xl, ql, xl, ql).percent == 0
    assert hysteresis_error(xl, scale * ql, xu, scale * qu).percent == pytest.approx(r.percent, rel=1e-9, abs=1e-12)


def test_curves_refine_sigma_d_of_a_closed_form():
    # Closed form: Q_u − Q_l = σ(1 − σ) has its maximum 1/4 at σd = 1/2; Q_l(1) = 2.
    r = hysteresis_error_curves(lambda x: 1 + np.asarray(x),
                                lambda x: 1 + np.asarray(x) + np.asarray(x) * (1 - np.asarray(x)),
                                1.0, n=8)
    assert r.stress_at_max_pa == pytest.approx(0.5, abs=1e-7)
    assert r.percent == pytest.approx(100 * 0.25 / 2, rel=1e-9)


@pytest.mark.parametrize("args, match", [
    (([0, 1], [1, 2], [2, 3], [1, 1]), "share no stress"),
    (([0, 1, 2], [1, 2], [0, 1], [1, 1]), "same length"),
    (([0], [1], [0, 1], [1, 1]), "at least 2"),
    (([0, np.nan], [1, 2], [0, 1], [1, 1]), "finite"),
])
def test_bad_data_is_named(args, match):
    with pytest.raises(ValueError, match=match):
        hysteresis_error(*args)
