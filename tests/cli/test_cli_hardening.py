"""The analysis commands: nothing lost, nothing silently wrong.

Data: synthetic runs from fsrlab.virtual.synthetic.synthetic_run (VirtualFSR -> LM555, R = 10 kΩ,
ideal D1 -> meter model) written in the run format; references are the runs' own construction
(a cell set to 1e308 at a known row, a circuit changed to R = 4.7 kΩ, a constant readout) and the
same command on the run without the fault.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.circuits.circuit import PAPER_CIRCUIT, LM555Circuit
from fsrlab.io.runformat import load_run, sidecar_path
from fsrlab.virtual.synthetic import synthetic_run


@pytest.fixture(scope="module")
def cal(runs, tmp_path_factory):
    p = tmp_path_factory.mktemp("cal") / "cal.json"
    code, _, err = run_cli(["calibrate", runs / "bench.csv", "--compensate", "-o", p])
    assert code == 0, err
    return p


def _corrupt(src, dst, row: int, column: str, text: str):
    lines = src.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(column)] = text
    lines[row] = ",".join(cells)
    dst.write_text("\n".join(lines) + "\n")
    # A CSV changed after its sidecar was written: without the sidecar's digest of the old content, which
    # load_run would refuse before any cell (docs/data-format.md, csv_sha256).
    meta = json.loads(sidecar_path(src).read_text())
    del meta["csv_sha256"]
    sidecar_path(dst).write_text(json.dumps(meta))
    return dst


# --- an incomplete run is read with one warning naming its last row -----------------------

@pytest.mark.parametrize("command", [["hysteresis"], ["calibrate"], ["apply", "{cal}", "-o", "{tmp}/est.csv"]])
def test_incomplete_run_warns_once_naming_the_last_row(runs, cal, tmp_path, command):
    src = runs / "other.csv"
    run = tmp_path / "killed.csv"
    run.write_text(src.read_text())
    meta = json.loads(sidecar_path(src).read_text())
    meta.update(complete=False, rows=None)
    sidecar_path(run).write_text(json.dumps(meta))
    n = load_run(run).n_rows
    args = [a.format(cal=cal, tmp=tmp_path) for a in command]
    args = args[:1] + ([args[1], run] + args[2:] if command[0] == "apply" else [run] + args[1:])
    code, _, err = run_cli(args)
    assert code == 0
    assert err.count("\n") == 1 and err.count("is incomplete") == 1
    assert f"row {n} (line {n + 1}" in err and str(run) in err


def test_complete_run_has_no_warning(runs):
    code, _, err = run_cli(["hysteresis", runs / "bench.csv"])
    assert code == 0 and err == ""


# --- a corrupt cell is rejected, or skipped and counted; it never poisons later rows -------

def test_corrupt_cell_is_rejected_with_row_and_column(runs, cal, tmp_path):
    bad = _corrupt(runs / "bench.csv", tmp_path / "bad.csv", 51, "frequency_hz", "1e308")
    for args in (["hysteresis", bad], ["calibrate", bad], ["apply", cal, bad, "-o", tmp_path / "e.csv"]):
        code, out, err = run_cli(args)
        assert code == 2 and out == "" and err.count("\n") == 1
        assert "bad.csv: row 51 (line 52), column 'frequency_hz': 1e+308" in err
    assert not (tmp_path / "e.csv").exists()


def test_skip_bad_rows_hysteresis_is_that_of_the_run_without_the_row(runs, tmp_path):
    # Reference: the same run with that row removed.
    bad = _corrupt(runs / "bench.csv", tmp_path / "bad.csv", 51, "frequency_hz", "1e308")
    code, out, err = run_cli(["hysteresis", bad, "--skip-bad-rows", "--json"])
    assert code == 0 and "skipped 1 bad row" in err
    d = json.loads(out)
    assert d["skipped_rows"] == 1 and d["skipped"][0]["row"] == 51 and d["skipped"][0]["column"] == "frequency_hz"
    lines = (runs / "bench.csv").read_text().splitlines()
    (tmp_path / "ref.csv").write_text("\n".join(lines[:51] + lines[52:]) + "\n")
    ref = json.loads(run_cli(["hysteresis", tmp_path / "ref.csv", "--json"])[1])
    assert d["hysteresis_error_percent"] == ref["hysteresis_error_percent"]
    assert np.isfinite(d["hysteresis_error_percent"])


def test_apply_skips_a_bad_row_and_later_estimates_are_untouched(runs, cal, tmp_path):
    # Reference: apply on the run without the row; before, every later compensated estimate was
    # empty while --json said "missing": 0.
    bad = _corrupt(runs / "other.csv", tmp_path / "bad.csv", 51, "frequency_hz", "1e308")
    code, out, err = run_cli(["apply", cal, bad, "-o", tmp_path / "est.csv", "--skip-bad-rows", "--json"])
    assert code == 0, err
    d = json.loads(out)
    est = load_run(tmp_path / "est.csv")
    assert d["rows"] == est.n_rows == load_run(runs / "other.csv").n_rows - 1 and d["skipped_rows"] == 1
    lines = (runs / "other.csv").read_text().splitlines()
    (tmp_path / "ref.csv").write_text("\n".join(lines[:51] + lines[52:]) + "\n")
    run_cli(["apply", cal, tmp_path / "ref.csv", "-o", tmp_path / "ref_est.csv"])
    np.testing.assert_array_equal(est["stress_pa_estimate"], load_run(tmp_path / "ref_est.csv")["stress_pa_estimate"])
    assert d["missing"] == int(np.isnan(est["stress_pa_estimate"]).sum())


def test_apply_json_counts_are_true(runs, cal, tmp_path):
    # A run with empty readouts and readings far outside the calibration (100 Hz, 1 MHz, 20 kHz).
    c = synthetic_run(cycles=2, seed=7).columns
    f = c["frequency_hz"]
    f[[3, 4]] = np.nan
    f[10], f[20], f[30] = 100.0, 1e6, 2e4
    synthetic_run(cycles=2, seed=7).write(tmp_path / "r.csv")
    from fsrlab.io.runwriter import write_run

    meta = json.loads(sidecar_path(runs / "other.csv").read_text())
    write_run(tmp_path / "r.csv", {k: v for k, v in c.items() if k not in ("c_fsr_farad", "r_fsr_ohm")},
              meta, overwrite=True)
    code, out, err = run_cli(["apply", cal, tmp_path / "r.csv", "-o", tmp_path / "e.csv", "--json", "--margin", "10%"])
    assert code == 0, err
    d = json.loads(out)
    est = load_run(tmp_path / "e.csv")
    e, flag = est["stress_pa_estimate"], est["in_range"]
    assert d["missing"] == int(np.isnan(e).sum()) == 5
    assert d["missing_reasons"] == {"no_readout": 2, "not_decodable": 0, "beyond_margin": 3, "below_activation": 0}
    assert np.isnan(e[[10, 20, 30]]).all() and (flag[[10, 20, 30]] == 0).all() and np.isnan(flag[[3, 4]]).all()
    lo, hi = d["readout_range"]
    inside = (f >= lo) & (f <= hi)
    assert d["in_range"] == int(inside.sum()) == int((flag == 1).sum())
    assert d["out_of_range"] == int((flag == 0).sum()) and d["extrapolated"] == d["out_of_range"] - 3
    # Every estimate written lies within 10 % of the calibrated span beyond the range.
    written = np.isfinite(e)
    assert np.all((f[written] >= lo - 0.1 * (hi - lo)) & (f[written] <= hi + 0.1 * (hi - lo)))


# --- a run recorded with another circuit or range is refused unless --force ---------------

def test_apply_refuses_another_circuit_naming_both(cal, tmp_path):
    synthetic_run(cycles=1, seed=3, circuit=LM555Circuit(r_ohm=4.7e3)).write(tmp_path / "r47.csv")
    code, out, err = run_cli(["apply", cal, tmp_path / "r47.csv", "-o", tmp_path / "e.csv"])
    assert code == 2 and err.count("\n") == 1 and not (tmp_path / "e.csv").exists()
    assert "R = 4.7 kΩ" in err and "R = 10 kΩ" in err and str(cal) in err and "--force" in err
    code, out, err = run_cli(["apply", cal, tmp_path / "r47.csv", "-o", tmp_path / "e.csv", "--force"])
    assert code == 0 and "--force" in err and (tmp_path / "e.csv").exists()
    assert load_run(tmp_path / "e.csv").metadata["calibration"]["forced"]


def test_apply_refuses_another_range(tmp_path):
    # Calibrated on range 0 with C_off = 470 pF in the sidecar; applied to a range-1 run.
    circuit = PAPER_CIRCUIT.replace(c_off_farad=470e-12)
    for name, rng, seed in (("r0.csv", 0.0, 1), ("r1.csv", 1.0, 2)):
        r = synthetic_run(cycles=2, seed=seed, circuit=circuit.on_range(int(rng)))
        r.metadata["circuit"] = circuit.to_dict()
        r.columns["range"] = np.full(r.columns["stress_pa"].size, rng)
        r.write(tmp_path / name)
    assert run_cli(["calibrate", tmp_path / "r0.csv", "-o", tmp_path / "c.json"])[0] == 0
    stored = json.loads((tmp_path / "c.json").read_text())["recorded_with"]
    assert stored["range"] == [0] and stored["circuit"]["c_off_farad"] == 470e-12
    code, _, err = run_cli(["apply", tmp_path / "c.json", tmp_path / "r1.csv", "-o", tmp_path / "e.csv"])
    assert code == 2 and "range 1 (C_off in)" in err and "C_off = 470 pF" in err and "C_off = 0 F" in err
    # The C_FSR calibration decodes each reading on its own range: another range is no reason to refuse.
    assert run_cli(["calibrate", tmp_path / "r0.csv", "--x", "c_fsr_farad", "-o", tmp_path / "cc.json"])[0] == 0
    assert run_cli(["apply", tmp_path / "cc.json", tmp_path / "r1.csv", "-o", tmp_path / "e.csv"])[0] == 0


def test_a_capacitance_calibration_applies_to_a_run_of_the_same_circuit(runs, tmp_path):
    # C_FSR is decoded through the sidecar's circuit of the calibration run; other.csv, from the same bench
    # (same sidecar), is decoded through it alike: nothing to refuse, nothing to warn about.
    cal = tmp_path / "c.json"
    assert run_cli(["calibrate", runs / "bench.csv", "--x", "c_fsr_farad", "-o", cal])[0] == 0
    code, _, err = run_cli(["apply", cal, runs / "other.csv", "-o", tmp_path / "e.csv"])
    assert code == 0 and err == ""


def test_older_calibration_file_loads_and_says_it_is_not_checked(cal, runs, tmp_path):
    d = json.loads(cal.read_text())
    del d["recorded_with"], d["readout_range"]
    (tmp_path / "old.json").write_text(json.dumps(d))
    code, _, err = run_cli(["apply", tmp_path / "old.json", runs / "other.csv", "-o", tmp_path / "e.csv"])
    assert code == 0 and err.count("\n") == 1 and "not checked" in err


@pytest.mark.parametrize("change, words", [
    (lambda d: d["calibration"].__setitem__("full_scale", 0.0), "full_scale"),
    (lambda d: d["calibration"].__setitem__("delay_s", -1.0), "delay_s"),
    (lambda d: d.__setitem__("lag_s", "soon"), "lag_s"),
])
def test_damaged_calibration_value_is_one_line_naming_the_file(cal, runs, tmp_path, change, words):
    # Property: a value no calibration can hold is refused at load, naming the file, and nothing is written.
    d = json.loads(cal.read_text())
    change(d)
    (tmp_path / "bad.json").write_text(json.dumps(d))
    code, _, err = run_cli(["apply", tmp_path / "bad.json", runs / "other.csv", "-o", tmp_path / "e.csv"])
    assert code == 2 and err.count("\n") == 1 and "bad.json" in err and words in err
    assert not (tmp_path / "e.csv").exists()


# --- a readout that does not respond has no hysteresis error ------------------------------

@pytest.mark.parametrize("fault", ["constant", "noise"])
def test_hysteresis_of_a_dead_sensor_is_an_error(tmp_path, fault):
    r = synthetic_run(cycles=2, seed=4)
    n = r.columns["stress_pa"].size
    rng = np.random.default_rng(0)
    r.columns["frequency_hz"] = (np.full(n, 1300.0) if fault == "constant"
                                 else 1300.0 * (1 + 0.002 * rng.standard_normal(n)))
    r.write(tmp_path / "dead.csv")
    code, out, err = run_cli(["hysteresis", tmp_path / "dead.csv"])
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "frequency_hz does not respond to the stress" in err and "dead.csv" in err


# --- iso376 without numpy warnings; non-finite creep readings rejected --------------------

def test_iso376_prints_no_warnings_and_rejects_non_finite_creep(tmp_path):
    p = tmp_path / "iso.csv"
    # Valid: decreasing readings at two of the five forces only.
    rows = ["series,rotation_deg,force_n,reading,direction"]
    for s, rot in ((1, 0), (2, 0), (3, 120)):
        rows += [f"{s},{rot},0,0,1"] + [f"{s},{rot},{f},{f * (1 + 0.01 * s)},1" for f in range(1, 6)]
    rows += ["3,120,5,5.0,-1", "3,120,3,3.05,-1", "3,120,0,0.02,-1"]
    p.write_text("\n".join(rows) + "\n")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        code, out, err = run_cli(["iso376", p, "--json"])
    assert code == 0 and err == ""
    for creep in ("nan,1", "1,inf", "1e308,-1e308", "1,2,3", "5k,1"):
        code, out, err = run_cli(["iso376", p, "--creep", creep])
        assert code == 2 and "--creep" in err and err.count("\n") == 1, creep


def test_apply_never_replaces_an_existing_run_unless_asked(runs, tmp_path):
    # Property: a command that fails leaves an existing run byte for byte; --overwrite replaces it.
    cal = tmp_path / "c.json"
    assert run_cli(["calibrate", runs / "bench.csv", "-o", cal])[0] == 0
    out = tmp_path / "keep.csv"
    out.write_text("time_s,stress_pa\n0,1\n")
    before = out.read_bytes()
    code, _, err = run_cli(["apply", cal, runs / "other.csv", "-o", out])
    assert code == 2 and "keep.csv exists" in err and "--overwrite" in err and err.count("\n") == 1
    assert out.read_bytes() == before
    assert run_cli(["apply", cal, runs / "other.csv", "-o", out, "--overwrite"])[0] == 0
    assert out.read_bytes() != before


@pytest.mark.parametrize("args, word", [(["-00", "--bogus"], "-00"), (["bench", "-xq"], "-xq")])
def test_an_unknown_cluster_of_short_options_names_the_word_given(args, word):
    """click reports ``-00`` as ``No such option: -0``; the line names the word that was typed."""
    code, _, err = run_cli(args)
    assert code == 2 and err.count("\n") == 1 and repr(word) in err and "Traceback" not in err, err
