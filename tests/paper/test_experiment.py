"""The virtual experiment with the paper-sensor preset against the paper's printed §6 numbers.

References: Table 3 (HE), Tables 4 and 5 (readings, RE1/RE2), Figures 17 and 19 (ranges read off the axes),
from fsrlab.reference.paper_values(). The aims are those stated in docs/experiment.md; the gaps the
mechanisms cannot close are asserted as documented there, so a change of the model shows up here.
"""

import numpy as np
import pytest

from fsrlab.paper.experiment import dead_weights, run_experiment, spring_cycle
from fsrlab.paper.preset_fit import SPREADS, fit_paper_sensor, preset_targets, quick_response, re2_design
from fsrlab.physics.paper_sensor import PAPER_SENSOR_PARAMETERS, paper_sensor, paper_sensors
from fsrlab.physics.sensor import VirtualFSR
from fsrlab.reference import paper_values


@pytest.fixture(scope="module")
def exp():
    return run_experiment(paper_sensors())


@pytest.fixture(scope="module")
def printed():
    return paper_values()


def test_table3_means_within_2pp(exp, printed):
    t3 = printed["table3_hysteresis_error_percent"]
    assert abs(exp.he_traditional.mean() - t3["traditional_mean"]) <= 2.0
    assert abs(exp.he_proposed.mean() - t3["proposed_mean"]) <= 2.0
    assert np.all(exp.he_proposed < exp.he_traditional)  # the paper's ordering, per sensor


def test_figure19_ranges(exp):
    # Figure 19a: f ≈ 3-10 kHz; 19b: V0 ≈ 0.4-1 V over 0-10 kPa (axis ranges): within ±60 % at the ends.
    for c in exp.cycles:
        f, v = c.columns["frequency_hz"], c.columns["voltage_v"]
        assert 3e3 / 1.6 < np.nanmin(f) < 3e3 * 1.6 and 10e3 / 1.6 < np.nanmax(f) < 10e3 * 1.6
        assert 0.4 / 1.6 < np.nanmin(v) < 0.4 * 1.6 and 1.0 / 1.6 < np.nanmax(v) < 1.0 * 1.6


def test_table4_readings_near_printed_means(exp, printed):
    t4 = printed["table4_repeatability_capacitive_kHz"]
    for label, ws in exp.weights.items():
        got = np.mean([w.frequency_khz.mean() for w in ws])
        want = np.mean(t4[label]["readings"])
        assert got == pytest.approx(want, rel=0.15)


@pytest.fixture(scope="module")
def expected_re2():
    # The mean RE2 the preset's placement spreads give on average (linearised; what they were fitted to).
    sensors = paper_sensors()
    a, printed, labels = re2_design(sensors)
    sd = np.array([getattr(sensors[0], n) for n in SPREADS])
    return dict(zip(labels, np.sqrt(a @ sd**2), strict=True)), dict(zip(labels, printed, strict=True))


def test_re2_of_the_right_size(expected_re2):
    # Aim: within a factor 1.5 of the printed mean RE2. Met except Table 4 at 400 g, the documented gap
    # (docs/experiment.md: 1.6 %), asserted within a factor 1.7.
    got, printed = expected_re2
    for label in ("table4 200g", "table5 200g", "table5 400g"):
        assert 1 / 1.5 <= got[label] / printed[label] <= 1.5, label
    assert 1 <= got["table4 400g"] / printed["table4 400g"] <= 1.7
    # the paper's ordering: the proposed readout repeats better than the traditional one
    assert got["table4 200g"] < got["table5 200g"] and got["table4 400g"] < got["table5 400g"]


def test_documented_gaps(exp, printed):
    # docs/experiment.md: Table 5's voltages are ~3x below what Figure 19b implies at the same load.
    t5 = printed["table5_repeatability_traditional_V"]
    for label, ws in exp.weights.items():
        v_ratio = np.mean([w.voltage_v.mean() for w in ws]) / np.mean(t5[label]["readings"])
        assert v_ratio > 2.0


def test_linearised_re2_matches_the_placements(expected_re2):
    # Property: the Monte Carlo of five placements (dead_weights: meter noise, creep, the three draws)
    # averages near the linearised spread it was fitted with (E[s] of 5 normals is 0.94 sigma).
    from fsrlab.paper.preset_fit import placement_sensitivities

    s, m = paper_sensor(2), 0.2
    sd = np.array([getattr(s, n) for n in SPREADS])
    lin = 100 * np.sqrt(placement_sensitivities(s, m) ** 2 @ sd**2)
    runs = [dead_weights(s, m, seed=k) for k in range(12)]
    mc = np.mean([[r.re_frequency.re2_percent, r.re_voltage.re2_percent] for r in runs], axis=0)
    assert mc == pytest.approx(0.94 * lin, rel=0.3)


def test_figure17_single_valued_fit_is_capped_by_the_gap(exp):
    # A single-valued σ(f) on both branches cannot follow a 16 % gap: R² stays well below the paper's 0.9974,
    # which one branch (or the branch means) reaches.
    f17 = exp.fig17
    assert f17["both"]["cubic"] < 0.97
    assert f17["loading"]["cubic"] > 0.997 and f17["means"]["cubic"] > 0.997


def test_stored_preset_is_the_fit():
    # Re-running the fit from the stored parameters stays at them (the constants are the fit's result).
    best, got, want = fit_paper_sensor(2, max_nfev=30)
    stored = PAPER_SENSOR_PARAMETERS[1]
    for key in ("modulus_pa", "k", "area_fraction_0", "dielectric_ratio"):
        assert getattr(best, key) == pytest.approx(stored[key], rel=0.05)
    assert got["he_tm"] == pytest.approx(want["he_tm"], abs=0.5)
    assert got["he_pm"] == pytest.approx(want["he_pm"], abs=0.5)


def test_targets_are_the_printed_values(printed):
    t = preset_targets(4)
    assert t["he_tm"] == 28.54 and t["he_pm"] == 18.77
    assert t["f200"] == pytest.approx(1e3 * np.mean([6.2, 6.3, 6.2, 6.2, 6.3]))


def test_any_sensor_runs_through_the_bench():
    c = spring_cycle(VirtualFSR(), peak_pa=50e3, points_per_ramp=20)
    assert c.he_traditional_percent > 0 and c.he_proposed_percent > 0
    assert quick_response(paper_sensor(1))["f400"] > quick_response(paper_sensor(1))["f200"]


def test_preset_films_stay_off_the_seams_of_the_tunnelling_equations():
    # Property: the paper's eqs. (10)-(12) jump where they join (R_A ≈ 2.4x at u = φ0/e); a preset state on a
    # seam would be an artefact of the piecewise equations, so every film stays in eq. (11)'s range.
    from fsrlab.paper.preset_fit import film_regimes

    for s in paper_sensors():
        assert film_regimes(s) == {11}, s.name
