"""The report's sections built in two processes (fsrlab.reports.paper.build_sections).

Reference: the sequential build of the same section modules: the same Sections, in the order of
SECTION_MODULES, the side sections built by another process (its pid in their data), a failure
there raised here.
"""

from __future__ import annotations

import os
import sys
import types

import pytest

import fsrlab.reports.paper as paper
from fsrlab.reports.model import Section


def _module(name: str, fail: bool = False) -> types.ModuleType:
    mod = types.ModuleType(name)

    def build(outdir):
        if fail:
            raise ValueError(f"{name}: cannot build")
        return Section(name, name.title(), data={name: {"pid": os.getpid()}})

    mod.build = build
    return mod


@pytest.fixture
def fake_sections(monkeypatch):
    names = ["fake_a", "fake_b", "fake_c"]
    for n in names:
        monkeypatch.setitem(sys.modules, n, _module(n))
    monkeypatch.setattr(paper, "SECTION_MODULES", names)
    monkeypatch.setattr(paper, "SIDE_SECTIONS", ("fake_a", "fake_c"))
    return names


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork is what the second process uses")
def test_side_sections_come_back_in_order_from_another_process(fake_sections, tmp_path):
    seq = paper.build_sections(tmp_path, parallel=False)
    par = paper.build_sections(tmp_path, parallel=True)
    assert [s.key for s in par] == [s.key for s in seq] == fake_sections
    pid = {s.key: s.data[s.key]["pid"] for s in par}
    assert pid["fake_b"] == os.getpid() and pid["fake_a"] == pid["fake_c"] != os.getpid()
    assert all(s.data[s.key]["pid"] == os.getpid() for s in seq)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="fork is what the second process uses")
def test_a_failure_in_the_second_process_is_raised_here(fake_sections, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "fake_c", _module("fake_c", fail=True))
    with pytest.raises(ValueError, match="fake_c: cannot build"):
        paper.build_sections(tmp_path, parallel=True)
