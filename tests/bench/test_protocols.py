"""Bench protocols: the plans' properties, and ``fsrlab bench`` end to end on the virtual device.

References: properties each plan must hold by its definition (acquisition/protocols.py: spring
cycles base → peak → base; dead weights reached from below once per cycle with unloading to 0 in
between, as for the paper's Tables 4 and 5; a creep hold), and the run file format
(docs/data-format.md). The end-to-end runs use real pseudo-terminals and run in real time: each
records a few seconds.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clirun import run_cli
from fsrlab.bench.protocols import CreepPlan, SpringPlan, WeightsPlan, run_protocol, twin_status
from fsrlab.io.runformat import load_run


@settings(max_examples=50)
@given(peak=st.floats(1e3, 1e5), base=st.floats(0, 900), cycles=st.integers(1, 6), period=st.floats(0.5, 10))
def test_spring_plan_cycles_between_base_and_peak(peak, base, cycles, period):
    plan = SpringPlan(peak_pa=peak, cycles=cycles, period_s=period, base_pa=base)
    t = np.linspace(0, plan.duration_s, 40 * cycles + 1)
    s = plan.stress(t)
    assert plan.duration_s == pytest.approx(cycles * period)
    assert np.all(s >= base - 1e-9) and np.all(s <= peak + 1e-9)
    # Property: every cycle starts and ends at the base and reaches the peak half-way.
    # (Tolerance: t/period in floating point, a few ulp of the phase times the peak.)
    k = np.arange(cycles)
    tol = 1e-9 * peak
    assert plan.stress(k * period) == pytest.approx(np.full(cycles, base), abs=tol)
    assert plan.stress((k + 0.5) * period) == pytest.approx(np.full(cycles, peak), abs=tol)
    assert plan.stress(plan.duration_s + period / 3) == pytest.approx(base, abs=tol)  # after the last cycle: unloaded


@settings(max_examples=50)
@given(masses=st.lists(st.integers(1, 2000), min_size=1, max_size=4, unique=True), repeat=st.integers(1, 6))
def test_weights_plan_reaches_each_mass_from_below_once_per_cycle(masses, repeat):
    m = tuple(x / 1000 for x in sorted(masses))
    steps = WeightsPlan(masses_kg=m, repeat=repeat).steps()
    assert len(steps) == repeat * (2 * len(m) + 1)
    assert [s.index for s in steps] == list(range(len(steps)))
    for c in range(repeat):
        cyc = [s for s in steps if s.cycle == c]
        assert cyc[0].mass_kg == 0 and cyc[-1].mass_kg == 0  # unloaded between the cycles
        loading = [s.mass_kg for s in cyc if s.direction > 0]
        assert loading == [0.0, *m]  # each mass once, from below
        assert max(s.mass_kg for s in cyc) == m[-1]


def test_weights_plan_default_is_the_papers():
    plan = WeightsPlan()
    assert plan.masses_kg == (0.2, 0.4) and plan.repeat == 5  # Tables 4 and 5: 200 g and 400 g, five times
    loads = [s.mass_kg for s in plan.steps() if s.direction > 0 and s.mass_kg > 0]
    assert loads.count(0.2) == 5 and loads.count(0.4) == 5


@given(hold=st.floats(0.1, 1000), before=st.floats(0, 100), after=st.floats(0, 100))
def test_creep_plan_holds_the_mass_for_the_hold(hold, before, after):
    plan = CreepPlan(mass_kg=0.3, hold_s=hold, before_s=before, after_s=after)
    assert plan.duration_s == pytest.approx(before + hold + after)
    assert plan.mass_at(before + hold / 2) == 0.3
    assert plan.mass_at(before + hold + after / 2 + 1e-9 * (after == 0)) == 0.0
    if before > 0:
        assert plan.mass_at(before / 2) == 0.0


@pytest.mark.parametrize("bad", [dict(cycles=0), dict(period_s=0.0), dict(peak_pa=0.0), dict(base_pa=-1.0)])
def test_spring_plan_refuses_bad_values(bad):
    with pytest.raises(ValueError):
        SpringPlan(**bad)


@pytest.mark.parametrize("bad", [dict(masses_kg=(0.4, 0.2)), dict(masses_kg=(0.0, 0.2)), dict(masses_kg=()),
                                 dict(repeat=0)])
def test_weights_plan_refuses_bad_values(bad):
    with pytest.raises(ValueError):
        WeightsPlan(**bad)


def test_twin_status_is_a_pair_with_a_reason():
    ok, reason = twin_status()
    assert isinstance(ok, bool) and (ok or reason)


def test_bench_spring_virtual_end_to_end(tmp_path):
    out = tmp_path / "spring.csv"
    code, stdout, err = run_cli(["bench", "spring", "--virtual", "--speed", "max", "--cycles", "2", "--period", "1s",
                                 "--peak", "10k", "--seed", "3", "--out", out, "--json"])
    assert code == 0, err
    info = json.loads(stdout)
    assert info["device"] == "virtual" and info["protocol"]["name"] == "spring"
    assert info["run_s"] == 2.0 and info["dropped"] == 0
    run = load_run(out)
    # 2 s of 20 ms windows on the device's clock (--speed max): exactly 100, ending at 2 s.
    assert run.n_rows == 100
    assert run["time_s"] == pytest.approx(0.02 * np.arange(1, 101), abs=1e-12)
    s = run["stress_pa"]
    assert np.nanmax(s) == pytest.approx(10e3, rel=0.03) and np.nanmin(s) < 300  # the applied triangle
    f = run["frequency_hz"]
    assert np.corrcoef(s, f)[0, 1] > 0.95  # the readout follows the load
    assert load_run(out).metadata["protocol"] == {"name": "spring", "peak_pa": 10e3, "base_pa": 0.0, "cycles": 2,
                                             "period_s": 1.0, "duration_s": 2.0}


def test_bench_weights_virtual_end_to_end(tmp_path):
    out = tmp_path / "w.csv"
    code, stdout, err = run_cli(["bench", "weights", "--virtual", "--speed", "max",
                                 "--masses", "200g,400g", "--repeat", "2",
                                 "--settle-hold", "100ms", "--seed", "4", "--out", out, "--json", "--quiet"])
    assert code == 0, err
    info = json.loads(stdout)
    assert info["recorded"] == 10 and info["skipped"] == 0
    run = load_run(out)
    assert set(np.unique(run["load"])) == {0.0, 200.0, 400.0}
    # Every placement's rows carry its nominal force m·g (standard gravity) and stress over the sensor's area.
    area = run.metadata["sensor"]["area_m2"]
    k = run["load"] == 400.0
    assert run["force_nominal_n"][k] == pytest.approx(0.4 * 9.80665)
    assert run["stress_pa"][k] == pytest.approx(0.4 * 9.80665 / area)
    placements = (tmp_path / "w.placements.csv").read_text().splitlines()
    assert placements[0].startswith("load,sensor,reading") and len(placements) == 1 + 2 * 3  # 0, 200, 400 per cycle
    f = {ld: run["frequency_hz"][run["load"] == ld].mean() for ld in (0.0, 200.0, 400.0)}
    assert f[0.0] < f[200.0] < f[400.0]


def test_creep_protocol_virtual_holds_the_mass(tmp_path):
    plan = CreepPlan(mass_kg=0.2, hold_s=1.5, before_s=0.5, after_s=0.5)
    said = []
    res = run_protocol(plan, tmp_path / "c.csv", seed=5, announce=said.append, speed="max")
    assert res.result.ended == "duration" and res.result.run_s == pytest.approx(plan.duration_s)
    run = load_run(tmp_path / "c.csv")
    t, planned = run["time_s"], run["mass_planned_kg"]
    assert np.all(planned[(t > 0.6) & (t < 1.9)] == 0.2) and np.all(planned[t < 0.45] == 0.0)
    held = (t > 0.8) & (t < 1.9)
    assert run["frequency_hz"][held].mean() > 1.5 * run["frequency_hz"][t < 0.45].mean()
    assert len(said) == 2 and "place 200 g" in said[0] and "remove" in said[1]


@pytest.mark.parametrize("args, option", [
    (["bench", "spin", "--virtual"], "PROTOCOL"),
    (["bench", "spring"], "--port"),
    (["bench", "spring", "--virtual", "--port", "/dev/null"], "--port"),
    (["bench", "spring", "--virtual", "--cycles", "0"], "--cycles"),
    (["bench", "spring", "--virtual", "--peak", "10 kV"], "--peak"),
    (["bench", "weights", "--virtual", "--masses", "400g,200g"], "--masses"),
    (["bench", "weights", "--virtual", "--repeat", "0"], "--repeat"),
    (["bench", "creep", "--virtual", "--hold", "0s"], "--hold"),
    (["bench", "spring", "--virtual", "--window", "2.5ms"], "--window"),
    (["bench", "spring", "--virtual", "--speed", "fast"], "--speed"),
    (["bench", "spring", "--port", "/dev/null", "--speed", "max"], "--speed"),
])
def test_bad_input_is_one_line_naming_the_option(args, option, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and option in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())  # nothing recorded


def test_twin_missing_is_one_line(tmp_path, monkeypatch):
    # The twin's firmware looked for in an empty directory: what a machine without `make firmware` sees.
    monkeypatch.setenv("FSRLAB_FIRMWARE_BUILD", str(tmp_path / "no-build"))
    assert not twin_status()[0]
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["bench", "spring", "--twin"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--twin" in err and "--virtual" in err


class _FakeTwin:
    """A stand-in for ``fsrlab.virtual.twin.Twin`` with only the documented API (open, close, failure): the
    Python virtual device without its load cell, so neither the applied stress nor a force comes back."""

    def __init__(self, source, speed="realtime", seed=0, loadcell=None):
        from fsrlab.virtual.device import VirtualDevice

        assert speed in ("realtime", "max")
        self._dev = VirtualDevice(source, seed=seed, load_cell=None)

    def open(self):
        return self._dev.open()

    def close(self):
        self._dev.close()

    @property
    def failure(self):
        return self._dev.failure


def test_bench_twin_path_with_a_device_that_sends_no_reference(tmp_path, monkeypatch):
    import sys
    import types

    twin = types.ModuleType("fsrlab.virtual.twin")
    twin.Twin, twin.twin_available = _FakeTwin, lambda: (True, "")
    monkeypatch.setitem(sys.modules, "fsrlab.virtual.twin", twin)
    assert twin_status() == (True, "")
    out = tmp_path / "t.csv"
    code, stdout, err = run_cli(["bench", "spring", "--twin", "--cycles", "1", "--period", "1s",
                                 "--out", out, "--json"])
    assert code == 0, err
    assert json.loads(stdout)["device"] == "twin"
    run = load_run(out)
    # The stress comes from the bench's model (the planned triangle, mean over each 20 ms window).
    t, s = run["time_s"], run["stress_pa"]
    expected = SpringPlan(peak_pa=10e3, cycles=1, period_s=1.0).stress(t - 0.01)
    assert np.nanmax(np.abs(s - expected)) < 0.05 * 10e3
    assert "origin" in run.metadata and "--twin" in run.metadata["origin"]
    # And a weights run on the twin: places by the run's clock (the twin has no time_since_start).
    code, stdout, err = run_cli(["bench", "weights", "--twin", "--repeat", "1", "--settle-hold", "60ms", "--quiet",
                                 "--out", tmp_path / "w.csv", "--json"])
    assert code == 0, err
    assert json.loads(stdout)["recorded"] == 5
    w = load_run(tmp_path / "w.csv")
    f = [w["frequency_hz"][(w["load"] == ld) & (w["direction"] > 0)].mean() for ld in (0.0, 200.0, 400.0)]
    assert f[0] < f[1] < f[2]  # each placement's windows are of its own mass


def test_bench_sensor_preset_gives_the_virtual_fsr_its_area(tmp_path):
    # Reference: the preset's datasheet area (physics/presets.py), 12.7 mm diameter for the FSR 402.
    from fsrlab.physics.presets import SENSOR_PRESETS

    out = tmp_path / "s.csv"
    code, _, err = run_cli(["bench", "weights", "--virtual", "--sensor", "interlink-402", "--masses", "200g",
                            "--repeat", "1", "--settle-hold", "40ms", "--quiet", "--out", out])
    assert code == 0, err
    run = load_run(out)
    area = SENSOR_PRESETS["interlink-402"].area_m2
    assert area == pytest.approx(np.pi * (12.7e-3 / 2) ** 2, rel=1e-9)
    assert run.metadata["sensor"]["preset"] == "interlink-402" and run.metadata["sensor"]["area_m2"] == area
    k = run["load"] == 200.0
    assert run["stress_pa"][k] == pytest.approx(0.2 * 9.80665 / area)


def test_bench_on_a_port_prompts_and_records_with_the_load_cell(tmp_path):
    # Hardware path through a real pseudo-terminal: the Python virtual device served on its own (the
    # command sees only a port). Standard input is closed under pytest: every prompt is answered "go on".
    # Reference: stress_pa = force_n / area with the preset's area (data-format.md), the load cell's
    # calibration being the virtual HX711's own.
    from fsrlab.physics.presets import SENSOR_PRESETS
    from fsrlab.virtual.device import VirtualDevice
    from fsrlab.virtual.sources import PhysicsSource, StressProfile

    dev = VirtualDevice(PhysicsSource(StressProfile("triangle", 10e3, 1.0)), seed=6)
    port = dev.open()
    try:
        dev.load_cell.calibration().save(tmp_path / "lc.json")
        out = tmp_path / "hw.csv"
        code, stdout, err = run_cli(["bench", "spring", "--port", port, "--cycles", "1", "--period", "1s",
                                     "--sensor", "flexiforce-a201", "--loadcell", tmp_path / "lc.json",
                                     "--out", out, "--json"])
    finally:
        dev.close()
    assert code == 0, err
    assert "start the spring cycles: 1 × (from 0 kPa up to 10 kPa and back)" in err
    assert json.loads(stdout)["device"] == port
    run = load_run(out)
    ok = np.isfinite(run["force_n"])
    assert ok.mean() > 0.9
    area = SENSOR_PRESETS["flexiforce-a201"].area_m2
    assert run["stress_pa"][ok] == pytest.approx(run["force_n"][ok] / area)
    assert np.nanmax(run["force_n"]) > 0.5 * 10e3 * run.metadata["sensor"]["area_m2"]


def test_hardware_runs_in_real_time_only(tmp_path):
    with pytest.raises(ValueError, match="speed"):
        run_protocol(SpringPlan(), tmp_path / "s.csv", device="port", port="/dev/null", speed="max")
