"""A calibrated run's estimate against the reference recorded with it (`fsrlab apply`, `fsrlab report`).

References: closed forms (an estimate that is a known straight line of the reference, errors against
a known uncertainty) and properties that must hold (a reference scaled by g scales the fitted line by
g; unloaded rows do not count); on real recordings (tests/data/real/belli-insole, BSD-3-Clause), the
coverage benchmarks/bench_realdata.py measured for this pair (98-99 %).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.io.runformat import load_run
from fsrlab.io.runwriter import write_run
from fsrlab.metrics.agreement import COVERAGE_AIM, LOADED, agreement

DATA = Path(__file__).resolve().parents[1] / "data" / "real" / "belli-insole"


def test_an_estimate_on_a_known_line_of_the_reference():
    y = np.r_[np.zeros(20), np.linspace(0.6, 10.0, 200)]
    est = 1.25 * y + 0.1
    u = np.full(y.size, 0.4)
    ag = agreement(y, est, u)
    loaded = y > LOADED * 10.0  # the zeros and nothing else are left out
    e = est[loaded] - y[loaded]
    assert ag.loaded == ag.estimated == int(loaded.sum()) == 200
    assert ag.rmse == pytest.approx(np.sqrt(np.mean((0.25 * y[loaded] + 0.1) ** 2)))
    assert ag.bias == pytest.approx(np.mean(0.25 * y[loaded] + 0.1))
    # y = (est - 0.1) / 1.25: slope 0.8, intercept -0.08
    assert ag.slope == pytest.approx(0.8) and ag.intercept == pytest.approx(-0.08)
    # |e| = 0.25 y + 0.1 <= 0.8 for y <= 2.8
    assert ag.coverage == pytest.approx(np.mean(e <= 0.8))
    assert ag.rmse_percent_span == pytest.approx(100 * ag.rmse / 10.0)
    assert ag.coverage < COVERAGE_AIM and "reference ≈ 0.8 × estimate − 0.08 N" in ag.warning("N")
    assert agreement(y, y + 0.01, u).warning("N") is None  # every error well within ±2u


def test_missing_estimates_uncertainties_and_too_few_rows():
    y = np.linspace(0.0, 5.0, 50)
    est = y.copy()
    est[::2] = np.nan
    ag = agreement(y, est)
    assert ag.estimated == int((np.isfinite(est) & (y > LOADED * 5.0)).sum()) and ag.coverage is None
    assert agreement(y, np.where(y > 4.9, y, np.nan)) is None  # fewer than ten loaded rows estimated
    assert agreement(np.zeros(50), y) is None  # a reference that never rises
    from fsrlab.errors import ParameterError

    with pytest.raises(ParameterError) as info:
        agreement(y, y[:-1])
    assert info.value.parameter == "estimate"
    with pytest.raises(ParameterError) as info:
        agreement(y, y, y[:-1])
    assert info.value.parameter == "uncertainty"


@pytest.fixture(scope="module")
def insole(tmp_path_factory):
    d = tmp_path_factory.mktemp("agreement")
    cal = d / "cal.json"
    code, _, err = run_cli(["calibrate", DATA / "left_t34_calibration.csv", "--x", "reading", "--reference", "force_n",
                            "--compensate", "-o", cal])
    assert code == 0, err
    new = load_run(DATA / "left_t34_validation1.csv")
    shifted = d / "shifted.csv"  # the same run read by a sensor whose gain moved by 1.5
    write_run(shifted, {**new.columns, "force_n": 1.5 * new.columns["force_n"]}, {"units": new.units})
    blind = d / "blind.csv"  # without its reference
    write_run(blind, {k: v for k, v in new.columns.items() if k != "force_n"}, {"units": new.units})
    return d, cal, DATA / "left_t34_validation1.csv", shifted, blind


def _apply(cal, run, out):
    code, stdout, err = run_cli(["apply", cal, run, "-o", out, "--json", "--overwrite"])
    assert code == 0, err
    return json.loads(stdout)["agreement"], err


def test_apply_states_how_the_calibration_holds_on_a_validation_run(insole):
    d, cal, new, shifted, blind = insole
    ag, err = _apply(cal, new, d / "new.csv")
    assert ag["coverage_percent"] >= 90 and "±2u covers only" not in err  # measured 98-99 % (bench_realdata)
    scaled, err = _apply(cal, shifted, d / "shifted_out.csv")
    assert scaled["slope"] == pytest.approx(1.5 * ag["slope"])
    assert scaled["intercept"] == pytest.approx(1.5 * ag["intercept"])
    assert scaled["coverage_percent"] < 90 and "±2u covers only" in err and "shifted.csv" in err
    none, _ = _apply(cal, blind, d / "blind_out.csv")
    assert none is None
    code, stdout, _ = run_cli(["apply", cal, new, "-o", d / "text.csv", "--overwrite"])
    assert code == 0 and "against force_n in the run" in stdout and "±2u covers" in stdout


def test_the_report_of_a_validation_run_shows_the_agreement_and_the_estimate_over_time(insole):
    d, cal, _, shifted, _ = insole
    out = d / "report"
    code, _, err = run_cli(["report", shifted, "--cal", cal, "--out", out])
    assert code == 0, err
    rep = json.loads((out / "report.json").read_text())
    assert rep["agreement"]["coverage_percent"] < 90
    assert (out / "estimate_time.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    html = (out / "index.html").read_text()
    assert "on this run: errors within ±2u" in html and "estimate_time.png" in html and "±2u covers only" in html


def test_an_estimate_that_does_not_vary_has_no_line():
    y = np.linspace(1.0, 5.0, 30)
    ag = agreement(y, np.full(30, 3.0), np.full(30, 0.1))
    assert np.isnan(ag.slope) and ag.line("N") == "the estimate did not vary" and "did not vary" in ag.warning("N")


def test_apply_says_when_some_loaded_rows_have_no_estimate(insole):
    d, cal, new, _, _ = insole
    run = load_run(new)
    x, y = run.columns["reading"].copy(), run.columns["force_n"]
    x[np.flatnonzero(y > 0.5 * np.nanmax(y))[:50]] = 150.0  # 50 loaded readings far beyond the calibrated range
    beyond = d / "beyond.csv"
    write_run(beyond, {**run.columns, "reading": x}, {"units": run.units})
    # a margin of 0: readings beyond the calibrated range are left empty, and the statistics say so
    code, stdout, err = run_cli(["apply", cal, beyond, "-o", d / "margin0.csv", "--margin", "0", "--overwrite"])
    out = json.loads(run_cli(["apply", cal, beyond, "-o", d / "margin0.csv",
                              "--margin", "0", "--overwrite", "--json"])[1])
    ag = out["agreement"]
    assert code == 0, err
    assert ag["estimated_rows"] == ag["loaded_rows"] - 50
    assert f"the {ag['estimated_rows']} estimated of its {ag['loaded_rows']} loaded rows" in stdout


@pytest.mark.parametrize("bad", [-0.1, np.inf, -np.inf])
def test_a_negative_or_infinite_uncertainty_is_refused_naming_it(bad):
    # Reference: issue 40 ("fl.agreement returns None silently on negative or infinite uncertainties"): a
    # standard uncertainty is >= 0 and finite by definition (GUM 2.3.1); NaN stays "no uncertainty here".
    from fsrlab.errors import ParameterError

    y = np.linspace(0.5, 10.0, 50)
    u = np.full(y.size, 0.4)
    u[7] = bad
    with pytest.raises(ParameterError) as info:
        agreement(y, y + 0.1, u)
    assert info.value.parameter == "uncertainty" and "row 7" in str(info.value)
    u[7] = np.nan  # one row without an uncertainty: the others still give the coverage
    assert agreement(y, y + 0.1, u).coverage == 1.0
    with pytest.raises(ParameterError) as info:  # refused before "no loaded rows" could return None
        agreement(np.zeros(50), np.zeros(50), np.full(50, -1.0))
    assert info.value.parameter == "uncertainty"


@pytest.mark.parametrize("argument", ["reference", "estimate", "uncertainty"])
def test_values_that_are_not_numbers_are_refused_naming_their_parameter(argument):
    # Reference: issue 40's API fuzzer: a str, a dict or a list of words is a ParameterError naming the
    # argument, never numpy's "could not convert string to float".
    from fsrlab.errors import ParameterError

    args = {"reference": np.ones(30), "estimate": np.ones(30), "uncertainty": np.ones(30)}
    for bad in ("x", {"a": 1}, ["a"] * 30):
        with pytest.raises(ParameterError) as info:
            agreement(**{**args, argument: bad})
        assert info.value.parameter == argument
