"""The static curve families: piecewise linear, polynomials and monotone cubic splines.

References: numpy's ``polyfit`` of the best degree (1–5, chosen against the truth: an oracle) on the same
rows is the peer for smooth, quiet readouts (issue 37 item 4); the generators are closed forms plus seeded
Gaussian noise, not the models fitted (a cubic of frequency on a 555's range, a power law). Properties:
every curve the engine promises to be monotone never falls; a polynomial continues linearly beyond its
readings; the file form gives the same numbers; one reading at a time gives the batch's numbers.
"""

import json

import numpy as np
import pytest

import fsrlab as fl
from fsrlab.calibration.curves import (
    PolynomialCurve,
    SplineCurve,
    curve_from_dict,
    fit_static,
)
from fsrlab.calibration.model import HeldoutCalibration
from fsrlab.calibration.monotone import MonotoneCurve
from fsrlab.calibration.scoring import Recording
from fsrlab.calibration.selection import calibrate_recordings
from fsrlab.io.runwriter import write_run

N, CYCLES = 800, 4


def _triangle() -> np.ndarray:
    phase = np.arange(N) / N * CYCLES
    return 1 - np.abs(2 * (phase % 1) - 1)


def _cubic(seed: int):
    """Stress a cubic of frequency (2–5 kHz, 0–18 kPa) plus 5 Pa of noise: four triangle cycles."""
    f = 2000.0 + 3000.0 * _triangle()
    s = (f - 2000.0) / 1000.0
    truth = 4000 * s + 1500 * s ** 2 + 400 * s ** 3
    return f, truth, 5.0, np.random.default_rng(seed).normal(0, 5.0, N)


def _cubic_quiet(seed: int):
    """Stress a cubic of frequency (5–8 kHz, 0–204 kPa) plus 5 Pa of noise: so quiet that one polynomial is
    held-out best by many standard errors, alone (the piecewise and spline curves 8x its error and more)."""
    f = 5000.0 + 3000.0 * _triangle()
    d = f - 5000.0
    truth = 2e-6 * d ** 3 + 0.01 * d ** 2 + 20 * d
    return f, truth, 5.0, np.random.default_rng(seed).normal(0, 5.0, N)


def _power(seed: int):
    """Force a power law of the reading, 0.8·x^0.6 for x in 1–100 (0.8–12.7 N), plus 0.01 N of noise."""
    x = 1.0 + 99.0 * _triangle()
    return x, 0.8 * x ** 0.6, 0.01, np.random.default_rng(seed).normal(0, 0.01, N)


def _numpy_best(x, y, truth) -> float:
    """RMS error against the truth of numpy.polyfit's best degree, 1 to 5, on the same rows."""
    return min(float(np.sqrt(np.mean((np.polyval(np.polyfit(x, y, d), x) - truth) ** 2))) for d in range(1, 6))


@pytest.mark.parametrize("make,column,reference", [(_cubic, "frequency_hz", "stress_pa"),
                                                   (_cubic_quiet, "frequency_hz", "stress_pa"),
                                                   (_power, "frequency_hz", "force_n")])
@pytest.mark.parametrize("seed", [0, 1, 2, 7, 10])  # 7, 10: one polynomial alone is held-out best
def test_a_smooth_quiet_readout_is_calibrated_as_closely_as_numpys_best_polynomial(tmp_path, make, column,
                                                                                   reference, seed):
    """Issue 37's criterion: within 3× numpy's best polynomial of the truth, or a quarter of the noise's
    standard deviation if that is larger. Measured (seeds 0–2): the cubic 0.41–0.43 Pa against numpy's
    0.38–0.42 Pa (the piecewise curve alone: 37 Pa); the power law 0.006 N against 0.025 N. With seeds 7 and 10
    one polynomial is best by more than a standard error, alone: the static estimate must be that polynomial,
    not the best curve that cannot fall (a spline, 7.8 Pa on the cubic, 44 Pa on the quiet cubic)."""
    x, truth, sigma, noise = make(seed)
    t = np.arange(N) * 0.05
    path = write_run(tmp_path / "run.csv", {"time_s": t, column: x, reference: truth + noise})
    cal = fl.calibrate(path, x=column, reference=reference)
    est = np.asarray(fl.apply(cal, fl.load_run(path))[f"{reference}_estimate"], dtype=float)
    rms = float(np.sqrt(np.mean((est - truth) ** 2)))
    assert rms <= max(3 * _numpy_best(x, truth + noise, truth), 0.25 * sigma)
    if seed == 0:  # measure/live one reading at a time equal apply, beyond the readings too
        from stepping import assert_steps_as_batch

        wider = write_run(tmp_path / "wider.csv", {"time_s": t, column: np.r_[x[:400] * 1.2, x[400:] * 0.8],
                                                   reference: truth})
        assert_steps_as_batch(cal, wider, reference)


def _random_clean(case: int):
    """A clean readout drawn at random: a cubic with positive coefficients or a power law (exponent 0.3–3) of
    frequency (0.5–20 kHz, spans 10–150 %), rising or falling with it, noise 30 to 30 000 times below its span."""
    rng = np.random.default_rng(1000 + case)
    f0 = rng.uniform(500, 20000)
    span = f0 * rng.uniform(0.1, 1.5)
    f = f0 + span * _triangle()
    z = (f - f.min()) / span if rng.random() < 0.5 else (f.max() - f) / span
    if rng.random() < 0.5:
        a = rng.uniform(0.2, 2, 3)
        truth = rng.uniform(1e3, 2e5) * (a[0] * z + a[1] * z ** 2 + a[2] * z ** 3) / a.sum()
    else:
        truth = rng.uniform(1, 1e5) * (z + rng.uniform(0, 0.3)) ** rng.uniform(0.3, 3)
    sigma = float(np.ptp(truth)) * 10 ** rng.uniform(-4.5, -1.5)
    return f, truth, sigma, rng.normal(0, sigma, N)


@pytest.mark.parametrize("case", range(40))
def test_random_clean_readouts_are_calibrated_as_closely_as_numpys_best_polynomial(tmp_path, case):
    """Issue 37's criterion on 40 clean curves drawn at random (every other one with the memory tried):
    within 3× numpy's best polynomial of the truth, or a quarter of the noise's standard deviation. (Five of
    them failed while a polynomial best alone gave way to the best curve that cannot fall.)"""
    f, truth, sigma, noise = _random_clean(case)
    path = write_run(tmp_path / "run.csv", {"time_s": np.arange(N) * 0.05, "frequency_hz": f,
                                            "stress_pa": truth + noise})
    cal = fl.calibrate(path, x="frequency_hz", reference="stress_pa", compensate=bool(case % 2))
    est = np.asarray(fl.apply(cal, fl.load_run(path))["stress_pa_estimate"], dtype=float)
    rms = float(np.sqrt(np.mean((est - truth) ** 2)))
    assert rms <= max(3 * _numpy_best(f, truth + noise, truth), 0.25 * sigma)


def _noisy(seed: int, n: int = 300):
    rng = np.random.default_rng(seed)
    x = np.sort(rng.uniform(1.0, 50.0, n))
    return x, np.sqrt(x) + rng.normal(0, 0.3, n) + 2 * np.sin(x / 3)  # a wavy reference: tempts a curve to fall


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("family,size", [("piecewise", 8), ("spline", 0), ("spline", 4), ("spline", 8)])
@pytest.mark.parametrize("variable,sign", [("readout", 1), ("log", 1), ("reciprocal", -1)])
def test_the_monotone_families_never_fall(seed, family, size, variable, sign):
    """Property: piecewise and spline curves rise with force over and beyond their readings, whatever the data."""
    x, y = _noisy(seed)
    if sign < 0:
        y = y[::-1]
    curve = fit_static(x, y, family, size, variable, sign, None)
    grid = np.linspace(0.5, 60.0, 4001) if sign > 0 else np.linspace(60.0, 0.5, 4001)  # force rising
    assert curve.monotone and curve.is_monotone()
    assert np.all(np.diff(curve(grid)) >= -1e-9 * np.ptp(y))


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("degree", [2, 3, 4, 5])
def test_a_polynomial_says_whether_it_falls_over_its_readings(seed, degree):
    """Reference: the polynomial's slope on a dense grid of its calibrated readings."""
    x, y = _noisy(seed)
    curve = fit_static(x, y, "polynomial", degree, "readout", 1, None)
    grid = np.linspace(x.min(), x.max(), 20001)
    assert curve.is_monotone() == bool(np.all(np.diff(curve(grid)) >= -1e-9 * np.ptp(y)))


def test_the_engine_keeps_only_polynomials_that_rise_over_the_readings():
    """A reference that falls back within its range (a parabola's top): the polynomials that follow it are
    not tried, and the static estimate written rises over the readings."""
    rng = np.random.default_rng(3)
    t = np.arange(1200) * 0.02
    x = 1.0 + 9.0 * np.abs(np.sin(2 * np.pi * t / 6.0))
    y = 10 * x - 0.45 * x ** 2 + rng.normal(0, 0.05, t.size)  # rising to x = 11.1: nearly flat at the top
    y[x > 9.5] -= 2.0 * (x[x > 9.5] - 9.5)  # then falling
    cal, sel = calibrate_recordings([Recording(t, x, y)], compensate=False)
    assert sel.steps[0]["not_monotone"], sel.steps[0]
    grid = np.linspace(x.min(), x.max(), 5001)
    assert np.all(np.diff(cal.static_estimate(grid)) >= -1e-9)


def test_a_polynomial_continues_linearly_beyond_its_readings():
    """Closed form: flat below, and above the top the mean slope over the top half of the readings' range
    (as the piecewise curve): a straight line, never the polynomial's own growth."""
    x = np.linspace(1.0, 3.0, 200)
    curve = fit_static(x, x ** 3, "polynomial", 3, "readout", 1, None)
    assert np.allclose(curve(np.array([0.0, 0.5, 1.0])), 1.0)
    above = curve(np.array([3.0, 4.0, 5.0, 10.0]))
    slope = (27.0 - 8.0) / 1.0  # (f(3) − f(2))/(3 − 2): the top half of 1…3
    np.testing.assert_allclose(above, 27.0 + slope * np.array([0.0, 1.0, 2.0, 7.0]), rtol=1e-9)


def test_a_spline_without_inner_knots_is_a_monotone_cubic():
    """Closed form: a cubic whose slope's Bernstein coefficients are all positive is fitted exactly."""
    x = np.linspace(0.0, 2.0, 100)
    y = 1 + x + 0.5 * x ** 2 + 0.2 * x ** 3
    curve = fit_static(x, y, "spline", 0, "readout", 1, None, lam=0.0)
    np.testing.assert_allclose(curve(x), y, atol=1e-9)


def _curves():
    x, y = _noisy(0)
    return [fit_static(x, y, f, k, v, 1, None) for f, k in (("piecewise", 4), ("polynomial", 3), ("spline", 2))
            for v in ("readout", "log", "reciprocal")]


@pytest.mark.parametrize("curve", _curves(), ids=lambda c: c.name)
def test_every_family_round_trips_through_its_file_form_and_steps_as_the_batch(curve):
    back = curve_from_dict(json.loads(json.dumps(curve.to_dict())))
    assert type(back) is type(curve) and back.name == curve.name
    x = np.r_[np.linspace(-5.0, 70.0, 301), np.nan]
    np.testing.assert_array_equal(back(x), curve(x))
    np.testing.assert_allclose([curve.at(v) for v in x[:-1]], curve(x[:-1]), rtol=0, atol=1e-12)


def test_a_file_without_a_family_is_a_piecewise_curve():
    old = {"variable": "readout", "sign": 1, "adc": None, "knots": [0.0, 1.0, 2.0], "coefficients": [0.0, 1.0, 2.0],
           "readout_range": [0.0, 2.0]}
    assert isinstance(curve_from_dict(old), MonotoneCurve)
    with pytest.raises(ValueError):
        curve_from_dict({**old, "family": "fourier"})
    with pytest.raises(ValueError):
        SplineCurve.from_dict({**old, "family": "spline", "breaks": [0.0, 2.0], "coefficients": [0.0, 1.0, -1.0, 1.0]})
    with pytest.raises(ValueError):
        PolynomialCurve.from_dict({**old, "family": "polynomial", "centre": 1.0, "half_width": 0.0})


@pytest.fixture(scope="module")
def smooth_with_memory():
    """The hand-loaded Bouc–Wen sensor (:mod:`fsrlab.virtual.handloaded`): a smooth static estimate
    (polynomials and splines among the curves averaged) with a memory kept."""
    from fsrlab.virtual.handloaded import fsr_bench_run

    run = fsr_bench_run("hand", seed=1)
    rec = Recording(run.columns["time_s"], np.round(run.columns["voltage_v"] / 5.0 * 1023), run.columns["force_n"])
    cal, sel = calibrate_recordings([rec], compensate=True)
    return rec, cal, sel


def test_a_smooth_calibration_with_memory_round_trips_and_steps_as_the_batch(smooth_with_memory):
    rec, cal, _ = smooth_with_memory
    assert cal.has_memory and {m.family for m in cal.mix + (cal.static,)} - {"piecewise"}
    back = HeldoutCalibration.from_dict(json.loads(json.dumps(cal.to_dict())))
    assert back.creep_start == cal.creep_start == 0.5
    older = {k: v for k, v in cal.to_dict().items() if k != "creep_start"}
    assert HeldoutCalibration.from_dict(older).creep_start == 1.0  # files written before it: as they were
    x = rec.x.copy()
    x[[50, 51]] = (-20.0, 2000.0)  # beyond the readings both ways
    batch = cal.run(rec.t, x)[0]
    np.testing.assert_array_equal(back.run(rec.t, x)[0], batch)
    stepper = cal.stepper()
    stepped = np.array([stepper.step(v, t)[0] for v, t in zip(x, rec.t, strict=True)])
    np.testing.assert_allclose(stepped, batch, rtol=0, atol=1e-9)
