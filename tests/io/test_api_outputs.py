"""The output policy in the Python API (issue 40): every public function that writes, given an output that
exists, is its input, is its input's sidecar, or is empty, refuses and changes no file.

Reference: the output policy (fsrlab.io.outputs, README "Files written"); each case compares the sha256 of
every file in the directory before and after.
"""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import pytest

import fsrlab as fl

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
CASES = ["exists", "input", "sidecar", "empty"]


def _hashes(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture
def work(tmp_path, monkeypatch):
    for name in ("bench.csv", "bench.meta.json", "calibration.json", "foreign_fsr.csv"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    (tmp_path / "old.json").write_text("{}\n")
    (tmp_path / "old.csv").write_text("time_s\n0\n")
    (tmp_path / "rep").mkdir()
    (tmp_path / "rep" / "index.html").write_text("<p>mine</p>\n")
    (tmp_path / "sketches" / "fsrlab_meter").mkdir(parents=True)
    (tmp_path / "sketches" / "fsrlab_meter" / "fsrlab_meter.ino").write_text("// mine\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _write_run(case):
    target = {"exists": "old.csv", "input": "bench.csv", "sidecar": "bench", "empty": ""}[case]
    fl.write_run(target, {"time_s": [0.0, 1.0]}, overwrite=case != "exists", inputs=["bench.csv"])


def _import(case):
    from fsrlab.io.foreign import import_foreign, write_imported

    target = {"exists": "old.csv", "input": "foreign_fsr.csv", "sidecar": "foreign_fsr", "empty": ""}[case]
    write_imported(import_foreign("foreign_fsr.csv"), target, overwrite=case != "exists")


def _sketch(case):
    from fsrlab.acquisition.firmware import write_sketch

    if case in ("input", "sidecar"):
        pytest.skip("write_sketch has no input")
    write_sketch({"exists": "sketches", "empty": ""}[case])


def _save_calibration(case):
    cal = fl.load_calibration("calibration.json")
    target = {"exists": "old.json", "input": "bench.csv", "sidecar": "bench.meta.json", "empty": ""}[case]
    fl.save_calibration(cal, target, overwrite=case != "exists", inputs=["bench.csv"])


def _report(case):
    if case == "sidecar":
        pytest.skip("a report is a directory: no sidecar")
    fl.report("bench.csv", {"exists": "rep", "input": "bench.csv", "empty": ""}[case], overwrite=case != "exists")


def _paper_report(case):
    if case in ("input", "sidecar"):
        pytest.skip("the reproduction report has no input")
    fl.paper_report({"exists": "rep", "empty": ""}[case])


WRITERS = {"write_run": _write_run, "write_imported": _import, "write_sketch": _sketch,
           "save_calibration": _save_calibration, "report": _report, "paper_report": _paper_report}


@pytest.mark.parametrize("writer, case", [(w, c) for w in WRITERS for c in CASES])
def test_writer_refuses_and_changes_nothing(work, writer, case):
    before = _hashes(work)
    with pytest.raises((ValueError, FileExistsError)) as info:
        WRITERS[writer](case)
    assert "Traceback" not in str(info.value)
    assert _hashes(work) == before


def test_save_calibration_replaces_only_when_asked_and_never_its_own_runs(work):
    # Reference: the output policy (fsrlab.io.outputs): overwrite=True replaces an output; the runs the
    # calibration was fitted on (cal.sources) stay protected without being named in inputs.
    cal = fl.calibrate("bench.csv", x="frequency_hz")
    written = fl.save_calibration(cal, "old.json", overwrite=True)
    assert fl.load_calibration(written).x_name == "frequency_hz"
    before = _hashes(work)
    with pytest.raises(fl.ParameterError) as info:
        fl.save_calibration(cal, "bench.meta.json", overwrite=True)
    assert info.value.parameter == "path" and "sidecar" in str(info.value)
    assert _hashes(work) == before


def test_refusals_name_the_parameter(work):
    # Reference: issue 40 ("raises a FsrlabError naming the parameter"): the library's refusals carry the
    # Python parameter, not a command-line option.
    cal = fl.load_calibration("calibration.json")
    for call, parameter in ((lambda: fl.save_calibration(cal, "old.json"), "path"),
                            (lambda: fl.report("bench.csv", "rep"), "outdir"),
                            (lambda: fl.paper_report(""), "outdir"),
                            (lambda: fl.save_calibration(cal, "x.json", overwrite="yes"), "overwrite")):
        with pytest.raises(fl.ParameterError) as info:
            call()
        assert info.value.parameter == parameter and "--" not in str(info.value)
