"""``fsrlab import`` of a large foreign CSV against pandas reading the same file.

A logger's file of about 50 MB (1.8 million rows: millis, fsr counts, a force in g, a temperature) is
written once; then, in the same process, :func:`fsrlab.io.foreign.import_foreign` and
:func:`fsrlab.io.foreign.write_imported` (what ``fsrlab import big.csv -o run.csv`` does: sniff, header,
units, every cell checked, the run written in shortest round-trip form) against ``pandas.read_csv``
of the same file and ``DataFrame.to_csv`` of the three converted columns (the peer: a C parser and
writer that check nothing). Wall time of each, and the peak memory of a fresh process for fsrlab's
(``ru_maxrss`` of a child, so the peer's allocations do not count).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

TITLE = "Import of a 50 MB foreign CSV"
ROWS = 1_800_000

_CHILD = """
import resource, sys, time
from fsrlab.io.foreign import import_foreign, write_imported
t = time.perf_counter()
write_imported(import_foreign(sys.argv[1]), sys.argv[2], overwrite=True)
print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
"""


def _write(path: Path) -> None:
    rng = np.random.default_rng(1)
    cols = np.column_stack([np.arange(ROWS) * 10, rng.integers(0, 1023, ROWS), rng.normal(500, 100, ROWS),
                            rng.normal(25, 1, ROWS)])
    np.savetxt(path, cols, fmt=["%d", "%d", "%.4f", "%.3f"], delimiter=",", header="millis,fsr,force_g,temp_c",
               comments="")


def run() -> str:
    import pandas as pd

    with tempfile.TemporaryDirectory() as tmp:
        src, out, peer = Path(tmp) / "big.csv", Path(tmp) / "run.csv", Path(tmp) / "peer.csv"
        _write(src)
        size_mb = src.stat().st_size / 1e6
        done = subprocess.run([sys.executable, "-c", _CHILD, str(src), str(out)], capture_output=True, text=True,
                              check=True)
        fsrlab_s, fsrlab_mb = (float(v) for v in done.stdout.split())
        t = time.perf_counter()
        df = pd.read_csv(src)
        pd.DataFrame({"time_s": df["millis"] / 1e3, "reading": df["fsr"],
                      "force_n": df["force_g"] * 9.80665 / 1e3}).to_csv(peer, index=False)
        pandas_s = time.perf_counter() - t
    return (f"{size_mb:.0f} MB, {ROWS} rows.\n\n"
            "| | wall time (s) | peak memory (MB) |\n|---|---|---|\n"
            f"| fsrlab import (every cell checked, shortest round-trip floats) | {fsrlab_s:.2f} | {fsrlab_mb:.0f} |\n"
            f"| pandas read_csv + to_csv (peer) | {pandas_s:.2f} | |\n\n"
            f"fsrlab / pandas: {fsrlab_s / pandas_s:.1f}×.\n")
