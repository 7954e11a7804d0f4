"""`make bench`: run every ``benchmarks/bench_*.py`` and write its section of docs/performance.md.

A benchmark module defines ``TITLE`` (section heading) and ``run() -> str`` returning Markdown.
Each figure is a ratio against a peer or a naive baseline measured in the same run.
Pass module names (``bench_physics``) to run only some.
"""

from __future__ import annotations

import importlib
import platform
import re
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
DOC = HERE.parent / "docs" / "performance.md"
HEADER = """# Performance

Written by `make bench` (`benchmarks/run.py`); each section is replaced when its benchmark runs.
Every figure is a ratio against a peer or a naive baseline measured in the same run, on the
machine named in the section. Unit tests never time anything.
"""


def update_section(doc: Path, key: str, markdown: str) -> None:
    """Replace (or append) the section between ``<!-- bench:key -->`` markers in ``doc``."""
    text = doc.read_text(encoding="utf-8") if doc.exists() else HEADER
    begin, end = f"<!-- bench:{key} -->", f"<!-- /bench:{key} -->"
    block = f"{begin}\n{markdown.strip()}\n{end}"
    pattern = re.compile(re.escape(begin) + r".*?" + re.escape(end), re.S)
    text = pattern.sub(lambda _m: block, text) if pattern.search(text) else text.rstrip() + "\n\n" + block + "\n"
    doc.write_text(text, encoding="utf-8")


def machine() -> str:
    """One line naming the machine the figures come from."""
    import os

    return (f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"{time.strftime('%Y-%m-%d')}")


def main(names: list[str]) -> int:
    sys.path.insert(0, str(HERE))
    modules = names or sorted(p.stem for p in HERE.glob("bench_*.py"))
    for name in modules:
        mod = importlib.import_module(name)
        print(f"== {name}: {mod.TITLE}", flush=True)
        markdown = f"## {mod.TITLE}\n\n_{machine()}_\n\n" + mod.run()
        update_section(DOC, name, markdown)
        print(markdown, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
