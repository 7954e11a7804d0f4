"""``fsrlab paper``: reproduce the paper's figures and tables into a directory.

Each capability adds a builder module to :data:`SECTION_MODULES`; a builder exposes
``build(outdir: pathlib.Path) -> Section``. The report writes ``index.html`` (self-contained:
images are embedded) and ``paper.json`` (every section's ``data`` merged at the top level, plus
the errata).
"""

from __future__ import annotations

import importlib
import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

from fsrlab import __version__
from fsrlab.reports.html import render_html
from fsrlab.reports.model import Section

__all__ = ["SECTION_MODULES", "ReportResult", "build_sections", "write_report"]

#: Section builders in report order. Add yours here.
SECTION_MODULES = [
    "fsrlab.reports.sections.physics",
    "fsrlab.reports.sections.oscillator",
    "fsrlab.reports.sections.measurements",
    "fsrlab.reports.sections.experiment",
]


@dataclass
class ReportResult:
    """Where the report went.

    Parameters
    ----------
    index : Path
        The HTML page.
    json : Path
        The machine-readable numbers.
    sections : list of Section
        The sections as built.
    """

    index: Path
    json: Path
    sections: list[Section]

    @property
    def figures(self) -> list[Path]:
        """PNG files written."""
        return [self.index.parent / f.filename for s in self.sections for f in s.figures]


def build_sections(outdir: Path, progress: Callable[[str], None] | None = None) -> list[Section]:
    """Run every section builder of :data:`SECTION_MODULES` into ``outdir``.

    Parameters
    ----------
    outdir : Path
        Directory the builders write their PNGs into.
    progress : callable, optional
        Called with each section's name before it is built.

    Returns
    -------
    list of Section
    """
    modules = [importlib.import_module(name) for name in SECTION_MODULES]
    # Slow external work (ngspice) starts first and runs while the other sections draw.
    started = {m.__name__: m.prefetch() for m in modules if hasattr(m, "prefetch")}
    sections = []
    for module in modules:
        if progress:
            progress(module.__name__.rsplit(".", 1)[-1])
        if module.__name__ in started:
            sections.append(module.build(outdir, prefetched=started[module.__name__]))
        else:
            sections.append(module.build(outdir))
    return sections


def write_report(outdir: str | Path, progress: Callable[[str], None] | None = None) -> ReportResult:
    """Build the reproduction report.

    Parameters
    ----------
    outdir : str or Path
        Directory to write ``index.html``, ``paper.json`` and the PNG figures into (created).
    progress : callable, optional
        Called with each section's name before it is built.

    Returns
    -------
    ReportResult
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    sections = build_sections(out, progress)
    data: dict = {"fsrlab_version": __version__,
                  "source": "Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901"}
    for section in sections:
        clash = set(section.data) & set(data)
        if clash:
            raise RuntimeError(f"report section {section.key!r} redefines {sorted(clash)}")
        data.update(section.data)
    data["errata"] = [asdict(e) for s in sections for e in s.errata]
    json_path = out / "paper.json"
    json_path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    index = out / "index.html"
    index.write_text(render_html(sections, out), encoding="utf-8")
    return ReportResult(index=index, json=json_path, sections=sections)
