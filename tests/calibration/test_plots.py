"""``.plot()`` of the analysis results: what is drawn is the result's own data.

Reference: the result objects' numbers (calibration polynomial over its calibrated range, the
branches eq. 13 compared, σd and the difference there) read back from the matplotlib lines (Agg
backend, no display). Data: the closed-form loop of tests/metrics/test_cycles.py (HE = a/(4 σf)
exactly) and synthetic_run (VirtualFSR -> lm555.astable -> 62.5 ns timer).
"""

from __future__ import annotations

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from fsrlab.calibration.result import calibrate  # noqa: E402
from fsrlab.metrics.cycles import run_hysteresis  # noqa: E402
from fsrlab.metrics.hysteresis import hysteresis_error, hysteresis_error_curves  # noqa: E402


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_calibration_plot_draws_data_then_curve_over_the_calibrated_range():
    x = np.linspace(3e3, 10e3, 60)
    y = 1e-4 * (x - 2e3) ** 1.5
    cal = calibrate(x, y, degree=3)
    ax = cal.plot(x=x, y=y)
    data, curve = ax.lines
    np.testing.assert_array_equal(data.get_xdata(), x)
    np.testing.assert_array_equal(data.get_ydata(), y)
    gx = curve.get_xdata()
    assert (gx[0], gx[-1]) == pytest.approx(cal.x_range) and cal.x_range == pytest.approx((3e3, 10e3))
    np.testing.assert_array_equal(curve.get_ydata(), cal(gx))
    assert ax.get_xlabel() == "frequency_hz [Hz]" and ax.get_ylabel() == "stress_pa [Pa]"
    _, ax2 = plt.subplots()
    assert cal.plot(ax=ax2) is ax2 and len(ax2.lines) == 1  # no data given: the curve only
    with pytest.raises(ValueError, match="x and y"):
        cal.plot(x=x)


def test_calibration_plot_shows_the_compensation_branches():
    from fsrlab.calibration.compensation import fit_direction_aware
    from fsrlab.virtual.synthetic import synthetic_run

    c = synthetic_run(cycles=2, seed=3).columns
    cal = calibrate(c["frequency_hz"], c["stress_pa"], degree=3)
    cal.compensation = fit_direction_aware(c["frequency_hz"], c["stress_pa"])
    _, load, unload = cal.plot().lines
    np.testing.assert_array_equal(load.get_ydata(), cal.compensation.load_model(load.get_xdata()))
    np.testing.assert_array_equal(unload.get_ydata(), cal.compensation.unload_model(unload.get_xdata()))


def test_hysteresis_result_plot_draws_both_branches_and_the_difference_at_sigma_d():
    s = np.linspace(0, 10e3, 101)
    ql, qu = s, s + 2e3 * s * (10e3 - s) / 10e3**2  # largest difference a/4 = 500 at σf/2
    res = hysteresis_error(s, ql, s[::-1], qu[::-1])
    ax = res.plot(label="Q")
    load, unload, diff = ax.lines
    np.testing.assert_array_equal(load.get_xdata(), s)
    np.testing.assert_array_equal(load.get_ydata(), ql)
    np.testing.assert_allclose(unload.get_ydata(), qu, rtol=1e-12)
    np.testing.assert_array_equal(diff.get_xdata(), [5e3, 5e3])
    np.testing.assert_allclose(diff.get_ydata(), [5e3, 5.5e3])
    assert "5.00 %" in ax.get_title()
    # Model curves: the branches evaluated on the search grid are drawn.
    curves = hysteresis_error_curves(lambda t: t, lambda t: t + 2e3 * t * (10e3 - t) / 10e3**2, 10e3, n=201)
    load, unload, diff = curves.plot().lines
    assert len(load.get_xdata()) == 201 and diff.get_xdata()[0] == pytest.approx(5e3)


def test_run_hysteresis_plot_draws_each_cycle_then_the_mean_branches():
    sf, a = 10e3, 2e3
    up = np.linspace(0, sf, 201)
    x = np.concatenate([up, up[::-1][1:], up[1:], up[::-1][1:]])
    q = np.where(np.arange(x.size) % 400 < 200, x, x + a * x * (sf - x) / sf**2)
    q[np.arange(x.size) % 400 == 200] = sf
    res = run_hysteresis(x, q)
    ax = res.plot()
    lines = ax.lines
    assert len(lines) == 2 * len(res.cycles) + 3
    for k, c in enumerate(res.cycles):
        np.testing.assert_array_equal(lines[2 * k].get_ydata(), c.q_load)
        np.testing.assert_array_equal(lines[2 * k + 1].get_ydata(), c.q_unload)
    load, unload, diff = lines[-3:]
    np.testing.assert_array_equal(load.get_xdata(), res.overall.stress_pa)
    np.testing.assert_array_equal(unload.get_ydata(), res.overall.q_unload)
    assert diff.get_xdata()[0] == res.stress_at_max_pa
    assert np.diff(diff.get_ydata())[0] == pytest.approx(res.overall.difference)
    assert len(res.plot(cycles=False).lines) == 3


def test_matplotlib_is_imported_only_by_plot():
    import subprocess

    code = ("import sys; from fsrlab.calibration import fit, result, apply; from fsrlab.metrics import cycles, hysteresis; "
            "print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
