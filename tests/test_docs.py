"""The manual's sources say what the package has: the API reference names every public name once, the user
guide's table of contents every page, the gallery at least five scripts that draw a figure.

References: ``fsrlab.__all__`` (the public API as the package declares it), the files under docs/ and
examples/ (read, not assumed), the claims' wording (README and docs never say a tolerance was set
"beforehand"), and the outputs the user-guide pages print under their Python examples.
"""

from __future__ import annotations

import ast
import re
import shlex
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

import fsrlab

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def test_the_api_reference_lists_every_public_name_once():
    text = (DOCS / "api.rst").read_text(encoding="utf-8")
    listed = Counter(re.findall(r"^   (\w+)$", text, flags=re.M))
    assert set(listed) == set(fsrlab.__all__), set(listed) ^ set(fsrlab.__all__)
    assert all(n == 1 for n in listed.values()), [name for name, n in listed.items() if n > 1]


def test_every_page_is_in_the_table_of_contents():
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    entries = set(re.findall(r"^([\w/-]+)$", index, flags=re.M))
    pages = {p.stem for p in DOCS.glob("*.md") if p.stem != "index"}
    assert pages <= entries, pages - entries
    assert "generated/cli" in entries and "api" in entries and "auto_examples/index" in entries


def test_the_gallery_has_five_scripts_that_draw():
    scripts = sorted((ROOT / "examples").glob("plot_*.py"))
    assert len(scripts) >= 5, scripts
    for script in scripts:
        tree = ast.parse(script.read_text(encoding="utf-8"))
        doc = ast.get_docstring(tree) or ""
        title, underline = (doc.splitlines() + ["", ""])[:2]
        assert title and set(underline) == {"="} and len(underline) >= len(title), script.name  # a gallery title
        assert "plt.show()" in script.read_text(encoding="utf-8"), script.name


def test_no_tolerance_is_said_to_be_set_beforehand():
    for path in [ROOT / "README.md", *DOCS.glob("*.md")]:
        assert "beforehand" not in path.read_text(encoding="utf-8").lower(), path.name


def test_the_readme_states_the_table2_match_as_the_choice_of_k():
    text = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    assert "the match is the choice of k" in text
    assert "trivial predictor" in text and "experiment.trivial_baseline" in text


# The user-guide pages written from the README keep its examples runnable: each page's Python blocks run in
# order in an empty directory (after the page's own ``python -c`` set-up lines), and a block followed at once
# by a plain block prints exactly what that block shows.
GUIDE = ("physics", "oscillator", "analysis")


def _page_steps(page: str) -> list[tuple[str, str, str | None]]:
    """(kind, code, shown output or None) in the page's order: kind "python" or "setup" (a ``python -c``)."""
    text = (DOCS / f"{page}.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```(\w*)\n(.*?)^```\n", text, flags=re.S | re.M)
    steps = []
    for i, (kind, code) in enumerate(blocks):
        if kind == "python":
            shown = blocks[i + 1][1] if i + 1 < len(blocks) and blocks[i + 1][0] == "" else None
            steps.append(("python", code, shown))
        elif kind == "sh":
            steps += [("setup", shlex.split(line)[2], None) for line in code.splitlines()
                      if line.startswith("python -c ")]
    return steps


@pytest.mark.parametrize("page", GUIDE)
def test_guide_python_examples_run_and_print_what_they_show(page, tmp_path):
    steps = _page_steps(page)
    assert any(kind == "python" for kind, _, _ in steps), page
    for kind, code, shown in steps:
        proc = subprocess.run([sys.executable, "-c", "import matplotlib; matplotlib.use('Agg')\n" + code], cwd=tmp_path,
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, (page, kind, proc.stderr[-3000:])
        if shown is not None:
            assert proc.stdout == shown, (page, proc.stdout, shown)
