"""Start-up of the command line: ``fsrlab --help`` and a closed-form command, as fresh processes.

Each command is started N times as its own process (the way a user runs it); min / median / max of the
wall time, against bare Python starting in the same run (``python -c pass``: the floor no command can
go under). Aims, as multiples of bare Python's median in the same run: ``--help`` ≤ 10× and
``fsrlab oscillator ... --json`` ≤ 16×. The machine's load is stated: on shared cores the ratios move.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

TITLE = "Command-line start-up"
N = 11
FSRLAB = str(Path(sys.executable).with_name("fsrlab"))
CASES = [
    ("bare Python (`python -c pass`)", [sys.executable, "-c", "pass"], None),
    ("`fsrlab --help`", [FSRLAB, "--help"], 10),
    ("`fsrlab oscillator --r 10k --rfsr 200k --cfsr 1n --json`",
     [FSRLAB, "oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--json"], 16),
]


def _times(argv) -> list[float]:
    subprocess.run(argv, check=True, capture_output=True)  # warm the file cache
    out = []
    for _ in range(N):
        t0 = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True)
        out.append(time.perf_counter() - t0)
    return out


def run() -> str:
    rows = []
    bare = None
    for label, argv, aim in CASES:
        t = _times(argv)
        med = statistics.median(t)
        bare = med if bare is None else bare
        ratio = med / bare
        verdict = "" if aim is None else f"≤ {aim}×: **{'met' if ratio <= aim else 'not met'}**"
        rows.append(f"| {label} | {min(t):.3f} s | {med:.3f} s | {max(t):.3f} s | {ratio:.1f}× | {verdict} |")
    load = " / ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"Each command started {N} times as a fresh process after one warm-up start (wall time; load average "
            f"{load}).\n\n"
            "| command | min | median | max | median / bare Python | aim |\n|---|---|---|---|---|---|\n"
            + "\n".join(rows) + "\n\n"
            "What keeps it short: heavy modules (numpy, scipy, matplotlib, pyserial, bokeh, the report) are "
            "imported only by the commands that use them (`tests/test_import_weight.py` checks that `import "
            "fsrlab.cli` imports none of numpy, scipy, matplotlib; the paper's circuit and parameters are checked "
            "without numpy when they are plain numbers); constants that are one number are literals with their "
            "CODATA source; typer ≥ 0.29 would check each option's value again with a pydantic TypeAdapter "
            "(importing pydantic and building the adapters, ~0.1–0.15 s here, cProfile): options that click has "
            "already read into their type skip it (`fsrlab.cli._light_coercion`, compared with typer's own "
            "coercion on every option in `tests/cli/test_main.py`; `tests/test_import_weight.py` checks that "
            "neither `--help` nor `oscillator --json` imports pydantic, and `--help` no numpy). What is left: "
            "`--help` imports typer and every command module to list the commands (lazy registration, which would "
            "import only the command that runs, is not done), and the oscillator imports numpy for the model "
            "(~0.05 s).\n")
