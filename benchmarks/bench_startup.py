"""Start-up of the command line: ``fsrlab --help`` and a closed-form command, as fresh processes.

Each command is started N times as its own process (the way a user runs it), the commands in turn; min /
median / max of the wall time, against bare Python starting in the same run (``python -c pass``: the floor
no command can go under). Aims, as multiples of bare Python's median in the same run: ``--help`` ≤ 10× and
``fsrlab oscillator ... --json`` ≤ 16×. Two floors are measured beside them: importing typer (what every
command needs) and typer with numpy (what the oscillator's closed form needs). The machine's load is
stated: on shared cores the ratios move.
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
    ("floor: `python -c 'import typer'`", [sys.executable, "-c", "import typer"], None),
    ("`fsrlab --help`", [FSRLAB, "--help"], 10),
    ("floor: `python -c 'import typer, numpy'`", [sys.executable, "-c", "import typer, numpy"], None),
    ("`fsrlab oscillator --r 10k --rfsr 200k --cfsr 1n --json`",
     [FSRLAB, "oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--json"], 16),
]


def _times() -> list[list[float]]:
    """Wall times of each case, started in turn N times (a change of the machine's load touches all alike)."""
    # The starts write and read bytecode caches, as an installed package has them (pip compiles them):
    # with PYTHONDONTWRITEBYTECODE set, a source tree would compile every module at every start.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    for _, argv, _ in CASES:
        subprocess.run(argv, check=True, capture_output=True, env=env)  # warm the file and bytecode caches
    out: list[list[float]] = [[] for _ in CASES]
    for _ in range(N):
        for times, (_, argv, _) in zip(out, CASES, strict=True):
            t0 = time.perf_counter()
            subprocess.run(argv, check=True, capture_output=True, env=env)
            times.append(time.perf_counter() - t0)
    return out


_OWN = """import contextlib, io, sys, time
import {floor}
t0 = time.perf_counter()
from fsrlab.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main({args!r})
    except SystemExit:
        pass
print(time.perf_counter() - t0)
"""


def _own(floor: str, args: list[str]) -> float:
    """Median time of fsrlab's own part of a command: in a fresh process, after importing ``floor``."""
    code = _OWN.format(floor=floor, args=args)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    runs = [float(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True,
                                 env=env).stdout) for _ in range(N)]
    return statistics.median(runs)


def run() -> str:
    rows = []
    medians = []
    for (label, _, aim), t in zip(CASES, _times(), strict=True):
        med = statistics.median(t)
        medians.append(med)
        ratio = med / medians[0]
        verdict = "" if aim is None else f"≤ {aim}×: **{'met' if ratio <= aim else 'not met'}**"
        rows.append(f"| {label} | {min(t):.3f} s | {med:.3f} s | {max(t):.3f} s | {ratio:.1f}× | {verdict} |")
    own_help = _own("typer", CASES[2][1][1:])
    own_oscillator = _own("typer, numpy", CASES[4][1][1:])
    load = " / ".join(f"{x:.1f}" for x in os.getloadavg())
    return (f"Each command started {N} times as a fresh process, the commands in turn, after one warm-up start "
            f"each (wall time; bytecode caches written, as an installed package has them; load average {load}).\n\n"
            "| command | min | median | max | median / bare Python | aim |\n|---|---|---|---|---|---|\n"
            + "\n".join(rows) + "\n\n"
            "What keeps it short: the command list of `fsrlab --help` comes from a table of names, topic modules "
            "and summaries (`COMMANDS` in `fsrlab/cli/__init__.py`), so `--help` imports typer and no command's "
            "module, and `fsrlab CMD` imports only CMD's (`tests/cli/test_lazy_commands.py` checks the table "
            "against the commands and that `--help` lists the same as the commands themselves; it and "
            "`tests/test_import_weight.py` check in a fresh interpreter which modules a start imports). Heavy "
            "modules (numpy, scipy, matplotlib, pyserial, bokeh, the report) are imported only by the commands "
            "that use them; constants that are one number are literals with their CODATA source; typer ≥ 0.29 "
            "would check each option's value again with a pydantic TypeAdapter (importing pydantic and building "
            "the adapters, ~0.1–0.15 s here, cProfile): options that click has already read into their type skip "
            "it (`fsrlab.cli._light_coercion`, compared with typer's own coercion on every option in "
            "`tests/cli/test_main.py`; no `--help` and no `oscillator --json` imports pydantic).\n\n"
            "What is left is mostly the floors: importing typer (its vendored click, `inspect`, its coercion "
            "module), and for the oscillator numpy too (the vectorised closed form of `fsrlab.circuits.lm555`). "
            f"fsrlab's own part, timed inside a fresh process after those imports (median of {N}): "
            f"{1e3 * own_help:.0f} ms for `--help`, {1e3 * own_oscillator:.0f} ms for the oscillator (its modules: "
            "the option parsers, the circuit dataclasses; building its one command; the model; `python -X "
            "importtime`, cProfile). The "
            f"oscillator's floor alone is {medians[3] / medians[0]:.1f}× bare Python (median), which leaves "
            f"{CASES[4][2] - medians[3] / medians[0]:.1f}× of its aim to fsrlab: on busy cores its ratio moves across "
            "the aim from run to run.\n")
