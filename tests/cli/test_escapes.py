"""The one rendering boundary: nothing fsrlab prints acts on a terminal (issue 40).

Reference: ECMA-48 (control functions: C0 characters, ESC sequences such as ``ESC [ 2 J``, erase the
display, and ``ESC ] 0 ; ... BEL``, set the window title) and Unicode's format characters (U+202E, the
right-to-left override of "Trojan source"); fsrlab.io.shown.printable writes each as its escape. Every
reading command is given a cell, a column name and a file name holding them, and its stdout and stderr
must hold no control character but line feeds and tabs.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from clirun import run_cli
from fsrlab.io.shown import printable

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ESCAPES = ["\x1b[2J", "\x1b]0;owned\x07", "\x9b31m", "\u202e", "\r\x08"]
RAW_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def test_printable_escapes_controls_and_keeps_lines():
    assert printable("200g\x1b[2J\n\tok") == "200g\\x1b[2J\n\tok"
    assert printable("a\u202eb\x9b") == "a\\u202eb\\x9b" and printable("µ Ω → \\") == "µ Ω → \\"
    assert printable("x\ny", keep="") == "x\\x0ay"


def _corpus(root: Path, esc: str) -> dict[str, str]:
    """Inputs whose cells, column names and file names hold ``esc``; what each reading command needs."""
    for name in ("bench.csv", "bench.meta.json", "calibration.json", "creep.csv", "creep.meta.json", "iso376.csv"):
        shutil.copy(EXAMPLES / name, root / name)
    run = f"run{esc}.csv"
    lines = (root / "bench.csv").read_text().splitlines()
    (root / run).write_text("\n".join([lines[0] + f",x{esc}"] + [ln + ",1" for ln in lines[1:]]) + "\n")
    shutil.copy(root / "bench.meta.json", root / f"run{esc}.meta.json")
    table = (EXAMPLES / "repeatability.csv").read_text().replace("200g,", f"200g{esc},")
    (root / f"rep{esc}.csv").write_text(table)
    (root / f"foreign{esc}.csv").write_text(f"time_ms,fsr{esc},force_N\n0,1,0\n10,2,{esc}\n")
    shutil.copy(root / "creep.csv", root / f"creep{esc}.csv")
    shutil.copy(root / "creep.meta.json", root / f"creep{esc}.meta.json")
    return {"run": run, "x": f"x{esc}", "rep": f"rep{esc}.csv", "foreign": f"foreign{esc}.csv",
            "creep": f"creep{esc}.csv", "bad": f"missing{esc}.csv"}


COMMANDS = [
    ["hysteresis", "{run}"], ["hysteresis", "{run}", "--quantity", "{x}"], ["hysteresis", "{bad}"],
    ["repeatability", "{rep}"], ["repeatability", "{rep}", "--json"], ["iso376", "{rep}"],
    ["calibrate", "{run}", "-o", "c.json"], ["calibrate", "{run}", "--x", "{x}", "-o", "c2.json"],
    ["apply", "calibration.json", "{run}", "-o", "e.csv"], ["apply", "calibration.json", "{bad}", "-o", "e2.csv"],
    ["creep", "{creep}"], ["report", "{run}", "--out", "rep-dir"], ["import", "{foreign}", "-o", "i.csv"],
    ["import", "{run}", "--reading", "{x}", "-o", "i2.csv"],
]


@pytest.mark.parametrize("esc", ESCAPES, ids=repr)
@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_reading_commands_print_no_control_character(tmp_path, monkeypatch, command, esc):
    names = _corpus(tmp_path, esc)
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli([a.format(**names) for a in command])
    assert code in (0, 1, 2), err
    assert "Traceback" not in err
    raw = RAW_CONTROL.search(out + err)
    assert raw is None, f"printed {raw.group(0)!r}: {(out + err)[max(0, raw.start() - 60):raw.end() + 20]!r}"
