"""The guided known-weight calibration: its plan, its stability criterion and its rows.

References: the plan and the criterion as the module states them (fsrlab.bench.weights):
masses up (+1), back down without the top one (−1), per cycle; stable when |mean(second half) −
mean(first half)| / mean over the last N windows ≤ max_drift; force_n = m·g with g = 9.80665 m/s²
(standard gravity) and stress = force / area. The procedure is driven by the windows' times, so
these tests feed it windows directly (no clock); one test runs the command end to end in real time.
"""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.bench.weights import WeightsProcedure, placements_table, plan_steps
from fsrlab.io.runformat import load_run

G = 9.80665
AREA = 7.13e-5


def test_plan_up_and_down_per_cycle():
    steps = plan_steps([0.0, 0.1, 0.2, 0.4], repeat=3, unload=True)
    assert len(steps) == 3 * (4 + 3)
    assert [s.mass_kg for s in steps[:7]] == [0.0, 0.1, 0.2, 0.4, 0.2, 0.1, 0.0]
    assert [s.direction for s in steps[:7]] == [1, 1, 1, 1, -1, -1, -1]
    assert [s.cycle for s in steps] == [c for c in range(3) for _ in range(7)]
    assert [s.index for s in steps] == list(range(21))
    assert [s.mass_kg for s in plan_steps([0.0, 0.05], repeat=2)] == [0.0, 0.05, 0.0, 0.05]
    with pytest.raises(ValueError, match="must increase"):
        plan_steps([0.0, 0.2, 0.1])


def _run(proc, readout, n=400, window=0.1):
    """Feed ``n`` windows whose readout is ``readout(t, step)``; return the rows kept."""
    rows = []
    for i in range(1, n + 1):
        t = round(i * window, 6)
        row = proc.on_row(None, {"time_s": t, "frequency_hz": readout(t, proc.k), "force_n": None})
        if row is not None:
            rows.append(row)
        if proc.done:
            break
    return rows


def test_steady_windows_are_kept_with_their_step_and_nominal_force():
    steps = plan_steps([0.0, 0.1, 0.2], unload=True)
    said, stop = [], threading.Event()
    proc = WeightsProcedure(steps, said.append, lambda: "ok", stop=stop, area_m2=AREA, settle_windows=4,
                            max_drift=0.005, hold_s=0.5)
    rows = _run(proc, lambda t, k: 1000.0 * (1 + k))  # steady at once: a level per step
    assert proc.done and stop.is_set() and len(said) == len(steps)
    for s in steps:
        mine = [r for r in rows if r["step"] == s.index]
        assert len(mine) == 5  # hold 0.5 s of 0.1 s windows
        assert all(r["force_n"] == r["force_nominal_n"] == pytest.approx(s.mass_kg * G) for r in mine)
        assert all(r["stress_pa"] == pytest.approx(s.mass_kg * G / AREA) for r in mine)
        assert all((r["direction"], r["cycle"], r["load"], r["reading"]) == (s.direction, 0, s.mass_kg * 1e3,
                                                                             1000.0 * (1 + s.index)) for r in mine)
    table = placements_table(proc.summary(), "frequency_hz").splitlines()
    assert table[0] == "load,sensor,reading,cycle,direction,step" and len(table) == 1 + 3  # loading only


def test_drift_criterion_waits_for_the_creep_to_slow():
    # Readout creeping as 1000·(1 + 0.2·exp(−t/τ)), τ = 1 s: the relative drift over the last 4
    # windows (0.1 s) is about 0.2·exp(−t)·0.2 → below 0.5 % once exp(−t) < 0.125, t > 2.1 s.
    proc = WeightsProcedure(plan_steps([0.0, 0.1]), lambda s: None, lambda: "ok", settle_windows=4,
                            max_drift=0.005, hold_s=0.2)
    _run(proc, lambda t, k: 1000.0 * (1 + 0.2 * np.exp(-t)) if k == 0 else 2000.0, n=200)
    assert proc.results[0]["settle_s"] == pytest.approx(2.1, abs=0.25)


def test_timeout_asks_again_then_skips_saying_why():
    said = []
    proc = WeightsProcedure(plan_steps([0.0, 0.1]), said.append, lambda: "ok", settle_windows=4, max_drift=0.005,
                            timeout_s=1.0, hold_s=0.2)
    _run(proc, lambda t, k: 1000.0 * (1 + 0.05 * t) if k == 0 else 2000.0)  # never settles on step 0
    assert proc.results[0]["status"] == "skipped: unstable" and proc.results[1]["status"] == "recorded"
    assert any("not stable after 1 s" in s and "press Enter to wait again" in s for s in said)
    assert any("skipped: not stable after a second 1 s" in s for s in said)


def test_windows_read_late_are_not_taken_for_the_new_mass():
    # The bench places step 1 at t = 5 s while the host still reads windows up to 5 s of step 0.
    proc = WeightsProcedure(plan_steps([0.0, 0.1]), lambda s: None, lambda: "ok",
                            place=lambda s: 5.0 if s.index == 1 else None, settle_windows=2, hold_s=0.1)
    rows = _run(proc, lambda t, k: 1000.0 if t <= 5.0 else 2000.0, n=100)
    assert all(r["reading"] == 2000.0 for r in rows if r["step"] == 1)


def test_user_skip():
    answers = iter([None, None, "skip"])
    proc = WeightsProcedure(plan_steps([0.0, 0.1]), lambda s: None, lambda: next(answers, "ok"), settle_windows=2,
                            hold_s=0.1)
    _run(proc, lambda t, k: 1000.0)
    assert [r["status"] for r in proc.results] == ["skipped", "recorded"]


def test_weights_virtual_run_is_ready_for_calibrate_and_repeatability(tmp_path, monkeypatch):
    """The documented guided calibration (README), with short windows (about 10 s in real time)."""
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["weights", "--virtual", "--masses", "0,100g,200g,400g", "--repeat", "3", "--unload",
                              "--out", "w.csv", "--window", "20ms", "--settle-windows", "5", "--hold", "100ms",
                              "--quiet", "--seed", "1", "--json"])
    assert code == 0, err
    info = json.loads(out)
    assert info["completed"] and info["recorded"] == 21 and info["skipped"] == 0
    run = load_run("w.csv")
    assert set(run["step"].astype(int)) == set(range(21))
    assert np.allclose(run["force_n"], run["force_nominal_n"]) and np.all(np.isfinite(run["reference_raw"]))
    assert set(np.round(run["force_nominal_n"] / G * 1e3, 6)) == {0, 100, 200, 400}
    assert run.metadata["weights"]["completed"] is True and run.metadata["sensor"]["area_m2"] > 0
    # The emulated load cell (exact virtual parameters, 40 counts noise) reads the placed force.
    lc = (run["reference_raw"] - 8192.0) / 87600.0
    assert np.all(np.abs(lc - run["force_nominal_n"]) < 5 * 40 / 87600.0)
    code, out, err = run_cli(["calibrate", "w.csv", "--x", "frequency_hz", "--json"])
    assert code == 0, err
    for table in ("w.csv", "w.placements.csv"):
        code, out, err = run_cli(["repeatability", table, "--json"])
        assert code == 0, err
    groups = json.loads(out)["groups"]
    assert sorted(g["load"] for g in groups) == [0, 100, 200, 400]
    # Loading placements only, each load reached from below in each cycle: the virtual sensor is
    # rate-independent, so they differ by the readout noise (1e-3 per window, 5 windows: ~0.05 %),
    # not by the hysteresis between branches (~20 % at 100 g when unloading placements are mixed in).
    assert all(g["re1_percent"] < 1.0 for g in groups)
    assert len(open("w.placements.csv").read().splitlines()) == 1 + 3 * 4


@pytest.mark.parametrize("masses, said", [("0,100g,50g", "'50g' is not larger"), ("0,10lb", "'10lb'"),
                                          ("0,500", "'500' has no unit")])
def test_bad_masses_exit_2_naming_the_value(masses, said, tmp_path):
    code, out, err = run_cli(["weights", "--virtual", "--masses", masses, "--out", str(tmp_path / "w.csv")])
    assert code == 2 and err.count("\n") == 1 and "--masses" in err and said in err, err
