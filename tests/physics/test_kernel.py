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


def _pipeline_from_public_functions(u_v, p, n):
    """The Table 2 pipeline as it was written before the fused kernel: public functions only."""
    from fsrlab.metrics.hysteresis import _curves_on_grid
    from fsrlab.physics.electrical import capacitance_per_area, resistance_per_area
    from fsrlab.physics.separation import separation_loading, separation_unloading

    def s_l(x):
        return separation_loading(x, p.s0_m, p.modulus_pa)

    def s_u(x):
        return separation_unloading(x, p.sigma_f_pa, p.s0_m, p.modulus_pa, p.k)

    x = np.linspace(0.0, p.sigma_f_pa, n)
    sl, su = s_l(x), s_u(x)
    he_r = _curves_on_grid(x, resistance_per_area(u_v, sl, p.phi0_j), resistance_per_area(u_v, su, p.phi0_j),
                           lambda t: resistance_per_area(u_v, s_l(t), p.phi0_j),
                           lambda t: resistance_per_area(u_v, s_u(t), p.phi0_j), refine=True)
    he_c = _curves_on_grid(x, capacitance_per_area(sl, p.eps_r), capacitance_per_area(su, p.eps_r),
                           lambda t: capacitance_per_area(s_l(t), p.eps_r),
                           lambda t: capacitance_per_area(s_u(t), p.eps_r), refine=True)
    return he_r, he_c


@pytest.mark.parametrize("u", [3, 2, 1, 0.5, 3.6])
@pytest.mark.parametrize("change", [{}, {"phi0_ev": 0.2295}, {"k": 4}, {"k": 3.3}])
@pytest.mark.parametrize("n", [3, 4001, 70001])  # 70001: several chunks, the last one partial
def test_table2_kernel_equals_the_public_functions(u, change, n):
    # Where eq. (12) holds on the whole cycle the kernel folds the constants (R_A = k3·s²/bracket),
    # so its curves agree with the public functions to a few units in the last place (rtol 1e-14; the
    # folded products round differently), and σd's grid point is the same; where it fails somewhere
    # (3.6 V, thin films) the exact path gives the public functions' NaN to the bit.
    import dataclasses

    from scipy.constants import electron_volt

    from fsrlab.metrics.hysteresis import model_cycle_errors

    change = dict(change)
    if "phi0_ev" in change:
        change["phi0_j"] = change.pop("phi0_ev") * electron_volt
    p = dataclasses.replace(PAPER, **change)
    got = model_cycle_errors(u, p, n)
    for res, ref in zip((got.resistance, got.capacitance), _pipeline_from_public_functions(u, p, n), strict=True):
        np.testing.assert_allclose([res.percent, res.stress_at_max_pa, res.difference, res.full_scale],
                                   [ref.percent, ref.stress_at_max_pa, ref.difference, ref.full_scale], rtol=1e-12)
        np.testing.assert_allclose(res.q_load, ref.q_load, rtol=1e-14)
        np.testing.assert_allclose(res.q_unload, ref.q_unload, rtol=1e-14)
        np.testing.assert_array_equal(np.isnan(res.q_load), np.isnan(ref.q_load))
        assert res.method == ref.method


def test_table2_kernel_raises_like_nanargmax_when_every_point_is_nan():
    # At 5 V eq. (12) fails on every separation of the cycle (voltage_limit): np.nanargmax's error.
    from fsrlab.metrics.hysteresis import model_cycle_errors

    with pytest.raises(ValueError, match="All-NaN"):
        model_cycle_errors(5.0)


@pytest.mark.parametrize("k", [1.0, 2.0, 3.3, 4.0])
def test_separation_cores_equal_the_printed_expressions_exactly(k):
    # Eq. (1) as s0 (1 − σ/M); eq. (9), simplified, as s_f + (s0 − s_f)(1 − σ/σf)^k (separation.py).
    from fsrlab.physics.separation import separation_loading, separation_unloading

    p = PAPER
    x = np.concatenate([np.linspace(0.0, p.sigma_f_pa, 10001), [-1.0, p.sigma_f_pa * 1.5]])
    s_f = p.s0_m * (1.0 - p.sigma_f_pa / p.modulus_pa)
    inside = (x >= 0) & (x <= p.sigma_f_pa)
    t = np.where(inside, 1.0 - x / p.sigma_f_pa, 0.0)
    np.testing.assert_array_equal(separation_unloading(x, k=k), np.where(inside, s_f + (p.s0_m - s_f) * t**k, np.nan))
    np.testing.assert_array_equal(separation_loading(x), np.where(x >= 0, p.s0_m * (1.0 - x / p.modulus_pa), np.nan))
    assert separation_loading(1e5) == p.s0_m * (1.0 - 1e5 / p.modulus_pa)


@pytest.mark.parametrize("cores", [2, 3, 4])
def test_table2_kernel_split_between_cores_equals_one_pass(monkeypatch, cores):
    # Property: splitting the grid between threads changes no number (each element is computed by the
    # same operations) and finds the same σd (the first of equal maxima, as one pass in order).
    import os

    from fsrlab.metrics.hysteresis import model_cycle_errors

    n = 400_001  # several chunks per thread, the last one partial
    monkeypatch.setattr(os, "cpu_count", lambda: 1)
    one = model_cycle_errors(2.0, PAPER, n)
    monkeypatch.setattr(os, "cpu_count", lambda: cores)
    split = model_cycle_errors(2.0, PAPER, n)
    for a, b in zip((one.resistance, one.capacitance), (split.resistance, split.capacitance), strict=True):
        assert (a.percent, a.stress_at_max_pa, a.difference) == (b.percent, b.stress_at_max_pa, b.difference)
        np.testing.assert_array_equal(a.q_load, b.q_load)
        np.testing.assert_array_equal(a.q_unload, b.q_unload)
