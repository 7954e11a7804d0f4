"""Start-up of the command line: ``fsrlab --help`` and a closed-form command, as fresh processes.

Each command is started N times as its own process (the way a user runs it); min / median / max of the
wall time, against bare Python starting in the same run (``python -c pass``: the floor no command can
go under). Aims: ``--help`` ≤ 0.2 s and ``fsrlab oscillator ... --json`` ≤ 0.3 s (medians).
"""

from __future__ import annotations

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
    ("`fsrlab --help`", [FSRLAB, "--help"], 0.2),
    ("`fsrlab oscillator --r 10k --rfsr 200k --cfsr 1n --json`",
     [FSRLAB, "oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--json"], 0.3),
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
    for label, argv, aim in CASES:
        t = _times(argv)
        med = statistics.median(t)
        verdict = "" if aim is None else f"≤ {aim} s: **{'met' if med <= aim else 'not met'}**"
        rows.append(f"| {label} | {min(t):.3f} s | {med:.3f} s | {max(t):.3f} s | {verdict} |")
    return (f"Each command started {N} times as a fresh process after one warm-up start (wall time).\n\n"
            "| command | min | median | max | aim (median) |\n|---|---|---|---|---|\n" + "\n".join(rows) + "\n\n"
            "What keeps it short: heavy modules (numpy, scipy, matplotlib, pyserial, bokeh, the report) are "
            "imported only by the commands that use them (`tests/test_import_weight.py` checks that `import "
            "fsrlab.cli` imports none of numpy, scipy, matplotlib; the paper's circuit and parameters are checked "
            "without numpy when they are plain numbers); constants that are one number are literals with their "
            "CODATA source. What is left of a command's start: typer ≥ 0.29 builds each option's converter with "
            "pydantic when the command runs (~0.1–0.15 s here, measured with cProfile), then numpy for the "
            "model (~0.05 s).\n")
