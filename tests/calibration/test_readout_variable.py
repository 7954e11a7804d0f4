"""The readout variable follows the physics: a resistance is calibrated in its conductance.

Reference: the hand-loaded sensor of :mod:`fsrlab.virtual.handloaded` (a Bouc–Wen FSR with creep behind a
divider: not the model fitted), its resistance recovered from the divider's voltage in closed form,
``R = R_m·(Vcc − V)/V`` (rows below its activation, an open circuit, not logged), and its own true force.
The peer is numpy's polynomial in the conductance 1/R, its degree (1–5) chosen on the training run's last
fifth. Properties: which variables are tried for which readout (a table of the rules), and that the
Selection says which one was used and why.
"""

import numpy as np
import pytest

from fsrlab.calibration.scoring import Recording, readout_variables
from fsrlab.calibration.selection import calibrate_recordings
from fsrlab.virtual.handloaded import fsr_bench_run

R_M, VCC = 10e3, 5.0  # fsr_bench_run's divider [Ω, V]
PAIRS = [(("hand", 1), ("motor", 3)), (("hand", 2), ("hand", 9)), (("hand", 4), ("motor", 6)),
         (("motor", 3), ("hand", 1)), (("hand", 7), ("hand", 8))]


def _ohms(kind: str, seed: int) -> tuple[Recording, np.ndarray]:
    run = fsr_bench_run(kind, seed=seed, r_m_ohm=R_M, vcc_v=VCC)
    v = run.columns["voltage_v"]
    r = np.where(v > 0.01, R_M * (VCC - v) / np.maximum(v, 1e-9), np.nan)
    return Recording(run.columns["time_s"], r, run.columns["force_n"]), run.truth["force_n"]


def _rmse(est, truth) -> float:
    k = (truth > 0.05 * truth.max()) & np.isfinite(est)
    return float(np.sqrt(np.mean((est[k] - truth[k]) ** 2)))


def _peer(train: Recording, test: Recording, truth) -> float:
    """numpy.polyfit in 1/R, the degree of least error on the training run's last fifth (fitted on the rest)."""
    k = train.usable
    g, y = 1 / train.x[k], train.y[k]
    cut = int(0.8 * g.size)
    errs = [np.mean((np.polyval(np.polyfit(g[:cut], y[:cut], d), g[cut:]) - y[cut:]) ** 2) for d in range(1, 6)]
    coef = np.polyfit(g, y, 1 + int(np.argmin(errs)))
    return _rmse(np.polyval(coef, 1 / test.x), truth)


def test_a_resistance_in_ohms_is_calibrated_in_its_conductance():
    """Measured on the five pairs: in its conductance (and logarithm) 0.707–0.885 N, in ohms alone 0.766–0.980 N
    (geometric mean 0.92×); against numpy's polynomial in 1/R 0.99–1.07×."""
    ratios = []
    for a, b in PAIRS:
        train, _ = _ohms(*a)
        test, truth = _ohms(*b)
        cal, sel = calibrate_recordings([train], compensate=False, unit="ohm")
        in_ohms, _ = calibrate_recordings([train], compensate=False, variables=("readout",))
        assert sel.readout["variables"] == ["reciprocal", "log"] and "resistance" in sel.readout["why"]
        mine = _rmse(cal.run(test.t, test.x)[0], truth)
        ratios.append(mine / _rmse(in_ohms.run(test.t, test.x)[0], truth))
        assert mine <= 1.1 * _peer(train, test, truth), (a, b)
    assert max(ratios) <= 1.0 and np.exp(np.mean(np.log(ratios))) < 0.97


def _rec(x, y=None) -> Recording:
    x = np.asarray(x, dtype=float)
    return Recording(np.arange(x.size) * 0.01, x, np.linspace(0, 10, x.size) if y is None else y)


FALLING_OHMS = np.geomspace(50e3, 800.0, 200)  # a film's resistance under a rising force
CASES = [  # (readings, sign, rail, unit, name, variables tried)
    (FALLING_OHMS, -1, None, "Ω", "reading", ("reciprocal", "log")),
    (FALLING_OHMS, -1, None, "", "r_fsr_ohm", ("reciprocal", "log")),
    (FALLING_OHMS * 1.5, -1, None, "", "reading", ("readout", "reciprocal", "log")),  # unitless: tried too
    (FALLING_OHMS * 1.5, -1, None, "1", "reading", ("readout", "reciprocal", "log")),
    (np.linspace(5000.0, 800.0, 200), -1, None, "", "reading", ("readout", "log")),  # less than a decade
    (FALLING_OHMS[::-1], 1, None, "", "reading", ("readout", "log")),  # rises with the force
    (FALLING_OHMS, -1, None, "V", "voltage", ("readout", "log")),  # a unit that is not a resistance
    (np.linspace(2e3, 5e3, 200), 1, None, "Hz", "frequency_hz", ("readout", "log")),  # as it is
    (np.round(np.linspace(1000, 20, 200)), -1, 1023.0, "", "reading", ("readout", "conductance", "log")),  # counts
    (np.linspace(-1.0, 3.0, 200), 1, None, "", "reading", ("readout",)),  # not above zero: no logarithm
]


@pytest.mark.parametrize("x,sign,rail,unit,name,tried", CASES)
def test_which_variables_are_tried_follows_the_readout(x, sign, rail, unit, name, tried):
    got, why = readout_variables([_rec(x)], sign, rail, unit, name)
    assert got == tried and why


def test_the_selection_says_which_variable_was_used_and_why():
    """A unitless resistance-like reading (the film of test_log_readout.py's kind: ``x ∝ (1 + F/F0)^−0.9``)
    is tried in its reciprocal, in which it is nearly straight, and the Selection names what was used."""
    rng = np.random.default_rng(5)
    t = np.arange(3000) * 0.02
    force = 15 * np.abs(np.sin(2 * np.pi * t / 5.0)) ** 2
    x = 1500.0 * (1 + force / 0.4) ** -0.9 * (1 + rng.normal(0, 0.01, t.size))
    _, sel = calibrate_recordings([Recording(t, x, force + rng.normal(0, 0.05, t.size))], compensate=False)
    assert "reciprocal" in sel.readout["variables"] and "like a resistance" in sel.readout["why"]
    assert sel.readout["used"] and set(sel.readout["used"]) <= set(sel.readout["variables"])
    assert sel.to_dict()["readout"] == sel.readout
    asked, why = readout_variables([Recording(t, x, force)], -1, None, asked=("readout", "conductance"))
    assert asked == ("readout",) and why == "the variables asked for"  # no rail: no divider ratio
