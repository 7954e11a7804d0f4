"""Every docstring example (``>>>``) in the package runs, and prints what it shows.

Reference: the outputs written in the docstrings (each names where its value comes from: a printed table,
a closed form); doctest compares them with what the code prints now. Examples marked ``# doctest: +SKIP``
(they would write files or need hardware) are parsed but not run.
"""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
# Modules whose source holds an example; found by reading the files, so none is left out by an import.
MODULES = sorted(
    ".".join(path.relative_to(SRC).with_suffix("").parts).removesuffix(".__init__")
    for path in (SRC / "fsrlab").rglob("*.py") if ">>>" in path.read_text(encoding="utf-8")
)


def test_the_package_has_docstring_examples():
    assert len(MODULES) >= 3, MODULES


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an example that writes, writes here
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = [t for t in finder.find(module, module.__name__) if t.examples]
    assert tests, f"{name}: '>>>' in the source but no docstring example found"
    for test in tests:
        runner.run(test, out=lambda text: None)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed (python -m doctest -v)"
