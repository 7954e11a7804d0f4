"""Report directories written file by file through a temporary name and a rename (``fsrlab report``,
``fsrlab paper``, ``bench --report``, the demo's reports).

Reference: the output policy (fsrlab.io.outputs; README "Files written"): an interrupted write never
leaves half a file under its final name, and no temporary file is left behind. Each test interrupts a
write half-way (Ctrl-C: ``KeyboardInterrupt``) over an existing report and compares the sha256 of every
file before and after; the files the report had written whole before the interruption may be new.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _files(root: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(root.iterdir()) if p.is_file()}


def _half_text_then_interrupted(monkeypatch):
    """Every ``Path.write_text`` writes half of its text and is then interrupted."""
    real = Path.write_text

    def write_text(self, text, *args, **kwargs):
        real(self, text[: len(text) // 2], *args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(Path, "write_text", write_text)


def test_a_figure_interrupted_while_saved_leaves_the_old_one(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from fsrlab.reports.figures import new_figure, save

    png = tmp_path / "fig.png"
    png.write_bytes(b"old figure")
    before = _files(tmp_path)
    real = Figure.savefig

    def half_then_interrupted(self, fname, **kwargs):
        real(self, fname, **kwargs)
        data = Path(fname).read_bytes()
        Path(fname).write_bytes(data[: len(data) // 2])
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", half_then_interrupted)
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    with pytest.raises(KeyboardInterrupt):
        save(fig, png)
    assert _files(tmp_path) == before
    monkeypatch.undo()
    fig, ax = new_figure()
    save(fig, png)
    assert png.read_bytes().startswith(b"\x89PNG") and _files(tmp_path).keys() == {"fig.png"}


def test_an_interrupted_run_report_keeps_the_old_index(tmp_path, monkeypatch):
    from fsrlab.reports.run_report import write_run_report

    out = tmp_path / "report"
    out.mkdir()
    (out / "index.html").write_text("<p>the old report</p>\n")
    (out / "report.json").write_text("{}\n")
    _half_text_then_interrupted(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        write_run_report(EXAMPLES / "bench.csv", out, overwrite=True)
    monkeypatch.undo()
    assert (out / "index.html").read_text() == "<p>the old report</p>\n"
    assert (out / "report.json").read_text() == "{}\n"
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]  # no temporary left


def test_an_interrupted_paper_report_keeps_its_old_files(tmp_path, monkeypatch):
    from fsrlab.reports import paper

    out = tmp_path / "paper"
    out.mkdir()
    (out / "index.html").write_text("<p>the old report</p>\n")
    (out / "paper.json").write_text('{"old": true}\n')
    before = _files(out)
    monkeypatch.setattr(paper, "build_sections", lambda outdir, progress=None: [])  # the files, not the sections
    _half_text_then_interrupted(monkeypatch)
    with pytest.raises(KeyboardInterrupt):
        paper.write_report(out, overwrite=True)
    monkeypatch.undo()
    assert _files(out) == before and not [p for p in out.iterdir() if p.name.startswith(".")]
