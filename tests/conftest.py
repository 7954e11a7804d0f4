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
