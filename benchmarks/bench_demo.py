"""`fsrlab demo`: the whole chain, the virtual bench at --speed max against --speed realtime, same run.

The demo records 16 s + 16 s of spring cycles and about 21 s of dead weights, then calibrates and writes
both reports. Peer: the same demo with ``--speed realtime`` (the way it ran before: the bench in real
time, one run after the other), measured in the same run. Aim: ``fsrlab demo`` ≤ 30 s (median, the twin
available). Each run is a separate process, as a user starts it; the steps' own times come from its
``--json``.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TITLE = "The demo (`fsrlab demo`): the virtual bench faster than real time"
REPEAT = 3
AIM_S = 30.0


def _demo(speed: str) -> tuple[float, dict]:
    exe = str(Path(sys.executable).with_name("fsrlab"))
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        out = subprocess.run([exe, "demo", "--out", tmp, "--speed", speed, "--json"], check=True,
                             capture_output=True, text=True).stdout
        return time.perf_counter() - t0, json.loads(out)


def run() -> str:
    fast = [_demo("max") for _ in range(REPEAT)]
    slow_t, slow = _demo("realtime")
    t = [x for x, _ in fast]
    lo, med, hi = min(t), statistics.median(t), max(t)
    info = fast[t.index(med)][1] if med in t else fast[0][1]
    steps = ", ".join(f"{s['step']} {s['seconds']:.1f} s" for s in info["steps"])
    load = " / ".join(f"{x:.1f}" for x in os.getloadavg())
    met = "met" if med <= AIM_S else "not met"
    return (
        f"Bench: {info['device']} "
        f"({'the digital twin, firmware in simavr' if info['device'] == 'twin' else 'Python virtual device'}).\n\n"
        "| way | runs | min | median | max | vs real time |\n|---|---|---|---|---|---|\n"
        f"| `--speed realtime` (the previous way) | 1 | {slow_t:.1f} s | {slow_t:.1f} s | {slow_t:.1f} s | 1 |\n"
        f"| `--speed max` (the default) | {REPEAT} | {lo:.1f} s | {med:.1f} s | {hi:.1f} s "
        f"| {slow_t / med:.2f}× faster |\n\n"
        f"Steps of the median `--speed max` run: {steps}. Aim ≤ {AIM_S:g} s (median): **{met}** (load average "
        f"{load} on cores shared with other jobs). The recordings are simavr's work on the twin (three at once at "
        "`--speed max`, one simavr process each): the section on the twin below gives simavr's pace here. "
        "The reproduction report is drawn in a process "
        "of its own at niceness +10 from the end of the spring runs, beside the dead weights (its step is the wait "
        "left when the chain is done).\n"
    )


if __name__ == "__main__":
    print(run())
