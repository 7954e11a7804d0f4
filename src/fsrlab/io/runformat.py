"""The run file format shared by acquisition and analysis (normative copy: ``docs/data-format.md``).

A run is ``NAME.csv`` -- UTF-8, comma separated, one header row, one row per reading in time order,
plain numbers, an empty cell meaning "missing" -- plus an optional sidecar ``NAME.meta.json``
(``"format": "fsrlab-run"``, ``"version": 1``) holding the units of every column, the circuit parts,
the sensor model and area, the origin of the data, the creation time and free notes.

:class:`fsrlab.io.runwriter.RunWriter` appends rows and hands each one to the operating system at once, so a crash or
a ``SIGKILL`` leaves a readable file that lacks at most the rows not yet written. :func:`load_run`
reads a run back and rejects a bad file with one line naming the file, the row and the column.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.io.csvtext import LongCellError, csv_cells, csv_rows
from fsrlab.io.schema import (
    CSV_SHA256,
    FORMAT,
    KNOWN_COLUMNS,
    QUANTITY_COLUMNS,
    VERSION,
    RunFormatError,
    check_columns,
    sidecar_path,
    where,
)
from fsrlab.io.shown import shown, shown_list

if TYPE_CHECKING:
    from fsrlab.circuits.circuit import LM555Circuit
    from fsrlab.io.recorded import RecordedWith

__all__ = [
    "read_table",
    "where",
    "FORMAT",
    "VERSION",
    "KNOWN_COLUMNS",
    "QUANTITY_COLUMNS",
    "RunFormatError",
    "Run",
    "load_run",
    "input_file",
    "as_run",
    "sidecar_path",
    "check_columns",
    "read_json_document",
    "C_FSR",
]

#: The readout name of C_FSR decoded through a run's circuit (:meth:`Run.readout_values`). [F]
C_FSR = "c_fsr_farad"


def _names(header: Sequence[str]) -> str:
    """A header as an error message shows it: control characters escaped, the length capped."""
    return shown_list(header)


@dataclass
class Run:
    """A loaded run.

    Parameters
    ----------
    path : Path
        The CSV file.
    columns : dict of str to ndarray
        Every column as float64 (missing cells are NaN), in file order.
    metadata : dict
        The sidecar (or defaults when there is none).
    truncated : bool
        True when an incomplete last line (a crash while writing) was dropped.
    skipped : list of BadRow
        Rows left out because of a bad cell (``load_run(..., skip_bad_rows=True)``), in file order.
    """

    path: Path
    columns: dict[str, np.ndarray]
    metadata: dict = field(default_factory=dict)
    truncated: bool = False
    skipped: list = field(default_factory=list)

    @property
    def n_rows(self) -> int:
        """Number of readings."""
        return len(next(iter(self.columns.values()))) if self.columns else 0

    @property
    def units(self) -> dict[str, str]:
        """Unit of each column."""
        units = self.metadata.get("units", {}) or {}
        return {c: units.get(c, KNOWN_COLUMNS.get(c, "")) for c in self.columns}

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.columns[name]
        except KeyError:
            raise RunFormatError(f"{self.path}: column {name!r} missing (columns: {', '.join(self.columns)})") from None

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def __repr__(self) -> str:
        """A summary: the file, the rows and the columns (not the numbers)."""
        notes = ", an incomplete last line dropped" if self.truncated else ""
        notes += f", {len(self.skipped)} bad rows skipped" if self.skipped else ""
        columns = _names(list(self.columns))
        return f"{type(self).__name__}({shown(str(self.path))}, {self.n_rows} rows, columns {columns}{notes})"

    def require(self, *names: str) -> None:
        """Raise :class:`RunFormatError` naming the first of ``names`` the run lacks."""
        for n in names:
            if n not in self.columns:
                raise RunFormatError(f"{self.path}: column {n!r} missing (columns: {', '.join(self.columns)})")

    def stress_pa(self) -> np.ndarray:
        """Reference stress [Pa]: ``stress_pa``, or ``force_n`` divided by the sidecar's ``sensor.area_m2``.

        Raises
        ------
        RunFormatError
            If neither is available.
        """
        if "stress_pa" in self.columns:
            return self.columns["stress_pa"]
        if "force_n" in self.columns:
            area = (self.metadata.get("sensor") or {}).get("area_m2")
            if not area or float(area) <= 0:
                raise RunFormatError(f"{self.path}: column 'force_n' needs sensor.area_m2 > 0 in "
                        f"{sidecar_path(self.path).name} to give stress")
            return self.columns["force_n"] / float(area)
        raise RunFormatError(f"{self.path}: column 'stress_pa' missing (or 'force_n' with a sensor area)")

    def circuits(self):
        """The readout circuits the sidecar describes (:func:`fsrlab.circuits.circuit.readout_from_metadata`).

        Returns
        -------
        (LM555Circuit or None, OpAmpReadout or None)
            The sidecar's ``circuit`` and ``opamp`` (earlier layouts included); None where it says
            nothing of that circuit. In a run with a ``range`` column the LM555's ``c_off_farad`` is
            in circuit where ``range`` is 1 (:meth:`LM555Circuit.on_range`), otherwise throughout.

        Raises
        ------
        RunFormatError
            A circuit part out of range or unknown (the message names the sidecar and the part).
        """
        from fsrlab.circuits.circuit import readout_from_metadata

        try:
            return readout_from_metadata(self.metadata)
        except ValueError as exc:
            raise RunFormatError(f"{sidecar_path(self.path).name}: {exc}") from None

    def circuit(self, circuit: LM555Circuit | None = None) -> LM555Circuit:
        """The LM555 circuit the run was recorded with.

        Parameters
        ----------
        circuit : LM555Circuit, optional
            Returned as is when given.

        Returns
        -------
        LM555Circuit
            ``circuit``, else the sidecar's (:func:`fsrlab.circuits.circuit.readout_from_metadata`),
            else :data:`fsrlab.circuits.circuit.PAPER_CIRCUIT` (R = 10 kΩ, ideal D1, no C_off).

        Raises
        ------
        RunFormatError
            The sidecar's circuit out of range or unknown (as :meth:`circuits`).
        """
        from fsrlab.circuits.circuit import PAPER_CIRCUIT, LM555Circuit

        if circuit is not None:
            if not isinstance(circuit, LM555Circuit):
                raise TypeError(f"circuit: must be an LM555Circuit, got {type(circuit).__name__}")
            return circuit
        found, _ = self.circuits()  # a sidecar's circuit out of range: RunFormatError naming the sidecar
        return PAPER_CIRCUIT if found is None else found

    def readout_values(self, x: str, circuit: LM555Circuit | None = None) -> tuple[np.ndarray, LM555Circuit | None]:
        """A calibration's readout of the run: a column, or C_FSR decoded through the run's circuit.

        Parameters
        ----------
        x : str
            A column (``frequency_hz``, ``duty_cycle``, ``voltage_v``, ...), or :data:`C_FSR`
            (``c_fsr_farad``): C_FSR decoded from ``frequency_hz`` and ``duty_cycle`` (when the run has
            no such column), honouring the ``range`` column.
        circuit : LM555Circuit, optional
            Circuit for the decoding (default: :meth:`circuit`).

        Returns
        -------
        values : ndarray
            One value per reading (NaN where missing or not decodable).
        circuit : LM555Circuit or None
            The circuit decoded through, or None for a column.

        Raises
        ------
        fsrlab.errors.ParameterError
            A column the run lacks (``parameter`` ``x``).
        """
        if not isinstance(x, str):
            raise TypeError(f"x: must be the name of a column, got {type(x).__name__}")
        if x != C_FSR and x not in self:
            raise ParameterError(f"{self.path} has no column {x!r} (columns: {', '.join(self.columns)})",
                                 parameter="x")
        if x == C_FSR and x not in self:
            from fsrlab.circuits.circuit import decode_capacitance

            self.require("frequency_hz", "duty_cycle")
            circ = self.circuit(circuit)
            return decode_capacitance(self["frequency_hz"], self["duty_cycle"], circ, self.columns.get("range")), circ
        return self[x], None

    def recorded_with(self, used=None) -> RecordedWith:
        """What the run was recorded with: its sidecar's circuits and the ranges of its readings.

        Parameters
        ----------
        used : array_like of bool, optional
            The readings that count (default all).

        Returns
        -------
        RecordedWith
            See :func:`fsrlab.io.recorded.recorded_with`.

        Raises
        ------
        RunFormatError
            A circuit part of the sidecar out of range or unknown.
        """
        from fsrlab.io.recorded import recorded_with

        try:
            return recorded_with(self.metadata, self.columns.get("range"), used)
        except ValueError as exc:
            raise RunFormatError(f"{self.path}: its sidecar's circuit: {exc}") from None

    def incomplete(self) -> str | None:
        """What to tell a user of a run whose writer never closed it, or None for a closed run.

        Returns
        -------
        str or None
            For a sidecar saying ``"complete": false`` (a recording killed, or still going): the
            file, that it is incomplete, its last row (number, file line and ``time_s``) and
            whether an incomplete last line was dropped. None when the sidecar says the run is
            complete, or there is no sidecar.
        """
        if self.metadata.get("complete") is not False:
            return None
        n_file = self.n_rows + len(self.skipped)
        if n_file == 0:
            last = "it holds no rows"
        else:
            row = int(_file_rows(n_file, self.skipped)[-1]) if self.n_rows else n_file
            time = self.columns.get("time_s")
            at = f", time_s {float(time[-1])!r} s" if time is not None and self.n_rows else ""
            last = f"the last row read is row {row} (line {row + 1}{at})"
        dropped = "; an incomplete last line was dropped" if self.truncated else ""
        return (f"{self.path} is incomplete (its sidecar says \"complete\": false: the recording was not closed); "
                f"{last}{dropped}")

    def to_pandas(self):
        """The run as a ``pandas.DataFrame`` (pandas is imported only here)."""
        import pandas as pd

        return pd.DataFrame(self.columns)


def _default_metadata(columns: list[str]) -> dict:
    return {"format": FORMAT, "version": VERSION, "created": None, "columns": columns,
            "units": {c: KNOWN_COLUMNS.get(c, "") for c in columns}, "circuit": {}, "sensor": {},
            "origin": "", "notes": "", "complete": None, "rows": None}


def read_json_document(path: Path, format_name: str, version: int, what: str, error=None) -> dict:
    """Read a JSON file of fsrlab's (a sidecar, a calibration) and check its ``format`` and ``version``.

    Parameters
    ----------
    path : Path
        The file.
    format_name : str
        Required value of its ``"format"`` key.
    version : int
        The version this fsrlab reads.
    what : str
        What the file is, for the messages (``"sidecar"``, ``"calibration"``).
    error : callable, optional
        Makes the exception raised from one line naming the file and what is wrong (default a
        :class:`~fsrlab.errors.FileFormatError` naming ``path``).

    Returns
    -------
    dict
    """
    path = input_file(path, "path")
    if not isinstance(format_name, str):
        raise TypeError(f"format_name: must be a str, got {type(format_name).__name__}")
    if isinstance(version, bool) or not isinstance(version, int):
        raise TypeError(f"version: must be an int, got {type(version).__name__}")
    if error is None:
        def error(message: str) -> FileFormatError:
            return FileFormatError(message, parameter="path")
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise error(f"{path}: not a valid JSON {what} ({exc})") from None
    if not isinstance(d, dict) or d.get("format") != format_name:
        raise error(f"{path}: not an fsrlab {what} (\"format\" must be {format_name!r})")
    if d.get("version") != version:
        raise error(f"{path}: {what} version {d.get('version')!r} not supported (this fsrlab reads version {version})")
    bad = _non_finite(d)
    if bad is not None:
        raise error(f"{path}: \"{bad}\" is not a finite number (JSON has no NaN or Infinity)")
    return d


def _non_finite(obj, key: str = "") -> str | None:
    """The key path of the first NaN or infinite number in a JSON document, or None."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return key or "(top level)"
    items = obj.items() if isinstance(obj, dict) else enumerate(obj) if isinstance(obj, list) else ()
    for k, v in items:
        found = _non_finite(v, f"{key}.{k}" if key else str(k))
        if found is not None:
            return found
    return None


def _load_metadata(path: Path) -> dict | None:
    mp = sidecar_path(path)
    if not mp.exists():
        return None
    meta = read_json_document(mp, FORMAT, VERSION, "sidecar", RunFormatError)
    for key in ("units", "circuit", "opamp", "sensor", "calibration", "acquisition"):
        if meta.get(key) is not None and not isinstance(meta[key], dict):
            raise RunFormatError(f"{mp}: \"{key}\" must be an object (a mapping), got {type(meta[key]).__name__}")
    return meta


def read_table(path: str | os.PathLike, required: Sequence[str],
               hint: str = "") -> tuple[dict[str, int], list[tuple[int, list[str]]], Path]:
    """Read a small CSV table that is not a run (grouped readings, ISO 376 series).

    Parameters
    ----------
    path : str or path-like
        The CSV file, with a header row.
    required : sequence of str
        Columns that must be present.
    hint : str
        Appended to the message for an empty file, e.g. ``"header load,sensor,reading needed"``.

    Returns
    -------
    columns : dict
        Column name → index in each row.
    rows : list of (int, list of str)
        Non-blank data rows with their 1-based row number (the file line is row + 1).
    path : Path
        The path, for messages (see :func:`where`).

    Raises
    ------
    fsrlab.errors.FileFormatError
        One line naming the file for an empty file or a missing column (parameter ``path``).
    """
    p = input_file(path, "path")
    if not isinstance(required, (list, tuple)) or not all(isinstance(c, str) for c in required):
        raise TypeError(f"required: must be a sequence of column names (str), got {required!r:.80}")
    with open(p, newline="", encoding="utf-8-sig") as fh:
        try:
            table = list(csv_rows(fh))
        except LongCellError as exc:
            raise FileFormatError(f"{p}: line {exc.line}: {exc}", parameter="path") from None
    if not table:
        raise FileFormatError(f"{p}: empty file" + (f" ({hint})" if hint else ""), parameter="path")
    header = [h.strip() for h in table[0]]
    for col in required:
        if col not in header:
            raise FileFormatError(f"{p}: column {col!r} missing (required; columns: {_names(header)})",
                                  parameter="path")
    rows = [(k, row) for k, row in enumerate(table[1:], start=1) if any(c.strip() for c in row)]
    return {c: i for i, c in enumerate(header)}, rows, p



def load_run(path: str | os.PathLike, require: Sequence[str] = (), skip_bad_rows: bool = False) -> Run:
    """Read a run written by :class:`RunWriter`, by acquisition, by hand or by a spreadsheet.

    Parameters
    ----------
    path : str or path-like
        The CSV file. Its sidecar ``NAME.meta.json`` is read when present (optional).
    require : sequence of str, or str, optional
        Columns that must be present (a string is one column's name).
    skip_bad_rows : bool
        Leave out the rows with a bad cell and list them in ``Run.skipped`` instead of raising.
        Rows out of time order are an error all the same (which row is wrong cannot be told).

    Returns
    -------
    Run

    Raises
    ------
    RunFormatError
        One line naming the file, the row (1-based data row, and its file line) and the column,
        for: a missing column, a row with too few or too many cells, a non-numeric cell, a NaN or
        infinite value, a value its column cannot hold (``1e308`` Hz, a duty cycle of 2, a
        ``direction`` other than -1, 0, +1, a ``range`` other than 0, 1: see
        :data:`fsrlab.io.runcells.COLUMN_LIMITS`), an empty ``time_s`` cell, ``time_s`` going
        backwards; or a bad sidecar, or one written with another CSV (its ``"csv_sha256"``: a replacement
        by :func:`~fsrlab.io.runwriter.write_run` interrupted between its two renames).
    fsrlab.errors.ParameterError
        A path that is empty, missing or a directory (parameter ``path``).
    TypeError
        A path or a ``require`` of the wrong type.
    OSError
        If the file cannot be read.

    Notes
    -----
    A last line without its newline is the trace of a crash while writing; when the sidecar says
    the run was not closed (``"complete": false``) that line is dropped and ``Run.truncated`` is
    set. Without a sidecar (a hand-made file) it is kept if it parses.
    """
    p = input_file(path, "path")
    if isinstance(require, str):  # one column's name, not its letters
        require = (require,)
    if not isinstance(require, (list, tuple)) or not all(isinstance(c, str) for c in require):
        raise TypeError(f"require: must be a column's name or a sequence of them (str), got {require!r:.80}")
    try:
        return _read_run(p, require, skip_bad_rows)
    except RunFormatError as exc:  # the file is this function's path
        if exc.parameter is not None:
            raise
        raise RunFormatError(exc.reason, parameter="path") from None


def _read_run(p: Path, require: Sequence[str], skip_bad_rows: bool) -> Run:
    """:func:`load_run` on a checked path: its errors name the file, the row and the column."""
    with open(p, "rb") as fh:
        raw = fh.read()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RunFormatError(f"{p}: not UTF-8 text (byte {exc.start})") from None
    meta = _load_metadata(p)
    if meta is not None and CSV_SHA256 in meta and meta[CSV_SHA256] != hashlib.sha256(raw).hexdigest():
        raise RunFormatError(f"{p}: not the CSV its sidecar {sidecar_path(p).name} was written with (its "
                             f"\"{CSV_SHA256}\" differs: the run's replacement was interrupted, or the CSV was changed "
                             f"since); write the run again, or remove \"{CSV_SHA256}\" from the sidecar to read the "
                             "two as one run")
    lines = text.splitlines()
    truncated = False
    unfinished = lines and not text.endswith(("\n", "\r"))
    if unfinished and meta is not None and meta.get("complete") is False and len(lines) > 1:
        lines = lines[:-1]
        truncated = True
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise RunFormatError(f"{p}: empty file (a header row is needed)")
    try:
        header = [h.strip() for h in csv_cells(lines[0])]
    except LongCellError as exc:
        raise RunFormatError(f"{p}: row 0 (line 1, header): {exc}") from None
    try:
        header = check_columns(header)
    except ValueError as exc:
        raise RunFormatError(f"{p}: row 0 (line 1, header): {exc}") from None
    for name in require:
        if name not in header:
            raise RunFormatError(f"{p}: column {name!r} missing (required; columns: {_names(header)})")
    from fsrlab.io.runcells import parse_cells

    data, skipped = parse_cells(p, lines[1:], header, skip_bad_rows)
    columns = {h: data[:, j].copy() for j, h in enumerate(header)}
    if "time_s" in columns:
        t = columns["time_s"]
        back = np.flatnonzero(np.diff(t) < 0)
        if back.size:
            # Which row is wrong cannot be told (one late row, or the rows after an early one), so
            # this stays an error even when bad rows are skipped.
            i = back[0] + 1
            row = _file_rows(len(lines) - 1, skipped)[i]
            raise RunFormatError(f"{where(p, row, 'time_s')}: time goes backwards ({float(t[i])!r} s after "
                    f"{float(t[i - 1])!r} s); "
                                 "rows must be in time order")
    if meta is None:
        meta = _default_metadata(header)
    return Run(path=p, columns=columns, metadata=meta, truncated=truncated, skipped=skipped)


def _file_rows(n_file_rows: int, skipped: Sequence) -> np.ndarray:
    """1-based file row of each row kept, when ``skipped`` rows were left out."""
    rows = np.arange(1, n_file_rows + 1)
    if skipped:
        rows = np.setdiff1d(rows, [b.row for b in skipped])
    return rows


def input_file(path, parameter: str = "path") -> Path:
    """``path`` as the Path of an existing file to read, or one error naming ``parameter``.

    Parameters
    ----------
    path : str or path-like
        The file.
    parameter : str
        The caller's name for it, in the error.

    Returns
    -------
    Path

    Raises
    ------
    TypeError
        If ``path`` is not a str or path-like (the message names ``parameter``).
    fsrlab.errors.ParameterError
        If it is empty, missing or a directory.
    """
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bool):
        raise TypeError(f"{parameter}: must be a file's path (str or path-like), got {type(path).__name__}")
    p = Path(path)
    if not str(path):
        raise ParameterError("must name a file, got an empty path", parameter=parameter)
    if p.is_dir():
        raise ParameterError(f"'{p}' is a directory, not a file", parameter=parameter)
    if not p.exists():
        raise ParameterError(f"'{p}': no such file", parameter=parameter)
    return p


def as_run(run, parameter: str = "run") -> Run:
    """``run`` as a :class:`Run`: a Run as it is, a path read by :func:`load_run`; one error naming ``parameter``.

    Parameters
    ----------
    run : Run, str or path-like
        A run, or its CSV file.
    parameter : str
        The caller's name for it, in the error.

    Returns
    -------
    Run

    Raises
    ------
    TypeError
        If ``run`` is neither a Run nor a path (the message names ``parameter``).
    fsrlab.errors.ParameterError
        If the path is empty, missing, a directory or unreadable.
    RunFormatError
        If the file is not a valid run (naming ``parameter``, the file, the row and the column).
    """
    if isinstance(run, Run):
        return run
    if not isinstance(run, (str, os.PathLike)) or isinstance(run, bool):
        raise TypeError(f"{parameter}: must be a run (fsrlab.load_run) or its path, got {type(run).__name__}")
    p = input_file(run, parameter)
    try:
        return load_run(p)
    except OSError as exc:
        raise ParameterError(f"{p}: {exc.strerror or exc}", parameter=parameter) from None
    except RunFormatError as exc:
        raise RunFormatError(exc.reason, parameter=parameter) from None

