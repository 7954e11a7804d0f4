"""The calibration's model families: the conductance transform through a divider, the power law, the floor.

References: closed forms written out in each test (the divider's V = Vcc·R·G/(1 + R·G); an exact power law;
a ramp with a dead zone put in by construction).
"""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.calibration.models import ConductanceTransform, cross_validate_families, find_floor


def test_power_law_through_a_divider_is_recovered():
    # Other data: an exact power law F = 0.5 + 30·G^0.8 [N, G in mS] through a 10 kΩ / 5 V divider.
    g = np.linspace(0.01e-3, 0.5e-3, 400)
    f = 0.5 + 30 * (g / 1e-3) ** 0.8
    tr = ConductanceTransform("divider", 10e3, 5.0)
    v = 5.0 * 10e3 * g / (1 + 10e3 * g)  # the divider's closed form
    sel = cross_validate_families(v, f, np.arange(v.size) % 5, 5, tr)
    assert sel.best.name == "conductance-power"
    assert sel.best.params["b"] == pytest.approx(0.8, rel=0.03)  # the exponent grid's spacing is 5.5 %
    np.testing.assert_allclose(sel.best(v), f, rtol=0.04)


def test_floor_is_found_only_where_the_readout_sticks():
    # Other data: a ramp whose first 50 of 500 readings sit at 0 V (a dead zone), and the same
    # ramp without it.
    f = np.linspace(0, 10, 500)
    v = np.round(np.clip(f - 1.0, 0, None) * 0.3 / (5 / 1023)) * (5 / 1023)
    fl = find_floor(v, f)
    assert fl is not None and fl.sign == 1 and fl.below(v).sum() == int((v == 0).sum())
    assert find_floor(np.linspace(1, 2, 500), f) is None
