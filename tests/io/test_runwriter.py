"""RunWriter's guarantees beyond the format itself: an existing run is kept unless replacing it is
asked for, errors name the files the user gave, and a write that fails half-way leaves whole rows.

References: docs/data-format.md (crash safety: a run file is made of whole rows, the sidecar is
replaced atomically) and the operating system's file-size limit (``RLIMIT_FSIZE``, POSIX), which
makes a write fail with EFBIG part of the way through a line.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import pytest

from fsrlab.errors import ParameterError
from fsrlab.io.runformat import RunFormatError, load_run, sidecar_path
from fsrlab.io.runwriter import RunWriter, write_run


def _run(path, rows=3, overwrite=False):
    with RunWriter(path, ["time_s", "frequency_hz"], overwrite=overwrite) as w:
        for i in range(rows):
            w.write({"time_s": i * 0.1, "frequency_hz": 5000.0 + i})


@pytest.mark.parametrize("which", ["csv", "sidecar"])
def test_an_existing_run_is_kept_without_overwrite(tmp_path, which):
    path = tmp_path / "run.csv"
    _run(path)
    if which == "sidecar":
        path.unlink()  # the sidecar alone still belongs to a run
    before = {p: p.read_bytes() for p in (path, sidecar_path(path)) if p.exists()}
    existing = path if which == "csv" else sidecar_path(path)
    with pytest.raises(FileExistsError, match=str(existing)):
        RunWriter(path, ["time_s"], overwrite=False)
    with pytest.raises(FileExistsError):
        write_run(path, {"time_s": [0.0]}, overwrite=False)
    assert {p: p.read_bytes() for p in (path, sidecar_path(path)) if p.exists()} == before


def test_overwrite_replaces_and_a_new_run_needs_no_flag(tmp_path):
    path = tmp_path / "run.csv"
    _run(path, rows=5)
    with pytest.raises(FileExistsError, match="run.csv exists"):
        _run(path, rows=2)  # the default refuses (the output policy)
    assert load_run(path).n_rows == 5
    _run(path, rows=2, overwrite=True)
    assert load_run(path).n_rows == 2
    with RunWriter(tmp_path / "new.csv", ["time_s"]) as w:
        w.write({"time_s": 0.0})
    assert load_run(tmp_path / "new.csv").n_rows == 1


def test_errors_name_the_users_files_not_a_temporary(tmp_path):
    with pytest.raises(OSError) as info:
        RunWriter(tmp_path / "missing" / "x.csv", ["time_s"])
    assert "x.csv" in str(info.value) and ".tmp" not in str(info.value)
    (tmp_path / "y.meta.json").mkdir()  # a directory where the sidecar goes
    with pytest.raises(OSError) as info:
        RunWriter(tmp_path / "y.csv", ["time_s"])
    assert str(tmp_path / "y.meta.json") in str(info.value) and ".tmp" not in str(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["y.meta.json"]  # no temporary left behind
    (tmp_path / "z.csv").mkdir()  # a directory where the CSV goes: refused before anything is written
    with pytest.raises(ParameterError) as info:
        RunWriter(tmp_path / "z.csv", ["time_s"])
    assert str(tmp_path / "z.csv") in str(info.value) and info.value.parameter == "path"
    assert not sidecar_path(tmp_path / "z.csv").exists()


def test_replacing_a_run_never_leaves_its_csv_beside_a_sidecar_not_its_own(tmp_path, monkeypatch):
    """Replacing a run: a sidecar that cannot be written (a full disk) leaves the old run as it was; a
    failure after the old rows are gone leaves the new CSV alone, without the old sidecar."""
    import errno

    from fsrlab.io import runwriter

    path = tmp_path / "run.csv"
    _run(path, rows=4)
    before = {p: p.read_bytes() for p in (path, sidecar_path(path))}

    def full(target, obj):
        raise runwriter._user_error(OSError(errno.ENOSPC, "No space left on device"), target)

    monkeypatch.setattr(runwriter, "_prepare_json", full)
    with pytest.raises(OSError, match="run.meta.json"):
        RunWriter(path, ["time_s", "force_n"], overwrite=True)
    assert {p: p.read_bytes() for p in (path, sidecar_path(path))} == before
    monkeypatch.undo()

    real = os.replace

    def no_rename(src, dst):
        if str(dst).endswith(".meta.json"):
            raise OSError(errno.EIO, "Input/output error")
        return real(src, dst)

    monkeypatch.setattr(runwriter.os, "replace", no_rename)
    with pytest.raises(OSError, match="run.meta.json"):
        RunWriter(path, ["time_s", "force_n"], overwrite=True)
    monkeypatch.undo()
    assert not sidecar_path(path).exists()  # the old sidecar went before the old rows
    assert path.read_text() == "time_s,force_n\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]  # no temporary left behind
    _run(path, rows=3, overwrite=True)
    rows = path.read_bytes()
    sidecar_path(path).unlink()
    sidecar_path(path).mkdir()  # a directory where the sidecar goes: refused before the old rows go
    with pytest.raises(OSError, match="run.meta.json"):
        RunWriter(path, ["time_s", "force_n"], overwrite=True)
    assert path.read_bytes() == rows


def test_update_metadata_is_on_disk_while_the_run_is_open(tmp_path):
    path = tmp_path / "run.csv"
    w = RunWriter(path, ["time_s"])
    w.update_metadata({"gaps": [{"start_s": 1.0, "length_s": 2.5}]})
    meta = json.loads(sidecar_path(path).read_text())
    assert meta["gaps"] == [{"start_s": 1.0, "length_s": 2.5}] and meta["complete"] is False
    w.close()
    meta = json.loads(sidecar_path(path).read_text())
    assert meta["gaps"][0]["length_s"] == 2.5 and meta["complete"] is True


def test_a_write_that_fails_half_way_leaves_whole_rows(tmp_path):
    """A file-size limit makes a write stop inside a line (EFBIG): the writer cuts that part off,
    raises one OSError naming the run, and still closes the run with the true row count."""
    path = tmp_path / "run.csv"
    script = f"""
import resource, signal
from fsrlab.io.runwriter import RunWriter
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (1000, 1000))
w = RunWriter({str(path)!r}, ["time_s", "frequency_hz"])
try:
    for i in range(1000):
        w.write({{"time_s": i * 0.001, "frequency_hz": 5123.456789 + i}})
except OSError as exc:
    print(exc)
w.close()
"""
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"cannot write '{path}': File too large"
    text = path.read_text()
    assert text.endswith("\n") and len(text) <= 1000
    run = load_run(path)
    assert run.metadata["complete"] is True and run.metadata["rows"] == run.n_rows == text.count("\n") - 1 > 0


def test_write_run_interrupted_leaves_the_old_run_and_no_temporary(tmp_path, monkeypatch):
    # Reference: the output policy's atomic write (fsrlab.io.outputs, README "Files written"): both files of the
    # old run stay byte for byte while the new one is written, and nothing else is left beside them. The
    # interruption (Ctrl-C) comes at the second fsync: after the new run's sidecar and its header were written.
    import hashlib

    from fsrlab.io.runwriter import write_run

    old = write_run(tmp_path / "run.csv", {"time_s": [0.1, 0.2], "frequency_hz": [5000.0, 5100.0]})

    def files():
        return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(tmp_path.iterdir())}

    before = files()
    calls = []
    real_fsync = os.fsync

    def interrupted_fsync(fd):
        calls.append(fd)
        if len(calls) == 2:
            raise KeyboardInterrupt
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", interrupted_fsync)
    with pytest.raises(KeyboardInterrupt):
        write_run(old, {"time_s": [0.1, 0.2, 0.3], "frequency_hz": [1.0, 2.0, 3.0]}, overwrite=True)
    monkeypatch.undo()
    assert files() == before and set(before) == {"run.csv", "run.meta.json"}
    # A directory that does not exist is named as the user gave it, not as a temporary file.
    with pytest.raises(OSError, match=r"cannot write '.*missing/run\.csv'"):
        write_run(tmp_path / "missing" / "run.csv", {"time_s": [0.1]})


# Two runs of the same shape, as `apply -o` run twice with calibrations of two circuits writes them: the
# row count alone cannot tell one from the other.
_OLD = ({"time_s": [0.1, 0.2], "frequency_hz": [5000.0, 5100.0]}, {"circuit": {"r_ohm": 10e3, "diode": True}})
_NEW = ({"time_s": [0.1, 0.2], "frequency_hz": [7000.0, 7100.0]}, {"circuit": {"r_ohm": 4.7e3, "diode": True}})

# write_run stopped after the first of its two renames (of a run's own file, not of a temporary) and before the
# second: by Ctrl-C (KeyboardInterrupt: write_run's clean-up runs) or by a kill (no handler, no clean-up).
_STOPPED_BETWEEN_THE_RENAMES = """
import os, sys
from fsrlab.io.runwriter import write_run
real, renamed = os.replace, []
def replace(src, dst):
    renamed.extend([dst] if not os.path.basename(dst).startswith(".") else [])
    if len(renamed) == 2:
        if sys.argv[2] == "kill":
            os._exit(9)
        raise KeyboardInterrupt
    real(src, dst)
os.replace = replace
write_run(sys.argv[1], {"time_s": [0.1, 0.2], "frequency_hz": [7000.0, 7100.0]},
          {"circuit": {"r_ohm": 4.7e3, "diode": True}}, overwrite=True)
"""


@pytest.mark.parametrize("old", ["write_run", "recorded"])
@pytest.mark.parametrize("how", ["Ctrl-C", "kill"])
def test_write_run_stopped_between_its_two_renames_leaves_no_pair_that_passes_for_one_run(tmp_path, how, old):
    # Reference: the crash-safety contract of docs/data-format.md (a run's two files are one run or refused as
    # a pair, never the new CSV under the old sidecar: another circuit, another calibration). The run replaced
    # was written whole, or recorded row by row (its sidecar names no content).
    path = tmp_path / "run.csv"
    if old == "write_run":
        write_run(path, *_OLD)
    else:
        with RunWriter(path, list(_OLD[0]), _OLD[1]) as w:
            for row in zip(*_OLD[0].values(), strict=True):
                w.write(dict(zip(_OLD[0], row, strict=True)))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    done = subprocess.run([sys.executable, "-c", _STOPPED_BETWEEN_THE_RENAMES, path, how], env=env,
                          capture_output=True, text=True)
    # (Python ends on an uncaught KeyboardInterrupt as killed by SIGINT)
    assert done.returncode == (9 if how == "kill" else -signal.SIGINT), done.stderr
    with pytest.raises(RunFormatError, match=r"run\.csv: not the CSV its sidecar run\.meta\.json was written with"):
        load_run(path)
    write_run(path, *_NEW, overwrite=True)  # written again: one run
    run = load_run(path)
    assert list(run["frequency_hz"]) == [7000.0, 7100.0] and run.metadata["circuit"]["r_ohm"] == 4.7e3


def test_a_sidecar_taken_from_a_run_read_names_the_new_csv(tmp_path):
    # The digest is of the file written, never carried over with the rest of a sidecar (a RunWriter copying a
    # run's metadata, write_run writing an estimate of it): both runs read back as written.
    write_run(tmp_path / "a.csv", *_OLD)
    meta = load_run(tmp_path / "a.csv").metadata
    with RunWriter(tmp_path / "b.csv", ["time_s", "frequency_hz"], meta) as w:
        w.write({"time_s": 0.1, "frequency_hz": 1.0})
    write_run(tmp_path / "c.csv", _NEW[0], meta)
    assert load_run(tmp_path / "b.csv").n_rows == 1 and load_run(tmp_path / "c.csv").n_rows == 2
    assert "csv_sha256" not in load_run(tmp_path / "b.csv").metadata  # a recording names no content
