"""What a report section is made of: figures, tables, errata and machine-readable data.

A section builder (a module in :mod:`fsrlab.reports.sections`) writes its PNGs into the output
directory and returns a :class:`Section`; :mod:`fsrlab.reports.paper` collects the sections and
:mod:`fsrlab.reports.html` renders them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["Figure", "Table", "Erratum", "Section"]


@dataclass
class Figure:
    """A reproduced figure: a PNG next to what the paper states and what fsrlab finds.

    Parameters
    ----------
    filename : str
        PNG file name inside the report directory.
    title : str
        E.g. ``"Figure 2a: separation for several σf"``.
    paper : str
        What the paper shows or states about this figure.
    fsrlab : str
        What fsrlab computes, and whether it agrees.
    """

    filename: str
    title: str
    paper: str
    fsrlab: str


@dataclass
class Table:
    """A table, typically with the paper's values beside fsrlab's.

    Parameters
    ----------
    title : str
        E.g. ``"Table 2: hysteresis error"``.
    columns : list of str
        Column headings.
    rows : list of list
        Cell values (str or numbers; floats are shown as given by ``fmt``).
    note : str
        How the values were computed, tolerances, sources.
    fmt : str
        Format for float cells.
    """

    title: str
    columns: list[str]
    rows: list[list[Any]]
    note: str = ""
    fmt: str = "{:.2f}"


@dataclass
class Erratum:
    """A statement of the paper that the equations or a simulation contradict.

    Parameters
    ----------
    key : str
        Stable identifier, e.g. ``"E1"``; the same key is used in ``docs/errata.md``.
    title : str
        One line.
    paper : str
        What the paper prints.
    fsrlab : str
        What fsrlab finds instead.
    evidence : str
        How it was established (derivation, independent computation, simulator).
    """

    key: str
    title: str
    paper: str
    fsrlab: str
    evidence: str


@dataclass
class Section:
    """One capability's part of the report.

    Parameters
    ----------
    key : str
        Short identifier used as the HTML anchor.
    title : str
        Section heading.
    intro : str
        Paragraphs of plain text (blank-line separated).
    figures, tables, errata : list
        The content.
    data : dict
        Top-level entries this section adds to ``paper.json``.
    """

    key: str
    title: str
    intro: str = ""
    figures: list[Figure] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    errata: list[Erratum] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)
