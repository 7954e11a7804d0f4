"""A reversed load cell is refused; a reference whose rest level sits below zero is calibrated as recorded.

References: the sign of the presses (a property of the data made here: presses that go negative, or
a rest level moved below zero with the presses still going up), and translation of the reference:
an offset ``c`` added to the reference of the calibration run and of the new run is the offset of
the estimate, row by row (the static curves have an intercept, and the memory's level is the load
above the curve's rest value).
"""

from __future__ import annotations

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.calibration.runs import reference_reversed
from fsrlab.io.runformat import load_run
from fsrlab.io.runwriter import write_run
from fsrlab.virtual.handloaded import fsr_bench_run


def test_reversed_means_presses_below_zero_not_a_rest_level_below_zero():
    t = np.linspace(0, 20, 2001)
    presses = np.clip(10 * np.sin(2 * np.pi * t / 4), 0, None)  # half the time at rest
    assert reference_reversed(presses) is None
    why = reference_reversed(-presses - 0.01)  # a load cell wired the wrong way round
    assert why is not None and "mostly negative" in why
    offset = presses - 0.5  # untared: the rest level at −0.5, most readings below zero
    assert np.mean(offset < 0) > 0.5
    assert reference_reversed(offset) is None
    assert reference_reversed(np.array([np.nan, np.nan])) is None


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("offset")
    fsr_bench_run("hand", seed=5, duration_s=90, reference_sps=80).write(d / "cal.csv")
    fsr_bench_run("hand", seed=6, reference_sps=80).write(d / "new.csv")
    return d


def _shifted(src, dst, c):
    run = load_run(src)
    cols = {k: np.asarray(run[k]) for k in run.columns}
    cols["force_n"] = cols["force_n"] + c
    write_run(dst, cols, run.metadata, overwrite=True)
    return cols["force_n"]


def _estimate(tmp, cal_csv, new_csv, name):
    code, _, err = run_cli(["calibrate", cal_csv, "--x", "voltage_v", "--compensate", "-o", tmp / f"{name}.json"])
    assert code == 0, err
    code, _, err = run_cli(["apply", tmp / f"{name}.json", new_csv, "-o", tmp / f"{name}_est.csv"])
    assert code == 0, err
    out = load_run(tmp / f"{name}_est.csv")
    return np.asarray(out["force_n_estimate"]), np.asarray(out["force_n"])


def test_untared_reference_is_calibrated_and_the_estimate_follows_it(runs, tmp_path):
    y = np.asarray(load_run(runs / "cal.csv")["force_n"])
    c = -(float(np.median(y)) + 0.02 * float(np.ptp(y)))  # the rest level and then some below zero
    shifted = _shifted(runs / "cal.csv", tmp_path / "cal_off.csv", c)
    assert np.mean(shifted < 0) > 0.5  # what the rule refused before
    _shifted(runs / "new.csv", tmp_path / "new_off.csv", c)
    est, ref = _estimate(tmp_path, runs / "cal.csv", runs / "new.csv", "tared")
    est_off, ref_off = _estimate(tmp_path, tmp_path / "cal_off.csv", tmp_path / "new_off.csv", "untared")
    np.testing.assert_allclose(ref_off, ref + c, atol=1e-6)
    # the offset of the reference is the offset of the estimate, row by row (the memory's level is the
    # load above the curve's rest value; with static(x)/FS the level-scaled terms moved, 1.28x the error)
    assert np.isfinite(est).all()
    np.testing.assert_allclose(est_off, est + c, atol=1e-6 * float(np.ptp(y)))


def test_reversed_reference_refused_by_the_held_out_calibration(runs, tmp_path):
    run = load_run(runs / "cal.csv")
    cols = {k: np.asarray(run[k]) for k in run.columns}
    cols["force_n"] = -cols["force_n"] - 0.01
    write_run(tmp_path / "rev.csv", cols, run.metadata, overwrite=True)
    code, out, err = run_cli(["calibrate", tmp_path / "rev.csv", "--x", "voltage_v", "-o", tmp_path / "c.json"])
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "force_n" in err and "mostly negative" in err and "wrong way round" in err
    assert not (tmp_path / "c.json").exists()
