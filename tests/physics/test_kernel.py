"""The in-place kernels behind eq. (12) and the Table 2 pipeline give the printed formulas' numbers.

References: eq. (12) of the paper evaluated term by term with numpy as printed (the same operations
in the same order, so equality is exact, NaN and 0 included), and the previous Table 2 pipeline
composed of the public vectorised functions (separation_loading/unloading, resistance_per_area,
capacitance_per_area, hysteresis_error_curves' grid and refinement).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.constants import e, h, m_e

from fsrlab.physics.params import PAPER
from fsrlab.physics.tunneling import _eq12


def _eq12_as_printed(u, s, phi0):
    b = 8 * np.pi * s * np.sqrt(2 * m_e) * phi0**1.5 / (2.96 * h * e * u)
    r = 1 + 2 * e * u / phi0
    bracket = np.exp(-b) - r * np.exp(-b * np.sqrt(r))
    j = 2.2 * e**3 * u**2 / (8 * np.pi * h * phi0 * s**2) * bracket  # Eq. (12)
    return np.where(bracket > 0, j, np.where(np.exp(-b) == 0, 0.0, np.nan))


@pytest.mark.parametrize("u_shape, s_shape", [((), (5000,)), ((5000,), ()), ((5000,), (5000,)), ((), ()),
                                              ((40, 1), (1, 60))])
def test_eq12_equals_the_printed_formula_exactly(u_shape, s_shape):
    # u over 1e-4..20 V and s over 0.2..30 nm: covers the positive bracket, the negative one (NaN,
    # thin films at high voltage) and the underflow to 0 at tiny u.
    rng = np.random.default_rng(3)
    u = np.exp(rng.uniform(np.log(1e-4), np.log(20.0), u_shape))
    s = np.exp(rng.uniform(np.log(0.2e-9), np.log(30e-9), s_shape))
    with np.errstate(all="ignore"):
        got, ref = _eq12(u, s, PAPER.phi0_j), _eq12_as_printed(u, s, PAPER.phi0_j)
    assert np.shape(got) == np.shape(ref)
    np.testing.assert_array_equal(got, ref)
