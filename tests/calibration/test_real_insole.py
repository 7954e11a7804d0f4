"""Calibration on real recordings: one taxel of a capacitive insole in an air chamber.

Reference: the chamber's measured air pressure times the taxel's area (tests/data/real/belli-insole,
third parties' recordings, BSD-3-Clause; PROVENANCE.md there). The calibration run (a slow staircase
up and down) calibrates; the validation run (steps, a 60 s hold, a staircase, a ramp down) is new to
it. What ``fsrlab calibrate --compensate`` and ``fsrlab apply`` run, in Python; the printed figures
are those of benchmarks/bench_realdata.py (docs/calibration.md).
"""

from pathlib import Path

import numpy as np
import pytest

from fsrlab.calibration.apply import apply_calibration
from fsrlab.calibration.runs import calibrate_runs

DATA = Path(__file__).resolve().parents[1] / "data" / "real" / "belli-insole"


def _columns(path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    return d["reading"], d["force_n"]


@pytest.fixture(scope="module")
def validation():
    cal_file, new_file = DATA / "left_t34_calibration.csv", DATA / "left_t34_validation1.csv"
    x_cal, y_cal = _columns(cal_file)
    x, y = _columns(new_file)
    loaded = y > 0.05 * y.max()

    def rmse(est):
        return float(np.sqrt(np.mean((est[loaded] - y[loaded]) ** 2)))

    # the best plain polynomial, its degree chosen on the validation run itself (an oracle)
    poly = min(rmse(np.polynomial.Polynomial.fit(x_cal, y_cal, d)(x)) for d in range(1, 6))
    out = {}
    for comp in (False, True):
        cal = calibrate_runs([str(cal_file)], x="reading", reference="force_n", compensate=comp)
        run = apply_calibration(cal, str(new_file))
        est = np.asarray(run["force_n_estimate"], float)
        u = np.asarray(run["force_n_uncertainty"], float)
        out[comp] = (est, u, cal)
    return y, loaded, rmse, poly, out


def test_the_memory_that_made_a_held_out_block_worse_is_not_kept_and_the_estimate_is_no_worse(validation):
    """The memory (hysteresis and creep) lowers the calibration run's held-out error overall but raises it in
    its first held-out block, so it is not kept: on this validation run of the same day it would have been
    0.81x the plain curve, on two runs of another day 1.06x (benchmarks/bench_realdata.py, pairs 32 and 35) --
    which one a new recording is cannot be told from the calibration run, and the rule does no harm."""
    y, loaded, rmse, poly, out = validation
    est, _, cal = out[True]
    assert np.all(np.isfinite(est[loaded]))  # every loaded row estimated
    memory = next(s for s in cal.selection.steps if s["step"] == "memory")
    assert not memory["kept"] and min(memory["heldout_gain_by_part"]) < 0 < max(memory["heldout_gain_by_part"])
    assert rmse(est) <= 1.05 * rmse(out[False][0])  # issue's do-no-harm bound
    # measured 1.04x the oracle polynomial (0.295 N against 0.285 N): its degree is chosen on this very run
    assert rmse(est) < 1.1 * poly


def test_its_uncertainty_covers_the_errors_on_the_new_run(validation):
    y, loaded, _, _, out = validation
    est, u, _ = out[True]
    cover = np.mean(np.abs(est[loaded] - y[loaded]) <= 2 * u[loaded])
    assert cover >= 0.90  # measured 0.99
