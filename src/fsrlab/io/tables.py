"""Readers of the small CSV tables that are not runs: grouped repeatability readings, ISO 376 series.

Reading files is kept apart from the computations that use the tables
(:mod:`fsrlab.metrics.repeatability`, :mod:`fsrlab.metrics.iso376`); the CSV dialect and the
one-line error messages (file, row, column) are those of :mod:`fsrlab.io.runformat`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fsrlab.errors import FileFormatError
from fsrlab.io.runcells import OTHER_LIMIT
from fsrlab.io.runformat import read_table, where
from fsrlab.io.shown import number_cell, shown

__all__ = ["CalibrationSeries", "load_grouped_csv", "load_iso376_csv"]


@dataclass(frozen=True)
class CalibrationSeries:
    """One ISO 376 measurement series.

    Parameters
    ----------
    rotation_deg : float
        Mounting rotation of the instrument in the machine (0, 120, 240 ...). [°]
    increasing : array_like
        Readings at the calibration forces, increasing. [reading unit]
    decreasing : array_like, optional
        Readings at the same forces on the way down (NaN where not taken). [reading unit]
    zero_before, zero_after : float, optional
        Zero readings before the series and after its force is removed. [reading unit]
    """

    rotation_deg: float
    increasing: Sequence[float]
    decreasing: Sequence[float] | None = None
    zero_before: float | None = None
    zero_after: float | None = None


def _label(cell: str) -> Any:
    try:
        v = number_cell(cell)
    except ValueError:
        return cell
    return int(v) if v.is_integer() else v


def _check_number(p, k: int, column: str, value: float, cell: str, low: float = -OTHER_LIMIT) -> None:
    """A cell must hold a finite number within what a reading can be (not 1e308)."""
    if not np.isfinite(value):
        raise FileFormatError(f"{where(p, k, column)}: {cell.strip()!r} is not a finite number")
    if not low <= value <= OTHER_LIMIT:
        raise FileFormatError(f"{where(p, k, column)}: {value:g} is beyond what the column can hold "
                         f"({low:g} to {OTHER_LIMIT:g})")


def load_grouped_csv(path: str | os.PathLike) -> tuple[list, list, np.ndarray]:
    """Read a CSV with columns ``load,sensor,reading`` (any order, other columns ignored).

    Parameters
    ----------
    path : str or path-like
        The file. ``load`` and ``sensor`` are labels (numbers or text); ``reading`` is numeric.

    Returns
    -------
    load, sensor : list
        Labels (numbers when the cell is numeric).
    reading : ndarray
        The readings.

    Raises
    ------
    FileFormatError
        One line naming the file, the row and the column for a missing column, an empty,
        non-numeric or non-finite reading, or one beyond what a reading can be (above 1e100).
    """
    ix, rows, p = read_table(path, ("load", "sensor", "reading"), hint="header load,sensor,reading needed")
    il, isn, ir = ix["load"], ix["sensor"], ix["reading"]
    loads, sensors, values = [], [], []
    for k, row in rows:
        for name, j in (("load", il), ("sensor", isn), ("reading", ir)):
            if j >= len(row) or not row[j].strip():
                raise FileFormatError(f"{where(p, k, name)}: empty cell")
        try:
            v = number_cell(row[ir].strip())
        except ValueError:
            raise FileFormatError(f"{where(p, k, 'reading')}: non-numeric cell {shown(row[ir].strip())}") from None
        _check_number(p, k, "reading", v, row[ir])
        loads.append(_label(row[il].strip()))
        sensors.append(_label(row[isn].strip()))
        values.append(v)
    if not values:
        raise FileFormatError(f"{p}: no readings")
    return loads, sensors, np.array(values)


def load_iso376_csv(path) -> tuple[np.ndarray, list[CalibrationSeries]]:
    """Read ISO 376 calibration readings from a long CSV.

    Columns: ``series`` (label), ``rotation_deg`` [°], ``force_n`` [N], ``reading``, and optional
    ``direction`` (+1 increasing, default; -1 decreasing). A row with ``force_n`` = 0 is a zero
    reading: direction +1 is the zero before the series, -1 the zero after it.

    Parameters
    ----------
    path : str or path-like
        The CSV file.

    Returns
    -------
    forces_n : ndarray
        The calibration forces (those of the first series). [N]
    series : list of CalibrationSeries
        In order of first appearance.

    Raises
    ------
    FileFormatError
        One line naming the file, row and column for a missing column, an empty, non-numeric or
        non-finite cell, a value beyond what a reading can be (magnitude above 1e100), a negative
        force, a second reading at the same force and direction of a series, a series whose
        rotation changes; or naming the series whose forces differ from the first series'.
    """
    ix, rows, p = read_table(path, ("series", "rotation_deg", "force_n", "reading"))
    data: dict[str, dict] = {}
    for k, row in rows:
        vals = _iso376_numbers(p, k, row, ix)
        label = row[ix["series"]].strip() if ix["series"] < len(row) else ""
        if not label:
            raise FileFormatError(f"{where(p, k, 'series')}: empty cell")
        _iso376_place(p, k, data, label, vals)
    return _iso376_series(p, data)


def _iso376_numbers(p, k: int, row: list, ix: dict) -> dict:
    """The numbers of one row of an ISO 376 table (``direction`` +1 when empty), each checked."""
    vals = {}
    for col in ("rotation_deg", "force_n", "reading", "direction"):
        if col not in ix:
            continue
        cell = row[ix[col]].strip() if ix[col] < len(row) else ""
        if not cell and col == "direction":
            vals[col] = 1.0
            continue
        if not cell:
            raise FileFormatError(f"{where(p, k, col)}: empty cell")
        try:
            vals[col] = number_cell(cell)
        except ValueError:
            raise FileFormatError(f"{where(p, k, col)}: non-numeric cell {shown(cell)}") from None
        _check_number(p, k, col, vals[col], cell, 0.0 if col == "force_n" else -OTHER_LIMIT)
    if vals.get("direction", 1.0) not in (1.0, -1.0):
        raise FileFormatError(f"{where(p, k, 'direction')}: must be +1 or -1, got {vals['direction']:g}")
    return vals


def _iso376_place(p, k: int, data: dict, label: str, vals: dict) -> None:
    """One reading into its series of ``data``: its zero before or after, or its increasing or decreasing force."""
    d = vals.get("direction", 1.0)
    s = data.setdefault(label, {"rot": vals["rotation_deg"], "inc": {}, "dec": {}, "z0": None, "z1": None})
    if vals["rotation_deg"] != s["rot"]:
        raise FileFormatError(f"{where(p, k, 'rotation_deg')}: series {label!r} was at {s['rot']:g}°, "
                              f"not {vals['rotation_deg']:g}°")
    if vals["force_n"] == 0:
        key = "z0" if d > 0 else "z1"
        if s[key] is not None:
            raise FileFormatError(f"{where(p, k, 'force_n')}: series {label!r} already has its zero reading "
                                  f"{'before' if d > 0 else 'after'} the forces")
        s[key] = vals["reading"]
        return
    branch = s["inc" if d > 0 else "dec"]
    if vals["force_n"] in branch:
        raise FileFormatError(f"{where(p, k, 'force_n')}: series {label!r} already has a reading at "
                              f"{vals['force_n']:g} N ({'increasing' if d > 0 else 'decreasing'})")
    branch[vals["force_n"]] = vals["reading"]


def _iso376_series(p, data: dict) -> tuple[np.ndarray, list[CalibrationSeries]]:
    """The forces of the first series and every series at them (all must share them)."""
    if not data:
        raise FileFormatError(f"{p}: no readings")
    first = next(iter(data.values()))
    forces = np.array(sorted(first["inc"]))
    if forces.size < 2:
        raise FileFormatError(f"{p}: series {next(iter(data))!r} has {forces.size} increasing force(s) above 0 N; "
                              "ISO 376 needs at least 2 (8 or more, spread over 20–100 % of the range)")
    series = []
    for label, s in data.items():
        if sorted(s["inc"]) != forces.tolist():
            raise FileFormatError(f"{p}: series {label!r} has increasing forces {sorted(s['inc'])}, not those of "
                                  f"the first series {forces.tolist()}")
        dec = [s["dec"].get(f, np.nan) for f in forces] if s["dec"] else None
        series.append(CalibrationSeries(s["rot"], [s["inc"][f] for f in forces], dec, s["z0"], s["z1"]))
    return forces, series
