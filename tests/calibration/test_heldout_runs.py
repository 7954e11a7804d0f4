"""The held-out calibration on runs: file, apply, live stepping, provenance and the command line.

References: properties that must hold (the file gives the same estimates, stepping one reading at
a time gives the batch's numbers, a run of another circuit is refused) and the generator's truth
(:mod:`fsrlab.virtual.handloaded`) for the command line's choices.
"""

import json

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.calibration.apply import apply_calibration
from fsrlab.calibration.document import load_calibration, save_calibration
from fsrlab.calibration.result import Calibration
from fsrlab.calibration.runs import calibrate_runs
from fsrlab.errors import ProvenanceError
from fsrlab.io.runformat import load_run
from fsrlab.io.runwriter import write_run
from fsrlab.virtual.handloaded import fsr_bench_run
from stepping import assert_steps_as_batch


def _write(path, kind, seed, **kw):
    run = fsr_bench_run(kind, seed=seed, **kw)
    cols = {"time_s": run.columns["time_s"], "reading": np.round(run.columns["voltage_v"] / 5.0 * 1023),
            "force_n": run.columns["force_n"]}
    write_run(path, cols, {"units": {"time_s": "s", "reading": "counts", "force_n": "N"}})
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("heldout")
    return {"hand": _write(d / "hand.csv", "hand", 1), "hand2": _write(d / "hand2.csv", "hand", 2, duration_s=40),
            "motor": _write(d / "motor.csv", "motor", 3)}


@pytest.fixture(scope="module")
def cal(runs):
    return calibrate_runs([runs["hand"]], x="reading", reference="force_n", compensate=True)


def test_the_file_gives_the_same_estimates(cal, runs, tmp_path):
    path = save_calibration(cal, tmp_path / "cal.json")
    again = load_calibration(path)
    assert isinstance(again, Calibration) and again.path == path
    a = apply_calibration(cal, runs["motor"])["force_n_estimate"]
    b = apply_calibration(again, runs["motor"])["force_n_estimate"]
    assert np.array_equal(a, b, equal_nan=True)


def test_stepping_gives_the_batch_estimates_and_uncertainties(cal, runs):
    assert_steps_as_batch(cal, load_run(runs["motor"]))


def test_margin_only_decides_what_is_reported_not_the_memory(cal, runs):
    """A narrow margin leaves the estimates beyond it empty; those it reports are the wide margin's."""
    run = load_run(runs["motor"])
    wide = apply_calibration(cal, run, margin=np.inf)["force_n_estimate"]
    narrow = apply_calibration(cal, run, margin=0.0)["force_n_estimate"]
    kept = np.isfinite(narrow)
    assert np.array_equal(narrow[kept], wide[kept])


def _two_circuits(runs, tmp_path):
    """The same frequency readings as two runs, recorded with R = 10 kΩ and with R = 22 kΩ."""
    src = load_run(runs["hand"])
    circuit = {"topology": "lm555-astable", "r_ohm": 10000.0, "c_off_farad": 0.0, "diode": True, "diode_drop_v": 0.0}
    cols = {"time_s": src["time_s"], "frequency_hz": 1000 + src["reading"], "force_n": src["force_n"]}
    units = {"time_s": "s", "frequency_hz": "Hz", "force_n": "N"}
    return (write_run(tmp_path / "mine.csv", cols, {"units": units, "circuit": circuit}),
            write_run(tmp_path / "other.csv", cols, {"units": units, "circuit": dict(circuit, r_ohm=22000.0)}))


def test_a_run_of_another_circuit_is_refused(runs, tmp_path):
    """A calibration of the 555's frequency records the circuit its run was recorded with; a run with
    another R (so the same frequency means another force) is refused, and applied only when forced."""
    mine, other = _two_circuits(runs, tmp_path)
    cal = calibrate_runs([mine], x="frequency_hz", reference="force_n")
    assert cal.recorded_with is not None and cal.recorded_with.circuit is not None
    with pytest.raises(ProvenanceError, match="22"):
        apply_calibration(cal, other)
    forced = apply_calibration(cal, other, force=True)
    assert np.isfinite(forced["force_n_estimate"]).any() and forced.metadata["calibration"]["forced"]
    saved = save_calibration(cal, tmp_path / "cal.json")
    code, _, err = run_cli(["apply", saved, other, "-o", tmp_path / "out.csv"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "22" in err


def test_cli_calibrates_several_runs_leaving_one_out(runs, tmp_path):
    out = tmp_path / "cal.json"
    code, stdout, err = run_cli(["calibrate", runs["hand"], runs["hand2"], runs["motor"], "--x", "reading",
                                 "--reference", "force_n", "--compensate", "-o", out, "--json"])
    assert code == 0, err
    doc = json.loads(stdout)
    assert doc["method"] == "held-out" and doc["scheme"] == "leave one recording out"
    assert [s["step"] for s in doc["steps"]] == ["static curve", "delay", "memory"]
    assert json.loads(out.read_text())["method"] == "held-out"


def test_cli_says_whether_the_relative_uncertainty_was_measured_or_assumed(runs, monkeypatch):
    """One run shows how the gain moves between its held-out blocks only: the table names the blocks' spread and
    asks for more runs; with several runs it names the held-out runs' gain spread (the term is the larger of
    it and the assumed floor)."""
    monkeypatch.setenv("COLUMNS", "300")  # the table's cells on one line each
    one = " ".join(run_cli(["calibrate", runs["hand"], "--x", "reading", "--reference", "force_n"])[1].split())
    code, stdout, err = run_cli(["calibrate", runs["hand"], runs["hand2"], runs["motor"], "--x", "reading",
                                 "--reference", "force_n"])
    assert code == 0, err
    several = " ".join(stdout.split())
    assert "held-out blocks' gain" in one and "calibrate from two or more runs" in one
    assert "held-out runs' gain" in several and "blocks'" not in several


def test_the_relative_term_between_runs_can_be_given(runs, cal, tmp_path, monkeypatch):
    """``between_runs`` is the floor of the relative term: with one run it is the term, so the uncertainty
    of each estimate grows in quadrature by exactly (0.30² − 0.15²)·estimate² (LevelUncertainty's closed
    form); the command line's --between-runs writes the same, says so, and refuses what is not 0–100 %."""
    wide = calibrate_runs([runs["hand"]], x="reading", reference="force_n", compensate=True, between_runs=0.30)
    assert cal.model.uncertainty.relative == 0.15 and wide.model.uncertainty.relative == 0.30
    a, b = apply_calibration(cal, runs["motor"]), apply_calibration(wide, runs["motor"])
    est = a["force_n_estimate"]
    ok = np.isfinite(est)
    assert np.array_equal(est, b["force_n_estimate"], equal_nan=True)  # the estimate itself does not change
    grown = b["force_n_uncertainty"][ok] ** 2 - a["force_n_uncertainty"][ok] ** 2
    assert np.allclose(grown, (0.30 ** 2 - 0.15 ** 2) * est[ok] ** 2, rtol=1e-6, atol=1e-12)
    with pytest.raises(ValueError, match="between_runs"):
        calibrate_runs([runs["hand"]], x="reading", reference="force_n", between_runs=1.5)
    monkeypatch.setenv("COLUMNS", "300")
    out = tmp_path / "wide.json"
    code, stdout, err = run_cli(["calibrate", runs["hand"], "--x", "reading", "--reference", "force_n",
                                 "--between-runs", "30%", "-o", out])
    assert code == 0, err
    assert "30 (the floor given by --between-runs; the held-out blocks' gains spread only" in " ".join(stdout.split())
    assert load_calibration(out).model.uncertainty.relative == pytest.approx(0.30)
    for bad in ("150%", "30", "-5%"):
        code, _, err = run_cli(["calibrate", runs["hand"], "--x", "reading", "--between-runs", bad])
        assert code == 2 and len(err.strip().splitlines()) == 1 and "--between-runs" in err, err


def test_cli_says_in_one_line_why_the_compensation_was_not_kept(tmp_path):
    """A sensor without memory: the compensation is tried, not kept, and the table says why."""
    rng = np.random.default_rng(7)
    t = np.arange(3000) * 0.02
    force = 10 * np.abs(np.sin(2 * np.pi * t / 7.3))
    reading = np.round(1023 * (force / 12) ** 0.7 / (1 + (force / 12) ** 0.7) + rng.normal(0, 3, t.size))
    p = write_run(tmp_path / "static.csv", {"time_s": t, "reading": reading,
                                            "force_n": force + rng.normal(0, .3, t.size)},
                  {"units": {"time_s": "s", "reading": "counts", "force_n": "N"}})
    code, stdout, err = run_cli(["calibrate", p, "--x", "reading", "--compensate"])
    assert code == 0, err
    lines = " ".join(stdout.split()).split("compensation: ")[1:]
    assert lines and "not kept" in lines[0] and "simpler calibration is kept" in lines[0]


@pytest.mark.parametrize("args, option", [
    (["--lag", "soon"], "--lag"),
    (["--method", "cv"], "--method"),  # the cross-validated engine is retired: no such option
])
def test_cli_bad_options_give_one_line(runs, args, option):
    args = [runs["hand2"] if a == "{other}" else a for a in args]
    code, stdout, err = run_cli(["calibrate", runs["hand"], "--x", "reading", *args])
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and option in err


def test_runs_of_different_circuits_are_not_calibrated_together(runs, tmp_path):
    """Leave-one-out across runs needs one readout: a second run with another R is refused, naming both."""
    a, b = _two_circuits(runs, tmp_path)
    with pytest.raises(ValueError, match="calibrate runs of one readout together"):
        calibrate_runs([a, b], x="frequency_hz", reference="force_n")


def _volts(path, seed=1):
    """A divider's voltage (5 V supply) logged as a plain column, no divider in the sidecar."""
    run = fsr_bench_run("hand", seed=seed)
    cols = {"time_s": run.columns["time_s"], "reading": run.columns["voltage_v"], "force_n": run.columns["force_n"]}
    return write_run(path, cols, {"units": {"time_s": "s", "reading": "V", "force_n": "N"}})


def test_rail_makes_a_voltage_readout_try_the_conductance(tmp_path):
    """Without --rail a voltage readout is fitted in the readout alone; with --rail 5 the divider's
    conductance ratio V/(5 − V) is among the candidates, and the file records that full scale."""
    p = _volts(tmp_path / "v.csv")
    code, stdout, err = run_cli(["calibrate", p, "--x", "reading", "--json"])
    assert code == 0, err
    assert not any(c["name"].startswith("conductance") for c in json.loads(stdout)["candidates"])
    out = tmp_path / "cal.json"
    code, stdout, err = run_cli(["calibrate", p, "--x", "reading", "--rail", "5", "--json", "-o", out])
    assert code == 0, err
    assert any(c["name"].startswith("conductance") for c in json.loads(stdout)["candidates"])
    assert json.loads(out.read_text())["calibration"]["static"]["adc"] == 5.0


@pytest.mark.parametrize("args, says", [
    (["--rail", "0"], "> 0"),
    (["--rail", "2"], "not below"),
])
def test_rail_refuses_what_cannot_be_a_full_scale(tmp_path, args, says):
    p = _volts(tmp_path / "v.csv")
    code, _, err = run_cli(["calibrate", p, "--x", "reading", *args])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--rail" in err and says in err, err


def test_a_resistance_column_is_calibrated_in_its_conductance(tmp_path):
    """A run whose readout is declared in ohms (the FSR's resistance behind the hand-loaded divider, a Bouc–Wen
    film: not the engine's model) is calibrated in 1/R and its logarithm, never in the ohms themselves: the unit
    reaches the engine (scoring.readout_variables); the same readings without a unit are tried in the readout too."""
    run = fsr_bench_run("hand", seed=4, duration_s=40)
    counts = np.round(run.columns["voltage_v"] / 5.0 * 1023)
    ohms = 10e3 * (1023.0 / (counts + 0.5) - 1.0)
    cols = {"time_s": run.columns["time_s"], "r_fsr": ohms, "force_n": run.columns["force_n"]}
    declared = write_run(tmp_path / "ohm.csv", cols, {"units": {"time_s": "s", "r_fsr": "Ω", "force_n": "N"}})
    plain = write_run(tmp_path / "plain.csv", cols, {"units": {"time_s": "s", "force_n": "N"}})
    cal = calibrate_runs(declared, x="r_fsr", reference="force_n")
    names = [c["name"] for c in cal.selection.candidates]
    assert names and all(n.startswith(("reciprocal", "log")) for n in names), names
    # the file keeps which variables were tried and why, and the command line says it
    again = load_calibration(save_calibration(cal, tmp_path / "cal.json"))
    assert again.selection.readout == cal.selection.readout and "resistance" in cal.selection.readout["why"]
    code, out, err = run_cli(["calibrate", declared, "--x", "r_fsr", "--reference", "force_n", "--json"])
    assert code == 0 and json.loads(out)["readout_variables"]["variables"] == ["reciprocal", "log"], err
    names = [c["name"] for c in calibrate_runs(plain, x="r_fsr", reference="force_n").selection.candidates]
    assert any(n.startswith("readout") for n in names), names
