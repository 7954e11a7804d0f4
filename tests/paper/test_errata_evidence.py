"""Computed evidence of errata P4 and X1 (fsrlab.paper.table2.simmons_terms, figure17_counterexample).

References: eq. (12)'s exponent B = 8π s √(2m) φ0^(3/2)/(2.96 h e u), typed in here from the paper with
CODATA constants (an independent closed form); eq. (13) and R² from their definitions via numpy.polyfit.
"""

import math

import numpy as np
import pytest
from scipy.constants import e, electron_volt, h, m_e

from fsrlab.paper.experiment import figure17_counterexample
from fsrlab.paper.table2 import simmons_terms


def test_simmons_b_and_reverse_ratio_at_3_volts():
    phi0 = 0.223 * electron_volt
    for s in (4.117e-9, 4.418e-9):  # s_f and s0 of Table 1
        b = 8 * math.pi * s * math.sqrt(2 * m_e) * phi0**1.5 / (2.96 * h * e * 3.0)
        r = 1 + 2 * e * 3.0 / phi0
        got_b, got_q = simmons_terms(3.0, s, phi0)
        assert float(got_b) == pytest.approx(b, rel=1e-12)
        assert float(got_q) == pytest.approx(r * math.exp(-b * math.sqrt(r)) / math.exp(-b), rel=1e-12)
    b, q = simmons_terms(3.0, np.array([4.117e-9, 4.418e-9]), phi0)
    assert 0.99 < b[0] < 1.01 and 1.06 < b[1] < 1.08      # B ≈ 1.0–1.07 at 3 V: not B ≫ 1
    assert 0.25 < q.min() and q.max() < 0.4               # the reverse term is a third of the forward one
    b1, q1 = simmons_terms(1.0, 4.418e-9, phi0)
    assert float(b1) > 3 and float(q1) < 0.02             # at 1 V the formula's assumption holds better


def test_counterexample_loop_keeps_high_r2_with_table3_hysteresis():
    cx = figure17_counterexample()
    x = np.linspace(0, 1, 41)
    s, fl = 10e3 * x, 3e3 + 7e3 * np.sqrt(x)
    g = x * np.exp(-x / 0.03) * (1 - x)
    g /= g.max()
    # eq. (13) by hand: largest branch difference over Q(σf) = 10 kHz, same stresses
    amp = cx["he_percent"] / 100 * 10e3
    fu = fl + amp * g
    f_all, s_all = np.concatenate([fl, fu]), np.concatenate([s, s])

    def r2(deg):
        res = s_all - np.polyval(np.polyfit(f_all, s_all, deg), f_all)
        return 1 - res @ res / np.sum((s_all - s_all.mean()) ** 2)

    assert cx["he_percent"] == pytest.approx(14.2, abs=1e-9)
    assert cx["cubic"] == pytest.approx(r2(3), abs=1e-6) and cx["cubic"] > 0.996
    assert cx["linear"] == pytest.approx(r2(1), abs=1e-6) and 0.93 < cx["linear"] < 0.95


def test_printed_eps0_changes_no_hysteresis_error():
    # Table 1 prints ε0 = 8.85e-12; fsrlab uses CODATA's. Eq. (13) divides by Q(σf), eq. (15) is linear in ε0:
    # HE of C_A is the same to rounding, and R_A (eqs. 16-18) does not contain ε0.
    from scipy.constants import epsilon_0

    from fsrlab.metrics.hysteresis import hysteresis_error
    from fsrlab.physics.params import PAPER
    from fsrlab.physics.separation import separation_loading, separation_unloading

    sig = np.linspace(0, PAPER.sigma_f_pa, 401)
    sl = separation_loading(sig, PAPER.s0_m, PAPER.modulus_pa)
    su = separation_unloading(sig, PAPER.sigma_f_pa, PAPER.s0_m, PAPER.modulus_pa, PAPER.k)
    he = [hysteresis_error(sig, PAPER.eps_r * e0 / sl, sig, PAPER.eps_r * e0 / su).percent
          for e0 in (8.85e-12, epsilon_0)]
    assert he[0] == pytest.approx(he[1], rel=1e-12)
    assert 8.85e-12 / epsilon_0 - 1 == pytest.approx(-4.7e-4, abs=0.1e-4)
