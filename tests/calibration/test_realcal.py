"""Calibration on realistic FSR recordings: families, lag, dead zone, causal compensation, uncertainty (the model
families, the play operators and the lag criteria on closed forms: test_models.py, test_play.py, test_alignment.py).

How the data were made: :func:`fsrlab.virtual.handloaded.fsr_bench_run` simulates an FSR in a
voltage divider (R_M = 10 kΩ, 5 V, 10-bit ADC averaged over 20 ms rows) under a load cell read by
an HX711. The sensor is a Bouc–Wen hysteresis (not fsrlab's play operators), with two creep time
constants, a dead zone below 3 % of full scale, a saturating power-law conductance, an electrical
lag, noise on both channels and a load-cell offset of −20 to −40 g drifting by up to ±10 g. The
"hand" runs are irregular turning points of every size (1–100 % of full scale), holds and tremor;
the "motor" run is one clean 15 s/15 s triangle. Where a test uses other data it says so.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.calibration.document import load_calibration, save_calibration
from fsrlab.virtual.handloaded import fsr_bench_run
from fsrlab.calibration.apply import apply_calibration
from fsrlab.calibration.fit import calibrate_run
from fsrlab.calibration.estimator import live_estimator
from fsrlab.io.runformat import load_run
from fsrlab.io.runwriter import write_run

FS_N = 20.0  # the generator's full scale [N]


@pytest.fixture(scope="module")
def hand(tmp_path_factory):
    """A 120 s hand-loaded calibration run and two held-out runs (same bench: HX711 at 80 SPS)."""
    d = tmp_path_factory.mktemp("hand")
    fsr_bench_run("hand", seed=1, duration_s=120, reference_sps=80).write(d / "cal.csv")
    for s in (21, 22):
        fsr_bench_run("hand", seed=s, reference_sps=80).write(d / f"held{s}.csv")
    fsr_bench_run("motor", seed=3, reference_sps=80).write(d / "motor.csv")
    return d


@pytest.fixture(scope="module")
def cal(hand):
    return calibrate_run(hand / "cal.csv", x="voltage_v", compensate=True)


def test_generator_is_deterministic_and_shows_what_real_recordings_show():
    a, b = fsr_bench_run("hand", seed=4), fsr_bench_run("hand", seed=4)
    for k in a.columns:
        np.testing.assert_array_equal(a.columns[k], b.columns[k])
    v, f, truth = a.columns["voltage_v"], a.columns["force_n"], a.truth["force_n"]
    lsb = 5.0 / 1023
    np.testing.assert_allclose(v / lsb, np.round(v / lsb), atol=1e-9)  # 10-bit ADC steps
    assert np.all(v[truth < 0.01 * FS_N] < 2 * lsb)  # dead zone: no reading below activation
    assert v.max() < 0.8 * 5.0  # saturation: full scale reads far below the supply
    rest = truth == 0
    # The load cell's offset at no load: drawn from -20..-40 g (drift ±10 g), i.e. -0.1..-0.5 N.
    assert -0.5 < np.nanmedian(f[rest]) < -0.1


def test_hand_loaded_run_calibrates_with_compensate_from_the_command_line(hand, tmp_path):
    # This run used to stop with "cycles: the branches share no stress range".
    code, out, err = run_cli(["calibrate", hand / "cal.csv", "--x", "voltage_v", "--method", "cv", "--compensate", "-o",
                              tmp_path / "cal.json", "--json"])
    assert code == 0, err
    d = json.loads(out)
    assert {"model", "lag_s", "cv_rmse", "cv_rmse_percent_fs", "candidates", "hysteresis_error_before_percent",
            "hysteresis_error_after_percent"} <= set(d)
    assert d["reference"] == "force_n" and d["unit"] == "N"  # force without a sensor area
    assert d["cv_rmse_percent_fs"] == pytest.approx(100 * d["cv_rmse"] / d["full_scale"])
    names = {c["model"] for c in d["candidates"]}
    assert {"polynomial-1", "polynomial-5", "conductance-power", "conductance-polynomial-2", "power"} <= names
    assert d["hysteresis_error_after_percent"] < d["hysteresis_error_before_percent"]
    code, out, err = run_cli(["apply", tmp_path / "cal.json", hand / "held21.csv", "-o", tmp_path / "e.csv", "--json"])
    assert code == 0, err
    e = load_run(tmp_path / "e.csv")
    assert {"force_n_estimate", "force_n_uncertainty", "in_range"} <= set(e.columns)
    assert e.units["force_n_estimate"] == "N"
    assert json.loads(out)["missing_reasons"]["below_activation"] > 0


def test_model_choice_is_the_smallest_cv_error(cal):
    # Property of --model auto: the chosen candidate's error is within 1 % of the smallest.
    errs = {c["model"]: c["cv_rmse"] for c in cal.candidates}
    assert errs[cal.model_name] <= 1.01 * min(errs.values())


def test_compensation_lowers_the_cross_validated_error(cal):
    c = cal.extra["compensation_candidates"]
    # Reference: the plain model's out-of-fold error on the same folds; the Bouc–Wen loop is ~±8 %.
    assert cal.cv_rmse < 0.6 * c["plain"]


def _tared(cal, run):
    """The held-out run's reference aligned by the calibration's lag, and as recorded."""
    from fsrlab.calibration.alignment import shift_reference

    y = run["force_n"]
    return shift_reference(run["time_s"], y, cal.lag_s), y


def _rms_percent(estimate, reference):
    ok = np.isfinite(estimate) & np.isfinite(reference)
    return 100 * np.sqrt(np.mean((estimate[ok] - reference[ok]) ** 2)) / FS_N


def test_held_out_error_compensated_beats_plain_and_the_best_polynomial(cal, hand):
    from fsrlab.calibration.result import calibrate

    c = load_run(hand / "cal.csv")
    fit = ~cal.floor.below(c["voltage_v"]) & np.isfinite(c["force_n"])
    y = c["force_n"]  # the plain polynomials: the reference as recorded (no lag)
    polys = [calibrate(c["voltage_v"][fit], y[fit], degree=d) for d in range(1, 6)]
    for s in (21, 22):
        run = load_run(hand / f"held{s}.csv")
        ref, unaligned = _tared(cal, run)
        comp = apply_calibration(cal, run)["force_n_estimate"]
        plain = apply_calibration(cal, run, compensation=False)["force_n_estimate"]
        rows = np.isfinite(comp)
        best_poly = min(_rms_percent(np.where(rows, p(run["voltage_v"]), np.nan), unaligned) for p in polys)
        # Reference: data from a different hysteresis model (Bouc–Wen); the aim is 0.6 (docs/performance.md).
        assert _rms_percent(comp, ref) < 0.7 * best_poly
        assert _rms_percent(comp, ref) < _rms_percent(plain, ref)


def test_offline_apply_equals_stepping_the_live_estimator(cal, hand):
    run = load_run(hand / "held22.csv")
    x = run["voltage_v"].copy()
    x[[5, 6, 300]] = np.nan  # gaps: the memory is kept
    x[400] = 50.0  # beyond the margin: no estimate, memory kept
    est = apply_calibration(cal, write_and_load({"time_s": run["time_s"], "voltage_v": x, "force_n": run["force_n"]},
                                                run.metadata, hand / "gaps.csv"))
    live = live_estimator(cal)
    assert live.reference == "force_n" and live.x == "voltage_v"
    steps = [live.step(None if np.isnan(v) else float(v)) for v in x]
    y = np.array([np.nan if s[0] is None else s[0] for s in steps])
    u = np.array([np.nan if s[1] is None else s[1] for s in steps])
    flag = np.array([s[2] for s in steps], dtype=float)
    np.testing.assert_allclose(y, est["force_n_estimate"], rtol=1e-12, atol=1e-12 * FS_N)
    np.testing.assert_allclose(u, est["force_n_uncertainty"], rtol=1e-12)
    np.testing.assert_array_equal(flag, np.nan_to_num(est["in_range"]))
    assert np.isnan(y[[5, 6, 300, 400]]).all()
    at_floor = cal.floor.below(x) & np.isfinite(x)
    assert at_floor.any() and np.isnan(y[at_floor]).all()  # below activation: no number


def write_and_load(columns, metadata, path):
    write_run(path, columns, metadata, overwrite=True)
    return load_run(path)


def test_calibration_file_round_trips(cal, hand, tmp_path):
    p = save_calibration(cal, tmp_path / "c.json")
    back = load_calibration(p)
    run = load_run(hand / "held21.csv")
    a, b = apply_calibration(cal, run), apply_calibration(back, run)
    np.testing.assert_array_equal(a["force_n_estimate"], b["force_n_estimate"])
    np.testing.assert_array_equal(a["force_n_uncertainty"], b["force_n_uncertainty"])
    assert back.model_name == cal.model_name and back.lag_s == cal.lag_s and back.floor == cal.floor


def test_uncertainty_covers_the_held_out_errors(cal, hand):
    run = load_run(hand / "held21.csv")
    est = apply_calibration(cal, run)
    ref = _tared(cal, run)[0]
    e, u = est["force_n_estimate"], est["force_n_uncertainty"]
    ok = np.isfinite(e) & np.isfinite(ref)
    assert np.all(u[ok] > 0)
    # A standard uncertainty: about 95 % of errors within 2u if it were complete. It comes from the
    # calibration run's own cross-validation, which cannot see how one run differs from the next
    # (load-cell offset and drift, HX711 phase): on held-out runs the RMS error is about 1.3 times
    # the cross-validated one (docs/calibration.md, "Limits"), so about 75-85 % are covered. The
    # test holds that documented level; a table that ignored level and direction would cover less.
    covered = np.mean(np.abs(e[ok] - ref[ok]) <= 2 * u[ok])
    assert 0.7 < covered <= 1.0


def test_clean_motor_cycle_hysteresis_error_falls(cal, hand):
    from fsrlab.calibration.readout import hysteresis_of_run

    run = load_run(hand / "motor.csv")
    est = apply_calibration(cal, run)
    plain = apply_calibration(cal, run, compensation=False)
    he_after = hysteresis_of_run(est, "force_n_estimate").percent
    he_before = hysteresis_of_run(plain, "force_n_estimate").percent
    # Reference: eq. (13) on the same run; the generator's loop is ±8 % of the effective force.
    assert he_before > 5
    assert he_after < 0.5 * he_before


def test_lag_follows_a_delay_added_by_construction(hand):
    run = load_run(hand / "cal.csv")
    base = calibrate_run(run, x="voltage_v").lag_s
    k = 3  # delay the readout by 3 rows (60 ms): the lag must grow by 60 ms
    v = np.concatenate([np.full(k, run["voltage_v"][0]), run["voltage_v"][:-k]])
    delayed = write_and_load({"time_s": run["time_s"], "voltage_v": v, "force_n": run["force_n"]}, run.metadata,
                             hand / "delayed.csv")
    dt = float(np.median(np.diff(run["time_s"])))
    assert calibrate_run(delayed, x="voltage_v").lag_s - base == pytest.approx(k * dt, abs=0.5 * dt)


def test_force_reference_without_area_in_hysteresis(hand, tmp_path):
    run = load_run(hand / "motor.csv")
    meta = {k: v for k, v in run.metadata.items() if k != "sensor"}  # no sensor area
    p = tmp_path / "noarea.csv"
    write_run(p, run.columns, meta)
    code, out, err = run_cli(["hysteresis", p, "--quantity", "voltage_v", "--json"])
    assert code == 0, err
    assert json.loads(out)["reference"] == "force_n"
    code, out, err = run_cli(["hysteresis", p, "--quantity", "voltage_v", "--unit", "g"])
    assert code == 0 and "Fd (g)" in out
    code, _, err = run_cli(["hysteresis", p, "--quantity", "voltage_v", "--unit", "kPa"])
    assert code == 2 and "--unit" in err


# ---- Bad input: one line naming the problem, exit 2 ----

def _bad(tmp_path, columns, meta=None, args=()):
    p = tmp_path / "bad.csv"
    write_run(p, columns, meta or {}, overwrite=True)
    code, out, err = run_cli(["calibrate", p, "--x", "voltage_v", "--method", "cv", *args])
    assert code == 2 and out == "" and err.count("\n") == 1, err
    return err


def test_bad_input_run_without_reference(tmp_path):
    err = _bad(tmp_path, {"time_s": np.arange(100.0), "voltage_v": np.linspace(0, 3, 100)})
    assert "no reference" in err and "force_n" in err


def test_bad_input_readout_that_does_not_respond(tmp_path):
    rng = np.random.default_rng(1)
    err = _bad(tmp_path, {"time_s": np.arange(200.0), "voltage_v": np.round(2 + 0.001 * rng.standard_normal(200), 2),
                          "force_n": np.linspace(0, 20, 200)})
    assert "voltage_v" in err and "respond" in err


def test_bad_input_fewer_readings_than_the_model_needs(tmp_path):
    err = _bad(tmp_path, {"voltage_v": np.array([1.0, 2.0, 3.0, 4.0]), "force_n": np.array([1.0, 2.5, 4.0, 5.0])},
               args=("--model", "polynomial-5"))
    assert "--model" in err and "readings" in err


def test_bad_input_lag_search_without_a_minimum(hand, tmp_path):
    run = load_run(hand / "cal.csv")
    k = 25  # the readout 25 rows (0.5 s) behind: beyond the ±0.25 s search
    v = np.concatenate([np.full(k, run["voltage_v"][0]), run["voltage_v"][:-k]])
    err = _bad(tmp_path, {"time_s": run["time_s"], "voltage_v": v, "force_n": run["force_n"]}, run.metadata)
    assert "lag" in err and "search range" in err


def test_bad_input_reference_mostly_negative(hand, tmp_path):
    run = load_run(hand / "held21.csv")
    err = _bad(tmp_path, {"time_s": run["time_s"], "voltage_v": run["voltage_v"], "force_n": -run["force_n"]},
               run.metadata)
    assert "force_n" in err and "mostly negative" in err


def test_bad_input_too_few_readings_to_compensate(tmp_path):
    f = np.linspace(0, 20, 40)
    err = _bad(tmp_path, {"voltage_v": 0.1 * f + 0.05, "force_n": f}, args=("--compensate",))
    assert "compensate" in err and "60 readings" in err


def test_calibration_file_of_an_earlier_fsrlab_still_applies_and_steps(runs):
    # examples/calibration.json was written by an earlier fsrlab (polynomial + branch compensation, no
    # lag, floor, uncertainty): it loads, applies offline with its branch method, and steps live
    # as its polynomial (the branch method needs the whole run).
    from pathlib import Path

    cal = load_calibration(Path(__file__).resolve().parents[2] / "examples" / "calibration.json")
    assert cal.memory is None and cal.floor is None and cal.uncertainty is None and cal.lag_s == 0.0
    other = load_run(runs / "other.csv")
    est = apply_calibration(cal, other)
    assert est.metadata["calibration"]["method"] == "direction-aware compensation"
    assert np.isnan(est["stress_pa_uncertainty"]).all()
    live = live_estimator(cal)
    f = float(other["frequency_hz"][50])
    y, u, inside = live.step(f)
    assert y == pytest.approx(float(cal.model(f)), rel=1e-12) and u is None and inside


def test_stress_reference_from_force_and_area(hand):
    # The hand-loaded runs' sidecar gives a sensor area of 1e-4 m²: stress = force / area.
    run = load_run(hand / "held21.csv")
    cal = calibrate_run(run, x="voltage_v", reference="stress_pa", lag=0)
    force = calibrate_run(run, x="voltage_v", reference="force_n", lag=0)
    assert cal.y_name == "stress_pa" and cal.y_unit == "Pa"
    assert cal.model_name == force.model_name
    np.testing.assert_allclose(cal(run["voltage_v"][100:110]), 1e4 * force(run["voltage_v"][100:110]), rtol=1e-9)


def test_calibrate_shows_force_errors_in_grams(hand):
    code, out, err = run_cli(["calibrate", hand / "held21.csv", "--x", "voltage_v", "--method", "cv", "--unit", "g",
                              "--lag", "0"])
    assert code == 0, err
    assert "CV RMSE (g)" in out
    code, out, err = run_cli(["calibrate", hand / "held21.csv", "--x", "voltage_v", "--method", "cv", "--unit", "kPa"])
    assert code == 2 and out == "" and "--unit" in err


def test_divider_read_in_adc_counts_gives_the_same_conductance(hand):
    # The same recording with the readout as analogRead counts (V·1023/5) and the sidecar naming
    # that column: the conductance (closed form of the divider) and the calibration are the same.
    from fsrlab.calibration.models import transform_from_metadata

    run = load_run(hand / "held21.csv")
    meta = dict(run.metadata, divider=dict(run.metadata["divider"], column="a0_count"))
    counts = np.round(run["voltage_v"] * 1023 / 5.0)
    tv = transform_from_metadata("voltage_v", meta)
    tc = transform_from_metadata("a0_count", meta)
    np.testing.assert_allclose(tc(counts), tv(run["voltage_v"]), rtol=1e-9)
    assert transform_from_metadata("a0_count", run.metadata) is None  # a column the sidecar does not name
    p = write_and_load({"time_s": run["time_s"], "a0_count": counts, "force_n": run["force_n"]}, meta,
                       hand / "counts.csv")
    a = calibrate_run(p, x="a0_count", lag=0, model="conductance-power")
    b = calibrate_run(run, x="voltage_v", lag=0, model="conductance-power")
    np.testing.assert_allclose(a(counts[200:210]), b(run["voltage_v"][200:210]), rtol=1e-9)


def test_plain_estimate_has_its_own_larger_uncertainty(cal, hand):
    # Reference: the plain model's cross-validated error is 3x the compensated one (test above), so
    # its uncertainty must be larger on average, not the compensated table's.
    run = load_run(hand / "held21.csv")
    comp = apply_calibration(cal, run)["force_n_uncertainty"]
    plain = apply_calibration(cal, run, compensation=False)["force_n_uncertainty"]
    assert np.nanmean(plain) > 1.5 * np.nanmean(comp)
    back = load_calibration(save_calibration(cal, hand / "u.json"))
    np.testing.assert_array_equal(apply_calibration(back, run, compensation=False)["force_n_uncertainty"], plain)


