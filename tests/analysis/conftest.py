"""Runs shared by the analysis tests (synthetic, not measurements).

``runs``: a directory with ``bench.csv`` (3 cycles, seed 1) and ``other.csv`` (2 cycles, seed 7)
written by fsrlab.virtual.synthetic.synthetic_run (VirtualFSR -> lm555.astable, R = 10 kΩ, ideal
D1 -> 100 ms windows, 62.5 ns quantization, 0.2 % frequency noise) in the run format.
"""

from __future__ import annotations

import pytest

from fsrlab.virtual.synthetic import synthetic_run


@pytest.fixture(scope="session")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("runs")
    synthetic_run(cycles=3, seed=1).write(d / "bench.csv")
    synthetic_run(cycles=2, seed=7).write(d / "other.csv")
    return d
