"""The command-line fuzzer's output cases: every command that writes, given an output that exists, is
an input, is an input's sidecar, is empty, or is a directory (a file, for a report directory).

Reference: the output policy (fsrlab.io.outputs, README "Files written"): each case is refused with one
line and exit code 2, and the sha256 of every file in the directory is the same before and after.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from clirun import run_cli
from fuzzing import OUTPUT_CASES, WRITERS, output_case, tree_hashes

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize("case", OUTPUT_CASES)
@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_output_refused_and_nothing_changed(writer, case, tmp_path, monkeypatch):
    for name in ("bench.csv", "bench.meta.json", "calibration.json", "creep.csv", "creep.meta.json"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    shutil.copy(EXAMPLES / "calibration.json", tmp_path / "bench.csv.json")
    # A load cell's tare (fsrlab loadcell tare writes this form), the input of loadcell scale.
    (tmp_path / "lc.json").write_text(json.dumps({"format": "fsrlab-loadcell", "version": 1, "offset_counts": 8192.0,
                                                  "scale_counts_per_n": None}))
    monkeypatch.chdir(tmp_path)
    argv = output_case(writer, case, tmp_path)
    if argv is None:
        pytest.skip(f"{writer} has no input whose path could be given as its output")
    before = tree_hashes(tmp_path)
    code, out, err = run_cli(argv)
    assert code == 2, f"fsrlab {' '.join(argv)}: exit {code}\n{out}\n{err}"
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert tree_hashes(tmp_path) == before, f"fsrlab {' '.join(argv)} changed files"
