"""The run file's schema: its format name and version, the known columns and their units, the sidecar's path.

What every reader and writer of runs shares (:mod:`fsrlab.io.runformat`, :mod:`fsrlab.io.runcells`,
:mod:`fsrlab.io.runwriter`); ``docs/data-format.md`` is the normative description.
"""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Iterable, Sequence
from numbers import Integral
from pathlib import Path

from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.io.shown import shown, shown_list

__all__ = ["FORMAT", "VERSION", "KNOWN_COLUMNS", "QUANTITY_COLUMNS", "CSV_SHA256", "RunFormatError", "check_columns",
           "sidecar_path", "where"]

#: Value of the sidecar's ``"format"`` key.
FORMAT = "fsrlab-run"
#: Version of the format described here.
VERSION = 1

#: Known columns and their units (``"1"``: dimensionless or a count).
KNOWN_COLUMNS: dict[str, str] = {
    "time_s": "s",
    "frequency_hz": "Hz",
    "duty_cycle": "1",
    "voltage_v": "V",
    "stress_pa": "Pa",
    "force_n": "N",
    "stress_pa_uncertainty": "Pa",
    "force_n_estimate": "N",
    "force_n_uncertainty": "N",
    "cycle": "1",
    "direction": "1",
    "range": "1",
    "periods": "1",
    "missed": "1",
    "seq": "1",
    "reference_raw": "count",
    "force_nominal_n": "N",
    "step": "1",
}

#: Readout quantities a calibration or a hysteresis error can be computed on.
QUANTITY_COLUMNS = ("frequency_hz", "duty_cycle", "voltage_v")

#: Sidecar key of a run written whole (:func:`fsrlab.io.runwriter.write_run`): the SHA-256 of its CSV's bytes
#: (hex), by which :func:`fsrlab.io.runformat.load_run` tells the sidecar of another CSV from the CSV's own.
CSV_SHA256 = "csv_sha256"


class RunFormatError(FileFormatError):
    """A run file that does not follow the format; the message is one line naming file, row, column.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


def check_columns(columns: Sequence[str]) -> list[str]:
    """Column names as strings, or ``ValueError`` for an empty, duplicate or unwritable name.

    Parameters
    ----------
    columns : sequence of str
        Header names.

    Returns
    -------
    list of str
    """
    if isinstance(columns, (str, bytes)) or not isinstance(columns, Iterable):
        raise TypeError(f"columns: must be a sequence of column names, got {type(columns).__name__}")
    cols = [str(c) for c in columns]
    if not cols:
        raise ParameterError("must name at least one column", parameter="columns")
    for c in cols:
        if not c or c != c.strip() or any(ch in c for ch in ',"\r\n'):
            raise ParameterError(f"invalid column name {shown(c)} (no commas, quotes, newlines or edge spaces)",
                                 parameter="columns")
    # One count per name (linear): a header of 100,000 columns is checked in milliseconds.
    dup = sorted(c for c, n in Counter(cols).items() if n > 1)
    if dup:
        raise ParameterError(f"duplicate column names {shown_list(dup)}", parameter="columns")
    return cols


def sidecar_path(path: str | os.PathLike) -> Path:
    """Return the metadata sidecar of a run: ``NAME.csv`` -> ``NAME.meta.json``.

    Parameters
    ----------
    path : str or path-like
        The run's CSV file.

    Returns
    -------
    Path
    """
    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: must be a path (str or path-like), got {type(path).__name__}")
    if not os.fspath(path):
        raise ParameterError("must name a run's file, got an empty path", parameter="path")
    p = Path(path)
    return p.with_name((p.name[:-4] if p.name.lower().endswith(".csv") else p.name) + ".meta.json")


def where(path: Path, row: int, column: str | None) -> str:
    """Where in a table a problem is, for one-line errors: ``"FILE: row R (line L), column 'C'"``.

    Parameters
    ----------
    path : Path
        The file.
    row : int
        1-based data row; the file line is row + 1 (the header is line 1).
    column : str or None
        The column, if the problem is in one cell.

    Returns
    -------
    str
    """
    if isinstance(row, bool) or not isinstance(row, Integral):
        raise TypeError(f"row: must be an int, got {type(row).__name__}")
    col = f", column {column!r}" if column is not None else ""
    return f"{path}: row {row} (line {row + 1}){col}"
