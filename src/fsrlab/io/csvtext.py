"""One line of CSV text as cells, with Python's field limit turned into a message instead of a traceback.

The :mod:`csv` module refuses a field over :func:`csv.field_size_limit` (128 KiB) with ``_csv.Error``.
No cell of a run, a table or a foreign logger's file is that long (a number is at most a few dozen
characters), so the limit is kept: a file with such a cell is not one fsrlab reads, and the caller
says so in one line naming the file, the line and what the limit is (:class:`LongCellError`).
"""

from __future__ import annotations

import csv
from collections.abc import Iterable, Iterator

__all__ = ["LongCellError", "csv_cells", "csv_rows", "long_cell_text"]


class LongCellError(ValueError):
    """A line the CSV reader refuses: a field longer than :func:`csv.field_size_limit`, or another of its errors.

    Parameters
    ----------
    line : int
        The 1-based line (of the lines given) where the reader stopped.
    reason : str
        The :mod:`csv` module's message.
    """

    def __init__(self, line: int, reason: str):
        super().__init__(long_cell_text(reason))
        self.line = line


def long_cell_text(reason: str = "field larger than field limit") -> str:
    """What is wrong with a line the CSV reader refuses, and what is allowed.

    Parameters
    ----------
    reason : str
        The :mod:`csv` module's message.

    Returns
    -------
    str
    """
    if not isinstance(reason, str):
        raise TypeError(f"reason: must be a str, got {type(reason).__name__}")
    if "field limit" in reason:
        return (f"a cell longer than {csv.field_size_limit()} characters (the CSV reader's limit); no cell of a run "
                "or table is that long: is this the right file?")
    return f"not CSV text ({reason})"


def csv_cells(line: str, delimiter: str = ",") -> list[str]:
    """The cells of one CSV line.

    Parameters
    ----------
    line : str
        One line of text, without its newline.
    delimiter : str
        The cell separator.

    Returns
    -------
    list of str

    Raises
    ------
    LongCellError
        A cell longer than the CSV reader's limit (``line`` is 1).
    """
    if not isinstance(line, str):
        raise TypeError(f"line: must be a str, got {type(line).__name__}")
    try:
        return next(csv.reader([line], delimiter=delimiter), [])
    except csv.Error as exc:
        raise LongCellError(1, str(exc)) from None


def csv_rows(lines: Iterable[str], delimiter: str = ",") -> Iterator[list[str]]:
    """The rows of CSV text given as lines (or an open file), as :func:`csv.reader` gives them.

    Parameters
    ----------
    lines : iterable of str
        The text's lines, or an open file (``newline=""``).
    delimiter : str
        The cell separator.

    Yields
    ------
    list of str

    Raises
    ------
    LongCellError
        A cell longer than the CSV reader's limit, with the 1-based line where the reader stopped.
    """
    if isinstance(lines, (str, bytes)) or not isinstance(lines, Iterable):
        raise TypeError(f"lines: must be an iterable of lines (or an open file), got {type(lines).__name__}")
    reader = csv.reader(lines, delimiter=delimiter)
    while True:
        try:
            row = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            raise LongCellError(reader.line_num, str(exc)) from None
        yield row
