"""Thevenin equivalents of the astable's two phases (fsrlab.circuits.phases).

References: values derived by hand for R = 10 kΩ, R_FSR = 200 kΩ, Vcc = 5 V (kept exact with
fractions), the paper's eq. (23) retyped, the classic 555 limit (R_FSR = ∞), and a property every
Thevenin equivalent has: its short-circuit current V∞/R_th is the driving network's own
short-circuit current (with C shorted, R_FSR carries none).
"""

from __future__ import annotations

import math
from fractions import Fraction as Fr

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.circuits.lm555 import astable, minimum_n_ratio
from fsrlab.circuits.phases import Thevenin, thevenin, timing_per_rc

R, RF = 10_000, 200_000


def close(value, exact: Fr):
    # A handful of floating-point operations: a few ulps.
    assert float(value) == pytest.approx(float(exact), rel=4e-16, abs=0)


def test_charge_by_hand():
    # Output high: Vcc → R_A → R_B → C with R_FSR across C: Vcc·R_FSR/(2R + R_FSR) behind 2R ∥ R_FSR.
    charge, _ = thevenin(R, RF)
    close(charge.source_v, Fr(5) * RF / (2 * R + RF))          # 50/11 V = 4.5454... V
    close(charge.resistance_ohm, Fr(2 * R * RF, 2 * R + RF))    # 200000/11 Ω = 18181.8... Ω
    assert (charge.drive_v, charge.drive_ohm) == (5.0, 2 * R)
    # A 0.6 V drop of D1 lowers the source: 4.4·200/220 = 4 V.
    close(thevenin(R, RF, diode=True, diode_drop_v=0.6)[0].source_v, Fr(4))


def test_discharge_by_hand():
    # Output low, no D1: C discharges through R_B to the grounded pin 7, R_FSR across: R ∥ R_FSR toward 0 V.
    _, dis = thevenin(R, RF)
    close(dis.resistance_ohm, Fr(R * RF, R + RF))               # 200000/21 Ω = 9523.8... Ω
    assert dis.source_v == 0.0
    # With D1, R_B is blocked: R_FSR alone.
    _, dis_d = thevenin(R, RF, diode=True)
    assert (dis_d.source_v, dis_d.resistance_ohm, dis_d.drive_ohm) == (0.0, RF, math.inf)
    # A 50 Ω discharge transistor: pin 7 = 5·50/10050 V behind R ∥ 50 Ω, in series with R_B.
    rd = 50
    v_t, r_t = Fr(5 * rd, R + rd), Fr(R * rd, R + rd)
    b = R + r_t
    _, dis_r = thevenin(R, RF, discharge_ohm=rd)
    close(dis_r.source_v, v_t * RF / (b + RF))                  # 50/2111 V
    close(dis_r.resistance_ohm, b * RF / (b + RF))              # 20200000/2111 Ω
    close(dis_r.drive_ohm, b)


def test_open_fsr_is_the_classic_555():
    charge, dis = thevenin(R, math.inf)
    assert (charge.source_v, charge.resistance_ohm) == (5.0, 2 * R)
    assert (dis.source_v, dis.resistance_ohm) == (0.0, R)
    assert thevenin(R, math.inf, diode=True)[1].resistance_ohm == math.inf


@given(r=st.floats(10, 1e6), n=st.floats(1e-3, 1e6), rd=st.floats(0, 1e3), vcc=st.floats(1, 15),
       drop=st.floats(0, 0.9), diode=st.booleans())
def test_short_circuit_current_is_the_drive_current(r, n, rd, vcc, drop, diode):
    # C shorted: R_FSR carries no current, so V∞/R_th = drive_v/drive_ohm whatever R_FSR is.
    charge, dis = thevenin(r, n * r, diode, drop if diode else 0.0, vcc, rd)
    assert charge.source_v / charge.resistance_ohm == pytest.approx(charge.drive_v / charge.drive_ohm, rel=1e-12)
    if not diode:
        assert dis.source_v / dis.resistance_ohm == pytest.approx(dis.drive_v / dis.drive_ohm, rel=1e-12, abs=1e-300)
    # And R_th is below both the drive's resistance and R_FSR (two resistances in parallel).
    for phase in (charge, dis):
        assert phase.resistance_ohm <= min(phase.drive_ohm, n * r) * (1 + 1e-15)


def test_arrays_broadcast_and_return_copies():
    rf = np.array([100e3, 200e3, np.inf])
    charge, dis = thevenin(np.array([[10e3], [20e3]]), rf, diode=True)
    assert charge.source_v.shape == charge.drive_ohm.shape == dis.resistance_ohm.shape == (2, 3)
    dis.resistance_ohm[0, 0] = -1.0
    assert rf[0] == 100e3  # the result is not a view of the input
    assert isinstance(thevenin(R, RF)[0], Thevenin) and np.ndim(thevenin(R, RF)[0].source_v) == 0


def test_accepts_every_circuit_part():
    circuit = LM555Circuit(r_ohm=12e3, c_off_farad=220e-12, diode=False, vcc_v=3.3, lower_fraction=0.3,
                           upper_fraction=0.7, discharge_ohm=40.0)
    charge, dis = thevenin(r_fsr_ohm=RF, **circuit.kwargs())
    assert charge.resistance_ohm == pytest.approx(24e3 * RF / (24e3 + RF), rel=1e-15)
    assert dis.drive_v == pytest.approx(3.3 * 40 / 12040, rel=1e-15)


@pytest.mark.parametrize("kw, name", [
    (dict(r_ohm=-1.0, r_fsr_ohm=RF), "r_ohm"),
    (dict(r_ohm=R, r_fsr_ohm=0.0), "r_fsr_ohm"),
    (dict(r_ohm=R, r_fsr_ohm=RF, discharge_ohm=-1.0), "discharge_ohm"),
    (dict(r_ohm=R, r_fsr_ohm=RF, diode_drop_v=0.6), "diode_drop_v"),
    (dict(r_ohm=R, r_fsr_ohm=RF, upper_fraction=0.2), "lower_fraction"),
])
def test_bad_parts_name_the_parameter(kw, name):
    with pytest.raises(ValueError, match=name):
        thevenin(**kw)


def test_timing_per_rc_is_eq23_and_eq34():
    # Eq. (23) retyped: τH = ln((2R − 2R_FSR)/(4R − R_FSR))·(2R·R_FSR/(2R + R_FSR))·C; eq. (34): τL = ln2·R_FSR·C.
    n = np.array([4.5, 20.0, 1000.0])
    th, tl = timing_per_rc(n, diode=True)
    eq23 = np.log((2 - 2 * n) / (4 - n)) * (2 * n / (2 + n))
    np.testing.assert_allclose(th, eq23, rtol=1e-13)
    np.testing.assert_allclose(tl, math.log(2) * n, rtol=1e-15)
    # The closed form is built on it: τ = (τ/RC)·R·C.
    res = astable(R, 20.0 * R, 1e-9, diode=True)
    assert res.tau_high_s == th[1] * (R * 1e-9) and res.tau_low_s == tl[1] * (R * 1e-9)


def test_timing_per_rc_domain():
    n_min = minimum_n_ratio(0.6)
    th, tl = timing_per_rc(np.array([-1.0, 0.0, 3.0, n_min, np.nan, np.inf]), diode=True, diode_drop_v=0.6)
    assert np.all(np.isnan(th[:5])) and np.isfinite(th[5])
    assert tl[5] == math.inf  # D1 and an open FSR: no discharge path
    # A discharge transistor too weak to pull C below the lower threshold: τL = ∞.
    assert timing_per_rc(20.0, discharge_ratio=2.0)[1] == math.inf
    with pytest.raises(ValueError, match="discharge_ratio"):
        timing_per_rc(20.0, discharge_ratio=-0.1)
