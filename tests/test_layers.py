"""fsrlab's layers: each part of the package imports only from the parts below it.

Reference: the layer order of docs/architecture.md (a property of the source). Every import counts:
module level, inside functions and under ``TYPE_CHECKING``, since any of them ties the parts together.
Parts on one level (bench and paper) may import each other only without a cycle between them.
"""

from __future__ import annotations

import ast
from pathlib import Path

import fsrlab

SRC = Path(fsrlab.__file__).parent

#: Lowest first; a part may import from its own level and below. The flat API (fsrlab/__init__.py)
#: sits above all of them and is left out.
LEVELS = (
    ("units", "errors", "hardware", "reference"),
    ("physics",),
    ("circuits",),
    ("io",),
    ("acquisition",),
    ("virtual",),
    ("metrics",),
    ("calibration",),
    ("bench", "paper"),
    ("reports",),
    ("live",),
    ("cli",),
)
RANK = {part: i for i, parts in enumerate(LEVELS) for part in parts}


def _part(path: Path) -> str:
    rel = path.relative_to(SRC)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def _imported_parts(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    parts = set()
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names if node.module == "fsrlab"]
        elif isinstance(node, ast.ImportFrom) and node.level:
            raise AssertionError(f"{path}: a relative import; fsrlab imports by absolute name")
        for name in names:
            bits = name.split(".")
            if bits[0] == "fsrlab" and len(bits) > 1:
                parts.add(bits[1])
    return parts


def _graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for path in SRC.rglob("*.py"):
        if path == SRC / "__init__.py":
            continue
        graph.setdefault(_part(path), set()).update(_imported_parts(path) - {_part(path)})
    return graph


def test_every_part_has_a_level():
    assert set(_graph()) <= set(RANK), f"parts without a level: {sorted(set(_graph()) - set(RANK))}"


def test_each_part_imports_only_from_its_level_and_below():
    wrong = sorted(f"{a} imports {b}" for a, deps in _graph().items() for b in deps
                   if b in RANK and a in RANK and RANK[b] > RANK[a])
    assert not wrong, "imports upwards: " + "; ".join(wrong)


def test_no_cycle_between_parts_of_one_level():
    graph = _graph()
    cycles = sorted(f"{a} <-> {b}" for a, deps in graph.items() for b in deps
                    if a < b and a in graph.get(b, set()))
    assert not cycles, "parts importing each other: " + ", ".join(cycles)
