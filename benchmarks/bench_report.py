"""`fsrlab paper`: the reproduction report, the current way against the previous way, same run.

The previous way, rebuilt here by swapping four functions back in (nothing else changes): ngspice runs
one after another when the oscillator section is built, each writing its waveform as text (``wrdata``,
15 digits) read with ``np.loadtxt``; every figure laid out by ``tight_layout`` (which renders the figure
once more to measure it). The current way: ngspice runs side by side (``simulate_spice_many``, as many
as the cores), started before the first section so they run while the physics figures draw
(``prefetch``), binary raw output (``read_raw``), fixed figure layouts (``reports.figures.fixed_layout``).

Both build the same sections in-process after a warm-up (imports and caches loaded), best of N each;
the current way also with every section in this one process (``build_sections(parallel=False)``), against
the default that builds the physics and measurements sections in a forked second process, the two
alternated.
The aim is for the whole command, process start-up included: ``fsrlab paper`` ≤ 3.5 s,
timed as separate processes (min / median / max of N).
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

TITLE = "Reproduction report (`fsrlab paper`)"
REPEAT = 3
AIM_S = 3.5


def _old_run_ngspice(text: str, output_file: str = "fsrlab_out.raw", timeout_s: float = 300.0) -> np.ndarray:
    """The previous runner: the same netlist with a text ``wrdata`` output, read by ``np.loadtxt``."""
    import shutil

    old = text.replace("set filetype=binary\n", "set wr_singlescale\nset wr_vecnames\noption numdgt=15\n")
    old = old.replace(f"write {output_file} v(out) v(thr)", "wrdata fsrlab_out.txt v(out) v(thr)")
    with tempfile.TemporaryDirectory(prefix="fsrlab-bench-") as tmp:
        (Path(tmp) / "circuit.cir").write_text(old, encoding="ascii")
        subprocess.run([shutil.which("ngspice"), "-b", "circuit.cir"], cwd=tmp, capture_output=True, check=True,
                       timeout=timeout_s)
        return np.loadtxt(Path(tmp) / "fsrlab_out.txt", skiprows=1, ndmin=2)


@contextmanager
def _previous_way():
    import fsrlab.circuits.paper_ratio as paper_ratio
    import fsrlab.circuits.spice as spice
    import fsrlab.reports.figures as figures
    import fsrlab.reports.sections.oscillator as oscillator

    saved = spice.run_ngspice, figures.fixed_layout, paper_ratio.simulate_spice_many, oscillator.prefetch
    spice.run_ngspice = _old_run_ngspice
    figures.fixed_layout = lambda fig: fig.tight_layout()
    paper_ratio.simulate_spice_many = lambda cases, jobs=None, **o: spice.simulate_spice_many(cases, jobs=1, **o)
    del oscillator.prefetch  # no background start: the section runs ngspice when it is built
    try:
        yield
    finally:
        spice.run_ngspice, figures.fixed_layout, paper_ratio.simulate_spice_many, oscillator.prefetch = saved


def _build_time(parallel: bool | None = None) -> float:
    from fsrlab.reports.paper import build_sections

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        build_sections(Path(tmp), parallel=parallel)
        return time.perf_counter() - t0


def _best(repeat: int, parallel: bool | None = None) -> float:
    _build_time(parallel)  # warm-up
    return min(_build_time(parallel) for _ in range(repeat))


def _process_times(repeat: int) -> list[float]:
    exe = str(Path(sys.executable).with_name("fsrlab"))
    out = []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            subprocess.run([exe, "paper", "--out", tmp], check=True, capture_output=True)
            out.append(time.perf_counter() - t0)
    return out


def run() -> str:
    from fsrlab.circuits.spice import ngspice_available

    if not ngspice_available():
        return "ngspice is not installed (`make sysdeps`): not measured.\n"
    import os

    # One process and two, alternated (a shared machine's load then weighs on both alike); best of each.
    _build_time(None), _build_time(False)
    pairs = [(_build_time(None), _build_time(False)) for _ in range(REPEAT + 1)]
    new, one = min(p[0] for p in pairs), min(p[1] for p in pairs)
    wins = sum(a < b for a, b in pairs)
    with _previous_way():
        old = _best(REPEAT, parallel=False)
    procs = _process_times(REPEAT)
    lo, med, hi = min(procs), statistics.median(procs), max(procs)
    met = "met" if med <= AIM_S else "not met"
    return (
        f"Sections built in-process after a warm-up, best of {REPEAT} each (same run, same machine):\n\n"
        "| way | build time | ratio |\n|---|---|---|\n"
        f"| previous: ngspice one at a time, text waveforms, `tight_layout` | {old:.2f} s | 1 |\n"
        f"| concurrent ngspice, binary raw output, fixed layouts, one process | {one:.2f} s | {old / one:.2f}× faster |\n"
        f"| current: the same, physics and measurements in a second process | {new:.2f} s | {old / new:.2f}× faster |\n\n"
        f"One process and two alternated {REPEAT + 1} times (best of each above): two were faster in {wins} of "
        f"the {REPEAT + 1} pairs.\n\n"
        f"Whole command as separate processes (`fsrlab paper --out DIR`, imports included), {REPEAT} runs: "
        f"min {lo:.2f} s, median {med:.2f} s, max {hi:.2f} s. Aim ≤ {AIM_S} s (median): **{met}** (load average "
        + " / ".join(f"{x:.1f}" for x in os.getloadavg()) + " on this machine's cores, shared with other jobs).\n"
    )
