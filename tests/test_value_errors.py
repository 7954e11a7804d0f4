"""Every bare ``raise ValueError(`` left in src is one its function's docstring justifies.

The library raises :class:`fsrlab.errors.ParameterError` (or FileFormatError, ProvenanceError) with the
parameter at fault; a plain ValueError stays only where the function says why in its docstring (a
``Raises`` entry naming ValueError): a parse helper whose caller turns it into a message, or numpy's own
error kept on a public path. Reference: the property, on the source (ast).
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "fsrlab"


def _bare_value_errors(root: Path = SRC):
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for func in ast.walk(tree):
            if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(func):
                exc = node.exc if isinstance(node, ast.Raise) else None
                if isinstance(exc, ast.Call) and isinstance(exc.func, ast.Name) and exc.func.id == "ValueError":
                    yield path.relative_to(root.parent), func.name, node.lineno, ast.get_docstring(func) or ""


def test_each_bare_value_error_is_justified_by_its_docstring():
    unjustified = [f"{p}:{line} in {name}()" for p, name, line, doc in _bare_value_errors()
                   if "ValueError" not in doc]
    assert not unjustified, "raise ValueError without a docstring saying why: " + ", ".join(unjustified)


def test_at_most_ten_are_left():
    assert len(list(_bare_value_errors())) <= 10


def test_the_scan_finds_an_unjustified_one(tmp_path):
    """The scan itself: a raise without a docstring saying why is found, one with it is not."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "m.py").write_text('def f(x):\n    raise ValueError("x")\n\n\n'
                              'def g(x):\n    """Raises\n    ------\n    ValueError\n        Why."""\n'
                              '    raise ValueError("x")\n')
    found = {(name, "ValueError" in doc) for _, name, _, doc in _bare_value_errors(pkg)}
    assert found == {("f", False), ("g", True)}
