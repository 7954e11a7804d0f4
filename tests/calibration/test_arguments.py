"""The calibration's arguments are checked by the library: a bad one is a ParameterError naming the Python parameter.

Reference: the rule of fsrlab.errors (``.parameter`` set, the message ``"<parameter>: <reason>"``, no
command-line option in it: the command line maps the parameter to its option), checked on each argument
of ``fl.calibrate``, ``fl.apply`` and ``Calibration.estimate``/``estimator``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import fsrlab as fl

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def bench():
    return fl.load_run(EXAMPLES / "bench.csv")


@pytest.fixture(scope="module")
def cal(bench):
    return fl.calibrate(bench)


@pytest.mark.parametrize("kwargs, parameter", [
    ({"x": "stress_pa"}, "x"),  # the reference against itself
    ({"x": "force_n"}, "x"),
    ({"x": "no_such_column"}, "x"),
    ({"x": 3}, "x"),
    ({"reference": "newtons"}, "reference"),
    ({"rail": -5}, "rail"),
    ({"rail": 0}, "rail"),
    ({"rail": "5V"}, "rail"),  # a number: units are for the command line
    ({"rail": 100.0}, "rail"),  # reached by the readings (frequencies up to 9.8 kHz)
    ({"between_runs": 2}, "between_runs"),
    ({"between_runs": -0.1}, "between_runs"),
    ({"between_runs": "20%"}, "between_runs"),
    ({"lag": "1s"}, "lag"),
    ({"lag": float("nan")}, "lag"),
    ({"compensate": "yes"}, "compensate"),
])
def test_calibrate_refuses_a_bad_argument_naming_it(bench, kwargs, parameter):
    with pytest.raises(fl.ParameterError) as info:
        fl.calibrate(bench, **kwargs)
    assert info.value.parameter == parameter and str(info.value).startswith(f"{parameter}: ")
    assert "--" not in str(info.value)  # no command-line option in a library message


def test_no_runs_is_a_parameter_error():
    with pytest.raises(fl.ParameterError) as info:
        fl.calibrate([])
    assert info.value.parameter == "runs"


@pytest.mark.parametrize("margin", [-0.1, float("nan"), "10%", True])
def test_margin_is_a_fraction_of_the_span(cal, bench, margin):
    for call in (lambda: fl.apply(cal, bench, margin=margin), lambda: cal.estimate(bench, margin=margin),
                 lambda: cal.estimator(margin=margin)):
        with pytest.raises(fl.ParameterError) as info:
            call()
        assert info.value.parameter == "margin" and "--" not in str(info.value)


def test_apply_takes_a_calibration_or_its_file(cal, bench, tmp_path):
    """A path is read as the calibration file it names (the same estimates as the object it was saved from);
    anything else is a ParameterError naming ``cal``."""
    path = fl.save_calibration(cal, tmp_path / "cal.json")
    for given in (path, str(path)):
        np.testing.assert_array_equal(fl.apply(given, bench)["stress_pa_estimate"],
                                      fl.apply(cal, bench)["stress_pa_estimate"])
    with pytest.raises(fl.ParameterError) as info:
        fl.apply({"x": "frequency_hz"}, bench)
    assert info.value.parameter == "cal"


def test_a_synthetic_run_is_calibrated_as_it_is():
    """``fl.synthetic_run()`` gives columns and a sidecar, not a file: calibrated like a loaded run, every
    reading of it counted."""
    syn = fl.synthetic_run(cycles=2, points_per_ramp=30, seed=3)
    cal = fl.calibrate(syn)
    assert isinstance(cal, fl.Calibration) and cal.x_name == "frequency_hz" and cal.y_name == "stress_pa"
    assert cal.n == syn.columns["stress_pa"].size
