"""Numbers the README, the docs and the help state, checked against what the code does now.

References: the live page's update periods (fsrlab.live.page.UPDATE_S, PLOT_S; docs/live.md measured
them); the transcript of a faulty virtual link (docs/hardware.md "Recording readings"); the calibration shipped
in examples/ (examples/README.md: fitted on a synthetic run from 0 to 50 kPa) and the virtual meter's
default profile (a 0 → 50 kPa → 0 triangle of 4 s, the --peak and --period defaults).
"""

from __future__ import annotations

import json
import re
import shlex
import shutil
from pathlib import Path

from clirun import run_cli

ROOT = Path(__file__).resolve().parents[2]


def test_live_help_and_docs_state_the_pages_update_periods():
    from fsrlab.live.page import PLOT_S, UPDATE_S

    code, out, _ = run_cli(["live", "--help"])
    text = " ".join(out.split())
    numbers, plots = f"{UPDATE_S * 1e3:g} ms", f"{PLOT_S * 1e3:g} ms"
    assert code == 0 and f"numbers every {numbers}" in text and f"plots every {plots}" in text, text
    docs = " ".join((ROOT / "docs" / "live.md").read_text().split())
    assert f"update every {numbers} (`live.page.UPDATE_S`), the plots every {plots}" in docs


def test_the_documented_transcript_of_a_faulty_link_is_what_acquire_prints(tmp_path, monkeypatch):
    # The same words, and the same counts within one: in real time the device may send one frame more while it
    # is being stopped (a corrupt line more or less), and the last window may or may not make it.
    readme = (ROOT / "docs" / "hardware.md").read_text().splitlines()
    command = next(i for i, ln in enumerate(readme) if ln.startswith("$ fsrlab acquire --virtual")
                   and "--corrupt" in ln and "--overwrite" in ln)
    shown = readme[command + 1]
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(shlex.split(readme[command])[2:] + ["--quiet"])
    assert code == 0, err
    printed = out.strip()
    number = r"\d+(?:\.\d+)?"
    assert re.sub(number, "N", printed) == re.sub(number, "N", shown), (printed, shown)
    for a, b in zip(re.findall(number, printed), re.findall(number, shown), strict=True):
        assert abs(float(a) - float(b)) <= 1, (printed, shown)


def test_the_measure_example_stays_in_the_calibrated_range(tmp_path, monkeypatch):
    # measure's first help example, over one period of the default triangle (0 → 50 kPa → 0) instead of 10 s.
    code, out, _ = run_cli(["measure", "--help"])
    example = next(ln.strip() for ln in out.splitlines() if ln.strip().startswith("fsrlab measure --virtual"))
    args = shlex.split(example)[1:]
    args[args.index("--duration") + 1] = "4s"
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args + ["--quiet", "--json"])
    assert code == 0, err

    info = json.loads(out)
    assert info["frames"] >= 30 and info["estimated"] == info["frames"] and info["out_of_range"] == 0, info
