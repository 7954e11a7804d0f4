"""Resistive readouts (fsrlab.circuits.opamp).

References: eq. (38) with the paper's values (Vcc = −5 V, R_F = 20 kΩ, paper.json "experiment"),
a brute-force self-consistent solution of the divider with a power-law R(V) (constant β) for the
sensitivities, and the ohmic limit of the tunnelling model (eq. 10: J ∝ u, so β = 0).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from fsrlab.circuits.opamp import inverting_amplifier, voltage_coefficient, voltage_divider


def test_eq38_with_paper_values(paper):
    exp = paper["experiment"]["opamp_readout"]
    res = inverting_amplifier(np.array([50e3, 100e3, 400e3]), exp["RF_ohm"], exp["Vcc_V"])
    np.testing.assert_allclose(res.v_out_v, [2.0, 1.0, 0.25], rtol=1e-15)
    assert np.all(res.v_fsr_v == 5.0)


def _divider_power_law(r0, r_m, vcc, beta, v0=1.0):
    """Solve R = r0·(V/v0)^β with V = Vcc·R/(R_M + R) by root finding in ln R; return V_out."""
    def h(x):
        r = np.exp(x)
        v = vcc * r / (r_m + r)
        return x - np.log(r0) - beta * np.log(v / v0)

    x = brentq(h, np.log(r0) - 30, np.log(r0) + 30, xtol=1e-15)
    r = np.exp(x)
    return vcc * r_m / (r_m + r), r


@pytest.mark.parametrize("beta", [0.0, -0.3, -1.5])
def test_divider_sensitivities_match_self_consistent_solution(beta):
    r0, r_m, vcc, h = 100e3, 10e3, 5.0, 1e-6
    vout, r = _divider_power_law(r0, r_m, vcc, beta)
    res = voltage_divider(r, r_m, vcc, voltage_coefficient=beta)
    assert res.v_out_v == pytest.approx(vout, rel=1e-12)
    up, _ = _divider_power_law(r0 * (1 + h), r_m, vcc, beta)
    dn, _ = _divider_power_law(r0 * (1 - h), r_m, vcc, beta)
    num = (np.log(up) - np.log(dn)) / (np.log1p(h) - np.log1p(-h))
    assert res.sensitivity_r == pytest.approx(num, rel=1e-6)
    up, _ = _divider_power_law(r0, r_m, vcc * (1 + h), beta)
    dn, _ = _divider_power_law(r0, r_m, vcc * (1 - h), beta)
    num = (np.log(up) - np.log(dn)) / (np.log1p(h) - np.log1p(-h))
    assert res.sensitivity_supply == pytest.approx(num, rel=1e-6)


def test_inverting_amplifier_supply_sensitivity():
    # V_out ∝ |Vcc|/R(|Vcc|) with R ∝ |Vcc|^β: ∂ln V_out/∂ln|Vcc| = 1 − β.
    assert inverting_amplifier(1e5, 20e3, -5.0, voltage_coefficient=-0.4).sensitivity_supply == pytest.approx(1.4)


def test_voltage_coefficient_ohmic_limit_and_sign():
    s = 4.418e-9  # Table 1's s0
    assert voltage_coefficient(1e-4, s) == pytest.approx(0.0, abs=1e-9)  # eq. (10): R_A independent of u
    assert np.all(voltage_coefficient(np.array([0.1, 0.2, 1.0, 3.0]), s) < 0)  # tunnelling: R falls with u


def test_validation():
    with pytest.raises(ValueError, match="r_fsr_ohm"):
        inverting_amplifier(0.0, 20e3, -5.0)
    with pytest.raises(ValueError, match="vcc_v"):
        voltage_divider(1e5, 1e4, vcc_v=-5)
    with pytest.raises(ValueError, match="voltage_coefficient"):
        voltage_divider(1e3, 1e5, voltage_coefficient=5.0)
