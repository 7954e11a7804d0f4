"""Dual decoding and sensitivities (fsrlab.circuits.decode.decode / sensitivity).

References: round trips through the closed forms and through the independent event-driven
simulation (decode(simulate(parts)) = parts), a Monte-Carlo of timer quantization for the
uncertainty, central finite differences for the analytic sensitivities, and the impossible-pair limits
of duty_cycle_limits.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.circuits.decode import decode
from fsrlab.circuits.lm555 import astable, sensitivity
from fsrlab.circuits.transient import simulate
from fsrlab.errors import ParameterError
from fsrlab.hardware import TICK_S as TIMER_TICK_S


@given(n=st.floats(4.05, 2000), c=st.floats(100e-12, 5e-9), coff=st.sampled_from([0.0, 470e-12]),
       variant=st.sampled_from([dict(), dict(diode=True), dict(diode=True, diode_drop_v=0.6)]))
def test_round_trip_closed_form(n, c, coff, variant):
    r = 10e3
    if variant.get("diode_drop_v") and n < 6.3:
        n += 6.3
    a = astable(r, n * r, c, coff, **variant)
    d = decode(a.frequency_hz, a.duty_cycle, r, coff, **variant)
    # Bisection to machine precision; near N → ∞ without the diode DC is flat in N (DC − 2/3 ∝ 1/N),
    # so the recovered N loses digits in proportion: 1e-9 relative up to N = 2000.
    assert d.r_fsr_ohm == pytest.approx(n * r, rel=1e-9)
    assert d.c_fsr_farad == pytest.approx(c, rel=1e-9)


@pytest.mark.parametrize("variant", [dict(), dict(diode=True), dict(diode=True, diode_drop_v=0.6)])
@pytest.mark.parametrize("rf, cf", [(200e3, 1e-9), (2e6, 0.5e-9), (100e3, 1.5e-9)])
def test_decode_of_transient_simulation_returns_the_parts(variant, rf, cf):
    # decode(simulate(parts)) returns the parts (exact simulation: 1e-8).
    sim = simulate(10e3, rf, cf, 470e-12, periods=50, **variant)
    d = decode(sim.frequency_hz, sim.duty_cycle, 10e3, 470e-12, periods=50, **variant)
    assert d.r_fsr_ohm == pytest.approx(rf, rel=1e-8)
    assert d.c_fsr_farad == pytest.approx(cf, rel=1e-8)


def test_impossible_pairs_raise_clear_errors():
    # Without the diode DC > 2/3 always (N → ∞ limit); 0.6 is impossible.
    with pytest.raises(ValueError, match=r"duty_cycle: 0\.6 cannot come from this circuit.*0\.666667"):
        decode(10e3, 0.6, 10e3)
    # A frequency so high that C < C_off.
    with pytest.raises(ParameterError, match="more than the whole timing capacitance"):
        decode(1e6, 0.5, 10e3, c_off_farad=1e-9, diode=True)
    with pytest.raises(ValueError, match="duty_cycle"):
        decode(1e3, 1.2, 10e3)
    with pytest.raises(ValueError, match="frequency_hz"):
        decode(-1.0, 0.5, 10e3)


def test_uncertainty_matches_monte_carlo_of_quantized_edges():
    # Each exact edge of n periods gets its own quantization error, uniform over one 62.5 ns tick (a
    # capture rounds down; the edge's phase against the clock is random and independent between
    # edges, as the propagation assumes); decode all draws at once and compare the spread with
    # the propagated standard deviation (4000 draws: the std estimate is good to ~±3 %; margin 10 %).
    r, rf, cf, nper, draws = 10e3, 200e3, 1e-9, 4, 4000
    sim = simulate(r, rf, cf, diode=True, periods=nper)
    rng = np.random.default_rng(1)
    q = TIMER_TICK_S
    rise = sim.rising_s - rng.uniform(0, q, (draws, sim.rising_s.size))
    fall = sim.falling_s - rng.uniform(0, q, (draws, sim.falling_s.size))
    total = rise[:, -1] - rise[:, 0]
    d = decode(nper / total, np.sum(fall[:, :nper] - rise[:, :-1], axis=1) / total, r, diode=True, periods=nper)
    pred = decode(sim.frequency_hz, sim.duty_cycle, r, diode=True, periods=nper)
    assert np.std(d.r_fsr_ohm) == pytest.approx(pred.r_fsr_std_ohm, rel=0.1)
    assert np.std(d.c_fsr_farad) == pytest.approx(pred.c_fsr_std_farad, rel=0.1)


def test_uncertainty_falls_with_averaged_periods():
    a = astable(10e3, 200e3, 1e-9, diode=True)
    one = decode(a.frequency_hz, a.duty_cycle, 10e3, diode=True, periods=1)
    many = decode(a.frequency_hz, a.duty_cycle, 10e3, diode=True, periods=100)
    # H̄'s variance falls as 1/n and dominates: about a factor 10 for 100 periods.
    assert 5 < one.r_fsr_std_ohm / many.r_fsr_std_ohm < 15


@pytest.mark.parametrize("variant", [dict(), dict(diode=True), dict(diode=True, diode_drop_v=0.6),
                                     dict(lower_fraction=0.3, upper_fraction=0.7)])
@pytest.mark.parametrize("rf", [80e3, 300e3, 3e6])
def test_sensitivity_matches_finite_differences(variant, rf):
    # Central differences in ln R_FSR and ln C_FSR (step 1e-5: truncation ~1e-10, rounding ~1e-10).
    r, cf, coff, h = 10e3, 1e-9, 470e-12, 1e-5
    s = sensitivity(r, rf, cf, coff, **variant)

    def lnf(x, c):
        return np.log(astable(r, x, c, coff, **variant).frequency_hz)

    def lndc(x):
        return np.log(astable(r, x, cf, coff, **variant).duty_cycle)

    d = np.log1p(h) - np.log1p(-h)
    assert s.r_fsr == pytest.approx((lnf(rf * (1 + h), cf) - lnf(rf * (1 - h), cf)) / d, rel=1e-6, abs=1e-9)
    assert s.c_fsr == pytest.approx((lnf(rf, cf * (1 + h)) - lnf(rf, cf * (1 - h))) / d, rel=1e-6)
    assert s.duty_r_fsr == pytest.approx((lndc(rf * (1 + h)) - lndc(rf * (1 - h))) / d, rel=1e-6, abs=1e-9)


def test_sensitivity_limits():
    # Ideal capacitor (R_FSR = inf): f does not depend on R_FSR. Diode variant at large N: f ≈ 1/(ln2·R_FSR·C).
    assert sensitivity(10e3, np.inf, 1e-9).r_fsr == 0.0
    assert sensitivity(10e3, 1e9, 1e-9, diode=True).r_fsr == pytest.approx(-1.0, abs=1e-4)


def test_check_false_gives_nan_for_impossible_elements():
    a = astable(10e3, 200e3, 1e-9)
    d = decode([a.frequency_hz, 10e3, 1e6], [a.duty_cycle, 0.6, 0.9], 10e3, c_off_farad=0.0, check=False)
    assert d.r_fsr_ohm[0] == pytest.approx(200e3, rel=1e-9)
    assert np.isnan(d.r_fsr_ohm[1]) and np.isnan(d.c_fsr_farad[1])  # DC 0.6 < 2/3: impossible
    assert np.isfinite(d.c_fsr_farad[2])
    d = decode([1e6], [0.5], 10e3, c_off_farad=1e-9, diode=True, check=False)
    assert np.isnan(d.c_fsr_farad[0])  # would need C < C_off


def test_round_trip_and_sensitivity_with_discharge_resistance():
    r, rf, cf, rd, h = 10e3, 300e3, 1e-9, 80.0, 1e-5
    a = astable(r, rf, cf, discharge_ohm=rd)
    d = decode(a.frequency_hz, a.duty_cycle, r, discharge_ohm=rd)
    assert d.r_fsr_ohm == pytest.approx(rf, rel=1e-9) and d.c_fsr_farad == pytest.approx(cf, rel=1e-9)
    s = sensitivity(r, rf, cf, discharge_ohm=rd)
    lnf = lambda x: np.log(astable(r, x, cf, discharge_ohm=rd).frequency_hz)  # noqa: E731
    num = (lnf(rf * (1 + h)) - lnf(rf * (1 - h))) / (np.log1p(h) - np.log1p(-h))
    assert s.r_fsr == pytest.approx(num, rel=1e-6)
