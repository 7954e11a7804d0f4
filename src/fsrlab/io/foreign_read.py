"""Reading a foreign CSV file's cells: a user's own Arduino sketch, data logger or spreadsheet export.

:func:`read_table` reads the text (UTF-8, UTF-16 with its BOM, or Latin-1), leaves out blank and
``#`` comment lines, sniffs the delimiter (tab, semicolon, comma, or runs of white space) and the
decimal comma, and tells a header row (and a units row under it) from data. The :class:`Table` it
returns turns a cell into a number in the file's own dialect (:meth:`Table.number`). Every problem in
a file is a :class:`ForeignFormatError` of one line naming the file, the line (1-based, as a text
editor shows it) and the column. Which column is which, and what the cells mean, is
:mod:`fsrlab.io.foreign`. (docs/data-format.md, "Foreign files")
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.io.csvtext import LongCellError, csv_cells
from fsrlab.io.shown import shown

__all__ = ["ForeignFormatError", "Table", "read_table", "is_number"]

_NUMBER = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$")
_COMMA_NUMBER = re.compile(r"^[+-]?\d*,\d+(?:[eE][+-]?\d+)?$")
_NOT_FINITE = re.compile(r"^[+-]?(?:nan|inf|infinity)$", re.IGNORECASE)
_DELIMITERS = ("\t", ";", ",", " ")  # in this order of preference when several split the lines alike
_DELIMITER_NAMES = {"\t": "tab", ";": "semicolon", ",": "comma", " ": "white space"}


class ForeignFormatError(FileFormatError):
    """A foreign file that cannot be imported; one line naming the file, the line and the column.

    Parameters
    ----------
    message : str
        The line.
    role : str, optional
        The mapping the user can give to settle it (``"time"``, ``"reading"``, ``"force"``,
        ``"reference_time"``, ``"offset"``), when the problem is which column is which or how two
        files line up.
    parameter : str, optional
        The parameter whose file it is (``sensor`` or ``reference``), as for :class:`~fsrlab.errors.FsrlabError`.
    """

    def __init__(self, message: str, role: str | None = None, parameter: str | None = None):
        super().__init__(message, parameter)
        self.role = role


def is_number(cell: str) -> bool:
    """Whether a cell reads as a number: decimal point or comma, exponent, or nan/inf.

    Parameters
    ----------
    cell : str
        The cell, stripped.

    Returns
    -------
    bool
    """
    if not isinstance(cell, str):
        raise TypeError(f"cell: must be a str, got {type(cell).__name__}")
    return bool(_NUMBER.match(cell) or _COMMA_NUMBER.match(cell) or _NOT_FINITE.match(cell))


@dataclass
class Table:
    """The cells of a foreign file, as text: the data lines kept whole, a column split out when it is read.

    Parameters
    ----------
    path : Path
        The file.
    names : list of str
        Header name of each column ("" without a header, or for an empty header cell).
    header_line : int or None
        File line of the header (1-based), None without one.
    units_row : list of str
        The units row under the header (e.g. ``s;N;V``), empty when there is none.
    body : list of str
        The data lines, as the file has them (comments, blanks, header and units row left out).
    lines : ndarray of int
        File line of each data line (1-based, as a text editor counts, comments and blanks included).
    delimiter : str
        ``","``, ``";"``, ``"\\t"`` or ``" "`` (runs of white space).
    decimal : str
        ``"."`` or ``","`` (decimal comma).
    encoding : str
        ``"utf-8"``, ``"utf-16"`` or ``"latin-1"``.
    sha256 : str
        The file's SHA-256, of the bytes read.
    """

    path: Path
    names: list[str]
    header_line: int | None
    units_row: list[str]
    body: list[str]
    lines: np.ndarray
    delimiter: str
    decimal: str
    encoding: str
    sha256: str = ""
    _numbers: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def n_rows(self) -> int:
        """Data rows."""
        return len(self.body)

    @functools.cached_property
    def n_columns(self) -> int:
        """Columns of the widest row or of the header."""
        if self.delimiter != " " and not self._quoted:
            widest = max(map(str.count, self.body, itertools.repeat(self.delimiter, self.n_rows)), default=-1) + 1
        else:
            widest = max((len(self.row(i)) for i in range(self.n_rows)), default=0)
        return max(len(self.names), widest)

    @functools.cached_property
    def _quoted(self) -> bool:
        return any('"' in ln for ln in self.body)

    @functools.cached_property
    def _plain(self) -> bool:
        """Whether the data lines are ASCII without quotes and underscores (numpy's parser reads them as fsrlab)."""
        text = "".join(self.body)
        return text.isascii() and '"' not in text and "_" not in text

    def label(self, j: int) -> str:
        """Column ``j`` (0-based) as a message names it: ``column 'fsr' (2)`` or ``column 2``."""
        name = self.names[j] if j < len(self.names) else ""
        return f"column {shown(name)} ({j + 1})" if name else f"column {j + 1}"

    def where(self, i: int, j: int) -> str:
        """Data row ``i``, column ``j`` (0-based) as a message names it: ``x.csv: line 4, column 'fsr' (2)``."""
        return f"{self.path}: line {self.lines[i]}, {self.label(j)}"

    def row(self, i: int) -> list[str]:
        """The cells of data row ``i`` (0-based), stripped."""
        try:
            return _split(self.body[i], self.delimiter)
        except LongCellError as exc:
            raise ForeignFormatError(f"{self.path}: line {self.lines[i]}: {exc}") from None

    def cell(self, i: int, j: int) -> str:
        """The text of data row ``i``, column ``j`` (0-based); ForeignFormatError when the row is short."""
        row = self.row(i)
        if j >= len(row):
            raise ForeignFormatError(f"{self.where(i, j)}: missing cell (the line has {len(row)} cells, "
                                     f"{_DELIMITER_NAMES[self.delimiter]}-separated)")
        return row[j]

    def texts(self, j: int) -> list[str]:
        """The text of column ``j`` (0-based) in every data row; ForeignFormatError at the first short row."""
        out = []
        for i in range(self.n_rows):
            row = self.row(i)
            if j >= len(row):
                self.cell(i, j)  # raises, naming the line
            out.append(row[j])
        return out

    def number(self, i: int, j: int, text: str, expected: str) -> float:
        """The finite number a cell's ``text`` holds in the file's decimal separator.

        Parameters
        ----------
        i, j : int
            Data row and column (0-based), for the message.
        text : str
            The cell (:meth:`cell`), not empty.
        expected : str
            What the column holds, for the message (``"a number in g"``).

        Returns
        -------
        float

        Raises
        ------
        ForeignFormatError
            A cell that is not a plain number, or nan/inf, or beyond a float.
        """
        cell = text.replace(",", ".") if self.decimal == "," else text
        if _NOT_FINITE.match(cell):
            raise ForeignFormatError(f"{self.where(i, j)}: {shown(text)} is not a finite number "
                                     "(leave the cell empty for a missing value)")
        if not _NUMBER.match(cell):
            point = "decimal comma" if self.decimal == "," else "decimal point"
            raise ForeignFormatError(f"{self.where(i, j)}: non-numeric cell {shown(text)}, expected {expected} "
                                     f"(a plain number, {point})")
        value = float(cell)
        if not np.isfinite(value):
            raise ForeignFormatError(f"{self.where(i, j)}: {shown(text)} is beyond any finite number")
        return value

    def numbers(self, j: int, expected: str) -> np.ndarray:
        """Column ``j`` (0-based) as finite numbers, NaN for an empty cell.

        numpy's C parser reads the column when every cell of it is a plain number; otherwise the
        cells are read one by one, and the first one that is not a finite number (:meth:`number`) or
        is missing stops the import, naming its line.

        Parameters
        ----------
        j : int
            The column.
        expected : str
            What the column holds, for a message (``"a number in g"``).

        Returns
        -------
        ndarray, shape (n_rows,)
        """
        if j not in self._numbers:
            fast = self._parse_fast(j)
            self._numbers[j] = fast if fast is not None else self._parse_slow(j, expected)
        return self._numbers[j].copy()

    def prefetch(self, columns) -> None:
        """Read the numeric ``columns`` (0-based) with one pass of numpy's parser, for :meth:`numbers`; a column
        the parser cannot read alone is left to :meth:`numbers`."""
        wanted = sorted({j for j in columns if j not in self._numbers})
        if len(wanted) > 1:
            values = self._parse_fast(wanted)
            if values is not None:
                for k, j in enumerate(wanted):
                    self._numbers[j] = values[:, k]

    def _parse_fast(self, j) -> np.ndarray | None:
        """Column ``j`` (or the columns of a list, as a 2-D array) by numpy's parser; None when it cannot read
        every cell of them as a finite number."""
        body = self.body
        # numpy reads quotes, 5_000 and other scripts' digits otherwise than a cell's plain number: cell by cell
        if not self._plain:
            return None
        if self.decimal == ",":
            body = [ln.replace(",", ".") for ln in body]
        try:
            values = np.loadtxt(body, delimiter=None if self.delimiter == " " else self.delimiter, usecols=j,
                                ndmin=1 if isinstance(j, int) else 2, comments=None, dtype=np.float64)
        except ValueError:
            return None
        shape = (self.n_rows,) if isinstance(j, int) else (self.n_rows, len(j))
        if values.shape != shape or not np.isfinite(values).all():
            return None
        return values

    def _parse_slow(self, j: int, expected: str) -> np.ndarray:
        texts = self.texts(j)
        cells = [t.replace(",", ".") for t in texts] if self.decimal == "," else texts
        out = np.full(len(cells), np.nan)
        for i, cell in enumerate(cells):
            if cell:
                if _NUMBER.match(cell):
                    out[i] = float(cell)
                if not np.isfinite(out[i]):
                    self.number(i, j, texts[i], expected)  # raises, saying what the cell is
        return out

    def describe(self) -> dict:
        """How the file was read, for the sidecar and ``--json``."""
        return {"file": str(self.path), "delimiter": _DELIMITER_NAMES[self.delimiter], "decimal": self.decimal,
                "header_line": self.header_line, "rows": self.n_rows, "encoding": self.encoding,
                "sha256": self.sha256 or hashlib.sha256(self.path.read_bytes()).hexdigest()}


def _decode(path: Path) -> tuple[str, str, str]:
    """The file's text, its encoding and its SHA-256."""
    raw = path.read_bytes()
    digest = hashlib.sha256(raw).hexdigest()
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):  # a spreadsheet's "Unicode text"
        return raw.decode("utf-16"), "utf-16", digest
    try:
        text, encoding = raw.decode("utf-8-sig"), "utf-8"
    except UnicodeDecodeError:
        text, encoding = raw.decode("latin-1"), "latin-1"  # a Windows logger's °C or µ: never fails
    if "\x00" in text:
        raise ForeignFormatError(f"{path}: not a text file (NUL bytes)")
    return text, encoding, digest


def _split(line: str, delimiter: str) -> list[str]:
    if delimiter == " ":
        return line.split()
    return [c.strip() for c in csv_cells(line, delimiter)]


def _count(line: str, delimiter: str) -> int:
    """Cells of ``line`` split at ``delimiter`` (for sniffing: a cell over the CSV reader's limit counts as text)."""
    try:
        return len(_split(line, delimiter))
    except LongCellError:
        return len(line.split(delimiter))


def _sniff(lines: Sequence[str]) -> str:
    """The delimiter that splits most lines into the same number (> 1) of cells."""
    best, best_key = ",", (0.0, 0)
    for rank, d in enumerate(_DELIMITERS):
        counts = [_count(ln, d) for ln in lines]
        values, freq = np.unique(counts, return_counts=True)
        k = int(np.argmax(freq))
        if values[k] > 1:
            key = (freq[k] / len(counts), -rank)
            if key > best_key:
                best, best_key = d, key
    return best


def _looks_like_header(rows: list) -> bool:
    """Whether the first of ``rows`` (line number, cells) is a header: a cell of it is not a number in a
    column whose cells below it (up to 20 rows, a units row among them) are mostly numbers."""
    first = rows[0][1]
    words = [j for j, c in enumerate(first) if c and not is_number(c)]
    below = [r for _, r in rows[1:21]]
    if not words or not below:
        return bool(words)
    for j in words:
        cells = [r[j] for r in below if j < len(r) and r[j]]
        if cells and sum(is_number(c) for c in cells) > len(cells) / 2:
            return True
    return False


def read_table(path: str | os.PathLike, header: bool | None = None, skip_lines: int = 0) -> Table:
    """Read a foreign CSV file's cells.

    Parameters
    ----------
    path : str or path-like
        The file.
    header : bool, optional
        Whether the first line read is a header; None: it is when one of its cells is not a number in a
        column that holds numbers below it (a column of text or separators in every row, such as the
        ``-`` of ``526 - 101.7``, makes no header: that line is data).
    skip_lines : int
        Lines to leave out at the top (a logger's preamble), before comments and blanks are. [lines]

    Returns
    -------
    Table

    Raises
    ------
    ForeignFormatError
        An empty file (no data rows), a file that is not text, duplicate header names.
    fsrlab.errors.ParameterError
        A path that is empty, missing or a directory, a negative ``skip_lines``.
    OSError
        The file cannot be read.
    """
    from fsrlab.io.runformat import input_file

    p = input_file(path, "path")
    if header is not None and not isinstance(header, bool):
        raise TypeError(f"header: must be True, False or None, got {type(header).__name__}")
    if isinstance(skip_lines, bool) or not isinstance(skip_lines, int):
        raise TypeError(f"skip_lines: must be an int, got {type(skip_lines).__name__}")
    if skip_lines < 0:
        raise ParameterError(f"must be >= 0, got {skip_lines}", parameter="skip_lines")
    text, encoding, digest = _decode(p)
    numbers, body = _data_lines(text, skip_lines)
    del text
    if not body:
        raise ForeignFormatError(f"{p}: empty file (no header and no data rows"
                                 + (f" after the {skip_lines} skipped lines)" if skip_lines else ")"))
    delimiter = _sniff(body[:50])

    def split(k: int) -> list[str]:
        try:
            return _split(body[k], delimiter)
        except LongCellError as exc:
            raise ForeignFormatError(f"{p}: line {numbers[k]}: {exc}") from None

    head = [(int(numbers[k]), split(k)) for k in range(min(len(body), 202))]
    if header is None:
        header = _looks_like_header(head)
    names: list[str] = []
    header_line, units_row, first = None, [], 0
    if header:
        header_line, names = head[0]
        first = 1
        _check_names(p, header_line, names)
        # A units row under the header ("s;N;V"): no cell of it is a number.
        if len(head) > 1 and any(head[1][1]) and not any(is_number(c) for c in head[1][1] if c):
            units_row = head[1][1]
            first = 2
    if first >= len(body):
        raise ForeignFormatError(f"{p}: no data rows" + (f" (line {header_line} is the header)" if header_line else ""))
    decimal = "," if any(_COMMA_NUMBER.match(c) for _, r in head[first:first + 200] for c in r) else "."
    return Table(path=p, names=names, header_line=header_line, units_row=units_row, body=body[first:],
                 lines=numbers[first:], delimiter=delimiter, decimal=decimal, encoding=encoding, sha256=digest)


def _check_names(p: Path, header_line: int, names: list[str]) -> None:
    seen: dict[str, int] = {}
    for j, name in enumerate(names):
        if name and name in seen:
            raise ForeignFormatError(f"{p}: line {header_line} (header), column {shown(name)} ({seen[name] + 1} and "
                                     f"{j + 1}): the same header name twice; each column needs its own name")
        seen.setdefault(name, j)


# Line ends str.splitlines() knows besides \r and \n; with none of them in a file it splits as the CSV does.
_OTHER_LINE_ENDS = re.compile("[\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029]")


def _data_lines(text: str, skip_lines: int) -> tuple[np.ndarray, list[str]]:
    """The lines that hold cells (1-based file line of each, and the text): after ``skip_lines``, without
    blank and ``#`` comment lines."""
    lines = text.splitlines() if _OTHER_LINE_ENDS.search(text) is None else re.split(r"\r\n|\r|\n", text)
    if "#" not in text and "" not in lines[skip_lines:] and not any(map(str.isspace, lines[skip_lines:])):
        return np.arange(skip_lines + 1, len(lines) + 1), lines[skip_lines:]
    keep = [k for k in range(skip_lines, len(lines))
            if (ln := lines[k]) and not ln.isspace() and not ln.lstrip().startswith("#")]
    if len(keep) == len(lines) - skip_lines:
        return np.arange(skip_lines + 1, len(lines) + 1), lines[skip_lines:]
    return np.asarray(keep, dtype=np.int64) + 1, [lines[k] for k in keep]
