"""Shared test configuration: hypothesis profiles and the paper's printed numbers."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI", "").lower() in {"1", "true", "yes"} else "dev")

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="session")
def paper() -> dict:
    """Every number the paper prints (tests/data/paper.json, see PROVENANCE.md)."""
    return json.loads((DATA / "paper.json").read_text(encoding="utf-8"))
