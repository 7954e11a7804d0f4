"""Command line of the analysis topic: `fsrlab hysteresis | repeatability | calibrate | apply`.

Through fsrlab.cli.main (exit codes and one-line errors). Data: the paper's Table 4/5 readings
(real), and synthetic runs from fsrlab.virtual.synthetic.synthetic_run (VirtualFSR ->
lm555.astable -> 62.5 ns quantization, 0.2 % frequency noise) written in the run format.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.io.runformat import load_run
from fsrlab.virtual.synthetic import synthetic_run


def test_hysteresis_json_keys(runs, capsys):
    code, out, _ = run_cli(["hysteresis", runs / "bench.csv", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert set(d) == {"hysteresis_error_percent", "stress_at_max_difference_pa", "cycles"}
    assert len(d["cycles"]) == 3
    assert all(set(c) == {"hysteresis_error_percent", "stress_at_max_difference_pa"} for c in d["cycles"])
    assert 10 < d["hysteresis_error_percent"] < 20  # the virtual sensor's ~14 % (see test_cycles)


def test_minimal_csv_works_for_hysteresis_and_calibrate(tmp_path, capsys):
    # Only stress_pa and one quantity, no sidecar, rows in time order.
    c = synthetic_run(cycles=2, seed=2).columns
    lines = ["stress_pa,frequency_hz"] + [f"{float(s)!r},{float(f)!r}"
                                          for s, f in zip(c["stress_pa"], c["frequency_hz"], strict=True)]
    p = tmp_path / "min.csv"
    p.write_text("\n".join(lines) + "\n")
    code, out, _ = run_cli(["hysteresis", p, "--json"], capsys)
    assert code == 0 and len(json.loads(out)["cycles"]) == 2
    code, out, _ = run_cli(["calibrate", p, "--x", "frequency_hz", "--json"], capsys)
    assert code == 0
    assert set(json.loads(out)) >= {"method", "scheme", "model", "heldout_rmse", "heldout_rmse_percent_fs",
                                    "readout_range", "lag_s", "delay_s", "candidates", "steps"}


def test_repeatability_cli_reproduces_table5(paper, tmp_path, capsys):
    t = paper["table5_repeatability_traditional_V"]
    lines = ["load,sensor,reading"] + [f"{load},{s + 1},{v}" for load in ("200g", "400g")
                                       for s, row in enumerate(t[load]["readings"]) for v in row]
    p = tmp_path / "t5.csv"
    p.write_text("\n".join(lines) + "\n")
    code, out, _ = run_cli(["repeatability", p, "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert set(d) == {"groups", "means"}
    re2 = [g["re2_percent"] for g in d["groups"]]
    np.testing.assert_allclose(re2, t["200g"]["RE2_percent"] + t["400g"]["RE2_percent"], atol=0.5)  # printed integers
    code, out, _ = run_cli(["repeatability", p, "--ddof", "0", "--json"], capsys)
    assert abs(json.loads(out)["groups"][0]["re2_percent"] - 9) > 0.5  # eq. (39) as printed misses 9 %
    code, _, err = run_cli(["repeatability", p, "--ddof", "3"], capsys)
    assert code == 2 and err.count("\n") == 1


def test_calibrate_apply_roundtrip_and_compensation(runs, tmp_path, capsys):
    """The file the command writes gives the library's estimates (round trip), and on a run the
    calibration never saw the compensated estimate keeps less hysteresis than the plain curve (eq. 13:
    measured 5.8 % against 14.6 % on examples/other.csv, whose frequency has 15.2 %)."""
    from fsrlab.calibration.document import load_calibration
    from fsrlab.metrics.cycles import run_hysteresis

    cal = tmp_path / "cal.json"
    code, out, _ = run_cli(["calibrate", runs / "bench.csv", "--x", "frequency_hz", "--compensate", "-o", cal,
                            "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert d["method"] == "held-out" and d["compensated"] and d["model"] == load_calibration(cal).model_name
    he = {}
    for args, key in (([], "compensated"), (["--no-compensation"], "plain")):
        out_csv = tmp_path / f"{key}.csv"
        code, _, _ = run_cli(["apply", cal, runs / "other.csv", "-o", out_csv, *args], capsys)
        assert code == 0
        run = load_run(out_csv)
        assert run.units["stress_pa_estimate"] == "Pa" and run.metadata["calibration"]["method"] == "held-out"
        direct = load_calibration(cal).estimate(load_run(runs / "other.csv"), compensation=not args)
        np.testing.assert_array_equal(run["stress_pa_estimate"], direct["stress_pa_estimate"])
        he[key] = run_hysteresis(run["stress_pa"], run["stress_pa_estimate"], run["direction"], run["cycle"]).percent
    assert he["compensated"] < 0.5 * he["plain"]


@pytest.mark.parametrize("args, needle", [
    (["hysteresis", "{bad}"], "non-numeric cell"),
    (["hysteresis", "{bench}", "--quantity", "nope"], "column 'nope' missing"),
    (["calibrate", "{bench}", "--between-runs", "150%"], "--between-runs"),
    (["calibrate", "{bench}", "--x", "nope"], "column 'nope' missing"),
    (["apply", "{bench}", "{bench}", "-o", "{tmp}/x.csv"], "not a valid JSON calibration"),
    (["hysteresis", "{tmp}/does-not-exist.csv"], "does-not-exist.csv"),
])
def test_bad_input_one_line_exit_2(runs, tmp_path, capsys, args, needle):
    bad = tmp_path / "bad.csv"
    bad.write_text("stress_pa,frequency_hz\n0,1\n1,x\n")
    sub = {"bad": bad, "bench": runs / "bench.csv", "tmp": tmp_path}
    code, out, err = run_cli([a.format(**sub) for a in args], capsys)
    assert code == 2
    assert err.count("\n") == 1 and needle in err


def test_calibrate_on_decoded_capacitance_stores_the_circuit_and_apply_reuses_it(runs, tmp_path, capsys):
    # Reference: the library called directly on the same run (the CLI only renders), and the circuit of
    # the run's sidecar (R = 10 kΩ, ideal D1) that C_FSR is decoded through.
    from fsrlab.calibration.apply import apply_calibration
    from fsrlab.calibration.runs import calibrate_runs
    from fsrlab.circuits.circuit import LM555Circuit

    cal = tmp_path / "calc.json"
    code, out, _ = run_cli(["calibrate", runs / "bench.csv", "--x", "c_fsr_farad", "-o", cal, "--json"], capsys)
    assert code == 0
    stored = json.loads(cal.read_text())["circuit"]
    assert LM555Circuit.from_dict(stored) == LM555Circuit(r_ohm=10e3, diode=True)
    ref = calibrate_runs(runs / "bench.csv", x="c_fsr_farad")
    assert json.loads(out)["model"] == ref.model_name
    code, _, _ = run_cli(["apply", cal, runs / "other.csv", "-o", tmp_path / "est.csv"], capsys)
    assert code == 0
    np.testing.assert_allclose(load_run(tmp_path / "est.csv")["stress_pa_estimate"],
                               apply_calibration(ref, runs / "other.csv")["stress_pa_estimate"], rtol=1e-12)


def test_apply_says_an_earlier_file_is_applied_read_only(runs, tmp_path, capsys):
    """A version-1 file of the cross-validated engine (tests/data/calibration) applies, with one warning line that
    says so and that its branch compensation is not applied; --margin changes no estimate inside the range
    (the memory takes every reading; the earlier engine's margin changed estimates in range, issue 37)."""
    from pathlib import Path

    old = Path(__file__).resolve().parents[1] / "data" / "calibration" / "v1-cross-validated.json"
    out = {}
    for margin in ("0", "200%"):
        code, _, err = run_cli(["apply", old, runs / "other.csv", "-o", tmp_path / f"m{margin[0]}.csv", "--margin",
                                margin], capsys)
        assert code == 0 and err.count("\n") == 1 and "read-only" in err and "not applied" in err, err
        out[margin] = load_run(tmp_path / f"m{margin[0]}.csv")
    inside = out["0"]["in_range"] == 1
    assert inside.sum() > 0
    np.testing.assert_array_equal(out["0"]["stress_pa_estimate"][inside], out["200%"]["stress_pa_estimate"][inside])
