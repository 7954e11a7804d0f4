"""Separation on loading (eq. 1), unloading (eq. 9) and under a stress history (extension)."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.physics.params import PAPER
from fsrlab.physics.separation import separation_history, separation_loading, separation_unloading

S0, M, SF = PAPER.s0_m, PAPER.modulus_pa, PAPER.sigma_f_pa


def printed_eq9(stress, sigma_f, s0, modulus, k):
    """Eq. (9) exactly as printed, with a and b from eqs. (7) and (8); real only for even k."""
    b = sigma_f  # Eq. (7)
    a = modulus * sigma_f ** (1 - k) / (modulus - sigma_f)  # Eq. (8)
    s_f = s0 * (1 - sigma_f / modulus)  # Eq. (3)
    return s_f * (1 + a * (stress - b) ** k / modulus)  # Eq. (4)/(9)


def test_loading_is_eq1_closed_form():
    # Reference: eq. (1) evaluated by hand at σ = M/2 gives s0/2.
    assert separation_loading(M / 2) == pytest.approx(S0 / 2, rel=1e-15)
    assert separation_loading(0.0) == S0


@pytest.mark.parametrize("k", [2, 4, 6, 8])
def test_unloading_simplified_equals_printed_form(k):
    # Reference: the printed eq. (9) with eqs. (7)-(8), independent of the simplified form we compute.
    x = np.linspace(0, SF, 57)
    np.testing.assert_allclose(separation_unloading(x, SF, S0, M, k), printed_eq9(x, SF, S0, M, k), rtol=1e-12)


materials = dict(
    s0=st.floats(0.5e-9, 20e-9),
    modulus=st.floats(1e5, 1e8),
    frac=st.floats(0.01, 0.95),
    k=st.floats(1.0, 10.0),
)


@given(**materials)
def test_branches_meet_at_zero_and_sigma_f(s0, modulus, frac, k):
    # Property (eq. 5): s_l(0) = s_u(0) = s0 and s_l(σf) = s_u(σf) = s_f.
    sf = frac * modulus
    assert separation_unloading(0.0, sf, s0, modulus, k) == pytest.approx(separation_loading(0.0, s0, modulus),
                                                                          rel=1e-12)
    assert separation_unloading(sf, sf, s0, modulus, k) == pytest.approx(separation_loading(sf, s0, modulus), rel=1e-12)


@given(**materials)
def test_unloading_lies_below_loading(s0, modulus, frac, k):
    # Property: for k ≥ 1, (1 − x)^k ≤ 1 − x, so the unloading separation never exceeds the loading one.
    sf = frac * modulus
    x = np.linspace(0, sf, 101)
    assert np.all(separation_unloading(x, sf, s0, modulus, k) <= separation_loading(x, s0, modulus) * (1 + 1e-12))


def test_out_of_domain_stress_is_nan():
    assert np.isnan(separation_unloading(SF * 1.01))
    assert np.isnan(separation_unloading(-1.0))
    assert np.isnan(separation_loading(M))
    assert np.isnan(separation_loading(-1.0))


def test_shape_is_kept():
    x = np.linspace(0, SF, 12).reshape(3, 4)
    assert separation_loading(x).shape == (3, 4)
    assert separation_unloading(x).shape == (3, 4)
    assert isinstance(separation_loading(1e3), float)


@pytest.mark.parametrize(
    "kwargs, field",
    [({"s0_m": 0.0}, "s0_m"), ({"s0_m": -1e-9}, "s0_m"), ({"modulus_pa": SF}, "modulus_pa"),
     ({"k": 0.5}, "k"), ({"k": float("nan")}, "k"), ({"sigma_f_pa": float("inf")}, "sigma_f_pa")],
)
def test_bad_parameters_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        separation_unloading(1e3, **kwargs)


@given(frac=st.floats(0.05, 0.9), k=st.floats(1.0, 8.0), n_up=st.integers(2, 60), n_down=st.integers(2, 60))
def test_history_single_cycle_is_eqs_1_and_9(frac, k, n_up, n_down):
    # Property demanded by the memory rule: one full cycle 0 → σf → 0 gives eq. (1) then eq. (9).
    sf = frac * M
    up = np.linspace(0, sf, n_up)
    down = np.linspace(sf, 0, n_down)[1:]
    h = separation_history(np.concatenate([up, down]), k=k)
    np.testing.assert_allclose(h.separation_m[:n_up], separation_loading(up), rtol=1e-12)
    np.testing.assert_allclose(h.separation_m[n_up:], separation_unloading(down, sf, k=k), rtol=1e-12)
    assert set(h.direction[1:n_up]) == {1} and set(h.direction[n_up:]) == {-1}


def test_minor_loop_closes_and_is_wiped_out():
    # Property (return-point memory): after a minor loop the path continues as if it never happened.
    a, b = 250e3, 120e3
    looped = np.concatenate([np.linspace(0, SF, 50), np.linspace(SF, b, 40)[1:], np.linspace(b, a, 30)[1:],
                             np.linspace(a, b, 30)[1:], np.array([60e3])])
    h = separation_history(looped)
    # back at b after the inner loop (b → a → b): the same separation as at the first visit of b
    first_b = 49 + 39
    assert h.separation_m[-2] == pytest.approx(h.separation_m[first_b], rel=1e-12)
    # continuing below b follows the original unloading branch from σf
    assert h.separation_m[-1] == pytest.approx(separation_unloading(60e3), rel=1e-12)


def test_reload_beyond_old_peak_rejoins_virgin_line():
    # Property (wiping out): loading past the old peak continues on eq. (1).
    path = np.concatenate([np.linspace(0, 200e3, 20), np.linspace(200e3, 50e3, 20)[1:],
                           np.linspace(50e3, 300e3, 40)[1:]])
    h = separation_history(path)
    beyond = path > 200e3
    beyond[:20] = False
    np.testing.assert_allclose(h.separation_m[beyond], separation_loading(path[beyond]), rtol=1e-12)


def test_history_rejects_bad_stress():
    with pytest.raises(ValueError, match="stress_pa"):
        separation_history([0, 1e3, -5.0])
    with pytest.raises(ValueError, match="stress_pa"):
        separation_history([0, np.nan])


@pytest.mark.parametrize("field, value", [("s0_m", 0.0), ("s0_m", -1e-9), ("modulus_pa", 1e5), ("k", 0.9),
                                          ("u_v", 0.0), ("phi0_j", float("inf")), ("eps_r", float("nan"))])
def test_parameter_set_is_validated(field, value):
    import dataclasses

    with pytest.raises(ValueError, match=field):
        dataclasses.replace(PAPER, **{field: value})
