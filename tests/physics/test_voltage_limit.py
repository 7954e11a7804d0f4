"""Where the paper's tunnelling equations stop giving a current density (voltage_limit)."""

import math

import numpy as np
import pytest

from fsrlab.physics.electrical import resistance_per_area
from fsrlab.physics.params import PAPER
from fsrlab.physics.tunneling import SMALL_U_FRACTION, current_density, voltage_limit
from reference_physics import REL, TABLE1, E, j11, j12

PHI0_V = TABLE1["phi0"] / E  # φ0/e = 0.223 V
S_F = TABLE1["s0"] * (1 - TABLE1["sigma_f"] / TABLE1["modulus"])  # eq. (3): smallest separation of the cycle


@pytest.mark.parametrize("s", [S_F, TABLE1["s0"], 1e-9, 2e-9, 20e-9])
def test_eq12_bracket_changes_sign_at_the_limit(s):
    # Reference: the independent scalar eq. (12) (tests/reference_physics.py) is positive just below
    # the limit and negative just above it; ±1e-6 because its typed-in CODATA 2018 constants agree
    # with scipy's to that (reference_physics.REL).
    u = voltage_limit(s, PAPER.phi0_j)
    assert u > PHI0_V
    assert j12(u * (1 - REL), s) > 0 > j12(u * (1 + REL), s)


def test_eq11_limits_very_thin_films():
    # Reference: the independent scalar eq. (11) turns negative just above the limit on a 0.43 nm
    # film, where eq. (12) has no valid value above φ0/e at all.
    s = 0.43e-9
    u = voltage_limit(s, PAPER.phi0_j)
    assert SMALL_U_FRACTION * PHI0_V < u < PHI0_V
    assert j11(u * (1 - REL), s) > 0 > j11(u * (1 + REL), s)


def test_eq10_is_always_valid():
    # Eq. (10) is a positive product: on a film too thin for eq. (11) the limit is where eq. (10) ends.
    assert voltage_limit(0.3e-9) == pytest.approx(SMALL_U_FRACTION * PHI0_V, rel=1e-12)
    assert voltage_limit(0.3e-9, small_u_fraction=0.0) == 0.0


@pytest.mark.parametrize("s", [0.3e-9, 0.43e-9, 0.441e-9, 0.46e-9, S_F, 10e-9])
def test_valid_below_the_limit_for_every_thicker_film_and_nan_above(s):
    # Property of the definition: below the limit J is a number at s and every larger separation;
    # just above it J is NaN at s. Checked on the implementation itself over a grid.
    u_max = voltage_limit(s)
    u = np.linspace(u_max * 1e-3, u_max * (1 - 1e-6), 400)[:, None]
    thicker = np.linspace(s, 3 * s, 50)[None, :]
    assert np.all(np.isfinite(current_density(u, thicker)))
    if u_max > 0:
        assert math.isnan(current_density(u_max * (1 + 1e-6), s))
        assert math.isnan(resistance_per_area(u_max * (1 + 1e-6), s))


def test_paper_cycle_holds_table2_voltages_not_the_uno_supply():
    # Table 2 uses u = 1, 2, 3 V; over 0 → 322 kPa the film thins to s_f = 4.117 nm, where eq. (12)
    # holds up to about 4.33 V: the Uno's 5 V and more are out of the formula's range.
    u_max = voltage_limit(S_F, PAPER.phi0_j)
    assert 4.3 < u_max < 4.35
    assert all(u < u_max for u in (1, 2, 3))
    assert all(u > u_max for u in (5, 6, 8, 10))


def test_vectorised_and_validated():
    s = np.array([1e-9, 2e-9])
    assert np.allclose(voltage_limit(s), [voltage_limit(1e-9), voltage_limit(2e-9)], rtol=0)
    with pytest.raises(ValueError, match="s_m"):
        voltage_limit(0.0)
    with pytest.raises(ValueError, match="phi0_j"):
        voltage_limit(1e-9, phi0_j=-1.0)
    with pytest.raises(ValueError, match="small_u_fraction"):
        voltage_limit(1e-9, small_u_fraction=1.0)
