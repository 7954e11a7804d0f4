"""The output policy (fsrlab.io.outputs) and the commands that follow it.

Reference: the policy as the module docstring of fsrlab.io.outputs states it; the run format's sidecar
rule NAME.csv -> NAME.meta.json (docs/data-format.md). Each case compares the bytes of every file in
the directory before and after, so a command that overwrote anything fails here.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

import pytest

from clirun import run_cli
from fsrlab.io.outputs import OutputError, atomic_path, check_output, write_text_atomic

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _hashes(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file() and not p.is_symlink()}


@pytest.fixture
def work(tmp_path, monkeypatch):
    for name in ("bench.csv", "bench.meta.json", "calibration.json", "creep.csv", "creep.meta.json"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    return tmp_path


# ---- the policy itself ---------------------------------------------------------------------------

def test_empty_path_refused(tmp_path):
    for text in ("", "  "):
        with pytest.raises(OutputError, match="--out: is empty"):
            check_output(text, "--out")


def test_existing_file_needs_overwrite(tmp_path):
    f = tmp_path / "a.json"
    f.write_text("x")
    with pytest.raises(OutputError, match="exists; pass --overwrite"):
        check_output(f, "-o")
    assert check_output(f, "-o", overwrite=True) == f


def test_input_and_its_sidecar_refused_even_with_overwrite(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.csv").write_text("time_s\n")
    (tmp_path / "b.meta.json").write_text("{}")
    (tmp_path / "sub").mkdir()
    os.symlink(tmp_path / "b.csv", tmp_path / "link.csv")
    os.link(tmp_path / "b.csv", tmp_path / "hard.csv")
    for spelling in ("b.csv", "./b.csv", "sub/../b.csv", str(tmp_path / "b.csv"), "link.csv", "hard.csv"):
        with pytest.raises(OutputError, match="is the input b.csv"):
            check_output(spelling, "-o", overwrite=True, inputs=["b.csv"])
    with pytest.raises(OutputError, match="sidecar of the input"):
        check_output("./sub/../b.meta.json", "-o", overwrite=True, inputs=[tmp_path / "b.csv"])
    # A run output whose own sidecar would land on an input.
    (tmp_path / "cal.meta.json").write_text("{}")
    with pytest.raises(OutputError, match="is the input cal.meta.json"):
        check_output("cal.csv", "-o", overwrite=True, inputs=["cal.meta.json"], kind="run")


def test_directory_where_a_file_is_expected(tmp_path):
    with pytest.raises(OutputError, match="is a directory, not a file"):
        check_output(tmp_path, "-o", overwrite=True)
    with pytest.raises(OutputError, match="does not exist"):
        check_output(tmp_path / "missing" / "x.json", "-o")


def test_report_directory(tmp_path):
    d = tmp_path / "rep"
    assert check_output(d, "--out", kind="dir") == d  # missing: created by the command
    d.mkdir()
    check_output(d, "--out", kind="dir")  # empty: fine
    (d / "index.html").write_text("old")
    with pytest.raises(OutputError, match="not empty; pass --overwrite"):
        check_output(d, "--out", kind="dir")
    check_output(d, "--out", kind="dir", overwrite=True)
    with pytest.raises(OutputError, match="would replace the input"):
        check_output(d, "--out", kind="dir", overwrite=True, inputs=[d / "index.html"], names=["index.html"])
    with pytest.raises(OutputError, match="is a file, not a directory"):
        check_output(d / "index.html", "--out", kind="dir", overwrite=True)


def test_atomic_write_leaves_old_file_when_interrupted(tmp_path):
    f = tmp_path / "cal.json"
    f.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(f) as tmp:
            tmp.write_text("half")
            raise RuntimeError("interrupted")
    assert f.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["cal.json"]  # no temporary left behind
    write_text_atomic(f, "new")
    assert f.read_text() == "new"
    # The umask's permissions, not a temporary file's 0600.
    mask = os.umask(0)
    os.umask(mask)
    assert f.stat().st_mode & 0o777 == 0o666 & ~mask


# ---- the commands --------------------------------------------------------------------------------

def _refused(argv, root: Path, match: str):
    before = _hashes(root)
    code, out, err = run_cli(argv)
    assert code == 2, (argv, out, err)
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert match in err, err
    assert _hashes(root) == before, f"{argv} changed files"


def test_calibrate_output_policy(work):
    _refused(["calibrate", "bench.csv", "-o", "bench.csv"], work, "is the input bench.csv")
    _refused(["calibrate", "bench.csv", "-o", "./bench.meta.json", "--overwrite"], work, "sidecar of the input")
    _refused(["calibrate", "bench.csv", "-o", ""], work, "--output: is empty")
    _refused(["calibrate", "bench.csv", "-o", "."], work, "is a directory, not a file")
    _refused(["calibrate", "bench.csv", "-o", "calibration.json"], work, "exists; pass --overwrite")
    code, _, err = run_cli(["calibrate", "bench.csv", "-o", "calibration.json", "--overwrite"])
    assert code == 0, err


def test_apply_output_policy(work):
    _refused(["apply", "calibration.json", "bench.csv", "-o", "bench.meta.json", "--overwrite"], work,
             "sidecar of the input")
    _refused(["apply", "calibration.json", "bench.csv", "-o", "calibration.json", "--overwrite"], work,
             "is the input calibration.json")
    code, _, err = run_cli(["apply", "calibration.json", "bench.csv", "-o", "est.csv"])
    assert code == 0, err
    assert sorted(p.name for p in work.iterdir() if p.name.startswith(("est", ".est"))) == ["est.csv", "est.meta.json"]
    _refused(["apply", "calibration.json", "bench.csv", "-o", "est.csv"], work, "exists; pass --overwrite")


def test_report_dirs_and_plot(work):
    (work / "rep").mkdir()
    (work / "rep" / "index.html").write_text("mine")
    _refused(["report", "bench.csv", "--out", "rep"], work, "not empty; pass --overwrite")
    _refused(["report", "bench.csv", "--out", ""], work, "--out: is empty")
    _refused(["paper", "--out", "rep"], work, "not empty; pass --overwrite")
    _refused(["demo", "--out", ""], work, "--out: is empty")
    _refused(["demo", "--out", "rep"], work, "not empty; pass --overwrite")
    (work / "x.png").write_text("mine")
    _refused(["creep", "creep.csv", "--plot", "x.png"], work, "x.png exists; pass --overwrite")
    _refused(["creep", "creep.csv", "--plot", "rep/index.html"], work, "must end in .png")


def test_recording_outputs_refused_before_the_device(work):
    _refused(["acquire", "--virtual", "--duration", "1s", "--out", ""], work, "--out: is empty")
    _refused(["acquire", "--virtual", "--duration", "1s", "--out", "bench.csv"], work, "exists; pass --overwrite")
    _refused(["acquire", "--virtual", "--duration", "1s", "--out", "bench.meta.json", "--overwrite"], work,
             "named like a run's sidecar")
    shutil.copy(work / "calibration.json", work / "c.meta.json")
    _refused(["measure", "--virtual", "--cal", "c.meta.json", "--out", "c.csv", "--overwrite"], work,
             "c.meta.json is the input c.meta.json")
    _refused(["live", "--virtual", "--out", "bench.csv"], work, "live never replaces a run")
    (work / "w.placements.csv").write_text("mine")
    _refused(["weights", "--virtual", "--masses", "0,100g", "--out", "w.csv"], work, "w.placements.csv exists")
    _refused(["bench", "weights", "--virtual", "--out", "w.csv"], work, "w.placements.csv exists")


# ------------------------------------------------------------------------------------------------
# The same policy in the library (issue 40): fl.write_run, import's write_imported
# ------------------------------------------------------------------------------------------------

def test_write_run_refuses_to_replace_unless_asked(tmp_path):
    import fsrlab as fl

    path = fl.write_run(tmp_path / "r.csv", {"time_s": [0.0, 1.0]})
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    with pytest.raises(FileExistsError, match="r.csv exists"):
        fl.write_run(path, {"time_s": [5.0]})
    assert hashlib.sha256(path.read_bytes()).hexdigest() == digest
    assert fl.load_run(fl.write_run(path, {"time_s": [5.0]}, overwrite=True))["time_s"].tolist() == [5.0]


@pytest.mark.parametrize("target", ["", " ", "in.csv", "in.meta.json"])
def test_write_run_refuses_an_empty_path_and_its_inputs(tmp_path, target, monkeypatch):
    """Even with overwrite=True: an input (or its sidecar, through the run's own sidecar) is never replaced."""
    import fsrlab as fl
    from fsrlab.errors import FsrlabError

    monkeypatch.chdir(tmp_path)
    src = fl.write_run("in.csv", {"time_s": [0.0, 1.0]})
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    with pytest.raises(OutputError) as info:
        fl.write_run(target if target != "in.meta.json" else "in", {"time_s": [5.0]}, overwrite=True, inputs=[src])
    assert isinstance(info.value, FsrlabError) and info.value.parameter == "path"
    assert str(info.value).startswith("path: ")
    assert ("is empty" in str(info.value)) if not target.strip() else ("overwrite=True never replaces an input"
                                                                       in str(info.value))
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_library_refusals_say_overwrite_true_and_the_cli_says_its_option(tmp_path):
    f = tmp_path / "a.json"
    f.write_text("x")
    with pytest.raises(OutputError, match=r"^path: .*a\.json exists; pass overwrite=True to replace it$"):
        check_output(f, "path")
    with pytest.raises(OutputError, match=r"^--out: .*a\.json exists; pass --overwrite to replace it$"):
        check_output(f, "--out")
