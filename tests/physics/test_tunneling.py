"""Simmons tunnelling (eqs. 10–12), R_A and C_A (eqs. 14–18)."""

import math
import warnings

import numpy as np
import pytest

from fsrlab.physics.electrical import capacitance, capacitance_per_area, resistance_per_area
from fsrlab.physics.params import PAPER
from fsrlab.physics.tunneling import current_density, tunneling_regime
from reference_physics import EPS0, ME, REL, E, H
from reference_physics import j11 as j11_scalar
from reference_physics import j12 as j12_scalar

PHI0 = 0.223 * E


@pytest.mark.parametrize("u, s", [(1.0, 4.2e-9), (2.0, 4.418e-9), (3.0, 4.1e-9), (0.5, 2e-9)])
def test_eq12_matches_independent_implementation(u, s):
    assert current_density(u, s, regime=12) == pytest.approx(j12_scalar(u, s), rel=REL)


@pytest.mark.parametrize("u, s", [(0.01, 4.418e-9), (0.2, 3e-9)])
def test_eq11_matches_independent_implementation(u, s):
    assert current_density(u, s, regime=11) == pytest.approx(j11_scalar(u, s), rel=REL)


@pytest.mark.parametrize("s", [2e-9, 4.418e-9, 10e-9])
def test_eq10_over_eq11_tends_to_the_closed_form_limit(s):
    # Independent closed form: expanding eq. (11) for u → 0 gives
    # J11 ≈ (2/3)·J10·(1 − 2/c) with c = (4πs/h)√(2mφ0), and eq. (10) is 3/2
    # of the leading term, so J10/J11 → (3/2)·c/(c − 2): 3/2 only as c → ∞ (thick barriers).
    c = 4 * math.pi * s / H * math.sqrt(2 * ME * PHI0)
    expected = 1.5 * c / (c - 2)
    u = 1e-6
    ratio = current_density(u, s, regime=10) / current_density(u, s, regime=11)
    assert ratio == pytest.approx(expected, rel=1e-4)


def test_eq10_over_eq11_at_s0_is_1_655_not_3_2():
    # Reference: eq. (10) retyped here and eq. (11) of tests/reference_physics.py at u = 1e-6 V, against
    # the closed form (3/2)·c/(c − 2) with c = 21.377 at s0 = 4.418 nm, φ0 = 0.223 eV: 1.6548.
    s = PAPER.s0_m
    j10 = 3 * math.sqrt(2 * ME * PHI0) / (2 * s) * (E / H) ** 2 * 1e-6 * math.exp(
        -(4 * math.pi * s / H) * math.sqrt(2 * ME * PHI0))
    ratio = j10 / j11_scalar(1e-6, s)
    c = 4 * math.pi * s / H * math.sqrt(2 * ME * PHI0)
    assert c == pytest.approx(21.377, abs=1e-3)
    assert ratio == pytest.approx(1.5 * c / (c - 2), rel=1e-5)
    assert ratio == pytest.approx(1.6548, abs=1e-4)
    assert abs(ratio / 1.5 - 1) > 0.1  # not "3/2 near u = 0"


def test_auto_regime_uses_paper_thresholds():
    # Paper: eq. (10) for u ≈ 0, eq. (11) for u ≤ φ0/e, eq. (12) above; φ0/e = 0.223 V here.
    u = np.array([1e-4, 0.1, 0.223, 0.2231, 2.0])
    assert list(tunneling_regime(u)) == [10, 11, 11, 12, 12]
    j, which = current_density(u, PAPER.s0_m, return_regime=True)
    assert list(which) == [10, 11, 11, 12, 12]
    assert j[-1] == pytest.approx(j12_scalar(2.0, PAPER.s0_m), rel=REL)


def test_regimes_do_not_join_at_phi0():
    # SPEC §2: at u = φ0/e eq. (11) and eq. (12) differ by about 2×; reported, not hidden.
    u = PHI0 / E
    ratio = current_density(u, PAPER.s0_m, regime=12) / current_density(u, PAPER.s0_m, regime=11)
    assert 1.8 < ratio < 2.5


def test_no_floating_point_warnings_over_the_required_domain():
    # No overflow or invalid-value warnings for s in [0.5, 20] nm and u in [1e-4, 10] V.
    u = np.geomspace(1e-4, 10, 200)[:, None]
    s = np.linspace(0.5e-9, 20e-9, 200)[None, :]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for regime in ("auto", 10, 11, 12):
            j = current_density(u, s, regime=regime)
            resistance_per_area(u, s, regime=regime)
            assert j.shape == (200, 200)
            assert np.all((j >= 0) | np.isnan(j))  # never a negative current density


def test_resistance_is_u_over_j():
    u, s = 2.0, 4.3e-9
    assert resistance_per_area(u, s) == pytest.approx(u / j12_scalar(u, s), rel=REL)


def test_capacitance_per_area_closed_form_and_figure_8b_range():
    # Eq. (15) with typed-in ε0; Figure 8b's axis runs from 14 to 15 mF/m² over 0–322 kPa.
    assert capacitance_per_area(PAPER.s0_m) == pytest.approx(7 * EPS0 / PAPER.s0_m, rel=REL)
    c0 = capacitance_per_area(PAPER.s0_m) * 1e3
    assert 14.0 < c0 < 14.1
    assert capacitance(PAPER.s0_m, 2e-6) == pytest.approx(capacitance_per_area(PAPER.s0_m) * 2e-6, rel=1e-15)


@pytest.mark.parametrize(
    "call, field",
    [(lambda: current_density(0.0, 4e-9), "u_v"), (lambda: current_density(-1.0, 4e-9), "u_v"),
     (lambda: current_density(1.0, 0.0), "s_m"), (lambda: current_density(1.0, 4e-9, phi0_j=float("nan")), "phi0_j"),
     (lambda: current_density(1.0, 4e-9, regime=13), "regime"), (lambda: capacitance_per_area(4e-9, eps_r=0), "eps_r"),
     (lambda: current_density(np.array([1.0, np.inf]), 4e-9), "u_v")],
)
def test_bad_inputs_name_the_parameter(call, field):
    with pytest.raises(ValueError, match=field):
        call()


def test_unvalidated_path_gives_the_same_numbers_to_the_bit():
    # validate=False only skips the input checks (a root finder's inner loop): same numbers and regimes as
    # the checked call, in one regime and with all three mixed in one array (eq. 10 at tiny u).
    u = np.array([1e-4, 0.5e-3, 0.05, 0.2, 0.3, 1.0, 2.0, 3.0])
    assert set(np.unique(tunneling_regime(u))) == {10, 11, 12}
    s = np.linspace(3e-9, 5e-9, u.size)
    for uu, ss in ((u, s), (u[5:], s[5:]), (2.0, 4.2e-9)):
        for call in (current_density, resistance_per_area):
            a, ra = call(uu, ss, return_regime=True)
            b, rb = call(uu, ss, return_regime=True, validate=False)
            assert np.array_equal(a, b) and np.array_equal(ra, rb)
