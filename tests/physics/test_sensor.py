"""The virtual FSR (extension): ranges, direction of change, hysteresis through s(σ)."""

import numpy as np
import pytest

from fsrlab.physics.electrical import capacitance
from fsrlab.physics.sensor import A201_AREA_M2, VirtualFSR
from fsrlab.physics.separation import separation_loading, separation_unloading


def cycle(peak=60e3, n=61):
    return np.concatenate([np.linspace(0, peak, n), np.linspace(peak, 0, n)[1:]])


def test_ranges_promised_to_the_readout_chain():
    # Contract with acquisition and analysis: R_FSR ≈ 2 MΩ → ≈ 0.1 MΩ, C_FSR ≈ 0.5–1.5 nF over 0–60 kPa.
    r = VirtualFSR().respond(cycle())
    assert 1.5e6 < r.r_fsr_ohm[0] < 3e6 and 5e4 < r.r_fsr_ohm.min() < 2e5
    assert 0.4e-9 < r.c_fsr_farad.min() and r.c_fsr_farad.max() < 1.5e-9


def test_loading_lowers_resistance_and_raises_capacitance():
    r = VirtualFSR().respond(np.linspace(0, 60e3, 50))
    assert np.all(np.diff(r.r_fsr_ohm) < 0) and np.all(np.diff(r.c_fsr_farad) > 0)


def test_hysteresis_follows_eqs_1_and_9():
    # Reference: the sensor's separation over one cycle is eqs. (1) and (9) with its own modulus, and
    # its capacitance is eq. (14) over `layers` films in series at that separation.
    v = VirtualFSR()
    x = cycle()
    r = v.respond(x)
    n = 61
    np.testing.assert_allclose(r.separation_m[:n], separation_loading(x[:n], v.s0_m, v.modulus_pa), rtol=1e-12)
    np.testing.assert_allclose(r.separation_m[n:], separation_unloading(x[n:], 60e3, v.s0_m, v.modulus_pa, v.k),
                               rtol=1e-12)
    a0 = v.dielectric_fraction_0
    area = A201_AREA_M2 * (a0 + (1 - a0) * x / (x + v.dielectric_half_pa))
    np.testing.assert_allclose(r.c_fsr_farad, capacitance(v.layers * r.separation_m, area, v.eps_r), rtol=1e-12)
    # unloading keeps the films closer: at equal stress, more capacitance and less resistance
    assert r.c_fsr_farad[n + 29] > r.c_fsr_farad[n - 31]
    assert r.r_fsr_ohm[n + 29] < r.r_fsr_ohm[n - 31]


@pytest.mark.parametrize("field, value", [("area_m2", 0.0), ("layers", -1.0), ("k", 0.5),
                                          ("conductive_fraction_0", 2.0)])
def test_bad_parameters_are_named(field, value):
    with pytest.raises(ValueError, match=field):
        VirtualFSR(**{field: value})
