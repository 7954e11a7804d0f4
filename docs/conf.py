"""Sphinx configuration of fsrlab's manual: ``make docs`` builds it into docs/_build/html, warnings as errors."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parent
import fsrlab  # noqa: E402

project = "fsrlab"
author = "fsrlab authors"
copyright = "fsrlab authors, MIT licence"
version = release = fsrlab.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.json", "auto_examples/*.md5", "auto_examples/*.codeobj.json"]
templates_path = ["_templates"]

# The API reference: a page per name of fsrlab.__all__ (api.rst), generated from the docstrings. fsrlab's
# namespace is lazy (PEP 562): autosummary and autodoc reach each name through getattr, which imports it.
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": False}
autodoc_typehints = "none"  # numpydoc's Parameters carry the types and units
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# The user guide is Markdown (myst-parser): the pages under docs/ as they are.
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath", "colon_fence"]

# The gallery: examples/plot_*.py, each run and its figure kept; examples' other files are data for the tests.
sphinx_gallery_conf = {
    "examples_dirs": str(DOCS.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"plot_",
    "ignore_pattern": r"make_",
    "download_all_examples": False,
    "within_subsection_order": "FileNameSortKey",
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "show_memory": False,
    "plot_gallery": os.environ.get("FSRLAB_DOCS_GALLERY", "True"),
}



def _cli_reference() -> str:
    """The command line's reference in Markdown: typer's own docs output for each command, in its help panel."""
    import typer
    from typer.cli import get_docs_for_click

    from fsrlab.cli import PANELS, _click_command

    group = _click_command()
    ctx = typer.Context(group, info_name="fsrlab")
    text = ["# Command line", "",
            "`fsrlab --help` lists the commands in the panels below; each command's `--help` says the same as its",
            "section here. Options state their unit; values accept engineering notation (`10k`, `4.7n`, `470p`,",
            "`4k7`); every command that prints numbers takes `--json`; bad input ends with one line naming the",
            "option, and exit code 2.", ""]
    for panel, names in PANELS.items():
        text += [f"## {panel}", ""]
        for name in names:
            text.append(_fenced(get_docs_for_click(obj=group.get_command(ctx, name), ctx=ctx, indent=2, name=name,
                                                   call_prefix="fsrlab")))
    return "\n".join(text)


def _fenced(markdown: str) -> str:
    """The help's indented example lines (click prints them as they are) as code blocks, not as one paragraph."""
    out, block = [], []
    for line in markdown.splitlines():
        if line.startswith("  ") and line.strip() and not out[-1:] == ["```console"]:
            block.append(line[2:])
            continue
        if block:
            out += ["```console", *block, "```"]
            block = []
        out.append(line)
    if block:
        out += ["```console", *block, "```"]
    return "\n".join(out) + "\n"


# Written before the sources are read, as autosummary writes generated/ (git ignores both).
(DOCS / "generated").mkdir(exist_ok=True)
(DOCS / "generated" / "cli.md").write_text(_cli_reference(), encoding="utf-8")

html_theme = "pydata_sphinx_theme"
html_title = f"fsrlab {version}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path: list[str] = []
html_show_sourcelink = False

# Run files and tables are shown as ```csv blocks: plain text (Pygments has no CSV lexer).
from pygments.lexers.special import TextLexer  # noqa: E402
from sphinx.highlighting import lexers  # noqa: E402

lexers["csv"] = TextLexer()
