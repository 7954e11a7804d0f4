"""The calibration package stays small enough to read: its lines in total, and each function's.

Reference: a property of the source, counted the way ``wc -l`` counts lines (newline characters) and
the way ``ast`` places a definition (``end_lineno - lineno + 1``, its ``def`` line to its last line, the
docstring included).
"""

from __future__ import annotations

import ast
from pathlib import Path

import fsrlab.calibration

PACKAGE = Path(fsrlab.calibration.__file__).parent
#: Lines of ``calibration/*.py`` together. [lines]
MAX_PACKAGE_LINES = 4000
#: Lines of one function or method, from its ``def`` to its last line. [lines]
MAX_FUNCTION_LINES = 80


def _sources() -> dict[Path, str]:
    return {path: path.read_text(encoding="utf-8") for path in sorted(PACKAGE.glob("*.py"))}


def package_lines(sources: dict[Path, str]) -> int:
    """Lines of the modules together, as ``wc -l`` counts them."""
    return sum(text.count("\n") for text in sources.values())


def long_functions(sources: dict[Path, str], limit: int) -> list[str]:
    """``module.py:line name (n lines)`` of every function or method longer than ``limit`` lines."""
    found = []
    for path, text in sources.items():
        for node in ast.walk(ast.parse(text, filename=str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > limit:
                    found.append(f"{path.name}:{node.lineno} {node.name} ({n} lines)")
    return found


def test_the_package_has_at_most_its_lines():
    sources = _sources()
    assert len(sources) > 1  # the package was found
    n = package_lines(sources)
    per_module = ", ".join(f"{p.name} {t.count(chr(10))}" for p, t in sources.items())
    assert n <= MAX_PACKAGE_LINES, f"calibration/ has {n} lines, over {MAX_PACKAGE_LINES}: {per_module}"


def test_no_function_is_longer_than_its_limit():
    long = long_functions(_sources(), MAX_FUNCTION_LINES)
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: " + "; ".join(long)


def test_the_counts_see_what_they_limit(tmp_path):
    """The counts on a module made here: 3 newlines are 3 lines; a function of 4 lines is found over 3."""
    path = tmp_path / "m.py"
    text = "def f():\n    x = 1\n    return x\n\n\nclass C:\n    async def g(self):\n        a = 1\n        b = 2\n" \
           "        return a + b\n"
    path.write_text(text, encoding="utf-8")
    assert package_lines({path: "a\nb\nc\n"}) == 3
    assert long_functions({path: text}, 3) == ["m.py:7 g (4 lines)"]
    assert long_functions({path: text}, 4) == []
