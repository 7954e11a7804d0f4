"""Text from files, as error messages show it: control characters escaped, length capped, numbers strict.

A CSV header or cell is echoed in one-line errors. Written raw, an escape sequence in it would act
on the user's terminal and a 100 kB header would become a 100 kB line; :func:`shown` and
:func:`shown_list` make it safe and short. :func:`number_cell` is the one spelling of a number a
data cell may use: Python's ``float`` also reads ``5_000`` and full-width or other Unicode digits
(``１０``, ``٣``), which a CSV cell should never be read as.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterable

from fsrlab.errors import ParameterError

__all__ = ["shown", "shown_list", "printable", "number_cell", "NUMBER"]

# ASCII digits, an optional sign, point and exponent; nan and inf in any case (checked later by value).
NUMBER = re.compile(r"^[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|nan|inf|infinity)$", re.IGNORECASE)


_CONTROL_CATEGORIES = ("Cc", "Cf", "Zl", "Zp", "Cs", "Co", "Cn")
_ASCII_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f]")  # all but tab and line feed


def _code(ch: str) -> str:
    return (f"\\x{ord(ch):02x}" if ord(ch) < 0x100 else f"\\u{ord(ch):04x}" if ord(ch) < 0x10000
            else f"\\U{ord(ch):08x}")


def _escape(text: str) -> str:
    out = []
    for ch in text:
        if ch == "\\":
            out.append("\\\\")
        elif unicodedata.category(ch) in _CONTROL_CATEGORIES:
            out.append(_code(ch))
        else:
            out.append(ch)
    return "".join(out)


def printable(text: str, keep: str = "\n\t") -> str:
    """``text`` as fsrlab prints it: every control or format character but those in ``keep`` written as its
    escape (ESC as ``\\x1b``, U+202E as ``\\u202e``), so that nothing printed acts on a terminal.

    The one rendering boundary: :func:`fsrlab.cli.main` passes everything a command writes to stdout and
    stderr through it (:class:`fsrlab.cli.console.EscapedStream`). Backslashes are left as they are (a
    message that quotes a name with :func:`shown` has escaped it already).

    Parameters
    ----------
    text : str
    keep : str
        Control characters printed as they are (line feed and tab by default).

    Returns
    -------
    str
    """
    if not isinstance(text, str):
        raise TypeError(f"text: must be a str, got {type(text).__name__}")
    if not isinstance(keep, str):
        raise TypeError(f"keep: must be a str of the characters kept, got {type(keep).__name__}")
    if text.isascii():
        if keep == "\n\t" and _ASCII_CONTROL.search(text) is None:
            return text
        return "".join(ch if ch in keep or not (ch < " " or ch == "\x7f") else _code(ch) for ch in text)
    return "".join(ch if ch in keep or unicodedata.category(ch) not in _CONTROL_CATEGORIES else _code(ch)
                   for ch in text)


def _limit(name: str, value) -> int:
    """A length limit: an int >= 1, or a TypeError or ParameterError naming it."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"{name}: must be an int, got {type(value).__name__}")
    if value < 1:
        raise ParameterError(f"must be >= 1, got {value}", parameter=name)
    return value


def shown(text, limit: int = 60) -> str:
    """``text`` quoted for a message: control and format characters escaped, at most ``limit`` characters.

    Parameters
    ----------
    text : object
        A header name, a cell.
    limit : int
        Characters of ``text`` kept. [1]

    Returns
    -------
    str
        ``'name'``, or ``'first characters…' (12345 characters)`` when cut.
    """
    limit = _limit("limit", limit)
    s = str(text)
    if len(s) <= limit:
        return f"'{_escape(s)}'"
    return f"'{_escape(s[:limit])}…' ({len(s)} characters)"


def shown_list(items: Iterable, limit: int = 200, item_limit: int = 40) -> str:
    """Names joined by ", " for a message, each :func:`shown` unquoted, the whole capped near ``limit``.

    Parameters
    ----------
    items : iterable
        Column names.
    limit : int
        Characters of the joined text before the rest is counted instead. [1]
    item_limit : int
        Characters kept of each name. [1]

    Returns
    -------
    str
        ``"time_s, frequency_hz, … and 9998 more"``.
    """
    if isinstance(items, (str, bytes)) or not isinstance(items, Iterable):
        raise TypeError(f"items: must be an iterable of names, got {type(items).__name__}")
    limit, item_limit = _limit("limit", limit), _limit("item_limit", item_limit)
    names = list(items)
    parts: list[str] = []
    size = 0
    for k, name in enumerate(names):
        part = shown(name, item_limit)[1:]
        part = part[:-1] if part.endswith("'") else part.replace("…'", "…", 1)
        if parts and size + len(part) > limit:
            return ", ".join(parts) + f", … and {len(names) - k} more"
        parts.append(part)
        size += len(part) + 2
    return ", ".join(parts)


def number_cell(cell: str) -> float:
    """A data cell's number: ASCII digits only (no ``_`` separators, no other scripts' digits).

    Parameters
    ----------
    cell : str
        The cell, stripped.

    Returns
    -------
    float

    Raises
    ------
    fsrlab.errors.ParameterError
        The cell is not written as a plain number (a ValueError: callers catch it as one).
    """
    if not isinstance(cell, str):
        raise TypeError(f"cell: must be a str, got {type(cell).__name__}")
    if not NUMBER.match(cell):
        raise ParameterError(f"not a plain number: {cell!r}", parameter="cell")
    return float(cell)
