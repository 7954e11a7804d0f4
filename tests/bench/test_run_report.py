"""The measurement report of a run: its numbers against independent references.

References:
- HE: hand-built runs whose unloading branch lies above the loading one by a known gap
  g·sin(πσ/σ_peak); eq. (13) is then g / Q(σ_peak) exactly (the gap's largest value, at σ_peak/2,
  is a sample of the run);
- RE1/RE2: the closed form of eq. (39) on the placements, computed here with the standard library
  (``statistics.stdev``, divisor n − 1 as the paper's tables), on the paper's own Table 4 and 5
  readings of sensor 1 (which the paper prints as RE1/RE2 = 2/1 % and 22/9 % at 200 g);
- ISO 376 b': |X₂ − X₁| / mean(X₁, X₂) of the first two series' deflections (ISO 376:2011, 7.5).
"""

from __future__ import annotations

import json
import statistics

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.bench.measurement import measure_run
from fsrlab.io.runwriter import write_run
from fsrlab.virtual.synthetic import triangle_stress

PEAK = 10e3


def _loop_run(path, gap_f=200.0, gap_v=0.15, cycles=3):
    """Triangle cycles; f and V0 linear in σ on loading, the unloading branch higher by gap·sin(πσ/peak)."""
    s = triangle_stress(cycles=cycles, peak_pa=PEAK, points_per_ramp=100)
    unloading = np.r_[False, np.diff(s) < 0]
    bump = np.sin(np.pi * s / PEAK)
    f = 1000 + 0.1 * s + np.where(unloading, gap_f * bump, 0.0)  # Q(σf) = 2000 Hz
    v = 0.1 + 9e-5 * s + np.where(unloading, gap_v * bump, 0.0)  # Q(σf) = 1.0 V
    write_run(path, {"time_s": 0.02 * np.arange(s.size), "stress_pa": s, "frequency_hz": f, "voltage_v": v})
    return path


def test_he_per_cycle_and_overall_against_the_known_gap(tmp_path):
    rep = measure_run(_loop_run(tmp_path / "loop.csv"), calibrate=False)
    h = {x.quantity: x for x in rep.hysteresis}
    assert h["frequency_hz"].percent == pytest.approx(100 * 200 / 2000, rel=1e-9)  # 10 %
    assert h["voltage_v"].percent == pytest.approx(100 * 0.15 / 1.0, rel=1e-9)  # 15 %
    assert len(h["frequency_hz"].cycles) == 3
    assert h["frequency_hz"].cycles == pytest.approx([10.0] * 3, rel=1e-9)
    assert h["voltage_v"].cycles == pytest.approx([15.0] * 3, rel=1e-9)
    assert rep.calibration is None and rep.calibration_reason


def test_he_of_a_loop_without_gap_is_zero(tmp_path):
    rep = measure_run(_loop_run(tmp_path / "flat.csv", gap_f=0.0, gap_v=0.0), calibrate=False)
    assert all(x.percent == pytest.approx(0.0, abs=1e-9) for x in rep.hysteresis)


# Sensor 1 of the paper's Tables 4 (kHz) and 5 (V) at 200 g and 400 g.
F200, F400 = [9, 8.8, 8.8, 9, 8.8], [10.5, 10.5, 10.6, 10.7, 10.7]
V200, V400 = [0.277, 0.248, 0.225, 0.225, 0.233], [0.418, 0.437, 0.365, 0.335, 0.38]


def _weights_run(path):
    """A dead-weight run: per cycle 0 → 200 g → 400 g → 200 g → 0, 4 steady windows per placement."""
    cols = {k: [] for k in ("time_s", "step", "load", "direction", "cycle", "force_nominal_n", "stress_pa",
                            "frequency_hz", "voltage_v")}
    step = 0
    for c in range(5):
        plan = [(0, 1, 1.0, 0.05), (200, 1, F200[c] * 1e3, V200[c]), (400, 1, F400[c] * 1e3, V400[c]),
                (200, -1, F200[c] * 1e3 + 300 + 10 * c, V200[c] + 0.05), (0, -1, 1.0 + 0.001 * c, 0.05)]
        for load, d, f, v in plan:
            for _ in range(4):
                cols["time_s"].append(0.02 * len(cols["time_s"]))
                cols["step"].append(step)
                cols["load"].append(load)
                cols["direction"].append(d)
                cols["cycle"].append(c)
                cols["force_nominal_n"].append(load * 1e-3 * 9.80665)
                cols["stress_pa"].append(load * 1e-3 * 9.80665 / 71.3e-6)
                cols["frequency_hz"].append(f)
                cols["voltage_v"].append(v)
            step += 1
    write_run(path, {k: np.asarray(v, dtype=float) for k, v in cols.items()})
    return path


def _eq39(x):
    m = statistics.fmean(x)
    return 100 * (max(x) - min(x)) / m, 100 * statistics.stdev(x) / m


def test_re_per_load_against_eq39_closed_form(tmp_path):
    rep = measure_run(_weights_run(tmp_path / "w.csv"), calibrate=False)
    got = {(p.quantity, p.load_g): p for p in rep.repeatability}
    assert set(got) == {("frequency_hz", 200.0), ("frequency_hz", 400.0), ("voltage_v", 200.0), ("voltage_v", 400.0)}
    for (q, load), x in {("frequency_hz", 200.0): [r * 1e3 for r in F200],
                         ("frequency_hz", 400.0): [r * 1e3 for r in F400],
                         ("voltage_v", 200.0): V200, ("voltage_v", 400.0): V400}.items():
        re1, re2 = _eq39(x)
        p = got[(q, load)]
        assert p.n == 5 and p.readings == pytest.approx(x)  # loading placements only: the unloading 200 g left out
        assert p.re1_percent == pytest.approx(re1, rel=1e-12) and p.re2_percent == pytest.approx(re2, rel=1e-12)
    # And the paper's printed (rounded) values for sensor 1 at 200 g: RE1/RE2 2/1 % (f), 22/9 % (V0).
    assert round(got[("frequency_hz", 200.0)].re1_percent) == 2 and round(got[("frequency_hz", 200.0)].re2_percent) == 1
    assert round(got[("voltage_v", 200.0)].re1_percent) == 22 and round(got[("voltage_v", 200.0)].re2_percent) == 9


def test_iso376_from_the_placements(tmp_path):
    rep = measure_run(_weights_run(tmp_path / "w.csv"), calibrate=False)
    r = rep.iso376
    assert r is not None and rep.iso376_reason is None
    assert r.forces_n == pytest.approx([0.2 * 9.80665, 0.4 * 9.80665])
    # b' at each force: the first two series' deflections (readings minus the series' zero before).
    x1 = np.array([F200[0], F400[0]]) * 1e3 - 1.0
    x2 = np.array([F200[1], F400[1]]) * 1e3 - 1.0
    assert r.b_prime == pytest.approx(100 * np.abs(x2 - x1) / ((x1 + x2) / 2), rel=1e-12)
    # One mounting position: no reproducibility b, hence no class; the report says what is missing.
    assert r.instrument_class == "incomplete" and "b" in r.missing
    # f0: the largest zero drift over a series, (i_f − i_0) / X_N with X_N the mean deflection at 400 g.
    xn = np.mean(np.array(F400) * 1e3 - 1.0)
    assert r.f0 == pytest.approx(100 * 0.004 / xn, rel=1e-9)


def test_a_run_without_placements_says_why(tmp_path):
    rep = measure_run(_loop_run(tmp_path / "loop.csv"), calibrate=False)
    assert rep.repeatability == [] and "fsrlab bench weights" in rep.repeatability_reason
    assert rep.iso376 is None and "ISO 376" in rep.iso376_reason


def test_report_cli_writes_html_json_and_pngs(tmp_path):
    run = _loop_run(tmp_path / "loop.csv")
    w = _weights_run(tmp_path / "w.csv")
    code, out, err = run_cli(["report", run, "--weights", w, "--out", tmp_path / "rep", "--json"])
    assert code == 0, err
    info = json.loads(out)
    assert info["hysteresis"][0]["hysteresis_error_percent"] == pytest.approx(10.0)
    assert info["calibration"]["model"] and info["estimate"]["hysteresis_error_percent"] is not None
    saved = json.loads((tmp_path / "rep" / "report.json").read_text())
    assert saved["repeatability"] == info["repeatability"]
    page = (tmp_path / "rep" / "index.html").read_text()
    for text in ("Table 3", "eq. 39", "ISO 376", "Calibration", "data:image/png;base64,"):
        assert text in page
    assert (tmp_path / "rep" / "loops.png").stat().st_size > 10_000


def test_report_cli_with_a_calibration_file(tmp_path):
    from fsrlab.calibration.document import save_calibration
    from fsrlab.calibration.runs import calibrate_runs

    run = _loop_run(tmp_path / "loop.csv")
    cal = save_calibration(calibrate_runs(run, compensate=True), tmp_path / "cal.json")
    code, out, err = run_cli(["report", run, "--cal", cal, "--out", tmp_path / "rep", "--json"])
    assert code == 0, err
    info = json.loads(out)
    assert info["calibration"]["source"].startswith("given")
    # The compensated estimate of this loop has less hysteresis than the raw frequency.
    assert info["estimate"]["hysteresis_error_percent"] < info["hysteresis"][0]["hysteresis_error_percent"]


@pytest.mark.parametrize("args, option", [
    (["report", "missing.csv", "--out", "r"], "RUN.csv"),
    (["report", "loop.csv", "--out", "r", "--cal", "nope.json"], "--cal"),
    (["report", "loop.csv", "--out", "loop.csv"], "--out"),
    (["report", "loop.csv", "--out", "r", "--weights", "nope.csv"], "--weights"),
])
def test_report_bad_input_is_one_line(args, option, tmp_path, monkeypatch):
    _loop_run(tmp_path / "loop.csv")
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and option in err


def test_report_of_a_file_that_is_not_a_run_is_one_line(tmp_path):
    p = tmp_path / "p.csv"
    p.write_text("load,sensor,reading\n200,1,9.0\n200,1,8.8\n")
    code, out, err = run_cli(["report", p, "--out", tmp_path / "r"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "p.csv" in err


def test_a_narrow_v0_span_is_said_to_limit_its_he(tmp_path):
    # Reference: the ADC step, protocol.ADC_V_PER_COUNT = 5 V / 1024 ≈ 4.88 mV; a 0.9 V span is ~184 steps
    # (no note), a 0.05 V span ~10 steps (HE moves in steps of ~10 percentage points).
    from fsrlab.hardware import ADC_V_PER_COUNT

    rep = measure_run(_loop_run(tmp_path / "wide.csv"), calibrate=False)
    assert {h.quantity: h.note for h in rep.hysteresis}["voltage_v"] is None
    s = triangle_stress(cycles=2, peak_pa=PEAK, points_per_ramp=50)
    v = 0.05 + 5e-6 * s  # 0.05 .. 0.10 V
    write_run(tmp_path / "narrow.csv", {"time_s": 0.02 * np.arange(s.size), "stress_pa": s,
                                        "frequency_hz": 1000 + 0.1 * s, "voltage_v": v})
    rep = measure_run(tmp_path / "narrow.csv", calibrate=False)
    note = {h.quantity: h.note for h in rep.hysteresis}["voltage_v"]
    assert note is not None and f"spans {0.05 / ADC_V_PER_COUNT:.0f} steps" in note


def test_placements_file_of_table4_gives_the_printed_re(tmp_path, paper):
    # Reference: the paper's printed Table 4 RE1/RE2 per sensor (integers: a recomputed value matches
    # when it rounds to the printed one), from its own printed readings (examples/repeatability.csv).
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    rep = measure_run(_loop_run(tmp_path / "loop.csv"), placements=root / "examples" / "repeatability.csv",
                      calibrate=False)
    t4 = paper["table4_repeatability_capacitive_kHz"]
    got = {(p.load_g, p.sensor): p for p in rep.repeatability}
    assert len(got) == 8
    for load in ("200g", "400g"):
        for k in range(4):
            p = got[(float(load[:-1]), k + 1)]
            assert p.n == 5 and p.readings == pytest.approx(t4[load]["readings"][k])
            assert round(p.re1_percent) == t4[load]["RE1_percent"][k]
            assert round(p.re2_percent) == t4[load]["RE2_percent"][k]
    assert rep.iso376 is None and "placements file" in rep.iso376_reason


def test_creep_part_is_fsrlab_creeps_numbers_and_says_why_when_absent(tmp_path):
    # Reference: metrics.creep.creep_of_run (fsrlab creep) on examples/creep.csv, whose holds are 2 N
    # for 30 s and 3.2 N for 45 s (examples/README.md).
    from pathlib import Path

    from fsrlab.io.runformat import load_run
    from fsrlab.metrics.creep import creep_of_run

    path = Path(__file__).resolve().parents[2] / "examples" / "creep.csv"
    rep = measure_run(path, calibrate=False)
    f = [c for c in rep.creep if c["quantity"] == "frequency_hz"]
    assert [round(c["level"], 1) for c in f] == [2.0, 3.2] and [round(c["duration_s"]) for c in f] == [30, 45]
    ref = creep_of_run(load_run(path), x="frequency_hz")
    assert [c["drift_percent_per_decade"] for c in f] == [h.drift_percent_per_decade for h in ref.holds]
    rep = measure_run(_loop_run(tmp_path / "loop.csv"), calibrate=False)
    assert rep.creep == [] and "fsrlab bench creep" in rep.creep_reason
