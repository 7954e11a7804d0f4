"""The flat public API of ``import fsrlab``: lazy (PEP 562), complete, and resolving to the library's objects.

Reference: ``sys.modules`` in a fresh interpreter after ``import fsrlab`` (a property of the import, not a
timing), and the modules each public name is documented to come from.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

import fsrlab as fl


def test_import_fsrlab_loads_no_numpy():
    code = "import fsrlab, sys; assert 'numpy' not in sys.modules, sorted(sys.modules)"
    subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)


def test_the_names_a_user_calibrates_with_resolve():
    from fsrlab.calibration.apply import apply_calibration
    from fsrlab.calibration.document import load_calibration, save_calibration
    from fsrlab.calibration.runs import calibrate_runs
    from fsrlab.io.runformat import load_run
    from fsrlab.reports.run_report import write_run_report

    assert fl.load_run is load_run and fl.calibrate is calibrate_runs and fl.apply is apply_calibration
    assert fl.load_calibration is load_calibration and fl.save_calibration is save_calibration
    # The function, even after the reports package has been imported (it sets no attribute named report).
    import fsrlab.reports.paper  # noqa: F401

    assert fl.report is write_run_report


@pytest.mark.parametrize("name", fl.__all__)
def test_every_public_name_resolves(name):
    assert getattr(fl, name) is not None
    assert name in dir(fl)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_name"):
        fl.no_such_name  # noqa: B018


def test_calibrate_and_apply_through_the_flat_api(tmp_path):
    # The README's Python example, end to end on two synthetic runs (sensor -> 555 -> meter model).
    from fsrlab.virtual.synthetic import synthetic_run

    bench = synthetic_run(cycles=3, points_per_ramp=40, seed=1).write(tmp_path / "bench.csv")
    other = synthetic_run(cycles=1, points_per_ramp=40, seed=2).write(tmp_path / "other.csv")
    cal = fl.calibrate(fl.load_run(bench))
    assert isinstance(cal, fl.Calibration) and repr(cal).startswith("Calibration(stress_pa(frequency_hz): ")
    import matplotlib

    matplotlib.use("Agg")
    assert cal.plot().get_lines()  # README: results draw themselves, cal.plot()
    path = fl.save_calibration(cal, tmp_path / "cal.json")
    est = fl.apply(fl.load_calibration(path), fl.load_run(other))
    assert est["stress_pa_estimate"].size == fl.load_run(other)["stress_pa"].size
    # a run of the same generator (no gain moved): the line must stay near the identity and ±2u must cover
    # at least the 90 % the calibration aims at (measured: slope 0.998, coverage 100 %)
    ag = fl.agreement(est["stress_pa"], est["stress_pa_estimate"], est["stress_pa_uncertainty"])
    assert 0.9 < ag.slope < 1.1 and ag.coverage >= 0.9


def test_errors_carry_the_parameter_and_keep_their_builtin_base():
    from fsrlab.acquisition.serial_link import LinkError, SerialLink
    from fsrlab.io.runformat import RunFormatError

    assert issubclass(RunFormatError, ValueError) and issubclass(RunFormatError, fl.FsrlabError)
    with pytest.raises(LinkError) as info:
        SerialLink("/dev/fsrlab-no-such-port")
    assert isinstance(info.value, OSError) and info.value.parameter == "port"
    assert str(info.value) == f"port: {info.value.reason}"
