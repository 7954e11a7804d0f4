"""Foreign CSV files made into runs: which column is which, their units, two files aligned, the run written.

:func:`import_foreign` reads one file, or two (a sensor file and a reference file from another
logger), with :func:`fsrlab.io.foreign_read.read_table`; finds or takes the time, readout and force
columns; converts them (time to seconds, force to newtons with the standard gravity of
:mod:`fsrlab.units`); aligns the reference on the sensor's time stamps (:func:`interpolate_reference`)
and returns the columns ``time_s`` [s], ``reading`` [its own unit] and ``force_n`` [N] with the
sidecar describing where they came from; :func:`write_imported` writes them through
:func:`fsrlab.io.runwriter.write_run`. Every problem in a file is a :class:`ForeignFormatError` of
one line naming the file, the line (1-based, as a text editor shows it) and the column.
(docs/data-format.md, "Foreign files")
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from datetime import time as clock_time
from pathlib import Path

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.io.foreign_read import ForeignFormatError, Table, is_number, read_table
from fsrlab.io.runcells import COLUMN_LIMITS, OTHER_LIMIT
from fsrlab.io.shown import shown
from fsrlab.units import STANDARD_GRAVITY

__all__ = ["TIME_UNITS", "FORCE_UNITS", "READING_UNITS", "ForeignFormatError", "Table", "read_table",
           "interpolate_reference", "Imported", "import_foreign", "write_imported"]

#: A time column's unit as (times, divided by) to seconds: one correctly rounded operation per cell
#: (50 ms -> 50 / 1000 s). [s]
_TIME = {"s": (1.0, 1.0), "ms": (1.0, 1e3), "us": (1.0, 1e6), "min": (60.0, 1.0), "h": (3600.0, 1.0)}
#: Seconds per unit of a time column. [s]
TIME_UNITS = {k: m / d for k, (m, d) in _TIME.items()}
#: The international pound (0.45359237 kg exactly, 1959 agreement; NIST SP 811 B.8). [kg]
_POUND_KG = 0.45359237
#: The avoirdupois ounce, 1/16 of the international pound (0.028349523125 kg exactly; NIST SP 811 B.8). [kg]
_OUNCE_KG = _POUND_KG / 16
#: Newtons per unit of a force column, as (times, divided by): one rounding for g and mN. Gram-, kilogram-,
#: pound- and ounce-force through the standard gravity g0 = 9.80665 m/s² (CGPM 1901).
_FORCE = {"N": (1.0, 1.0), "kN": (1e3, 1.0), "mN": (1.0, 1e3), "g": (STANDARD_GRAVITY, 1e3),
          "kg": (STANDARD_GRAVITY, 1.0), "lbf": (_POUND_KG * STANDARD_GRAVITY, 1.0),
          "ozf": (_OUNCE_KG * STANDARD_GRAVITY, 1.0)}
FORCE_UNITS = {k: m / d for k, (m, d) in _FORCE.items()}
#: Readout units kept as they are: option spelling -> unit written to the sidecar.
READING_UNITS = {"counts": "count", "V": "V", "mV": "mV", "ohm": "Ω", "kohm": "kΩ"}

# Other spellings of the units above (lower case). A mass unit in a force column (g, kg, lb, oz) is the force
# standard gravity gives that mass: what a scale or a load cell calibrated with weights shows, and the only
# force such a logger can mean; so ``oz`` is ounce-force and ``lb`` pound-force, as ``g`` is gram-force.
_ALIASES = {
    "time": {"sec": "s", "secs": "s", "second": "s", "seconds": "s", "msec": "ms", "millis": "ms",
             "millisecond": "ms", "milliseconds": "ms", "µs": "us", "μs": "us", "usec": "us", "micros": "us",
             "microsecond": "us", "microseconds": "us", "mins": "min", "minute": "min", "minutes": "min",
             "hr": "h", "hrs": "h", "hour": "h", "hours": "h"},
    "force": {"n": "N", "newton": "N", "newtons": "N", "kn": "kN", "kilonewton": "kN", "kilonewtons": "kN",
              "millinewton": "mN", "millinewtons": "mN", "gf": "g", "gram": "g", "grams": "g", "kgf": "kg",
              "kilogram": "kg", "kilograms": "kg", "kp": "kg", "lb": "lbf", "lbs": "lbf", "oz": "ozf"},
    "reading": {"count": "counts", "ω": "ohm", "ohms": "ohm", "kω": "kohm", "kohms": "kohm"},
}
_TABLES = {"time": TIME_UNITS, "force": FORCE_UNITS, "reading": READING_UNITS}
# Spellings whose case is the unit: MN is meganewton, not mN.
_CASE_MATTERS = {"MN": "meganewtons"}


def _canonical(text: str, kind: str) -> str | None:
    """The canonical spelling of ``text`` as a unit of ``kind`` (time, force, reading), or None."""
    if text in _CASE_MATTERS:
        return None
    table = _TABLES[kind]
    if text in table:
        return text
    lower = text.lower()
    return next((k for k in table if k.lower() == lower), None) or _ALIASES[kind].get(lower)


# What a run can hold in these columns ("reading" is not listed in COLUMN_LIMITS and gets its
# OTHER_LIMIT): a cell beyond is refused here, where its line is known.
_LIMITS = {"time_s": COLUMN_LIMITS["time_s"][1], "reading": OTHER_LIMIT, "force_n": COLUMN_LIMITS["force_n"][1]}


def _unit(value: str | None, kind: str, parameter: str) -> str | None:
    """The canonical spelling of a unit of ``kind`` given as a parameter (case-insensitive, a few aliases)."""
    if value is None:
        return None
    if not isinstance(value, str):
        raise ParameterError(f"must be a unit's name (one of {', '.join(_TABLES[kind])}), got {type(value).__name__}",
                             parameter=parameter)
    key = _canonical(value.strip(), kind)
    if key is None:
        raise ParameterError(f"{shown(value.strip())} is not one of {', '.join(_TABLES[kind])}", parameter=parameter)
    return key


# ------------------------------------------------------------------------------------------------
# Which column is which
# ------------------------------------------------------------------------------------------------

_WORDS = {
    "time": ({"time", "timestamp", "elapsed", "millis", "micros", "datetime", "date", "clock", "ms", "us", "µs",
              "μs", "msec", "usec"}, {"s", "sec", "secs", "seconds", "t"}),
    "force": ({"force", "load", "loadcell", "weight", "mass", "reference", "ref", "hx711", "newton", "newtons",
               "gram", "grams", "lbf", "lbs", "kgf", "gf", "kilograms", "ozf"},
               {"n", "g", "kg", "mn", "lb", "f", "kn", "oz"}),
    "reading": ({"fsr", "analog", "analogread", "adc", "reading", "raw", "sensor", "counts", "voltage", "volts",
                 "resistance", "value", "val", "velostat", "pressure", "a0", "a1", "a2", "a3", "a4", "a5", "a6", "a7"},
                {"v", "mv", "ohm", "ohms", "kohm", "ω", "kω"}),
}
_INDEX_NAMES = {"n", "i", "index", "sample", "no", "nr", "row", "idx", "#", "id"}
_UNIT_WORDS = {
    "time": [("us", {"us", "µs", "μs", "micros", "usec", "microseconds"}),
             ("ms", {"ms", "millis", "msec", "milliseconds"}),
             ("s", {"s", "sec", "secs", "seconds"}), ("min", {"minutes"}), ("h", {"hours"})],
    "force": [("mN", {"mn"}), ("kN", {"kn"}), ("kg", {"kg", "kgf", "kilograms"}), ("lbf", {"lbf", "lb", "lbs"}),
              ("ozf", {"oz", "ozf"}), ("g", {"g", "gf", "gram", "grams"}), ("N", {"n", "newton", "newtons"})],
    "reading": [("mV", {"mv"}), ("kohm", {"kohm", "kω", "kohms"}), ("ohm", {"ohm", "ohms", "ω", "resistance"}),
                ("V", {"v", "volts", "voltage"}), ("counts", {"counts", "count", "adc", "analog", "analogread"})],
}
# Units of other quantities, or of these quantities that fsrlab does not convert: stated in a header's last word
# (``force_stone``), they are that column's unit, refused rather than taken as N or s.
_OTHER_UNITS = {"st", "stone", "stones", "dyn", "dyne", "dynes", "kip", "kips", "pdl", "poundal", "ton", "tons",
                "tonne", "tonnes", "mg", "ug", "µg", "lbm", "psi", "pa", "kpa", "mpa", "bar", "mbar", "ns", "ps",
                "day", "days", "wk", "week", "weeks", "ua", "ma", "µa", "a", "uv", "µv", "hz", "khz", "pf", "nf",
                "uf", "µf", "mohm", "mω"}
# Words in brackets that say something else than a unit: "time (UTC)", "A0 (raw)".
_NOT_UNITS = {"utc", "gmt", "local", "unix", "epoch", "iso", "raw", "avg", "mean", "filtered", "smoothed", "ref"}
_BRACKETED = re.compile(r"[(\[{]\s*([^()\[\]{}]*?)\s*[)\]}]\s*$")
_LAST_WORD = re.compile(r"(?:^|[\s_/.-])([^\s_/.()\[\]{}-]+)\s*$")
_UNIT_LIKE = re.compile(r"^[A-Za-zµμΩω°]{1,8}[23²³]?(?:/[A-Za-zµμ]{1,3})?$")


def _is_unit_word(text: str) -> bool:
    return (any(_canonical(text, kind) for kind in _TABLES) or text.lower() in _OTHER_UNITS
            or text in _CASE_MATTERS)


def _said_unit(table: Table, j: int) -> tuple[str, str] | None:
    """The unit a column's units row or header states, and where it says it; None if neither states one.

    A header states its unit in brackets at its end (``force (kN)``, ``t [ms]``) or as its last word when
    that word is a unit (``force_kN``, ``time/min``, ``millis``)."""
    where = f"{table.path}: line {table.header_line} (header), {table.label(j)}"
    unit = table.units_row[j].strip() if j < len(table.units_row) else ""
    if unit:
        inner = _BRACKETED.fullmatch(unit) or re.fullmatch(r"[(\[{]\s*(.*?)\s*[)\]}]", unit)
        return (inner.group(1) if inner else unit), f"{where}: the units row under it"
    name = table.names[j].strip() if j < len(table.names) else ""
    m = _BRACKETED.search(name)
    if m and m.group(1):
        return m.group(1), where
    m = _LAST_WORD.search(name)
    if m and _is_unit_word(m.group(1)):
        return m.group(1), where
    return None


def _unit_from_header(table: Table, j: int, role: str) -> str | None:
    """The unit of column ``j`` for ``role`` (time, force, reading) its header or units row says; None when they
    say none. A unit stated that is not one of the role's is refused, naming the file, the column and the unit."""
    said = _said_unit(table, j)
    if said is not None:
        text, where = said
        unit = _canonical(text, role)
        if unit is not None:
            return unit
        if (_UNIT_LIKE.match(text) or _is_unit_word(text)) and text.lower() not in _NOT_UNITS | _WORDS[role][0]:
            known = ", ".join(_TABLES[role])
            raise ForeignFormatError(f"{where}: unit {shown(text)} is not a {role} unit fsrlab converts ({known}); "
                                     f"it is refused rather than taken as {_DEFAULT_UNITS[role]}: give the column's "
                                     "unit", role=f"{role}_unit")
    name = table.names[j] if j < len(table.names) else ""
    unit = table.units_row[j] if j < len(table.units_row) else ""
    words = _tokens(f"{name} {unit}")
    return next((u for u, spellings in _UNIT_WORDS[role] if words & spellings), None)


_DEFAULT_UNITS = {"time": "s", "force": "N", "reading": "counts"}


def _tokens(text: str) -> set[str]:
    spaced = re.sub(r"([a-z]{2,})([A-Z])", r"\1 \2", text).lower()  # sensorValue, forceN; not mV, kOhm
    return set(re.findall(r"[a-zµμω]+", spaced)) | set(re.findall(r"[a-z]+\d+", spaced))


def _score(table: Table, j: int, role: str) -> int:
    """How strongly column ``j``'s header (and units row) says ``role``: 2 per strong word, 1 per weak."""
    name = table.names[j] if j < len(table.names) else ""
    if _is_index(table, j):
        return 0
    if role == "time" and name.strip().lower() == "t":  # "t" alone; "t" among other words is weak
        return 2
    unit = table.units_row[j] if j < len(table.units_row) else ""
    words = _tokens(f"{name} {unit}")
    strong, weak = _WORDS[role]
    return 2 * len(words & strong) + len(words & weak)


def _is_index(table: Table, j: int) -> bool:
    """A sample counter ("n", "index", "#"): never taken for a role unless given."""
    return j < len(table.names) and table.names[j].strip().lower() in _INDEX_NAMES


def _resolve(table: Table, spec: str | int, what: str) -> int:
    """The 0-based index of the column given by header name or 1-based number."""
    text = str(spec).strip()
    if text and text in table.names:  # header names are unique (read_table)
        return table.names.index(text)
    folded = [n.lower() for n in table.names]
    if text and folded.count(text.lower()) == 1:
        return folded.index(text.lower())
    if text.isdigit() and 1 <= int(text) <= table.n_columns:
        return int(text) - 1
    where = f"line {table.header_line} (header)" if table.header_line else f"line {table.lines[0]}"
    listing = ", ".join(f"{j + 1} {n!r}" if n else str(j + 1) for j, n in
                        enumerate(table.names + [""] * (table.n_columns - len(table.names))))
    raise ForeignFormatError(f"{table.path}: {where}: no column {text!r} for the {what} "
                             f"(give a header name or a number 1..{table.n_columns}; columns: {listing})",
                             role=what.replace(" ", "_"))


def _increasing_column(table: Table, j: int) -> bool:
    try:
        t = table.numbers(j, "a time")
    except ForeignFormatError:
        return False
    return t.size > 1 and bool(np.all(np.diff(t) > 0))


def _choose(table: Table, roles: Sequence[str], given: dict[str, str | int | None]) -> dict[str, tuple[int, str]]:
    """Column of each role: (index, how it was chosen); a role not found is left out."""
    out: dict[str, tuple[int, str]] = {}
    for role in roles:
        if given.get(role) is not None:
            j = _resolve(table, given[role], role.replace("_", " "))
            clash = next((r for r, (k, _) in out.items() if k == j), None)
            if clash:
                raise ForeignFormatError(f"{table.path}: {table.label(j)} is given as both the "
                        f"{clash.replace('_', ' ')} "
                                         f"and the {role.replace('_', ' ')}", role=role)
            out[role] = (j, "given")
    taken = {j for j, _ in out.values()}
    if table.header_line is None:
        return _choose_headless(table, roles, out, taken)
    for role in roles:
        if role in out:
            continue
        kind = role.removeprefix("reference_")
        scores = {j: _score(table, j, kind) for j in range(table.n_columns)
                  if j not in taken and not _is_index(table, j)}
        top = max(scores.values(), default=0)
        best = [j for j, s in scores.items() if s == top]
        if top >= 2 and len(best) == 1:
            out[role] = (best[0], f"found: the header says {table.names[best[0]]!r}")
        elif top >= 2:
            raise ForeignFormatError(f"{table.path}: line {table.header_line} (header): "
                                     f"{' and '.join(table.label(j) for j in best)} could each be the "
                                     f"{kind}; say which", role=role)
        elif kind == "reading" and len(scores) == 1:
            # Never the force: in a reference file, the one column left may be anything (a temperature).
            j = next(iter(scores))
            out[role] = (j, "found: the only column left")
        else:
            continue
        taken.add(out[role][0])
    return out


def _choose_headless(table: Table, roles, out, taken) -> dict[str, tuple[int, str]]:
    """Without a header: one column is the value; two are time and value when the first increases."""
    free = [j for j in range(table.n_columns) if j not in taken]
    value = "reading" if "reading" in roles else "force"
    time_role = next((r for r in roles if r.endswith("time")), None)
    if value in out and time_role in out:
        return out
    if value not in out and len(free) == 1:
        out[value] = (free[0], "found: the only column (no header)")
    elif (value not in out and time_role and time_role not in out and len(free) == 2
          and _increasing_column(table, free[0])):
        out[time_role] = (free[0], "found: the first column increases (no header)")
        out[value] = (free[1], "found: the second column (no header)")
    elif value not in out:
        raise ForeignFormatError(f"{table.path}: line {table.lines[0]}: no header and {len(free)} columns: "
                                 f"say which column (1..{table.n_columns}) is the {value}", role=value)
    return out


# ------------------------------------------------------------------------------------------------
# Cells to numbers
# ------------------------------------------------------------------------------------------------

def _values(table: Table, j: int, factor: tuple[float, float], column: str, unit: str) -> np.ndarray:
    """A value column in its run unit; an empty cell is missing (NaN)."""
    cells = table.numbers(j, f"a number in {unit}")
    out = cells * factor[0] / factor[1]
    limit = _LIMITS[column]
    with np.errstate(invalid="ignore"):
        beyond = np.flatnonzero(np.abs(out) > limit)
    if beyond.size:
        i = int(beyond[0])
        raise ForeignFormatError(f"{table.where(i, j)}: {table.cell(i, j)} {unit} is beyond what a run's {column} can "
                                 f"hold (±{limit:g}; docs/data-format.md)")
    return out


def _clock(text: str) -> float | None:
    """Seconds of an ISO date-time (UTC when it has no zone) or of a time of day; None if neither."""
    try:
        stamp = datetime.fromisoformat(text)
    except ValueError:
        try:
            t = clock_time.fromisoformat(text)
        except ValueError:
            return None
        return t.hour * 3600 + t.minute * 60 + t.second + t.microsecond * 1e-6
    if stamp.tzinfo is None:
        stamp = stamp.replace(tzinfo=UTC)
    return stamp.timestamp()


def _is_clock(table: Table, j: int) -> bool:
    """Whether a time column holds date-times or times of day (its first cell is one, not a number)."""
    first = table.cell(0, j)
    return bool(first) and not is_number(first) and _clock(first) is not None


def _clock_times(table: Table, j: int) -> np.ndarray:
    texts = table.texts(j)
    t = np.empty(len(texts))
    for i, text in enumerate(texts):
        if not text:
            raise ForeignFormatError(f"{table.where(i, j)}: empty cell, expected a time (every row needs one)")
        stamp = None if is_number(text) else _clock(text)
        if stamp is None:
            raise ForeignFormatError(f"{table.where(i, j)}: {shown(text)} is not a date-time or time of day "
                                     f"like the column's first ({shown(texts[0])})")
        t[i] = stamp
    return t


def _times(table: Table, j: int, unit: str) -> tuple[np.ndarray, str]:
    """Time [s] of every row, strictly increasing: numbers in ``unit``, or date-times; and their kind."""
    if _is_clock(table, j):
        t, said = _clock_times(table, j), "date-time"
    else:
        cells = table.numbers(j, f"a time in {unit}")
        empty = np.flatnonzero(np.isnan(cells))
        if empty.size:
            raise ForeignFormatError(f"{table.where(int(empty[0]), j)}: empty cell, expected a time (every row "
                                     "needs one)")
        m, d = _TIME[unit]
        t, said = cells * m / d, unit
        beyond = np.flatnonzero(np.abs(t) > _LIMITS["time_s"])
        if beyond.size:
            i = int(beyond[0])
            raise ForeignFormatError(f"{table.where(i, j)}: {table.cell(i, j)} {unit} is beyond what a run's time_s "
                                     "can hold")
    back = np.flatnonzero(~(np.diff(t) > 0))
    if back.size:
        i = int(back[0]) + 1
        raise ForeignFormatError(f"{table.where(i, j)}: time does not increase ({shown(table.cell(i, j))} after "
                                 f"{shown(table.cell(i - 1, j))} on line {table.lines[i - 1]}); rows must be in "
                                 "time order, each at its own time")
    return t, said


def interpolate_reference(t: np.ndarray, t_ref: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Reference values at the times ``t``, linear between neighbouring reference samples.

    Parameters
    ----------
    t : array_like
        Times at which the reference is wanted. [s]
    t_ref : array_like
        The reference's times, strictly increasing. [s]
    values : array_like
        The reference's values at ``t_ref`` (NaN: missing).

    Returns
    -------
    ndarray
        Same shape as ``t``: NaN outside ``[t_ref[0], t_ref[-1]]`` (no extrapolation) and between
        two samples of which one is missing; at a reference sample's own time, its value.
    """
    from fsrlab.physics.params import float_array, paired_series

    t = float_array("t", t)
    t_ref, values = paired_series("t_ref", t_ref, "values", values)
    out = np.full(t.shape, np.nan)
    if t_ref.size == 0:
        return out
    if t_ref.size == 1:
        return np.where(t == t_ref[0], values[0], np.nan)
    inside = (t >= t_ref[0]) & (t <= t_ref[-1])
    k = np.clip(np.searchsorted(t_ref, t, side="right") - 1, 0, t_ref.size - 2)
    w = (t - t_ref[k]) / (t_ref[k + 1] - t_ref[k])
    with np.errstate(invalid="ignore"):
        linear = values[k] + w * (values[k + 1] - values[k])
    # At a sample's own time the neighbour does not matter (it may be missing).
    linear = np.where(w == 0, values[k], np.where(w == 1, values[k + 1], linear))
    out[inside] = linear[inside]
    return out


# ------------------------------------------------------------------------------------------------
# The import
# ------------------------------------------------------------------------------------------------

@dataclass
class Imported:
    """A foreign file (or two) as the columns of a run.

    Parameters
    ----------
    columns : dict of str to ndarray
        ``time_s`` [s] (absent when neither a time column nor a rate was there), ``reading`` [its
        unit], ``force_n`` [N] (absent when no force was found or given).
    units : dict of str to str
        Unit of each column.
    mapping : dict
        Per role (``time``, ``reading``, ``force``, ``reference_time``): ``file``, ``column`` (header
        name or ""), ``index`` (1-based), ``unit`` and ``how`` (``given``, ``found: ...``), or for a
        time from a rate ``rate_hz``.
    sources : list of dict
        How each file was read (:meth:`Table.describe`), sensor first.
    rows : int
        Rows of the run (the sensor file's data rows).
    matched : int or None
        Rows with a reference force from the reference file (None: one file).
    rate_hz : float or None
        The sample rate given, or the median rate of the time stamps. [Hz]
    offset_s : float
        Added to the reference's times. [s]
    notes : list of str
        What was assumed (a unit the header does not say).
    """

    columns: dict[str, np.ndarray]
    units: dict[str, str]
    mapping: dict[str, dict]
    sources: list[dict]
    rows: int
    matched: int | None
    rate_hz: float | None
    offset_s: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def metadata(self) -> dict:
        """The run's sidecar: units, origin (the source files) and ``import`` (mapping, rate, counts)."""
        files = [s["file"] for s in self.sources]
        origin = f"fsrlab import: {files[0]}" + (f", reference {files[1]}" if len(files) > 1 else "")
        return {"units": dict(self.units), "origin": origin,
                "import": {"sources": self.sources, "mapping": self.mapping, "rate_hz": self.rate_hz,
                           "offset_s": self.offset_s, "rows": self.rows, "matched": self.matched,
                           "notes": self.notes}}


def _entry(table: Table, role: str, j: int, how: str, unit: str) -> dict:
    name = table.names[j] if j < len(table.names) else ""
    return {"file": str(table.path), "column": name, "index": j + 1, "unit": unit, "how": how}


def _time_of(table: Table, role: str, chosen: dict, unit: str | None, rate_hz: float | None, notes: list,
             mapping: dict) -> np.ndarray | None:
    if role in chosen and rate_hz is not None:
        raise ParameterError(f"{table.path} has a time column ({table.label(chosen[role][0])}); give either the "
                             "column or a rate",
                             parameter=f"{'reference_' if role.startswith('reference') else ''}rate_hz")
    if rate_hz is not None:
        mapping[role] = {"file": str(table.path), "rate_hz": rate_hz, "how": "given"}
        return np.arange(table.n_rows) / rate_hz
    if role not in chosen:
        return None
    j, how = chosen[role]
    if unit is None and not _is_clock(table, j):
        unit = _unit_from_header(table, j, "time")
        if unit is None:
            unit = "s"
            notes.append(f"{table.path}: {table.label(j)} taken in s (its header does not say)")
    t, said = _times(table, j, unit)
    mapping[role] = _entry(table, role, j, how, said)
    return t


def _median_rate(t: np.ndarray | None) -> float | None:
    if t is None or t.size < 2:
        return None
    return float(1.0 / np.median(np.diff(t)))


def import_foreign(sensor: str | os.PathLike, reference: str | os.PathLike | None = None, *,
                   time: str | int | None = None, time_unit: str | None = None, rate_hz: float | None = None,
                   reading: str | int | None = None, reading_unit: str | None = None,
                   force: str | int | None = None, force_unit: str | None = None,
                   reference_time: str | int | None = None, reference_time_unit: str | None = None,
                   reference_rate_hz: float | None = None, offset_s: float = 0.0,
                   header: bool | None = None, skip_lines: int = 0) -> Imported:
    """Turn a foreign CSV file (and a reference file) into the columns and sidecar of a run.

    Parameters
    ----------
    sensor : str or path-like
        The sensor's file: the readout, and the force when there is no reference file.
    reference : str or path-like, optional
        A second file with the reference force, from another logger; aligned on the time stamps.
    time, reading, force, reference_time : str or int, optional
        Columns by header name or 1-based number; None: found from the header (``time``, ``ms``,
        ``millis``; ``fsr``, ``analog``, ``adc``, ``reading``; ``force``, ``load``, ``N``, ``g``...).
        ``force`` is in the reference file when there is one.
    time_unit, reference_time_unit : {'s', 'ms', 'us', 'min', 'h'}, optional
        Unit of a numeric time column (default: what its header or units row says, else s; a unit stated
        there that is not one of these is refused).
    rate_hz, reference_rate_hz : float, optional
        Sample rate of a file without a time column: row k is at k / rate. [Hz]
    reading_unit : {'counts', 'V', 'mV', 'ohm', 'kohm'}, optional
        Unit of the readout, kept as it is (default: what its header says, else counts).
    force_unit : {'N', 'kN', 'mN', 'g', 'kg', 'lbf', 'ozf'}, optional
        Unit of the force column, converted to N with g0 = 9.80665 m/s² (default: what its header or
        units row says, else N; a unit stated there that is not one of these is refused). Also spelled
        gf, kgf, lb and oz: a mass unit in a force column is the weight of that mass under standard
        gravity, what a scale or a load cell calibrated with weights shows.
    offset_s : float
        Added to the reference's times before alignment. [s]
    header : bool, optional
        Whether each file's first line is a header (None: guessed, see :func:`read_table`).
    skip_lines : int
        Lines left out at the top of each file. [lines]

    Returns
    -------
    Imported

    Raises
    ------
    ParameterError
        A parameter out of its range or of the wrong type (``.parameter`` names it);
        :class:`ForeignFormatError` for a file's problem (file, line, column), and for a unit its header
        states that is not one of the role's.
    """
    from fsrlab.io.runformat import input_file

    input_file(sensor, "sensor")
    if reference is not None:
        input_file(reference, "reference")
    units = {"time_unit": (time_unit, "time"), "reference_time_unit": (reference_time_unit, "time"),
             "reading_unit": (reading_unit, "reading"), "force_unit": (force_unit, "force")}
    time_unit, reference_time_unit, reading_unit, force_unit = (_unit(v, t, k) for k, (v, t) in units.items())
    for name, rate in (("rate_hz", rate_hz), ("reference_rate_hz", reference_rate_hz)):
        if rate is not None and not _number(rate, name) > 0:
            raise ParameterError(f"must be > 0 Hz, got {rate:g}", parameter=name)
    if reference is None and (reference_time is not None or reference_rate_hz is not None):
        raise ParameterError("given without a reference file",
                             parameter="reference_time" if reference_time is not None else "reference_rate_hz")
    if not abs(_number(offset_s, "offset_s")) <= _LIMITS["time_s"]:
        raise ParameterError(f"must be a time within ±{_LIMITS['time_s']:g} s (what a run's time_s holds), got "
                             f"{offset_s!r}", parameter="offset_s")
    if reference is not None and _same_file(Path(sensor), Path(reference)):
        raise ParameterError(f"{reference} is the sensor's file itself; give the file the reference force was "
                             "logged in", parameter="reference")
    notes: list[str] = []
    mapping: dict[str, dict] = {}
    sens = _read(sensor, "sensor", header, skip_lines)
    ref = _read(reference, "reference", header, skip_lines) if reference is not None else None
    # A rate given means the rows are evenly spaced: no time column is looked for.
    roles = ((("time",) if time is not None or rate_hz is None else ())
             + (("force",) if ref is None else ()) + ("reading",))
    given = {"time": time, "reading": reading, "force": force if ref is None else None}
    try:
        chosen = _choose(sens, roles, given)
    except ForeignFormatError as exc:  # the column the call named, else the file
        raise _named(exc, exc.role if given.get(exc.role) is not None else "sensor") from None
    if "reading" not in chosen:
        raise ForeignFormatError(f"{sens.path}: no readout column found ({_header_text(sens)}); say which column is "
                                 "the reading", role="reading", parameter="sensor")
    if ref is not None and "time" not in chosen and rate_hz is None:
        raise ForeignFormatError(f"{sens.path}: no time column found ({_header_text(sens)}); two files are aligned "
                                 "on their times: say which column is the time, or give the sample rate", role="time",
                                 parameter="sensor")
    sens.prefetch(j for j, _ in chosen.values())  # one pass of numpy's parser for the columns used
    t = _time_of(sens, "time", chosen, time_unit, rate_hz, notes, mapping)
    columns: dict[str, np.ndarray] = {}
    out_units: dict[str, str] = {}
    if t is not None:
        columns["time_s"], out_units["time_s"] = t, "s"
    j, how = chosen["reading"]
    unit = reading_unit or _unit_from_header(sens, j, "reading") or "counts"
    columns["reading"], out_units["reading"] = _values(sens, j, (1.0, 1.0), "reading", unit), READING_UNITS[unit]
    mapping["reading"] = _entry(sens, "reading", j, how, unit)
    matched = None
    if ref is None:
        if "force" in chosen:
            columns["force_n"] = _force(sens, chosen["force"], force_unit, notes, mapping)
    else:
        try:
            columns["force_n"] = _reference_force(ref, sens, t, reference_time, reference_time_unit,
                                                  reference_rate_hz, force, force_unit, offset_s, notes, mapping)
        except ForeignFormatError as exc:  # the column the call named, else the file
            named = {"reference_time": reference_time, "force": force}
            raise _named(exc, exc.role if named.get(exc.role) is not None else "reference") from None
        matched = int(np.isfinite(columns["force_n"]).sum())
    if "force_n" in columns:
        out_units["force_n"] = "N"
    sources = [sens.describe()] + ([ref.describe()] if ref is not None else [])
    return Imported(columns=columns, units=out_units, mapping=mapping, sources=sources, rows=sens.n_rows,
                    matched=matched, rate_hz=rate_hz if rate_hz is not None else _median_rate(t),
                    offset_s=float(offset_s), notes=notes)


def _named(exc: ForeignFormatError, parameter: str) -> ForeignFormatError:
    """``exc`` naming ``parameter`` (the file it is about) when it names none."""
    return exc if exc.parameter is not None else ForeignFormatError(exc.reason, exc.role, parameter)


def _read(path, parameter: str, header, skip_lines) -> Table:
    """:func:`read_table`, its file's errors naming ``parameter`` (sensor or reference)."""
    try:
        return read_table(path, header, skip_lines)
    except ForeignFormatError as exc:
        if exc.parameter not in (None, "path"):
            raise
        raise ForeignFormatError(exc.reason, exc.role, parameter) from None


def _number(value, parameter: str) -> float:
    """``value`` as a float; a string or another type is refused naming the parameter."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"must be a number, got {type(value).__name__} {value!r}", parameter=parameter)
    if not np.isfinite(value):
        raise ParameterError(f"must be finite, got {value!r}", parameter=parameter)
    return float(value)


def _reference_force(ref: Table, sens: Table, t: np.ndarray, reference_time, reference_time_unit,
                     reference_rate_hz, force, force_unit, offset_s: float, notes: list, mapping: dict) -> np.ndarray:
    """The reference file's force [N] at the sensor's times ``t``: its time and force columns found or given,
    its times shifted by ``offset_s``, linear between its samples."""
    rroles = (("reference_time",) if reference_time is not None or reference_rate_hz is None else ()) + ("force",)
    rchosen = _choose(ref, rroles, {"reference_time": reference_time, "force": force})
    if "reference_time" not in rchosen and reference_rate_hz is None:
        raise ForeignFormatError(f"{ref.path}: no time column found ({_header_text(ref)}); say which column is "
                                 "the reference's time, or give its sample rate", role="reference_time")
    if "force" not in rchosen:
        raise ForeignFormatError(f"{ref.path}: no force column found ({_header_text(ref)}); say which column "
                                 "is the force", role="force")
    t_ref = _time_of(ref, "reference_time", rchosen, reference_time_unit, reference_rate_hz, notes, mapping)
    f_ref = _force(ref, rchosen["force"], force_unit, notes, mapping)
    shifted = t_ref + offset_s
    if shifted.size > 1 and not np.all(np.diff(shifted) > 0):
        raise ParameterError(f"{offset_s:g} s added to {ref.path}'s times makes two of them equal (a float's "
                             "resolution); give an offset of the size of the clocks' difference", parameter="offset_s")
    force_n = interpolate_reference(t, shifted, f_ref)
    if not np.isfinite(interpolate_reference(t, shifted, np.zeros_like(t_ref))).any():
        raise ForeignFormatError(f"{ref.path}: no time in common with {sens.path} (sensor {t[0]:.6g} … "
                                 f"{t[-1]:.6g} s, reference {shifted[0]:.6g} … {shifted[-1]:.6g} s "
                                 f"with the offset of {offset_s:g} s): the two clocks differ; shift the reference "
                                 "by an offset", role="offset")
    return force_n


def _header_text(table: Table) -> str:
    if table.header_line is None:
        return f"no header, {table.n_columns} columns"
    return f"header on line {table.header_line}: {', '.join(repr(n) for n in table.names)}"


def _force(table: Table, choice: tuple[int, str], unit: str | None, notes: list, mapping: dict) -> np.ndarray:
    j, how = choice
    if unit is None:
        unit = _unit_from_header(table, j, "force")
        if unit is None:
            unit = "N"
            notes.append(f"{table.path}: {table.label(j)} taken in N (its header does not say)")
    mapping["force"] = _entry(table, "force", j, how, unit)
    return _values(table, j, _FORCE[unit], "force_n", unit)


def write_imported(imported: Imported, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Write an import as a run (``NAME.csv`` and ``NAME.meta.json``) with :func:`fsrlab.io.runwriter.write_run`.

    Parameters
    ----------
    imported : Imported
        From :func:`import_foreign`.
    path : str or path-like
        The run's CSV file.
    overwrite : bool
        Replace an existing run; never one of the source files.

    Returns
    -------
    Path

    Raises
    ------
    OutputError
        An empty ``path``, or a run or sidecar that would replace a source file or its sidecar (the output
        policy, :mod:`fsrlab.io.outputs`; ``.parameter`` is ``"path"``).
    fsrlab.io.outputs.OutputExistsError
        The run exists and ``overwrite`` is False (a FileExistsError and a ParameterError naming ``path``).
    """
    from fsrlab.io.runwriter import write_run

    if not isinstance(imported, Imported):
        raise TypeError(f"imported: must be an Imported (import_foreign), got {type(imported).__name__}")
    return write_run(path, imported.columns, imported.metadata, overwrite=overwrite,
                     inputs=[source["file"] for source in imported.sources])


def _same_file(a: Path, b: Path) -> bool:
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()

