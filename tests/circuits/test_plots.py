"""Plots of the circuits' results (AstableResult.plot, DecodeResult.plot) on matplotlib's Agg backend.

Reference: the results' own arrays (the plotted data must be exactly them, in SI; the axes only
format them) and a property of the package (importing it does not import matplotlib).
"""

from __future__ import annotations

import subprocess
import sys

import matplotlib
import numpy as np
import pytest

from fsrlab.circuits.decode import decode
from fsrlab.circuits.lm555 import astable
from fsrlab.circuits.plotting import plot_twin

matplotlib.use("Agg", force=True)
import matplotlib.pyplot as plt  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def test_astable_plot_draws_frequency_and_duty_cycle_against_n():
    rf = np.array([35e3, 45e3, 100e3, 1e6])  # the first does not oscillate (N = 3.5 < 4): a gap
    res = astable(10e3, rf, 1e-9, diode=True, check=False)
    ax_f, ax_dc = res.plot()
    (line_f,) = ax_f.get_lines()
    (line_dc,) = ax_dc.get_lines()
    np.testing.assert_array_equal(line_f.get_xdata(), res.n_ratio)
    np.testing.assert_array_equal(line_f.get_ydata(), res.frequency_hz)
    np.testing.assert_array_equal(line_dc.get_ydata(), res.duty_cycle)
    assert np.isnan(line_f.get_ydata()[0])
    assert ax_f.get_xlabel() == "N = R_FSR/R" and ax_dc.get_shared_x_axes().joined(ax_f, ax_dc)
    assert ax_dc.yaxis.get_major_formatter().format_pct(0.25, 1.0) == "25%"  # fraction shown in percent


def test_astable_plot_into_given_axes_against_given_x():
    c = np.linspace(0.5e-9, 2e-9, 5)
    res = astable(10e3, 200e3, c, diode=True)
    _, ax = plt.subplots()
    ax_f, ax_dc = res.plot(ax=ax, x=c, xlabel="C_FSR [F]")
    assert ax_f is ax and ax.get_xlabel() == "C_FSR [F]"
    np.testing.assert_array_equal(ax_f.get_lines()[0].get_xdata(), c)
    np.testing.assert_array_equal(ax_dc.get_lines()[0].get_ydata(), res.duty_cycle)
    with pytest.raises(ValueError, match="frequency"):
        res.plot(x=c[:3])


def test_decode_plot_draws_parts_with_one_sigma_bands():
    a = astable(10e3, np.array([100e3, 200e3, 400e3]), 1e-9, diode=True)
    res = decode(a.frequency_hz, a.duty_cycle, 10e3, diode=True, periods=2)
    ax_r, ax_c = res.plot()
    np.testing.assert_array_equal(ax_r.get_lines()[0].get_xdata(), [0, 1, 2])
    np.testing.assert_array_equal(ax_r.get_lines()[0].get_ydata(), res.r_fsr_ohm)
    np.testing.assert_array_equal(ax_c.get_lines()[0].get_ydata(), res.c_fsr_farad)
    for axis, y, sd in ((ax_r, res.r_fsr_ohm, res.r_fsr_std_ohm), (ax_c, res.c_fsr_farad, res.c_fsr_std_farad)):
        (band,) = axis.collections
        corners = {tuple(v) for v in band.get_paths()[0].vertices}
        for i in range(3):
            assert (float(i), y[i] + sd[i]) in corners and (float(i), y[i] - sd[i]) in corners
    assert ax_r.get_xlabel() == "sample"


def test_scalar_result_is_one_marked_point():
    ax_f, _ = astable(10e3, 200e3, 1e-9).plot()
    assert ax_f.get_lines()[0].get_marker() == "o"


def test_plot_twin_rejects_two_dimensional_x():
    with pytest.raises(ValueError, match="x"):
        plot_twin(np.ones((2, 2)), (np.ones(4), None, "a", "V"), (np.ones(4), None, "b", "V"))


def test_importing_the_circuits_does_not_import_matplotlib():
    code = ("import sys, fsrlab.circuits.lm555, fsrlab.circuits.decode, fsrlab.circuits.plotting, "
            "fsrlab.circuits.circuit; print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
