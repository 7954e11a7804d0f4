"""Shared test configuration: hypothesis profiles and the paper's printed numbers."""

from __future__ import annotations

import os

import pytest
from hypothesis import settings

from fsrlab.reference import paper_values

settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI", "").lower() in {"1", "true", "yes"} else "dev")


@pytest.fixture(scope="session")
def paper() -> dict:
    """Every number the paper prints (fsrlab/data/paper.json, see its PROVENANCE.md)."""
    return paper_values()


@pytest.fixture(scope="session")
def runs(tmp_path_factory):
    """A directory with ``bench.csv`` (3 cycles, seed 1) and ``other.csv`` (2 cycles, seed 7): synthetic runs.

    Written by fsrlab.virtual.synthetic.synthetic_run (VirtualFSR -> lm555.astable, R = 10 kΩ, ideal D1 ->
    100 ms windows, 62.5 ns quantization, 0.2 % frequency noise) in the run format; not measurements.
    """
    from fsrlab.virtual.synthetic import synthetic_run

    d = tmp_path_factory.mktemp("runs")
    synthetic_run(cycles=3, seed=1).write(d / "bench.csv")
    synthetic_run(cycles=2, seed=7).write(d / "other.csv")
    return d
