"""``fsrlab calibrate --compensate`` on 10⁶ readings, as a user runs it: time and peak memory.

One run of 10⁶ rows (100 Hz, 10⁴ s: a 10-bit divider reading of a power-law sensor with a loop-like
phase lag and noise, against a reference with noise), written as a run file; then, each as its own
process, the whole command (CSV read, held-out selection with the memory step, uncertainty, file
written) and, as the floor it is measured against, reading the same CSV into numpy
(``fsrlab.io.runformat.load_run``).
Peak memory is the child's maximum resident set size. Aims: ≤ 30 s and ≤ 1 GiB.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

TITLE = "Held-out calibration of 10^6 readings through the command line"
ROWS = 1_000_000
FSRLAB = str(Path(sys.executable).with_name("fsrlab"))


def _write(path: Path) -> None:
    from fsrlab.io.runwriter import write_run

    rng = np.random.default_rng(0)
    t = np.arange(ROWS) * 0.01
    f = 5 + 5 * np.sin(2 * np.pi * t / 7.3) * np.sin(2 * np.pi * t / 61)
    x = np.round(1023 * (f / 12) ** 0.7 / (1 + (f / 12) ** 0.7) + 8 * np.sin(2 * np.pi * t / 7.3 + 0.3)
                 + rng.normal(0, 2, ROWS))
    write_run(path, {"time_s": t, "reading": x, "force_n": f + rng.normal(0, 0.05, ROWS)},
              {"units": {"time_s": "s", "reading": "counts", "force_n": "N"}})


def _child(argv) -> tuple[float, float]:
    """Wall time [s] and peak resident memory [GiB] of one process (run alone, so the children's
    maximum is its own)."""
    code = ("import resource, subprocess, sys, time; t0 = time.perf_counter(); "
            "subprocess.run(sys.argv[1:], check=True, capture_output=True); dt = time.perf_counter() - t0; "
            "print(dt, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    out = subprocess.run([sys.executable, "-c", code, *argv], check=True, capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1]) * 1024 / 2 ** 30


def run() -> str:
    with tempfile.TemporaryDirectory() as tmp:
        run_file = Path(tmp) / "big.csv"
        _write(run_file)
        cases = [
            ("`fsrlab calibrate RUN --x reading --reference force_n --compensate`",
             [FSRLAB, "calibrate", str(run_file), "--x", "reading", "--reference", "force_n", "--compensate",
              "-o", str(Path(tmp) / "a.json")]),
            ("reading the CSV alone (`load_run`, the floor)",
             [sys.executable, "-c", f"from fsrlab.io.runformat import load_run; load_run({str(run_file)!r})"]),
        ]
        results = []
        for _name, argv in cases:
            dt, gib = _child(argv)
            results.append((dt, gib))
        ref, floor = results[0], results[-1]
        lines = ["| command | time (s) | peak memory (GiB) | time / reading the CSV | memory / reading the CSV |",
                 "|---|---:|---:|---:|---:|"]
        for (name, _), (dt, gib) in zip(cases, results, strict=True):
            lines.append(f"| {name} | {dt:.1f} | {gib:.2f} | {dt / floor[0]:.2f} | {gib / floor[1]:.2f} |")
        load = os.getloadavg()
        met_t, met_m = ref[0] <= 30, ref[1] <= 1.0
        lines.append("")
        lines.append(f"{ROWS:,} rows, {run_file.stat().st_size / 1e6:.0f} MB of CSV; one process each, in turn "
                     f"(load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}). Aims ≤ 30 s: "
                     f"{'met' if met_t else '**not met**'} ({ref[0]:.1f} s); ≤ 1 GiB: "
                     f"{'met' if met_m else '**not met**'} ({ref[1]:.2f} GiB).")
    return "\n".join(lines) + "\n"
