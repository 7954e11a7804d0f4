"""The cells of a run file: parsing them and checking that each holds a value it can hold.

The reading half of :func:`fsrlab.io.runformat.load_run` (the normative description is
``docs/data-format.md``): the body of ``NAME.csv`` becomes a float64 array, an empty cell NaN
("missing"), and every cell is checked against what its column can hold (:data:`COLUMN_LIMITS`):
``nan`` or ``inf`` written as text, a number no instrument reads (``1e308`` Hz), a direction
other than -1, 0, +1, a range other than 0 or 1, an empty time. Each problem is named by file,
row and column. A caller that asks to skip bad rows gets the good rows and the list of the rows
it left out (:class:`BadRow`) instead of the first error.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from fsrlab.io.csvtext import LongCellError, csv_cells
from fsrlab.io.schema import KNOWN_COLUMNS, RunFormatError, where
from fsrlab.io.shown import number_cell, shown

__all__ = ["COLUMN_LIMITS", "OTHER_LIMIT", "BadRow", "parse_cells"]

#: What a known column can hold: (lowest, highest) in its unit, or a tuple of the allowed values.
#: The bounds are far beyond any reading of the instruments the format describes; they reject the
#: corrupt cell (``1e308``), not an unusual measurement.
COLUMN_LIMITS: dict[str, tuple] = {
    "time_s": (-1e15, 1e15),
    "frequency_hz": (0.0, 1e9),
    "duty_cycle": (0.0, 1.0),
    "voltage_v": (-1e3, 1e3),
    "stress_pa": (-1e12, 1e12),
    "stress_pa_estimate": (-1e12, 1e12),
    "stress_pa_uncertainty": (0.0, 1e12),
    "force_n_estimate": (-1e9, 1e9),
    "force_n_uncertainty": (0.0, 1e9),
    "force_n": (-1e9, 1e9),
    "cycle": (-1e15, 1e15),
    "periods": (0.0, 1e15),
    "missed": (0.0, 1e15),
    "seq": (0.0, 1e15),
    "direction": ((-1.0, "unloading"), (0.0, "hold"), (1.0, "loading")),
    "range": ((0.0, "C_off out"), (1.0, "C_off in")),
    "in_range": ((0.0, "outside the calibrated readout range"), (1.0, "inside it")),
    "reference_raw": (-8388608.0, 8388607.0),  # the HX711's 24-bit two's complement
    "force_nominal_n": (-1e9, 1e9),
    "step": (0.0, 1e15),
}
#: Largest magnitude of a cell in a column not listed in :data:`COLUMN_LIMITS`.
OTHER_LIMIT = 1e100


class BadRow(NamedTuple):
    """A row left out of a run because one of its cells is bad.

    Parameters
    ----------
    row : int
        1-based data row (the file line is ``row + 1``).
    column : str or None
        The first bad cell's column (None for a row with too many cells).
    reason : str
        What is wrong, as the error would have said it (with file, row and column).
    """

    row: int
    column: str | None
    reason: str


#: A comma with nothing but white space after it up to the end of its line: an empty last cell.
_EMPTY_LAST = re.compile(r",\s*(?:\n|\Z)")


def _has_empties(text: str) -> bool:
    """Whether a line of ``text`` (the data lines joined by newlines) has an empty cell."""
    return ",," in text or text.startswith(",") or "\n," in text or _EMPTY_LAST.search(text) is not None


def _parse_fast(body: list[str], ncol: int) -> np.ndarray | None:
    """numpy's C parser for the common case; None when anything is unusual (empties, text, quotes)."""
    if not body:
        return np.empty((0, ncol))
    text = "\n".join(body)  # one string: each check below runs in C, not once per line
    if _has_empties(text) or '"' in body[0]:
        return None
    # numpy, like float(), reads 5_000 and non-ASCII digits as numbers; such cells go cell by cell.
    if not text.isascii() or "_" in text:
        return None
    try:
        arr = np.loadtxt(body, delimiter=",", dtype=np.float64, ndmin=2, comments=None)
    except ValueError:
        return None
    if arr.shape != (len(body), ncol):
        return None
    return arr


# A check is (rows: ndarray of int, column index, message: Callable[[row index], str]); messages are
# written only for the rows that are reported, so a column of a million bad cells stays cheap.


def _parse_slow(path: Path, body: list[str], header: list[str], checks: list) -> tuple[np.ndarray, np.ndarray]:
    """Cell by cell, naming each bad cell exactly; returns the values and the mask of empty cells.

    A row that cannot be parsed (too few or too many cells, a non-numeric cell) is reported in
    ``checks``; its cells are set to 0 and marked empty, so that the value checks pass over it.
    """
    ncol = len(header)
    out = np.full((len(body), ncol), np.nan)
    empty = np.zeros((len(body), ncol), dtype=bool)
    broken: list[int] = []

    def report(i: int, j: int, message: str) -> None:
        checks.append((np.array([i]), j, lambda _i, m=message: m))
        broken.append(i)

    for i, line in enumerate(body):
        try:
            row = csv_cells(line)
        except LongCellError as exc:
            report(i, 0, f"{where(path, i + 1, None)}: {exc}")
            continue
        if len(row) < ncol:
            report(i, len(row),
                   f"{where(path, i + 1, header[len(row)])}: missing ({len(row)} cells, the header has {ncol})")
            continue
        if len(row) > ncol and any(c.strip() for c in row[ncol:]):
            report(i, ncol, f"{where(path, i + 1, None)}: {len(row)} cells, the header has {ncol}")
            continue
        for j in range(ncol):
            cell = row[j].strip()
            if not cell:
                empty[i, j] = True
                continue
            try:
                out[i, j] = number_cell(cell)
            except ValueError:
                report(i, j, f"{where(path, i + 1, header[j])}: non-numeric cell {shown(cell)}")
                break
    # Empty and 0 (a value every column can hold): the value checks pass over a broken row.
    empty[broken] = True
    out[broken] = 0.0
    return out, empty


def _cell_text(line: str, j: int) -> str:
    """Cell ``j`` of a data line, as the file has it (for a message)."""
    try:
        cells = csv_cells(line)
    except LongCellError:  # a cell over the CSV reader's limit: the numbers' fast path had no quotes to undo
        cells = line.split(",")
    return cells[j].strip() if j < len(cells) else line


def _value_checks(path: Path, body: list[str], header: list[str], data: np.ndarray, empty: np.ndarray) -> list:
    """One check per column and kind of problem: the cells a column cannot hold."""
    checks = []
    for j, name in enumerate(header):
        col = data[:, j]
        fin = np.isfinite(col)
        textual = np.flatnonzero(~empty[:, j] & ~fin)
        if textual.size:
            checks.append((textual, j, lambda i, j=j, name=name: (
                f"{where(path, i + 1, name)}: {shown(_cell_text(body[i], j))} is not a finite number "
                "(leave the cell empty for a missing value)")))
        limits = COLUMN_LIMITS.get(name, (-OTHER_LIMIT, OTHER_LIMIT))
        if isinstance(limits[0], tuple):
            bad = np.flatnonzero(fin & ~np.isin(col, [v for v, _ in limits]))
            allowed = ", ".join(f"{v:g} ({label})" for v, label in limits)

            def text(i, col=col, name=name, allowed=allowed):
                return f"{where(path, i + 1, name)}: {col[i]:g} is not one of {allowed}"

        else:
            lo, hi = limits
            bad = np.flatnonzero(fin & ((col < lo) | (col > hi)))
            unit = KNOWN_COLUMNS.get(name, "")
            unit = f" {unit}" if unit not in ("", "1") else ""

            def text(i, col=col, name=name, lo=lo, hi=hi, unit=unit):
                return (f"{where(path, i + 1, name)}: {col[i]:g} is beyond what the column can hold "
                        f"({lo:g} to {hi:g}{unit}; docs/data-format.md)")

        if bad.size:
            checks.append((bad, j, text))
        if name == "time_s":
            gaps = np.flatnonzero(empty[:, j] & ~np.isfinite(col))
            if gaps.size:
                checks.append((gaps, j, lambda i, name=name: f"{where(path, i + 1, name)}: empty time cell"))
    return checks


def parse_cells(path: Path, body: list[str], header: Sequence[str],
                skip_bad_rows: bool = False) -> tuple[np.ndarray, list[BadRow]]:
    """The cells of a run's data rows as numbers, every cell checked against its column.

    Parameters
    ----------
    path : Path
        The file, for messages.
    body : list of str
        The data lines (without the header).
    header : sequence of str
        The column names.
    skip_bad_rows : bool
        Leave out each row with a bad cell and list it, instead of raising at the first one.

    Returns
    -------
    data : ndarray, shape (rows kept, columns)
        The values (NaN for an empty cell).
    skipped : list of BadRow
        The rows left out, in file order (empty unless ``skip_bad_rows``).

    Raises
    ------
    RunFormatError
        Unless ``skip_bad_rows``: one line naming the file, row and column of the first bad cell
        (by row, then column): too few or too many cells, a non-numeric cell, ``nan``/``inf`` as
        text, a value outside :data:`COLUMN_LIMITS` (|x| > :data:`OTHER_LIMIT` in other columns),
        an empty ``time_s``.
    """
    if not isinstance(body, list) or not all(isinstance(line, str) for line in body):
        raise TypeError(f"body: must be a list of lines (str), got {type(body).__name__}")
    if isinstance(header, (str, bytes)) or not isinstance(header, Sequence) or \
            not all(isinstance(h, str) for h in header):
        raise TypeError(f"header: must be a sequence of column names (str), got {type(header).__name__}")
    header = list(header)
    checks: list = []
    data = _parse_fast(body, len(header))
    if data is None:
        data, empty = _parse_slow(path, body, header, checks)
    else:
        empty = np.zeros(data.shape, dtype=bool)
    checks += _value_checks(path, body, header, data, empty)
    if not checks:
        return data, []
    if not skip_bad_rows:
        rows, j, text = min(checks, key=lambda c: (int(c[0][0]), c[1]))
        raise RunFormatError(text(int(rows[0])))
    first: dict[int, tuple[int, object]] = {}
    for rows, j, text in checks:
        for i in rows.tolist():
            if i not in first or j < first[i][0]:
                first[i] = (j, text)
    skipped = [BadRow(i + 1, header[j] if j < len(header) else None, text(i))
               for i, (j, text) in sorted(first.items())]
    keep = np.ones(len(body), dtype=bool)
    keep[list(first)] = False
    return data[keep], skipped
