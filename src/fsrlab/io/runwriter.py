"""Writing runs (docs/data-format.md): rows appended crash-safely, the sidecar replaced atomically.

:class:`RunWriter` appends rows and hands each one to the operating system at once, so a crash or a
``SIGKILL`` leaves a readable file that lacks at most the rows not yet written; its sidecar is
rewritten through a temporary file and a rename, and errors name the run's own files. Reading is
:func:`fsrlab.io.runformat.load_run`.
"""

from __future__ import annotations

import errno
import json
import math
import os
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.io.outputs import OutputExistsError, atomic_run
from fsrlab.io.schema import CSV_SHA256, FORMAT, KNOWN_COLUMNS, VERSION, check_columns, sidecar_path

__all__ = ["RunWriter", "write_run"]


def _utc_now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")


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
        raise ParameterError(f"value must be finite, got {value!r}", parameter="row")
    if v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    return repr(v)


_CHUNK_ROWS = 1 << 16


def _format_column(values: np.ndarray) -> list[str]:
    """Every cell of a column as :func:`_format_value` writes it, a float column at C speed."""
    if values.dtype.kind != "f":
        return [_format_value(v) for v in values.tolist()]
    inf = np.isinf(values)
    if inf.any():
        raise ParameterError(f"values must be finite, got {values[inf][0]!r}", parameter="columns")
    finite = np.isfinite(values)
    whole = finite & (np.abs(values) < 1e15)
    whole[whole] = values[whole] == np.trunc(values[whole])
    if whole.all():
        return list(map(str, values.astype(np.int64).tolist()))
    vals = values.tolist()
    cells = list(map(repr, vals))
    for i in np.flatnonzero(whole).tolist():
        cells[i] = str(int(vals[i]))
    for i in np.flatnonzero(~finite).tolist():
        cells[i] = ""
    return cells


def _user_error(exc: OSError, path: Path) -> OSError:
    """``exc`` about ``path`` (the file the user named), never about a temporary file beside it."""
    why = ("it is a directory" if isinstance(exc, IsADirectoryError)
           else getattr(exc, "why", None) or exc.strerror or exc)  # (an error already said of another name)
    err = type(exc)(f"cannot write '{path}': {why}")
    err.errno, err.why = exc.errno, why
    return err


def _prepare_json(path: Path, obj: dict) -> Path:
    """``obj`` as JSON in a temporary file beside ``path``, on disk, for :func:`os.replace` to put in place
    (a full disk fails here, before anything is replaced); an error names ``path``, not the temporary."""
    text = json.dumps(obj, indent=2, allow_nan=False) + "\n"
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
    except BaseException as exc:  # Ctrl-C included: no temporary left behind
        _unlink_quietly(tmp)
        if isinstance(exc, OSError):
            raise _user_error(exc, path) from None
        raise
    return tmp


def _unlink_quietly(path: Path) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def _write_json_atomic(path: Path, obj: dict) -> None:
    """Replace ``path`` by ``obj`` as JSON in one rename; an error names ``path``, not the temporary."""
    tmp = _prepare_json(path, obj)
    try:
        os.replace(tmp, path)
    except OSError as exc:
        _unlink_quietly(tmp)
        raise _user_error(exc, path) from None


def _build_metadata(columns: list[str], metadata: Mapping[str, Any] | None) -> dict:
    meta = dict(metadata or {})
    meta.pop(CSV_SHA256, None)  # another CSV's (metadata taken from a run read); a run renamed into place gets its own
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
        Replace an existing run. With False (the default), an existing CSV or sidecar raises
        :class:`~fsrlab.io.outputs.OutputExistsError` (a ``FileExistsError``) naming it, and nothing is written.

    Raises
    ------
    fsrlab.io.outputs.OutputExistsError
        ``overwrite=False`` and the CSV or its sidecar exists (a FileExistsError and a ParameterError naming
        ``path``).
    OSError
        The files cannot be written; the message names the CSV or the sidecar, never a temporary file.

    Examples
    --------
    >>> with RunWriter("run.csv", ["time_s", "frequency_hz"], {"origin": "virtual"}) as w:  # doctest: +SKIP
    ...     w.write({"time_s": 0.1, "frequency_hz": 5123.4})
    """

    def __init__(self, path: str | os.PathLike, columns: Sequence[str], metadata: Mapping[str, Any] | None = None,
                 overwrite: bool = False):
        if metadata is not None and not isinstance(metadata, Mapping):
            raise TypeError(f"metadata: must be a mapping (a dict of the sidecar's content), got "
                            f"{type(metadata).__name__}")
        if not isinstance(overwrite, bool):
            raise TypeError(f"overwrite: must be True or False, got {type(overwrite).__name__}")
        from fsrlab.io.outputs import output_path

        self.path = output_path(path, "path")
        if self.path.is_dir():
            raise ParameterError(f"'{self.path}' is a directory, not a run's file", parameter="path")
        self.columns = check_columns(columns)
        self._set = set(self.columns)
        self.metadata = _build_metadata(self.columns, metadata)
        self.meta_path = sidecar_path(self.path)
        self.rows = 0
        self._size = 0  # bytes of whole lines in the CSV
        if not overwrite:
            for existing in (self.path, self.meta_path):
                if os.path.lexists(existing):
                    raise OutputExistsError("path", f"{existing} exists; a run is replaced only when asked to "
                                            "(overwrite=True)")
        existed = os.path.lexists(self.path)
        try:  # opened without truncating: a CSV that cannot be written leaves the old run as it was
            fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | (0 if overwrite else os.O_EXCL), 0o666)
        except OSError as exc:
            raise _user_error(exc, self.path) from None
        # buffering=0: every write() below is one system call carrying one whole line.
        self._fd = open(fd, "wb", buffering=0)
        tmp = None
        try:
            tmp = _prepare_json(self.meta_path, self.metadata)
            # The old run's sidecar goes before its rows, and the new one comes after the new header:
            # a crash in between leaves a CSV alone (the old rows, or the new header), never a CSV
            # beside a sidecar that is not its own.
            if os.path.isdir(self.meta_path):  # the new sidecar could not replace it: stop before the rows go
                raise _user_error(IsADirectoryError(errno.EISDIR, "Is a directory"), self.meta_path)
            if os.path.lexists(self.meta_path):
                try:
                    os.unlink(self.meta_path)
                except OSError as exc:
                    raise _user_error(exc, self.meta_path) from None
            os.ftruncate(fd, 0)
            self._raw(",".join(self.columns) + "\n")
            self.sync()
            try:
                os.replace(tmp, self.meta_path)
            except OSError as exc:
                raise _user_error(exc, self.meta_path) from None
        except BaseException:
            self._fd.close()
            if tmp is not None:
                _unlink_quietly(tmp)
            if not existed:  # do not leave a run the caller did not get
                _unlink_quietly(self.path)
            raise

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
            raise ParameterError(f"unknown columns {unknown}; the run has {self.columns}", parameter="row")
        line = ",".join(_format_value(row.get(c)) for c in self.columns) + "\n"
        self._raw(line)
        self.rows += 1

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

    def __enter__(self) -> RunWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_run(path: str | os.PathLike, columns: Mapping[str, Any], metadata: Mapping[str, Any] | None = None,
              overwrite: bool = False, inputs: Sequence[str | os.PathLike] = ()) -> Path:
    """Write a whole run at once from column arrays.

    Both files are written under temporary names beside the run and renamed over ``NAME.meta.json`` and
    then ``NAME.csv`` at the end (:func:`fsrlab.io.outputs.replace_run`): an interrupted write leaves the
    old files (or none), never half of one, and no temporary file. The sidecar records the CSV's SHA-256
    (``"csv_sha256"``), so a write interrupted between the two renames leaves the old CSV beside a sidecar
    that :func:`~fsrlab.io.runformat.load_run` refuses as not its own, never a pair that passes for one run.

    Parameters
    ----------
    path : str or path-like
        The CSV file; the sidecar goes next to it.
    columns : mapping of str to array_like
        Column name -> 1-D values, all of the same length (NaN = missing).
    metadata : mapping, optional
        As for :class:`RunWriter`.
    overwrite : bool
        Replace an existing run (its CSV or sidecar); with False (the default) one raises ``FileExistsError``.
    inputs : sequence of path-like
        Files the run was made from: neither they nor their sidecars are ever replaced, even with ``overwrite``.

    Returns
    -------
    Path
        The CSV file written.

    Raises
    ------
    fsrlab.io.outputs.OutputExistsError
        The run exists and ``overwrite`` is False (a FileExistsError and a ParameterError naming ``path``).
    OutputError
        An empty ``path``, or one that is an input or an input's sidecar (the output policy,
        :func:`fsrlab.io.outputs.check_output`); ``.parameter`` is ``"path"``.
    """
    from fsrlab.io.outputs import output_path, refuse_inputs

    if not isinstance(overwrite, bool):
        raise TypeError(f"overwrite: must be True or False, got {type(overwrite).__name__}")
    if not isinstance(columns, Mapping):
        raise TypeError(f"columns: must be a mapping of column name to values, got {type(columns).__name__}")
    if metadata is not None and not isinstance(metadata, Mapping):
        raise TypeError(f"metadata: must be a mapping (a dict of the sidecar's content), got "
                        f"{type(metadata).__name__}")
    path = output_path(path, "path")
    if path.is_dir():
        raise ParameterError(f"'{path}' is a directory, not a run's file", parameter="path")
    refuse_inputs(path, "path", inputs, kind="run")
    check_columns(list(columns))
    names = list(columns)
    arrays = [np.asarray(columns[c]) for c in names]
    n = {a.shape for a in arrays}
    if len(n) != 1 or arrays[0].ndim != 1:
        raise ParameterError("every column must be a 1-D array of the same length", parameter="columns")
    if not overwrite:
        for existing in (path, sidecar_path(path)):
            if os.path.lexists(existing):
                raise OutputExistsError("path", f"{existing} exists; a run is replaced only when asked to "
                                            "(overwrite=True)")
    try:
        with atomic_run(path) as tmp:
            with RunWriter(tmp, names, metadata, overwrite=True) as w:
                n_rows = arrays[0].shape[0]
                for k in range(0, n_rows, _CHUNK_ROWS):  # the text of a chunk of rows at a time: memory bounded
                    cells = [_format_column(a[k:k + _CHUNK_ROWS]) for a in arrays]
                    w._raw("".join([",".join(row) + "\n" for row in zip(*cells, strict=True)]))
                w.rows = n_rows
    except OSError as exc:  # name the run, not the temporary files
        raise _user_error(exc, path) from None
    return path
