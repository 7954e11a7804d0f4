"""The compensation choice: play operators or causal branch polynomials, by grouped cross-validation.

References, by test: hand-worked label sequences (a readout going up and down past a known band);
causality as a property (the estimate of a prefix of a run equals the first rows of the estimate of
the whole run); the live estimator stepped row by row against the offline apply (same numbers);
synthetic runs with clean whole cycles (fsrlab.virtual.synthetic: VirtualFSR -> lm555.astable,
0.2 % frequency noise) and hand-loaded runs from a Bouc–Wen sensor (fsrlab.virtual.handloaded),
a model neither compensation assumes.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from fsrlab.calibration.document import load_calibration, save_calibration
from fsrlab.calibration.compensation import (
    BranchState, DirectionAwareCalibration, causal_readout_directions, fit_direction_aware
)
from fsrlab.metrics.cycles import run_hysteresis
from fsrlab.virtual.handloaded import fsr_bench_run
from fsrlab.calibration.play import fold_assignment
from fsrlab.calibration.fit import BRANCHES, PLAY, calibrate_run, fit_causal_branches
from fsrlab.calibration.apply import apply_calibration
from fsrlab.calibration.estimator import live_estimator
from fsrlab.calibration.readout import run_groups
from fsrlab.virtual.synthetic import synthetic_run
from fsrlab.io.runformat import load_run


def test_causal_labels_switch_at_the_reading_that_confirms_the_reversal():
    # Hand-worked: band 0.1; up to 1.0, then down. 0.95 is within the band (still loading), 0.85
    # is 0.15 below the maximum (unloading from there on); 0.9 after a minimum of 0.5 is 0.4 up.
    x = np.array([0.0, 0.5, 1.0, 0.95, 0.85, 0.5, 0.55, 0.9, np.nan, 0.2])
    np.testing.assert_array_equal(causal_readout_directions(x, 1.0, 0.1), [1, 1, 1, 1, -1, -1, -1, 1, 1, -1])
    # A readout that falls with stress (sign −1) mirrors it.
    np.testing.assert_array_equal(causal_readout_directions(-x, -1.0, 0.1), causal_readout_directions(x, 1.0, 0.1))


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    """A calibration run (3 whole cycles) and a held-out run (2 cycles), clean triangles."""
    d = tmp_path_factory.mktemp("clean")
    synthetic_run(cycles=3, seed=1).write(d / "cal.csv")
    synthetic_run(cycles=2, seed=7).write(d / "other.csv")
    return load_run(d / "cal.csv"), load_run(d / "other.csv")


@pytest.fixture(scope="module")
def branches(clean):
    run = clean[0]
    return fit_direction_aware(run["frequency_hz"], run["stress_pa"]), run


@settings(max_examples=25, deadline=None)
@given(n=st.integers(min_value=1, max_value=599), band=st.sampled_from([0.01, 0.02, 0.05]))
def test_causal_branch_estimate_of_a_prefix_is_the_prefix_of_the_estimate(branches, n, band):
    # Property (causality): what the estimate says at row i depends on rows ≤ i only.
    import dataclasses

    comp, run = branches
    causal = dataclasses.replace(comp, causal=True, threshold=band)
    x = run["frequency_hz"]
    whole = causal.predict(x)[0]
    np.testing.assert_array_equal(causal.predict(x[:n])[0], whole[:n])
    np.testing.assert_array_equal(causal_readout_directions(x[:n], 1.0, 50.0), causal_readout_directions(x, 1.0, 50.0)[:n])


def test_the_offline_branch_labels_are_not_causal(branches):
    # The earlier method dates each reversal back to its extremum once confirmed: cut a run just
    # after a peak, before the reversal is confirmed, and the last rows change branch.
    comp, run = branches
    x = run["frequency_hz"]
    peak = int(np.argmax(x[:200]))
    assert not comp.causal
    short = comp.predict(x[: peak + 3])[1]
    assert not np.array_equal(short, comp.predict(x)[1][: peak + 3])


def test_stepping_the_branch_state_gives_the_offline_numbers(branches):
    import dataclasses

    comp, run = branches
    causal = dataclasses.replace(comp, causal=True, threshold=0.02)
    x = run["frequency_hz"].copy()
    x[[3, 4, 150, 151, 152, 400]] = np.nan  # gaps, one across a reversal region
    x[77] = 1e308  # a corrupt reading: missing for the branches
    state = BranchState(causal)
    stepped = np.array([np.nan if (v := state.step(None if np.isnan(xi) else float(xi))) is None else v for xi in x])
    np.testing.assert_array_equal(stepped, causal.predict(x)[0])
    with pytest.raises(ValueError, match="causal"):
        BranchState(comp)


def test_fold_assignment_keeps_groups_whole():
    groups = np.repeat(np.arange(7), 10)
    use = np.ones(groups.size, bool)
    use[::9] = False
    fold, k = fold_assignment(groups, use, 5)
    assert k == 5
    g = groups[use]
    for gr in np.unique(g):
        assert np.unique(fold[g == gr]).size == 1
    with pytest.raises(ValueError, match="2 groups"):
        fold_assignment(np.zeros(10, int), np.ones(10, bool), 5)


def test_clean_whole_cycles_choose_the_causal_branches_and_live_equals_offline(clean, tmp_path):
    cal_run, other = clean
    cal = calibrate_run(cal_run, x="frequency_hz", compensate=True)
    cands, choice = cal.extra["compensation_candidates"], cal.extra["compensation_choice"]
    # Both compensations are cross-validated on the same folds; the smaller RMSE wins.
    assert {PLAY, BRANCHES, "plain"} <= set(cands)
    assert choice["chosen"] == BRANCHES and cands[BRANCHES] < min(v for k, v in cands.items()
                                                                    if k not in ("plain", BRANCHES))
    assert cal.compensation.causal and cal.memory is None and cal.cv_rmse == pytest.approx(cands[BRANCHES])
    # Reference: the held-out run's own reference; the chosen compensation cuts eq. (13) by ≥ 3×.
    est = apply_calibration(cal, other)
    plain = apply_calibration(cal, other, compensation=False)
    he_c = run_hysteresis(other["stress_pa"], est["stress_pa_estimate"]).percent
    he_p = run_hysteresis(other["stress_pa"], plain["stress_pa_estimate"]).percent
    assert he_c * 3 <= he_p
    # Live equals offline for the chosen method: stepping the estimator row by row, with gaps and a
    # reading beyond the margin (no estimate, a gap for the branch labels).
    f = other["frequency_hz"].copy()
    f[[5, 6, 60]] = np.nan
    f[30] = 10 * cal.x_range[1]
    from fsrlab.io.runwriter import write_run

    write_run(tmp_path / "holey.csv", {"stress_pa": other["stress_pa"], "frequency_hz": f}, other.metadata)
    holey = apply_calibration(cal, load_run(tmp_path / "holey.csv"))
    for xs, ref in ((other["frequency_hz"], est), (f, holey)):
        live = live_estimator(cal)
        steps = [live.step(None if np.isnan(v) else float(v)) for v in xs]
        y = np.array([np.nan if s[0] is None else s[0] for s in steps])
        u = np.array([np.nan if s[1] is None else s[1] for s in steps])
        np.testing.assert_array_equal(y, ref["stress_pa_estimate"])
        np.testing.assert_allclose(u, ref["stress_pa_uncertainty"], rtol=1e-12)
        np.testing.assert_array_equal(np.array([s[2] for s in steps], float), np.nan_to_num(ref["in_range"]))
    assert np.isnan(holey["stress_pa_estimate"][[5, 6, 30, 60]]).all()
    # The file records the choice and the causal labels, and reads back to the same estimate.
    p = save_calibration(cal, tmp_path / "cal.json")
    d = json.loads(p.read_text())
    assert d["compensation"]["causal"] is True and d["compensation_choice"]["chosen"] == BRANCHES
    back = load_calibration(p)
    np.testing.assert_array_equal(apply_calibration(back, other)["stress_pa_estimate"], est["stress_pa_estimate"])


def test_an_older_branch_file_keeps_the_offline_labels(branches):
    comp, _ = branches
    d = comp.to_dict()
    del d["causal"]
    assert DirectionAwareCalibration.from_dict(d).causal is False


def test_forced_methods(clean):
    cal_run, _ = clean
    play = calibrate_run(cal_run, x="frequency_hz", compensate=True, compensation_method="memory")
    assert play.memory is not None and play.compensation is None and BRANCHES not in play.extra["compensation_candidates"]
    br = calibrate_run(cal_run, x="frequency_hz", compensate=True, compensation_method="branches")
    assert br.compensation.causal and br.memory is None and set(br.extra["compensation_candidates"]) == {BRANCHES}
    with pytest.raises(ValueError, match="compensation_method"):
        calibrate_run(cal_run, compensate=True, compensation_method="preisach")


@pytest.fixture(scope="module")
def hand(tmp_path_factory):
    d = tmp_path_factory.mktemp("hand_choice")
    fsr_bench_run("hand", seed=1, duration_s=120, reference_sps=80).write(d / "cal.csv")
    return load_run(d / "cal.csv")


def test_hand_loaded_runs_keep_the_play_operators(hand):
    cal = calibrate_run(hand, x="voltage_v", compensate=True)
    choice = cal.extra["compensation_choice"]
    assert choice["chosen"] == PLAY and cal.memory is not None and cal.compensation is None
    assert "not tried" in choice["note"]  # partial presses and minor loops: not whole cycles
    # Were the branches cross-validated anyway, on the same folds, they would lose by far.
    from fsrlab.calibration.alignment import shift_reference

    x, y = hand["voltage_v"], shift_reference(hand["time_s"], hand["force_n"], cal.lag_s)  # as the fit saw it
    ok = np.isfinite(x) & np.isfinite(y) & ~cal.floor.below(x)
    bf = fit_causal_branches(x, y, ok, run_groups(hand), folds=5)
    play_cv = min(v for k, v in cal.extra["compensation_candidates"].items() if k != "plain")
    assert bf.cv_rmse > 2 * play_cv
