"""The extension mechanisms of fsrlab.physics.paper_sensor against closed forms and properties."""

import numpy as np
import pytest

from fsrlab.physics.paper_sensor import (
    PAPER_SENSOR_NAMES,
    PaperFSR,
    conductive_area,
    contact_resistance,
    creep_factor,
    hold_time,
    memory_stress,
    paper_sensor,
    paper_sensors,
    series_contact,
)
from fsrlab.physics.separation import separation_history

CYCLE = np.concatenate([np.linspace(0, 10e3, 21), np.linspace(10e3, 0, 21)[1:]])


def test_series_contact_ohmic_closed_form():
    # Independent closed form: an ohmic film R in series with R_C takes u = V·R/(R + R_C).
    v, rc, r = 5.0, np.array([0.0, 1e3, 1e5, 1e7]), 2e5
    u, total = series_contact(v, rc, lambda uu: np.full(np.shape(uu), r))
    assert u == pytest.approx(v * r / (r + rc), rel=1e-12)
    assert total == pytest.approx(r + rc, rel=1e-12)


def test_series_contact_solves_fig3_with_tunnelling():
    # Property: the solution satisfies V = u + R_C·u/R(u) (paper Fig. 3) for the non-ohmic film.
    s = paper_sensor(1)
    sep, area = np.full(3, 4.9e-9), np.full(3, 1e-6)
    rc = np.array([1e4, 1e5, 1e6])
    u, total = series_contact(5.0, rc, lambda uu: s.film_resistance(uu, sep, area))
    film = s.film_resistance(u, sep, area)
    assert u + rc * u / film == pytest.approx(np.full(3, 5.0), rel=1e-9)
    assert total == pytest.approx(rc + film, rel=1e-12)


def test_no_contact_gives_the_film_model():
    # R_C = 0: R_FSR is the films' n·R_A(V/n, s)/A exactly (the model without Fig. 3's contact).
    s = paper_sensor(2).replace(contact_ohm=0.0)
    r = s.respond(CYCLE, 5.0)
    assert np.array_equal(r.film_voltage_v, np.full(CYCLE.size, 5.0))
    assert r.r_fsr_ohm == pytest.approx(s.film_resistance(5.0, r.separation_m, r.area_m2), rel=1e-12)


def test_contact_resistance_halves_at_its_stress():
    assert contact_resistance([0.0, 5e3], 3e4, 5e3) == pytest.approx([3e4, 1.5e4])


def test_voltage_dependence_lower_resistance_at_higher_voltage():
    # Tunnelling (eqs. 16-18): the op-amp's 5 V sees a lower R_FSR than the 555's 2.5 V.
    s = paper_sensor(1)
    assert np.all(s.respond(CYCLE, 5.0).r_fsr_ohm < s.respond(CYCLE, 2.5).r_fsr_ohm)


def test_memory_stress_identity_without_memory_and_branches_meet():
    assert memory_stress(CYCLE, 1.0) == pytest.approx(CYCLE, rel=1e-9, abs=1e-6)
    x = memory_stress(CYCLE, 3.0)
    assert x[:21] == pytest.approx(CYCLE[:21], rel=1e-9, abs=1e-6)  # loading: the stress itself
    assert np.all(x[21:-1] > CYCLE[21:-1])  # unloading above loading
    assert x[20] == pytest.approx(10e3) and x[-1] == pytest.approx(0.0, abs=1e-6)  # branches meet


def test_area_hysteresis_opens_and_closes():
    s = paper_sensor(3)
    a = s.respond(CYCLE, 2.5).area_m2
    load, unload = a[:21], a[20:][::-1]
    assert np.all(unload[1:-1] > load[1:-1])
    assert unload[0] == pytest.approx(load[0]) and unload[-1] == pytest.approx(load[-1])


def test_area_factor_cancels_in_rc_without_contact_or_parasitic():
    # Closed form: R = n·R_A/A and C = ε·d·A/(n s) make R·C independent of A when R_C = C_p = 0.
    s = paper_sensor(1).replace(contact_ohm=0.0, parasitic_farad=0.0)
    r1, r2 = s.respond(CYCLE, 2.5), s.respond(CYCLE, 2.5, area_factor=1.3)
    assert r2.r_fsr_ohm * r2.c_fsr_farad == pytest.approx(r1.r_fsr_ohm * r1.c_fsr_farad, rel=1e-12)
    assert r2.r_fsr_ohm == pytest.approx(r1.r_fsr_ohm / 1.3, rel=1e-12)


def test_conductive_area_capped():
    assert conductive_area(1e9, 1e-4, 0.5, 1e3) == pytest.approx(1e-4)


def test_creep_grows_with_log_time():
    # ln-law: equal increments per decade, β·ln 10 for t ≫ τ.
    f = creep_factor(np.array([1e2, 1e3, 1e4]), 0.01, 1.0)
    assert np.diff(f) == pytest.approx(np.full(2, 0.01 * np.log(10)), rel=1e-2)
    assert creep_factor(0.0, 0.01, 1.0) == 1.0


def test_hold_time_restarts_at_each_step():
    t = np.arange(6.0)
    assert hold_time(t, [0, 1e3, 1e3, 1e3, 2e3, 2e3]) == pytest.approx([0, 0, 1, 2, 0, 1])


def test_creep_under_held_load_lowers_resistance():
    s = paper_sensor(1)
    t = np.array([0.0, 0.0, 1.0, 10.0, 100.0])
    r = s.respond(np.array([0.0, 5e3, 5e3, 5e3, 5e3]), 2.5, time_s=t).r_fsr_ohm
    assert np.all(np.diff(r[1:]) < 0)
    # without time, respond(stress, voltage) is unchanged (existing callers)
    r0 = s.respond(np.array([0.0, 5e3, 5e3]), 2.5).r_fsr_ohm
    assert r0[1] == r0[2] == pytest.approx(r[1])


def test_separation_memory_is_the_paper_rule():
    s = paper_sensor(4)
    r = s.respond(CYCLE, 2.5)
    ref = separation_history(CYCLE, s0_m=s.s0_m, modulus_pa=s.modulus_pa, k=s.k).separation_m
    assert np.array_equal(r.separation_m, ref)


def test_spread_sensors_differ():
    sensors = paper_sensors()
    assert [s.name for s in sensors] == list(PAPER_SENSOR_NAMES)
    f = [s.respond(CYCLE, 5.0).r_fsr_ohm[20] for s in sensors]
    assert len({round(float(x)) for x in f}) == 4


def test_placement_draws_and_names():
    s = paper_sensor("paper-a201-2")
    s = s.replace(placement_stress_sd=0.01, placement_contact_sd=0.1, placement_area_sd=0.1)
    a = s.placement(np.random.default_rng(1))
    b = s.placement(np.random.default_rng(2))
    assert a != b and set(a) == {"stress_factor", "contact_factor", "area_factor"} and a["contact_factor"] > 0
    s.respond([0.0, 5e3], 2.5, **a)  # the draws are respond's keywords
    with pytest.raises(ValueError, match="paper-a201-1"):
        paper_sensor("nope")
    with pytest.raises(ValueError, match="1-4"):
        paper_sensor(5)
    with pytest.raises(ValueError, match="area_k"):
        PaperFSR(area_k=0.5)


def test_interfaces_accepted_by_synthetic_runs():
    from fsrlab.virtual.synthetic import synthetic_run

    run = synthetic_run(cycles=1, peak_pa=10e3, points_per_ramp=10, sensor=paper_sensor(1))
    assert np.all(np.isfinite(run.columns["frequency_hz"][1:]))


def test_presets_registry_names_the_paper_sensors():
    from fsrlab.physics.presets import sensor_preset

    for name in PAPER_SENSOR_NAMES:
        p = sensor_preset(name)
        assert p.area_m2 == pytest.approx(paper_sensor(name).area_m2)


def test_virtual_device_source_accepts_a_paper_sensor():
    from fsrlab.circuits.circuit import PAPER_CIRCUIT
    from fsrlab.virtual.sources import PhysicsSource, StressProfile

    # The preset's range: the paper's 0-10 kPa spring cycle.
    src = PhysicsSource(StressProfile(peak_pa=10e3), sensor=paper_sensor(1), circuit=PAPER_CIRCUIT)
    sig = src.window(1.0, 1.1, 0)
    assert np.isfinite(sig.frequency_hz) and sig.frequency_hz > 0


def test_series_contact_stopping_early_is_bisection_bit_for_bit():
    """series_contact stops once the bracket is two adjacent floats; the reference is the plain
    60-step bisection written out here: the same bits, with fewer evaluations of R(u)."""
    from fsrlab.physics.paper_sensor import paper_sensor, series_contact

    sensor = paper_sensor("paper-a201-1")
    sigma = np.linspace(0.0, 50e3, 200)
    resp = sensor.respond(sigma, voltage_v=2.5)
    calls = [0]

    def film(u):
        calls[0] += 1
        return sensor.film_resistance(u, resp.separation_m, resp.area_m2)

    v, rc = np.full(sigma.shape, 2.5), resp.contact_ohm
    lo, hi = np.zeros(v.shape), v.copy()
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        up = mid + rc * mid / film(mid) - v > 0
        hi, lo = np.where(up, mid, hi), np.where(up, lo, mid)
    calls[0] = 0
    u, r = series_contact(v, rc, film)
    assert np.array_equal(u, 0.5 * (lo + hi)) and calls[0] < 60


def test_respond_many_gives_each_respond_to_the_bit():
    # Reference: one respond call per request. The contact solve goes element by element, so solving the
    # requests together (different voltages, histories, placement factors, creep) changes no number.
    from fsrlab.physics.paper_sensor import paper_sensor

    fsr = paper_sensor(1)
    stress = np.array([0.0, 4e3, 9e3, 5e3, 0.0])
    asked = [dict(stress_pa=stress, voltage_v=2.5), dict(stress_pa=stress, voltage_v=5.0),
             dict(stress_pa=stress[:3], voltage_v=2.5, stress_factor=1.01, contact_factor=0.9, area_factor=1.1,
                  time_s=np.array([0.0, 1.0, 5.0])),
             dict(stress_pa=[], voltage_v=5.0)]
    together = fsr.respond_many(asked)
    assert len(together) == len(asked) and fsr.respond_many([]) == []
    for got, a in zip(together, asked, strict=True):
        alone = fsr.respond(**a)
        for name in ("r_fsr_ohm", "c_fsr_farad", "film_voltage_v", "contact_ohm", "area_m2", "separation_m"):
            assert np.array_equal(getattr(got, name), getattr(alone, name)), name
