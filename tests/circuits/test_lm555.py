"""Closed forms of the FSR-timed LM555 astable (fsrlab.circuits.lm555).

References: the classic 555 astable formulas (an independent closed form: datasheet
f = 1.44/((R_A + 2R_B)·C), τH = ln2·(R_A + R_B)·C, τL = ln2·R_B·C), the paper's eqs. (23), (26), (34)
typed in again here from the paper text, and properties (monotonicity, limits).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.circuits.lm555 import (
    NoOscillationError,
    astable,
    duty_cycle_limits,
    minimum_n_ratio,
    oscillation_margin,
    tau_ratio,
)

LN2 = math.log(2.0)


def paper_eq23(r, rf, c):
    # Eq. (23) of the paper, written independently of the implementation.
    return math.log((2 * r - 2 * rf) / (4 * r - rf)) * (2 * r * rf / (2 * r + rf)) * c


def test_classic_555_limit_without_fsr_resistance():
    # R_FSR = inf: datasheet astable with R_A = R_B = R: τH = 2RC ln2, τL = RC ln2, f = 1/(3 ln2 RC).
    r, c = 10e3, 1e-9
    res = astable(r, np.inf, c)
    assert res.tau_high_s == pytest.approx(2 * r * c * LN2, rel=1e-14)
    assert res.tau_low_s == pytest.approx(r * c * LN2, rel=1e-14)
    assert res.frequency_hz == pytest.approx(1 / (3 * LN2 * r * c), rel=1e-14)
    # and the limit is approached continuously: R_FSR = 1e6·R differs by O(1/N).
    big = astable(r, 1e6 * r, c)
    assert big.frequency_hz == pytest.approx(res.frequency_hz, rel=1e-5)


def test_paper_equations_default_thresholds():
    # Eqs. (23), (26), (34) retyped from the paper; relative 1e-12 (floating point only).
    r, rf, c = 10e3, 200e3, 1e-9
    res = astable(r, rf, c)
    assert res.tau_high_s == pytest.approx(paper_eq23(r, rf, c), rel=1e-12)
    assert res.tau_low_s == pytest.approx(LN2 * r * rf / (r + rf) * c, rel=1e-12)
    res_d = astable(r, rf, c, diode=True)
    assert res_d.tau_high_s == pytest.approx(paper_eq23(r, rf, c), rel=1e-12)
    assert res_d.tau_low_s == pytest.approx(LN2 * rf * c, rel=1e-12)
    assert res_d.frequency_hz == pytest.approx(1 / (paper_eq23(r, rf, c) + LN2 * rf * c), rel=1e-12)


def test_readme_example_decode_values():
    # The README's `fsrlab decode --frequency 6478.5 --duty 0.10189` for R = 10k with the diode:
    # that pair is R_FSR = 200k, C = 1n (rounding of the printed values: 1e-5 relative).
    res = astable(10e3, 200e3, 1e-9, diode=True)
    assert res.frequency_hz == pytest.approx(6478.5, rel=1e-5)
    assert res.duty_cycle == pytest.approx(0.10189, rel=1e-4)


def test_c_off_adds_to_c_fsr():
    a = astable(10e3, 300e3, 0.7e-9, c_off_farad=0.3e-9, diode=True)
    b = astable(10e3, 300e3, 1.0e-9, diode=True)
    assert a.frequency_hz == pytest.approx(b.frequency_hz, rel=1e-14)


def test_diode_drop_closed_form():
    # Independent closed form: charge from Vs = Vcc − V_D through 2R∥R_FSR, thresholds Vcc/3, 2Vcc/3.
    r, rf, c, vcc, vd = 10e3, 100e3, 1e-9, 5.0, 0.6
    vs = vcc - vd
    vinf = vs * rf / (2 * r + rf)
    tau = c * 2 * r * rf / (2 * r + rf)
    th = tau * math.log((vinf - vcc / 3) / (vinf - 2 * vcc / 3))
    res = astable(r, rf, c, diode=True, diode_drop_v=vd, vcc_v=vcc)
    assert res.tau_high_s == pytest.approx(th, rel=1e-12)
    assert res.tau_low_s == pytest.approx(LN2 * rf * c, rel=1e-12)


def test_minimum_n_ratio():
    assert minimum_n_ratio() == pytest.approx(4.0, rel=1e-15)  # eq. (30)
    # Vs = 4.4 V, u·Vcc = 10/3 V: N_min = 2·(10/3)/(4.4 − 10/3) = 6.25.
    assert minimum_n_ratio(0.6) == pytest.approx(6.25, rel=1e-12)
    assert math.isinf(minimum_n_ratio(5 / 3 + 1e-9))


def test_no_oscillation_message_names_condition_and_shortfall():
    with pytest.raises(NoOscillationError, match=r"N = R_FSR/R = 3\.5 must exceed 4.*12\.5 %") as err:
        astable(10e3, 35e3, 1e-9)
    assert err.value.condition == "charge"
    assert err.value.shortfall == pytest.approx(0.125)
    with pytest.raises(NoOscillationError, match="diode drop") as err:
        astable(10e3, 1e6, 1e-9, diode=True, diode_drop_v=2.0)
    assert err.value.condition == "diode_drop"
    with pytest.raises(NoOscillationError, match="discharge only through R_FSR") as err:
        astable(10e3, np.inf, 1e-9, diode=True)
    assert err.value.condition == "discharge"
    assert isinstance(err.value, ValueError)


def test_arrays_nan_where_no_oscillation_with_check_false():
    res = astable(10e3, np.array([30e3, 40e3, 50e3]), 1e-9, check=False)
    assert np.isnan(res.frequency_hz[:2]).all() and np.isfinite(res.frequency_hz[2])
    assert res.oscillates.tolist() == [False, False, True]
    with pytest.raises(NoOscillationError, match="2 of 3 elements"):
        astable(10e3, np.array([30e3, 40e3, 50e3]), 1e-9)


@pytest.mark.parametrize("kwargs, name", [
    (dict(r_ohm=-1.0), "r_ohm"), (dict(r_fsr_ohm=0.0), "r_fsr_ohm"), (dict(c_fsr_farad=-1e-9), "c_fsr_farad"),
    (dict(c_off_farad=-1e-12), "c_off_farad"), (dict(vcc_v=0.0), "vcc_v"),
    (dict(lower_fraction=0.7), "lower_fraction"), (dict(diode_drop_v=0.6), "diode_drop_v"),
    (dict(c_fsr_farad=0.0), "timing capacitance"),
])
def test_validation(kwargs, name):
    args = dict(r_ohm=10e3, r_fsr_ohm=200e3, c_fsr_farad=1e-9) | kwargs
    with pytest.raises(ValueError, match=name):
        astable(**args)


def test_oscillation_margin():
    assert oscillation_margin(10e3, 50e3) == pytest.approx(0.25)
    assert oscillation_margin(10e3, 30e3) < 0


def test_tau_ratio_limits_and_monotonicity():
    # Property: eq. (32) decreases from ∞ (N → 4+) to 2 (N → ∞); the diode variant to 0.
    n = np.geomspace(4.0 + 1e-6, 1e7, 20000)
    g = tau_ratio(n)
    gd = tau_ratio(n, diode=True)
    assert np.all(np.diff(g) < 0) and np.all(np.diff(gd) < 0)
    assert g[-1] == pytest.approx(2.0, rel=1e-5) and g.min() > 2.0
    assert gd[-1] < 1e-5
    assert duty_cycle_limits() == pytest.approx((2 / 3, 1.0))
    assert duty_cycle_limits(diode=True) == (0.0, 1.0)


@given(r=st.floats(1e3, 1e5), n=st.floats(4.01, 1e4), c=st.floats(1e-12, 1e-6),
       vd=st.floats(0.0, 1.5), lo=st.floats(0.1, 0.45), hi=st.floats(0.5, 0.8))
def test_properties(r, n, c, vd, lo, hi):
    # Invariants: 0 < DC < 1; the diode lengthens τL; the diode drop lengthens τH; f·C is scale-free.
    n_min = minimum_n_ratio(vd, 5.0, hi)
    if n <= 1.001 * n_min:
        return
    kw = dict(lower_fraction=lo, upper_fraction=hi)
    plain = astable(r, n * r, c, **kw) if n > minimum_n_ratio(0.0, 5.0, hi) else None
    dio = astable(r, n * r, c, diode=True, diode_drop_v=vd, **kw)
    assert 0 < dio.duty_cycle < 1
    if plain is not None:
        assert dio.tau_low_s > plain.tau_low_s
        assert dio.tau_high_s >= plain.tau_high_s * (1 - 1e-12)
    scaled = astable(r, n * r, 2 * c, diode=True, diode_drop_v=vd, **kw)
    assert scaled.frequency_hz == pytest.approx(dio.frequency_hz / 2, rel=1e-12)


def test_thresholds_from_control_pin():
    # LM555 internal divider: open control pin sits at 2/3·Vcc, trigger at half the control voltage.
    from fsrlab.circuits.lm555 import thresholds_from_control

    assert thresholds_from_control(10 / 3, 5.0) == pytest.approx((1 / 3, 2 / 3), rel=1e-15)
    lo, hi = thresholds_from_control(4.0, 5.0)
    assert (lo, hi) == pytest.approx((0.4, 0.8))
    # The charge must now reach 4 V: N_min = 2·4/(5 − 4) = 8.
    assert minimum_n_ratio(0.0, 5.0, hi) == pytest.approx(8.0)
    with pytest.raises(ValueError, match="control_v"):
        thresholds_from_control(6.0, 5.0)


@given(lo=st.floats(0.05, 0.6), width=st.floats(0.02, 0.35), diode=st.booleans(), drop_share=st.floats(0, 0.95))
def test_tau_ratio_monotone_for_any_thresholds_and_drop(lo, width, diode, drop_share):
    # decode() inverts DC(N) by bisection: this property (τH/τL strictly falling in N) is what it needs.
    hi = min(lo + width, 0.95)
    vd = drop_share * (1 - hi) * 5.0 if diode else 0.0
    n = minimum_n_ratio(vd, 5.0, hi) * (1 + np.geomspace(1e-6, 1e6, 400))
    g = tau_ratio(n, diode=diode, diode_drop_v=vd, lower_fraction=lo, upper_fraction=hi)
    assert np.all(np.diff(g) < 0)


def test_discharge_resistance_closed_form():
    # Independent derivation: pin 7 = Vcc·Rd/(R + Rd) behind R∥Rd; C discharges through
    # (R + R∥Rd)∥R_FSR toward that source divided by R_FSR. With D1 nothing changes (D1 blocks R_B).
    r, rf, c, rd, vcc = 10e3, 200e3, 1e-9, 50.0, 5.0
    vt, rt = vcc * rd / (r + rd), r * rd / (r + rd)
    vinf = vt * rf / (r + rt + rf)
    rth = (r + rt) * rf / (r + rt + rf)
    tl = c * rth * math.log((2 * vcc / 3 - vinf) / (vcc / 3 - vinf))
    res = astable(r, rf, c, discharge_ohm=rd)
    assert res.tau_low_s == pytest.approx(tl, rel=1e-12)
    assert res.tau_high_s == astable(r, rf, c).tau_high_s
    assert astable(r, rf, c, diode=True, discharge_ohm=rd).tau_low_s == astable(r, rf, c, diode=True).tau_low_s
    # A huge on-resistance keeps C above Vcc/3: no oscillation, condition "discharge".
    with pytest.raises(NoOscillationError, match="discharge transistor") as err:
        astable(r, rf, c, discharge_ohm=20e3)
    assert err.value.condition == "discharge"


def test_diode_drop_without_headroom_is_one_error_everywhere():
    # Vcc − V_D must exceed the upper threshold 2/3·5 V: a 2 V drop leaves 3 V, short by 1/3 V.
    from fsrlab.circuits.decode import decode

    err = NoOscillationError.for_diode_drop(2.0, 5.0, 2 / 3)
    assert err.condition == "diode_drop" and err.shortfall == pytest.approx(2.0 / (5 / 3) - 1, rel=1e-15)
    assert "leaves Vcc − V_D = 3 V" in str(err) and "below 1.667 V" in str(err)
    for call in (lambda: astable(10e3, 200e3, 1e-9, diode=True, diode_drop_v=2.0),
                 lambda: duty_cycle_limits(diode=True, diode_drop_v=2.0),
                 lambda: decode(5e3, 0.5, 10e3, diode=True, diode_drop_v=2.0)):
        with pytest.raises(NoOscillationError) as raised:
            call()
        assert raised.value.condition == "diode_drop" and str(raised.value).startswith(str(err))
