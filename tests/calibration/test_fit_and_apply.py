"""The run → calibration → estimate pipeline (fsrlab.calibration.fit).

References, by test: the array-level functions called by hand with groups derived by
construction (triangle stress: each cycle is 2·points_per_ramp readings, the bottom turning point
closing the previous cycle); the calibration's own polynomial evaluated row by row;
LM555Circuit.decode called directly per range, and the closed-form astable (lm555.astable) that
made the readings; a calibration file written by hand in the earlier layout. Synthetic runs come
from fsrlab.virtual.synthetic.synthetic_run (VirtualFSR -> lm555.astable, R = 10 kΩ, ideal D1 ->
62.5 ns timer quantization, 0.2 % frequency noise).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from fsrlab.calibration.result import calibrate
from fsrlab.calibration.document import load_calibration, save_calibration
from fsrlab.physics.history import branch_directions, cycle_numbers
from fsrlab.metrics.cycles import run_hysteresis
from fsrlab.calibration.estimator import live_estimator
from fsrlab.calibration.apply import apply_calibration
from fsrlab.calibration.fit import calibrate_run
from fsrlab.calibration.readout import (
    decode_capacitance, hysteresis_of_run, run_cycles, run_directions, run_groups, run_readout
)
from fsrlab.virtual.synthetic import synthetic_run
from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.io.runformat import load_run
from fsrlab.io.runwriter import write_run

#: The five lines a Python user writes to calibrate one run and apply it to another.
SNIPPET = '''\
from fsrlab.io.runformat import load_run
from fsrlab.calibration.fit import calibrate_run
from fsrlab.calibration.apply import apply_calibration
cal = calibrate_run(load_run("bench.csv"), x="frequency_hz", compensate=True)
est = apply_calibration(cal, load_run("other.csv"))["stress_pa_estimate"]
'''


def _minimal(path, columns):
    """A run with the given columns only and no sidecar (docs/data-format.md, minimal run)."""
    write_run(path, columns)
    (path.parent / (path.stem + ".meta.json")).unlink()
    return load_run(path)


def test_snippet_runs_in_five_lines(runs, monkeypatch):
    assert len(SNIPPET.strip().splitlines()) <= 5
    monkeypatch.chdir(runs)
    scope: dict = {}
    exec(SNIPPET, scope)
    est, other = scope["est"], load_run(runs / "other.csv")
    assert est.shape == (other.n_rows,)
    # The compensated estimate follows the reference on a run the calibration never saw.
    assert np.sqrt(np.nanmean((est - other["stress_pa"]) ** 2)) < 0.05 * np.ptp(other["stress_pa"])


@settings(max_examples=15, deadline=None)
@given(st.integers(2, 4), st.integers(20, 60), st.integers(0, 2**16))
def test_calibrate_run_equals_calibrate_with_groups_derived_by_hand(cycles, per_ramp, seed):
    # Property: without direction and cycle columns, calibrate_run's groups are the run's cycles
    # found from the stress, and the fit is the one calibrate gives with those groups.
    import tempfile
    from pathlib import Path

    c = synthetic_run(cycles=cycles, points_per_ramp=per_ramp, seed=seed).columns
    with tempfile.TemporaryDirectory() as d:
        run = _minimal(Path(d) / "min.csv", {"stress_pa": c["stress_pa"], "frequency_hz": c["frequency_hz"]})
        cal = calibrate_run(run, x="frequency_hz", degree="auto", folds=3, lag=0)
    n = c["stress_pa"].size
    groups = np.maximum(np.arange(n) - 1, 0) // (2 * per_ramp)  # by construction of the triangles
    ref = calibrate(c["frequency_hz"], c["stress_pa"], degree="auto", groups=groups, folds=3)
    np.testing.assert_array_equal(cal.model.coefficients, ref.model.coefficients)
    assert cal.cv.groups == cycles and cal.degree == ref.degree


def test_calibrate_run_uses_the_cycle_column_and_records_units(runs):
    run = load_run(runs / "bench.csv")
    cal = calibrate_run(run, x="voltage_v", degree="auto", lag=0, model="polynomial")
    ref = calibrate(run["voltage_v"], run["stress_pa"], groups=run["cycle"])
    np.testing.assert_array_equal(cal.model.coefficients, ref.model.coefficients)
    assert (cal.x_name, cal.x_unit, cal.y_name, cal.y_unit) == ("voltage_v", "V", "stress_pa", "Pa")
    assert cal.source == str(runs / "bench.csv") and cal.circuit is None


def test_directions_and_cycles_come_from_columns_else_from_stress(runs):
    run = load_run(runs / "bench.csv")
    np.testing.assert_array_equal(run_directions(run), run["direction"])
    np.testing.assert_array_equal(run_cycles(run), run["cycle"])
    np.testing.assert_array_equal(run_groups(run), run["cycle"])
    stress = run["stress_pa"].copy()
    stress[[5, 77]] = np.nan  # rows without a reference take no part
    bare = _minimal(runs / "bare.csv", {"stress_pa": stress, "frequency_hz": run["frequency_hz"]})
    lab = run_directions(bare)
    ok = np.isfinite(stress)
    np.testing.assert_array_equal(lab[ok], branch_directions(stress[ok]))
    assert lab[5] == lab[77] == 0
    np.testing.assert_array_equal(run_cycles(bare), cycle_numbers(lab))
    # The hysteresis error reads the same rule.
    res = hysteresis_of_run(bare, "frequency_hz")
    ref = run_hysteresis(stress, run["frequency_hz"])
    assert res.percent == ref.percent and res.cycle_numbers == ref.cycle_numbers


def test_apply_round_trip_estimate_is_the_polynomial_row_by_row(runs, tmp_path):
    cal = calibrate_run(runs / "bench.csv", x="frequency_hz", degree=3)
    other = load_run(runs / "other.csv")
    f = other["frequency_hz"].copy()
    f[[0, 10, 200]] = np.nan  # missing readings
    holey = _minimal(tmp_path / "holey.csv", {"stress_pa": other["stress_pa"], "frequency_hz": f})
    est = apply_calibration(cal, holey)
    e = est["stress_pa_estimate"]
    for i in range(f.size):
        if np.isnan(f[i]):
            assert np.isnan(e[i])
        else:
            assert e[i] == cal(f[i])
    # Reference independent of the calibration object: numpy's least-squares cubic through the calibration
    # run (the synthetic run has no lag and no floor, so calibrate_run fits exactly that); both solve the
    # same problem, so they agree to the conditioning of the fit (1e-15 of the stress span seen, 1e-9 allowed).
    bench = load_run(runs / "bench.csv")
    both = np.isfinite(bench["frequency_hz"]) & np.isfinite(bench["stress_pa"])
    cubic = np.polynomial.Polynomial.fit(bench["frequency_hz"][both], bench["stress_pa"][both], 3)
    given = ~np.isnan(f)
    assert cal.lag_s == 0 and cal.floor is None
    np.testing.assert_allclose(e[given], cubic(f[given]), rtol=0, atol=1e-9 * np.ptp(bench["stress_pa"]))
    assert est.units["stress_pa_estimate"] == "Pa"
    meta = est.metadata["calibration"]
    inside = (f >= cal.x_range[0]) & (f <= cal.x_range[1])
    counts = {"estimated": f.size - 3, "in_range": int(inside.sum()), "out_of_range": f.size - 3 - int(inside.sum()),
              "extrapolated": f.size - 3 - int(inside.sum()),
              "missing": 3, "no_readout": 3, "not_decodable": 0, "beyond_margin": 0, "below_activation": 0}
    assert meta == {"x": "frequency_hz", "reference": "stress_pa", "model": "polynomial-3", "lag_s": cal.lag_s,
                    "degree": 3, "method": "polynomial of degree 3",
                    "data_fingerprint": cal.data_fingerprint, "created": cal.created,
                    "readout_range": list(cal.x_range), "margin": 0.1, "counts": counts}
    np.testing.assert_array_equal(est["in_range"], np.where(np.isnan(f), np.nan, inside))
    # Written and read back, the estimate is the same (the format stores shortest round-trip numbers).
    write_run(tmp_path / "est.csv", est.columns, est.metadata)
    back = load_run(tmp_path / "est.csv")
    np.testing.assert_array_equal(back["stress_pa_estimate"], e)
    assert back.metadata["calibration"] == meta and np.array_equal(back["frequency_hz"], f, equal_nan=True)


def test_apply_uses_the_compensation_unless_told_not_to(runs, tmp_path):
    cal = calibrate_run(runs / "bench.csv", x="frequency_hz", degree=3, compensate=True)
    before, after = cal.compensation_he_percent
    assert before / after >= 3
    other = load_run(runs / "other.csv")
    est = apply_calibration(cal, other)
    # The compensation is causal; offline it equals stepping the live estimator row by row.
    live = live_estimator(cal)
    stepped = [live.step(v)[0] for v in other["frequency_hz"]]
    np.testing.assert_allclose(est["stress_pa_estimate"], [np.nan if v is None else v for v in stepped], rtol=1e-12)
    # Clean whole cycles: the grouped CV keeps the causal branches (tests/calibration/test_compensation_choice.py).
    assert cal.extra["compensation_choice"]["chosen"] == "branches (causal)" and cal.memory is None
    assert est.metadata["calibration"]["method"].startswith("causal branch compensation")
    plain = apply_calibration(cal, other, compensation=False)
    np.testing.assert_array_equal(plain["stress_pa_estimate"], cal(other["frequency_hz"]))
    # Saved and loaded, the calibration gives the same estimate and names its file.
    p = save_calibration(cal, tmp_path / "cal.json")
    again = apply_calibration(load_calibration(p), other)
    np.testing.assert_array_equal(again["stress_pa_estimate"], est["stress_pa_estimate"])
    assert again.metadata["calibration"]["file"] == str(p)


def _ranged_run(path, circuit, with_range=True):
    """Readings made by the closed-form astable: C_off switched in on odd rows (range 1)."""
    from fsrlab.circuits.lm555 import astable

    n = 40
    c_fsr = np.linspace(0.5e-9, 4e-9, n)
    r_fsr = np.linspace(400e3, 60e3, n)
    rng = (np.arange(n) % 2).astype(float)
    c_off = np.where(rng == 1, circuit.c_off_farad, 0.0) if with_range else circuit.c_off_farad
    osc = astable(circuit.r_ohm, r_fsr, c_fsr, c_off_farad=c_off, diode=circuit.diode)
    cols = {"stress_pa": np.linspace(0, 40e3, n), "frequency_hz": osc.frequency_hz, "duty_cycle": osc.duty_cycle}
    if with_range:
        cols["range"] = rng
    write_run(path, cols, {"circuit": circuit.to_dict()})
    return load_run(path), c_fsr


def test_range_aware_decode_matches_the_circuit_decode_row_by_row(tmp_path):
    circuit = LM555Circuit(r_ohm=10e3, c_off_farad=2.2e-9, diode=True)
    run, c_true = _ranged_run(tmp_path / "ranged.csv", circuit)
    values, used = run_readout(run, "c_fsr_farad")
    assert used == circuit  # from the sidecar
    for i, r in enumerate(run["range"]):
        ref = (circuit if r == 1 else circuit.replace(c_off_farad=0.0)).decode(
            run["frequency_hz"][i], run["duty_cycle"][i])
        assert values[i] == pytest.approx(float(ref.c_fsr_farad), rel=1e-12)
    np.testing.assert_allclose(values, c_true, rtol=1e-9)  # the closed form that made the readings
    # Ignoring the range would subtract C_off from the range-0 rows too (C_FSR off by C_off, or
    # negative and so NaN).
    wrong = decode_capacitance(run["frequency_hz"], run["duty_cycle"], circuit)
    off = wrong[::2] - c_true[::2]
    assert np.all(np.isnan(off) | (np.abs(off) > 0.5 * circuit.c_off_farad)) and np.isfinite(off).any()
    np.testing.assert_allclose(wrong[1::2], c_true[1::2], rtol=1e-9)


def test_without_range_column_c_off_applies_to_every_row(tmp_path):
    circuit = LM555Circuit(r_ohm=10e3, c_off_farad=1e-9, diode=True)
    run, c_true = _ranged_run(tmp_path / "fixed.csv", circuit, with_range=False)
    values, _ = run_readout(run, "c_fsr_farad")
    np.testing.assert_allclose(values, c_true, rtol=1e-9)


def test_decode_range_values_checked_and_missing_range_is_nan():
    c = LM555Circuit(r_ohm=10e3, c_off_farad=1e-9, diode=True)
    osc = c.astable(200e3, 1e-9)
    f, dc = np.full(3, osc.frequency_hz), np.full(3, osc.duty_cycle)
    out = decode_capacitance(f, dc, c, [1, np.nan, 1])
    assert out[0] == pytest.approx(1e-9, rel=1e-9) and np.isnan(out[1])
    with pytest.raises(ValueError, match="range_"):
        decode_capacitance(f, dc, c, [0, 2, 1])


def test_calibrate_on_decoded_capacitance_records_the_circuit(tmp_path):
    sidecar = LM555Circuit(r_ohm=10e3, c_off_farad=2.2e-9, diode=True)
    run, c_true = _ranged_run(tmp_path / "ranged.csv", sidecar)
    cal = calibrate_run(run, x="c_fsr_farad", degree=2, lag=0)
    assert cal.circuit == sidecar and cal.x_unit == "F"
    ref = calibrate(run_readout(run, "c_fsr_farad")[0], run["stress_pa"], degree=2)
    np.testing.assert_array_equal(cal.model.coefficients, ref.model.coefficients)
    # A circuit given by the caller overrides the sidecar's.
    other = sidecar.replace(r_ohm=12e3)
    assert calibrate_run(run, x="c_fsr_farad", degree=2, circuit=other).circuit == other
    # Saved as LM555Circuit.to_dict() and read back as the same circuit.
    p = save_calibration(cal, tmp_path / "cal.json")
    assert json.loads(p.read_text())["circuit"] == sidecar.to_dict()
    assert load_calibration(p).circuit == sidecar


def test_earlier_calibration_file_with_a_decode_dict_still_loads_and_applies(tmp_path):
    # Written by hand in the layout of earlier fsrlab files: the circuit's parts under "decode",
    # the compensation with its hysteresis errors. The polynomial is y = 1 + 2·(x − 5e-9)/2e-9.
    old = {
        "format": "fsrlab-calibration", "version": 1, "model": "polynomial", "basis": "chebyshev",
        "x": "c_fsr_farad", "y": "stress_pa", "units": {"x": "F", "y": "Pa"}, "degree": 1,
        "chebyshev_coefficients": [1.0, 2.0], "x_center": 5e-9, "x_half_width": 2e-9,
        "coefficients": [-4.0, 1e9], "metrics": {"r2": 0.99, "rmse": 10.0, "max_error_percent_fs": 1.0, "n": 50},
        "cross_validation": None, "data_fingerprint": "sha256:0123456789abcdef", "created": "2026-01-01T00:00:00Z",
        "decode": {"r_ohm": 12000.0, "c_off_farad": 1e-9, "diode": True, "diode_drop_v": 0.0},
        "source": "bench.csv", "operator": "kept as extra",
    }
    p = tmp_path / "old.json"
    p.write_text(json.dumps(old))
    cal = load_calibration(p)
    assert cal.circuit == LM555Circuit(r_ohm=12e3, c_off_farad=1e-9, diode=True, diode_drop_v=0.0)
    assert cal(5e-9) == pytest.approx(1.0) and cal(7e-9) == pytest.approx(3.0)
    assert cal.extra == {"operator": "kept as extra"} and cal.compensation is None
    # Applied to a run without a sidecar, C_FSR is decoded through the calibration's circuit.
    run, c_true = _ranged_run(tmp_path / "r.csv", cal.circuit, with_range=False)
    (tmp_path / "r.meta.json").unlink()
    # margin=inf: every estimate written, the file's range only flags (it predates readout_range).
    est = apply_calibration(cal, load_run(tmp_path / "r.csv"), margin=np.inf)
    np.testing.assert_allclose(est["stress_pa_estimate"], 1 + (c_true - 5e-9) / 1e-9, rtol=1e-8)
    np.testing.assert_array_equal(est["in_range"], (c_true >= 3e-9) & (c_true <= 7e-9))
    # Saved again, it is in the current layout.
    d = json.loads(save_calibration(cal, tmp_path / "new.json").read_text())
    assert "decode" not in d and d["circuit"]["r_ohm"] == 12e3 and d["operator"] == "kept as extra"


def test_apply_reports_a_missing_readout(runs, tmp_path):
    cal = calibrate_run(runs / "bench.csv", x="voltage_v", degree=1)
    run = _minimal(tmp_path / "f.csv", {"stress_pa": [0.0, 1.0], "frequency_hz": [1.0, 2.0]})
    with pytest.raises(ValueError, match="column 'voltage_v' \\(the calibration's readout\\) missing"):
        apply_calibration(cal, run)
