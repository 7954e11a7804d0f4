"""The run file format shared by acquisition and analysis (normative copy: ``docs/data-format.md``).

A run is ``NAME.csv`` -- UTF-8, comma separated, one header row, one row per reading in time order,
plain numbers, an empty cell meaning "missing" -- plus an optional sidecar ``NAME.meta.json``
(``"format": "fsrlab-run"``, ``"version": 1``) holding the units of every column, the circuit parts,
the sensor model and area, the origin of the data, the creation time and free notes.

:class:`RunWriter` appends rows and hands each one to the operating system at once, so a crash or
a ``SIGKILL`` leaves a readable file that lacks at most the rows not yet written. :func:`load_run`
reads a run back and rejects a bad file with one line naming the file, the row and the column.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

__all__ = [
    "read_table",
    "where",
    "FORMAT",
    "VERSION",
    "KNOWN_COLUMNS",
    "QUANTITY_COLUMNS",
    "RunFormatError",
    "Run",
    "RunWriter",
    "load_run",
    "write_run",
    "sidecar_path",
]

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
    "cycle": "1",
    "direction": "1",
    "range": "1",
    "periods": "1",
    "missed": "1",
    "seq": "1",
}

#: Readout quantities a calibration or a hysteresis error can be computed on.
QUANTITY_COLUMNS = ("frequency_hz", "duty_cycle", "voltage_v")


class RunFormatError(ValueError):
    """A run file that does not follow the format; the message is one line naming file, row, column."""


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
    p = Path(path)
    return p.with_name((p.name[:-4] if p.name.lower().endswith(".csv") else p.name) + ".meta.json")


def _utc_now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


def _format_value(value: Any) -> str:
    """One cell: plain numbers, shortest round-trip form; ``None``/NaN -> empty (missing)."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "1" if value else "0"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    v = float(value)
    if math.isnan(v):
        return ""
    if math.isinf(v):
        raise ValueError(f"row value must be finite, got {value!r}")
    if v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    return repr(v)


def _check_columns(columns: Sequence[str]) -> list[str]:
    cols = [str(c) for c in columns]
    if not cols:
        raise ValueError("columns must name at least one column")
    for c in cols:
        if not c or c != c.strip() or any(ch in c for ch in ',"\r\n'):
            raise ValueError(f"columns: invalid column name {c!r} (no commas, quotes, newlines or edge spaces)")
    dup = sorted({c for c in cols if cols.count(c) > 1})
    if dup:
        raise ValueError(f"columns: duplicate column names {dup}")
    return cols


def _user_error(exc: OSError, path: Path) -> OSError:
    """``exc`` about ``path`` (the file the user named), never about a temporary file beside it."""
    err = type(exc)(f"cannot write {path}: {exc.strerror or exc}")
    err.errno = exc.errno
    return err


def _write_json_atomic(path: Path, obj: dict) -> None:
    """Replace ``path`` by ``obj`` as JSON in one rename; an error names ``path``, not the temporary."""
    text = json.dumps(obj, indent=2, allow_nan=False) + "\n"
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise _user_error(exc, path) from None


def _build_metadata(columns: list[str], metadata: Mapping[str, Any] | None) -> dict:
    meta = dict(metadata or {})
    units = {c: KNOWN_COLUMNS.get(c, "") for c in columns}
    units.update({k: str(v) for k, v in dict(meta.pop("units", {}) or {}).items() if k in units})
    out = {
        "format": FORMAT,
        "version": VERSION,
        "created": meta.pop("created", None) or _utc_now(),
        "columns": columns,
        "units": units,
        "circuit": meta.pop("circuit", {}),
        "sensor": meta.pop("sensor", {}),
        "origin": meta.pop("origin", ""),
        "notes": meta.pop("notes", ""),
    }
    out.update(meta)  # anything else the writer wants to keep
    out["complete"] = False
    out["rows"] = None
    return out


class RunWriter:
    """Write a run row by row, crash-safe.

    The header and the sidecar are written when the writer opens. Each :meth:`write` appends one
    whole line with a single write to the operating system, so a process killed at any moment
    leaves a file whose rows are all complete; :meth:`sync` also asks the OS to put them on disk
    (``fsync``), which protects against power loss. A write that fails half-way (disk full, file
    size limit) is cut back to the last whole row before the error is raised. Closing records the
    row count and ``"complete": true`` in the sidecar.

    Parameters
    ----------
    path : str or path-like
        The CSV file (``NAME.csv``); the sidecar is ``NAME.meta.json``.
    columns : sequence of str
        Column names in order, e.g. ``["time_s", "frequency_hz", "duty_cycle"]``.
    metadata : mapping, optional
        Sidecar content: ``units`` (per column, defaults from :data:`KNOWN_COLUMNS`), ``circuit``
        (e.g. ``{"r_ohm": 10e3, "c_off_farad": 0, "diode": true}``), ``sensor`` (e.g.
        ``{"model": "FlexiForce A201-1", "area_m2": 7.1e-5}``), ``origin``, ``notes``; other keys are kept.
    overwrite : bool
        Replace an existing run (the default). With False, an existing CSV or sidecar raises
        ``FileExistsError`` naming it, and nothing is written.

    Raises
    ------
    FileExistsError
        ``overwrite=False`` and the CSV or its sidecar exists.
    OSError
        The files cannot be written; the message names the CSV or the sidecar, never a temporary file.

    Examples
    --------
    >>> with RunWriter("run.csv", ["time_s", "frequency_hz"], {"origin": "virtual"}) as w:  # doctest: +SKIP
    ...     w.write({"time_s": 0.1, "frequency_hz": 5123.4})
    """

    def __init__(self, path: str | os.PathLike, columns: Sequence[str], metadata: Mapping[str, Any] | None = None,
                 overwrite: bool = True):
        self.path = Path(path)
        self.columns = _check_columns(columns)
        self._set = set(self.columns)
        self.metadata = _build_metadata(self.columns, metadata)
        self.meta_path = sidecar_path(self.path)
        self.rows = 0
        self._size = 0  # bytes of whole lines in the CSV
        if not overwrite:
            for existing in (self.path, self.meta_path):
                if os.path.lexists(existing):
                    raise FileExistsError(f"{existing} exists; a run is replaced only when asked to")
        had_sidecar = os.path.lexists(self.meta_path)
        _write_json_atomic(self.meta_path, self.metadata)
        try:
            # buffering=0: every write() below is one system call carrying one whole line.
            self._fd = open(self.path, "wb" if overwrite else "xb", buffering=0)
        except OSError as exc:
            if not had_sidecar:  # do not leave a sidecar without its run
                try:
                    os.unlink(self.meta_path)
                except OSError:
                    pass
            raise _user_error(exc, self.path) from None
        self._raw(",".join(self.columns) + "\n")
        self.sync()

    def _raw(self, text: str) -> None:
        data = text.encode("utf-8")
        view = memoryview(data)
        try:
            while view:
                n = self._fd.write(view)
                view = view[n:]
        except OSError as exc:
            try:  # keep the file made of whole lines: cut the part of this write that got through
                os.ftruncate(self._fd.fileno(), self._size)
                self._fd.seek(self._size)
            except OSError:
                pass
            raise _user_error(exc, self.path) from None
        self._size += len(data)

    @property
    def closed(self) -> bool:
        """Whether the writer has been closed."""
        return self._fd.closed

    def write(self, row: Mapping[str, Any]) -> None:
        """Append one reading.

        Parameters
        ----------
        row : mapping
            Column name -> number; absent columns, ``None`` and NaN are written as empty (missing) cells.

        Raises
        ------
        ValueError
            If ``row`` names a column the run does not have, or holds a non-finite number.
        OSError
            If the row cannot be written (the file then still ends with the previous whole row).
        """
        unknown = [k for k in row if k not in self._set]
        if unknown:
            raise ValueError(f"row: unknown columns {unknown}; the run has {self.columns}")
        line = ",".join(_format_value(row.get(c)) for c in self.columns) + "\n"
        self._raw(line)
        self.rows += 1

    def write_many(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Append several readings (see :meth:`write`)."""
        for row in rows:
            self.write(row)

    def sync(self) -> None:
        """Force the rows written so far to disk (``os.fsync``)."""
        try:
            os.fsync(self._fd.fileno())
        except OSError as exc:
            raise _user_error(exc, self.path) from None

    def update_metadata(self, changes: Mapping[str, Any]) -> None:
        """Merge ``changes`` into the sidecar and write it now (the run stays open, ``complete: false``).

        Parameters
        ----------
        changes : mapping
            Sidecar keys and their new values, e.g. ``{"gaps": [...]}``.
        """
        self.metadata.update(changes)
        _write_json_atomic(self.meta_path, self.metadata)

    def close(self) -> None:
        """Sync, close the CSV and mark the sidecar complete with the row count.

        The sidecar says ``"complete": false`` when the last ``fsync`` failed (the rows may not be
        on disk); the error is raised after the sidecar is written.
        """
        if self._fd.closed:
            return
        error = None
        try:
            self.sync()
        except OSError as exc:
            error = exc
        self._fd.close()
        self.metadata["complete"] = error is None
        self.metadata["rows"] = self.rows
        self.metadata["closed"] = _utc_now()
        _write_json_atomic(self.meta_path, self.metadata)
        if error is not None:
            raise error

    def __enter__(self) -> "RunWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_run(path: str | os.PathLike, columns: Mapping[str, Any], metadata: Mapping[str, Any] | None = None,
              overwrite: bool = True) -> Path:
    """Write a whole run at once from column arrays.

    Parameters
    ----------
    path : str or path-like
        The CSV file; the sidecar goes next to it.
    columns : mapping of str to array_like
        Column name -> 1-D values, all of the same length (NaN = missing).
    metadata : mapping, optional
        As for :class:`RunWriter`.
    overwrite : bool
        As for :class:`RunWriter`: with False an existing run raises ``FileExistsError``.

    Returns
    -------
    Path
        The CSV file written.
    """
    names = list(columns)
    arrays = [np.asarray(columns[c]) for c in names]
    n = {a.shape for a in arrays}
    if len(n) != 1 or arrays[0].ndim != 1:
        raise ValueError("columns: every column must be a 1-D array of the same length")
    buf = io.StringIO()
    for i in range(arrays[0].shape[0]):
        buf.write(",".join(_format_value(a[i]) for a in arrays))
        buf.write("\n")
    with RunWriter(path, names, metadata, overwrite=overwrite) as w:
        w._raw(buf.getvalue())
        w.rows = arrays[0].shape[0]
    return Path(path)


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
                raise RunFormatError(f"{self.path}: column 'force_n' needs sensor.area_m2 > 0 in {sidecar_path(self.path).name} to give stress")
            return self.columns["force_n"] / float(area)
        raise RunFormatError(f"{self.path}: column 'stress_pa' missing (or 'force_n' with a sensor area)")

    def readout(self):
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


def _load_metadata(path: Path) -> dict | None:
    mp = sidecar_path(path)
    if not mp.exists():
        return None
    try:
        meta = json.loads(mp.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise RunFormatError(f"{mp}: not valid JSON ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise RunFormatError(f"{mp}: not an {FORMAT!r} sidecar (\"format\" must be {FORMAT!r})")
    if meta.get("version") != VERSION:
        raise RunFormatError(f"{mp}: format version {meta.get('version')!r} not supported (this fsrlab reads version {VERSION})")
    return meta


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
    col = f", column {column!r}" if column is not None else ""
    return f"{path}: row {row} (line {row + 1}){col}"


def read_table(path: str | os.PathLike, required: Sequence[str], hint: str = "") -> tuple[dict[str, int], list[tuple[int, list[str]]], Path]:
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
    ValueError
        One line naming the file for an empty file or a missing column.
    """
    p = Path(path)
    with open(p, newline="", encoding="utf-8-sig") as fh:
        table = list(csv.reader(fh))
    if not table:
        raise ValueError(f"{p}: empty file" + (f" ({hint})" if hint else ""))
    header = [h.strip() for h in table[0]]
    for col in required:
        if col not in header:
            raise ValueError(f"{p}: column {col!r} missing (columns: {', '.join(header)})")
    rows = [(k, row) for k, row in enumerate(table[1:], start=1) if any(c.strip() for c in row)]
    return {c: i for i, c in enumerate(header)}, rows, p



def load_run(path: str | os.PathLike, require: Sequence[str] = (), skip_bad_rows: bool = False) -> Run:
    """Read a run written by :class:`RunWriter`, by acquisition, by hand or by a spreadsheet.

    Parameters
    ----------
    path : str or path-like
        The CSV file. Its sidecar ``NAME.meta.json`` is read when present (optional).
    require : sequence of str, optional
        Columns that must be present.
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
        :data:`fsrlab.runcells.COLUMN_LIMITS`), an empty ``time_s`` cell, ``time_s`` going
        backwards; or a bad sidecar.
    OSError
        If the file cannot be read.

    Notes
    -----
    A last line without its newline is the trace of a crash while writing; when the sidecar says
    the run was not closed (``"complete": false``) that line is dropped and ``Run.truncated`` is
    set. Without a sidecar (a hand-made file) it is kept if it parses.
    """
    p = Path(path)
    with open(p, "rb") as fh:
        raw = fh.read()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RunFormatError(f"{p}: not UTF-8 text (byte {exc.start})") from None
    meta = _load_metadata(p)
    lines = text.splitlines()
    truncated = False
    if lines and not text.endswith(("\n", "\r")) and meta is not None and meta.get("complete") is False and len(lines) > 1:
        lines = lines[:-1]
        truncated = True
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise RunFormatError(f"{p}: empty file (a header row is needed)")
    header = next(csv.reader([lines[0]]))
    header = [h.strip() for h in header]
    try:
        header = _check_columns(header)
    except ValueError as exc:
        raise RunFormatError(f"{p}: row 0 (line 1, header): {exc}") from None
    for name in require:
        if name not in header:
            raise RunFormatError(f"{p}: column {name!r} missing (columns: {', '.join(header)})")
    from fsrlab.runcells import parse_cells

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
            raise RunFormatError(f"{where(p, row, 'time_s')}: time goes backwards ({float(t[i])!r} s after {float(t[i - 1])!r} s); "
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
