"""Event-driven transient (fsrlab.circuits.transient).

References: the closed forms of fsrlab.circuits.lm555 (which an exact simulation must match to
1e-9 relative for constant parts), an independent numerical ODE integration with scipy's
solve_ivp (for time-varying parts), and properties (Q = C·V across a capacitance step).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fsrlab.circuits.lm555 import astable
from fsrlab.circuits.transient import simulate
from fsrlab.errors import ParameterError


@pytest.mark.parametrize("kw", [
    dict(r_fsr_ohm=200e3, c_fsr_farad=1e-9),
    dict(r_fsr_ohm=45e3, c_fsr_farad=1e-9),
    dict(r_fsr_ohm=10e6, c_fsr_farad=0.5e-9, c_off_farad=470e-12),
    dict(r_fsr_ohm=200e3, c_fsr_farad=1e-9, diode=True),
    dict(r_fsr_ohm=80e3, c_fsr_farad=1.5e-9, diode=True, diode_drop_v=0.6),
    dict(r_fsr_ohm=np.inf, c_fsr_farad=1e-9),
    dict(r_fsr_ohm=500e3, c_fsr_farad=1e-9, lower_fraction=0.3, upper_fraction=0.75, vcc_v=3.3),
    dict(r_fsr_ohm=150e3, c_fsr_farad=1e-9, discharge_ohm=60.0),
    dict(r_fsr_ohm=np.inf, c_fsr_farad=1e-9, discharge_ohm=60.0),
])
def test_constant_parts_match_closed_form(kw):
    # Constant parts agree with the closed forms to 1e-9 relative, every period.
    sim = simulate(10e3, periods=200, **kw)
    ref = astable(10e3, **kw)
    assert sim.periods_s.size == 200
    np.testing.assert_allclose(sim.periods_s, ref.period_s, rtol=1e-9)
    np.testing.assert_allclose(sim.high_times_s, ref.tau_high_s, rtol=1e-9)
    assert sim.frequency_hz == pytest.approx(ref.frequency_hz, rel=1e-9)
    assert sim.duty_cycle == pytest.approx(ref.duty_cycle, rel=1e-9)


def test_power_up_first_period_longer_then_steady():
    # From 0 V the first charge must also cross 0 → Vcc/3: longer by τc·ln(V∞/(V∞ − Vcc/3)).
    r, rf, c = 10e3, 200e3, 1e-9
    sim = simulate(r, rf, c, periods=3, v_initial_v=0.0)
    ref = astable(r, rf, c)
    vinf = 5.0 * rf / (2 * r + rf)
    tau_c = c * 2 * r * rf / (2 * r + rf)
    first_high = sim.falling_s[0]
    assert first_high == pytest.approx(ref.tau_high_s + tau_c * math.log(vinf / (vinf - 5 / 3)), rel=1e-12)
    np.testing.assert_allclose(sim.periods_s, ref.period_s, rtol=1e-9)


def test_waveform_stays_between_thresholds_and_hits_them():
    sim = simulate(10e3, 200e3, 1e-9, diode=True, periods=5, waveform=True)
    assert sim.v_cap_v.min() == pytest.approx(5 / 3, rel=1e-12)
    assert sim.v_cap_v.max() == pytest.approx(10 / 3, rel=1e-12)
    # Output is high exactly while the capacitor charges (voltage rising).
    dv = np.diff(sim.v_cap_v)
    same = sim.output_high[1:] == sim.output_high[:-1]
    assert np.all(dv[same & sim.output_high[1:]] >= 0)
    assert np.all(dv[same & ~sim.output_high[1:]] <= 0)


def test_no_oscillation_gives_no_edges():
    # N = 3 < 4: the capacitor settles at Vcc·N/(N+2) = 3 V < 10/3 V, no edge after the start.
    sim = simulate(10e3, 30e3, 1e-9, t_stop_s=1e-3, v_initial_v=0.0)
    assert sim.rising_s.size == 0 and sim.falling_s.size == 0
    assert sim.v_end_v == pytest.approx(3.0, rel=1e-9)


def test_time_series_constant_equals_constant_parts():
    t = np.linspace(0, 2e-3, 57)
    a = simulate(10e3, np.full(t.size, 150e3), np.full(t.size, 1.2e-9), diode=True, time_s=t)
    b = simulate(10e3, 150e3, 1.2e-9, diode=True, t_stop_s=2e-3)
    np.testing.assert_allclose(a.rising_s, b.rising_s, rtol=1e-12)
    np.testing.assert_allclose(a.falling_s, b.falling_s, rtol=1e-12)


def _reference_ode(r, t, rf, cf, diode, v0):
    """Independent integration (solve_ivp, rtol 1e-11) of the same piecewise-constant circuit."""
    v, high = v0, True
    rising, falling = [0.0], []
    for k in range(t.size - 1):
        if k and cf[k] != cf[k - 1]:
            v *= cf[k - 1] / cf[k]
        ta = t[k]
        while True:
            if high and v >= 10 / 3:
                falling.append(ta)
                high = False
            elif not high and v <= 5 / 3:
                rising.append(ta)
                high = True

            def rhs(_t, y, high=high, k=k):
                vc = y[0]
                i = -vc / rf[k]
                if high:
                    i += (5.0 - vc) / (2 * r)
                elif not diode:
                    i += -vc / r
                return [i / cf[k]]

            level = 10 / 3 if high else 5 / 3
            ev = lambda _t, y, level=level: y[0] - level  # noqa: E731
            ev.terminal = True
            sol = solve_ivp(rhs, (ta, t[k + 1]), [v], method="DOP853", rtol=1e-11, atol=1e-14, events=ev)
            if sol.t_events[0].size:
                ta = float(sol.t_events[0][0])
                v = level
                if high:
                    falling.append(ta)
                    high = False
                else:
                    rising.append(ta)
                    high = True
                continue
            v = float(sol.y[0, -1])
            break
    return np.array(rising), np.array(falling)


@pytest.mark.parametrize("diode", [False, True])
def test_time_varying_parts_match_independent_ode(diode):
    # A load ramp: R_FSR falls 2M → 100k and C_FSR rises 0.5n → 1.5n over 2 ms (20 samples).
    t = np.linspace(0, 2e-3, 21)
    rf = np.geomspace(2e6, 100e3, t.size)
    cf = np.linspace(0.5e-9, 1.5e-9, t.size)
    sim = simulate(10e3, rf, cf, diode=diode, time_s=t)
    rising, falling = _reference_ode(10e3, t, rf, cf, diode, 5 / 3)
    assert sim.rising_s.size == rising.size and sim.falling_s.size == falling.size
    # solve_ivp's event location with rtol 1e-11 over many periods: agree to 1e-8 relative.
    np.testing.assert_allclose(sim.rising_s, rising, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(sim.falling_s, falling, rtol=1e-8, atol=1e-14)


def test_capacitance_step_conserves_charge_or_voltage():
    # Diode variant with R_FSR = inf and the output low: nothing discharges C, so V only changes at
    # the step. Q = C·V: 1n → 2n takes 4 V to 2 V exactly; "voltage" keeps 4 V.
    t = np.array([0.0, 1e-6, 2e-6])
    kw = dict(diode=True, time_s=t, v_initial_v=4.0)
    q = simulate(10e3, np.inf, [1e-9, 2e-9, 2e-9], **kw)
    v = simulate(10e3, np.inf, [1e-9, 2e-9, 2e-9], capacitance_step="voltage", **kw)
    assert (q.v_end_v, q.high_end) == (2.0, False)
    assert (v.v_end_v, v.high_end) == (4.0, False)
    # 1n → 3n takes 4 V to 4/3 V, below Vcc/3: the output rises at the step time itself.
    s = simulate(10e3, np.inf, [1e-9, 3e-9, 3e-9], **kw)
    assert s.rising_s[0] == 1e-6


def test_validation():
    with pytest.raises(ParameterError, match="exactly one of periods and t_stop_s") as info:
        simulate(10e3, 200e3, 1e-9)
    assert info.value.parameter == "periods"
    with pytest.raises(ParameterError, match="time_s") as info:
        simulate(10e3, [1e5, 2e5], 1e-9, periods=3)
    assert info.value.parameter == "r_fsr_ohm"
    with pytest.raises(ParameterError, match="capacitance_step"):
        simulate(10e3, 200e3, 1e-9, periods=3, capacitance_step="x")


def test_oscillation_stops_and_resumes_when_n_dips_below_4():
    # R_FSR dips to 30 kΩ (N = 3 < 4) between 0.5 and 1 ms: the output stays high there (the
    # capacitor settles toward 3 V < 10/3 V) and oscillation resumes afterwards; every edge agrees
    # with the independent solve_ivp integration.
    t = np.array([0.0, 0.5e-3, 1.0e-3, 1.5e-3])
    rf = np.array([200e3, 30e3, 200e3, 200e3])
    cf = np.full(t.size, 1e-9)
    sim = simulate(10e3, rf, cf, time_s=t)
    rising, falling = _reference_ode(10e3, t, rf, cf, False, 5 / 3)
    assert not np.any((sim.falling_s > 0.5e-3 + 1e-4) & (sim.falling_s < 1.0e-3))
    assert np.any(sim.falling_s > 1.0e-3)
    np.testing.assert_allclose(sim.rising_s, rising, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(sim.falling_s, falling, rtol=1e-8, atol=1e-14)


_FAST_CIRCUITS = [
    dict(r_fsr_ohm=200e3, c_fsr_farad=1e-9),
    dict(r_fsr_ohm=10e6, c_fsr_farad=0.5e-9, c_off_farad=470e-12),
    dict(r_fsr_ohm=200e3, c_fsr_farad=1e-9, diode=True),
    dict(r_fsr_ohm=80e3, c_fsr_farad=1.5e-9, diode=True, diode_drop_v=0.6, c_off_farad=100e-12),
    dict(r_fsr_ohm=150e3, c_fsr_farad=1e-9, discharge_ohm=60.0),
    dict(r_fsr_ohm=np.inf, c_fsr_farad=1e-9, discharge_ohm=60.0, c_off_farad=220e-12),
    dict(r_fsr_ohm=500e3, c_fsr_farad=1e-9, lower_fraction=0.3, upper_fraction=0.75, vcc_v=3.3),
    dict(r_fsr_ohm=30e3, c_fsr_farad=1e-9),  # N = 3: no oscillation
]
_FAST_RUNS = [
    dict(periods=1), dict(periods=2), dict(periods=5000), dict(periods=300, v_initial_v=0.0),
    dict(periods=40, v_initial_v=4.0), dict(t_stop_s=1e-6), dict(t_stop_s=2e-3),
    dict(t_stop_s=3e-2, v_initial_v=0.0), dict(t_stop_s=2e-3, v_initial_v=4.5),
]


def _assert_same_run(fast, loop, rtol):
    assert fast.rising_s.shape == loop.rising_s.shape
    assert fast.falling_s.shape == loop.falling_s.shape
    np.testing.assert_allclose(fast.rising_s, loop.rising_s, rtol=rtol, atol=0)
    np.testing.assert_allclose(fast.falling_s, loop.falling_s, rtol=rtol, atol=0)
    assert fast.high_end == loop.high_end
    assert fast.t_end_s == pytest.approx(loop.t_end_s, rel=rtol, abs=0)
    assert fast.v_end_v == pytest.approx(loop.v_end_v, rel=1e-9)


@pytest.mark.parametrize("kw", _FAST_CIRCUITS)
@pytest.mark.parametrize("run", _FAST_RUNS)
def test_closed_form_path_equals_event_loop(kw, run):
    # Reference: the event loop itself (method="events"). The closed-form path's edges differ only
    # by the rounding of the loop's running sum t += Δt: 1e-10 relative is the stated bound. v_end
    # after a cut last period comes from exp() at a start time that differs by that rounding.
    fast = simulate(10e3, **kw, **run)
    loop = simulate(10e3, **kw, **run, method="events")
    _assert_same_run(fast, loop, rtol=1e-10)


def test_closed_form_path_equals_event_loop_over_many_periods():
    # 2·10^5 periods: the loop's accumulated rounding stays well inside 1e-10 relative.
    kw = dict(r_fsr_ohm=80e3, c_fsr_farad=1.5e-9, diode=True, diode_drop_v=0.6, periods=200_000)
    _assert_same_run(simulate(10e3, **kw), simulate(10e3, **kw, method="events"), rtol=1e-10)


def test_method_validation():
    with pytest.raises(ValueError, match="method"):
        simulate(10e3, 200e3, 1e-9, periods=3, method="fast")
