"""Repeatability errors RE1 and RE2 of grouped readings (paper eq. 39, Tables 4 and 5).

RE1 is the range of a set of repeated readings over its mean, RE2 its standard deviation over its
mean, both in percent. The paper prints eq. (39) with the population standard deviation (divisor
n), but every RE2 printed in its Tables 4 and 5 is reproduced only with the sample standard
deviation (divisor n - 1); fsrlab therefore defaults to ``ddof=1`` and offers ``ddof=0``
(see docs/errata.md, M1). :func:`recompute_printed_table` and :func:`ddof_finding` show it on the
printed tables; :func:`force_repeatability` restates a readout's RE2 in force terms (M2).

References
----------
A. Matute et al., "A Novel and Inexpensive Approach for Force Sensing Based on FSR
Piezocapacitance Aimed at Hysteresis Error Reduction", J. Sensors 2018, 6561901,
doi:10.1155/2018/6561901, eq. (39), Tables 4 and 5.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import float_array

__all__ = [
    "RepeatabilityResult",
    "PRINTED_ROUNDING_PERCENT",
    "PrintedRowCheck",
    "PrintedTableCheck",
    "recompute_printed_table",
    "DdofFinding",
    "ddof_finding",
    "ForceRepeatability",
    "force_repeatability",
    "GroupRepeatability",
    "LoadMean",
    "GroupedRepeatability",
    "repeatability",
    "grouped_repeatability",
]


@dataclass(frozen=True)
class RepeatabilityResult:
    """RE1 and RE2 of one or more sets of repeated readings.

    Parameters
    ----------
    re1_percent : ndarray or float
        ``100 (X_max - X_min) / mean``. [%]
    re2_percent : ndarray or float
        ``100 std / mean`` with the chosen ``ddof``. [%]
    mean : ndarray or float
        Mean of each set. [unit of the readings]
    std : ndarray or float
        Standard deviation of each set. [unit of the readings]
    n : int
        Readings per set.
    ddof : int
        Delta degrees of freedom of ``std`` (0: divisor n as printed in eq. 39; 1: n - 1 as in the tables).
    """

    re1_percent: Any
    re2_percent: Any
    mean: Any
    std: Any
    n: int
    ddof: int


def _check_ddof(ddof: int) -> int:
    if isinstance(ddof, bool) or not isinstance(ddof, (int, np.integer)) or ddof not in (0, 1):
        raise ParameterError(f"must be 0 (divisor n, eq. 39 as printed) or 1 (divisor n - 1), got {ddof!r}",
                             parameter="ddof")
    return int(ddof)


def repeatability(readings, ddof: int = 1) -> RepeatabilityResult:
    """RE1 and RE2 of repeated readings (eq. 39), vectorised over leading axes.

    Parameters
    ----------
    readings : array_like, shape (..., n)
        Repeated readings of the same load; the last axis is the repetition. [any unit]
    ddof : {1, 0}
        1 (default): sample standard deviation, divisor n - 1, which reproduces every RE2 in the
        paper's Tables 4 and 5; 0: divisor n, eq. (39) as printed.

    Returns
    -------
    RepeatabilityResult

    Raises
    ------
    ValueError
        If ``ddof`` is not 0 or 1, fewer than ``ddof + 1`` (and at least 2) readings are given,
        a reading is not finite, or a set's mean is zero.

    Notes
    -----
    Eq. (39)::

        RE1 = 100 % (X_max - X_min) / X_mean
        RE2 = 100 % sqrt(sum (X - X_mean)^2 / (n - ddof)) / X_mean

    The paper's text says RE2 is "the ratio between the standard deviation of the set and its
    mean"; its printed formula divides by n, its tables by n - 1 (docs/errata.md, M1).

    References
    ----------
    Matute et al. 2018, doi:10.1155/2018/6561901, eq. (39).

    Examples
    --------
    The paper's Table 5, 200 g, sensor 1 (printed: RE1 22 %, RE2 9 %):

    >>> r = repeatability([0.277, 0.248, 0.225, 0.225, 0.233])
    >>> print(f"RE1 {r.re1_percent:.2f} %, RE2 {r.re2_percent:.2f} %")
    RE1 21.52 %, RE2 9.07 %
    """
    ddof = _check_ddof(ddof)
    x = float_array("readings", readings)
    if x.ndim == 0 or x.shape[-1] < 2:
        raise ParameterError("must hold at least 2 repeated readings along the last axis", parameter="readings")
    if not np.all(np.isfinite(x)):
        raise ParameterError("must be finite numbers", parameter="readings")
    mean = x.mean(axis=-1)
    if np.any(mean == 0):
        raise ParameterError("a set has zero mean; RE1 and RE2 are relative to the mean", parameter="readings")
    std = x.std(axis=-1, ddof=ddof)
    re1 = 100.0 * (x.max(axis=-1) - x.min(axis=-1)) / np.abs(mean)  # Eq. (39), RE1
    re2 = 100.0 * std / np.abs(mean)  # Eq. (39), RE2
    return RepeatabilityResult(re1_percent=re1, re2_percent=re2, mean=mean, std=std, n=x.shape[-1], ddof=ddof)


#: A recomputed value matches a printed one when it rounds to it: Tables 4 and 5 print integers. [%]
PRINTED_ROUNDING_PERCENT = 0.5


@dataclass(frozen=True)
class PrintedRowCheck:
    """One printed row of Table 4 or 5 (a sensor, or a load's "Average errors") beside its recomputation.

    Parameters
    ----------
    load : str or float
        Load label, e.g. ``"200g"``.
    sensor : int or None
        Sensor number; None for the row of means.
    readings : tuple of float or None
        The printed readings of a sensor row; None for the row of means. [unit of the readings]
    re1_printed, re2_printed : float
        RE1 and RE2 as printed. [%]
    re1 : float
        RE1 recomputed from the printed readings (eq. 39). [%]
    re2_n_minus_1 : float
        RE2 with the sample standard deviation (divisor n − 1). [%]
    re2_n : float
        RE2 with divisor n, as eq. (39) is printed. [%]
    """

    load: Any
    sensor: Any
    readings: tuple | None
    re1_printed: float
    re1: float
    re2_printed: float
    re2_n_minus_1: float
    re2_n: float

    @property
    def re1_match(self) -> bool:
        """RE1 rounds to the printed value (within :data:`PRINTED_ROUNDING_PERCENT`)."""
        return bool(abs(self.re1 - self.re1_printed) <= PRINTED_ROUNDING_PERCENT)

    @property
    def re2_n_minus_1_match(self) -> bool:
        """RE2 with divisor n − 1 rounds to the printed value."""
        return bool(abs(self.re2_n_minus_1 - self.re2_printed) <= PRINTED_ROUNDING_PERCENT)

    @property
    def re2_n_match(self) -> bool:
        """RE2 with divisor n rounds to the printed value."""
        return bool(abs(self.re2_n - self.re2_printed) <= PRINTED_ROUNDING_PERCENT)

    def to_dict(self) -> dict:
        """Values and matches; ``sensor`` and ``readings`` only for a sensor row (the report's JSON shape)."""
        head = {"load": self.load}
        if self.sensor is not None:
            head.update(sensor=self.sensor, readings=list(self.readings))
        return {**head, "re1_printed": self.re1_printed, "re1": self.re1, "re2_printed": self.re2_printed,
                "re2_n_minus_1": self.re2_n_minus_1, "re2_n": self.re2_n, "re1_match": self.re1_match,
                "re2_n_minus_1_match": self.re2_n_minus_1_match, "re2_n_match": self.re2_n_match}


@dataclass(frozen=True)
class PrintedTableCheck:
    """A printed repeatability table (Table 4 or 5) recomputed from its own readings.

    Parameters
    ----------
    rows : tuple of PrintedRowCheck
        One per (load, sensor), loads in the order given.
    means : tuple of PrintedRowCheck
        One per load: the mean of the unrounded sensor values against the printed "Average errors".
    """

    rows: tuple
    means: tuple

    def to_dict(self) -> dict:
        """``rows`` and ``means`` as lists of dicts (see :meth:`PrintedRowCheck.to_dict`)."""
        return {"rows": [r.to_dict() for r in self.rows], "means": [m.to_dict() for m in self.means]}


def recompute_printed_table(printed: Mapping) -> PrintedTableCheck:
    """Recompute RE1, RE2 (n − 1) and RE2 (n) for every sensor and load of a printed table.

    Parameters
    ----------
    printed : mapping
        Load label → ``{"readings": [[...], ...], "RE1_percent": [...], "RE2_percent": [...],
        "mean_RE1": ..., "mean_RE2": ...}``, one readings row per sensor, as the paper's Tables 4
        and 5 are transcribed in ``fsrlab/data/paper.json``. Entries that are not mappings (a
        ``"note"``) are skipped. [%, readings in any unit]

    Returns
    -------
    PrintedTableCheck

    Notes
    -----
    Eq. (39) on each sensor's readings; the mean rows average the four unrounded sensor values, as
    the paper's "Average errors". Printed values are integers, so a recomputed one matches when it
    lies within 0.5 of it (docs/errata.md, M1).
    """
    if not isinstance(printed, Mapping):
        raise TypeError(f"printed: must be a mapping of load label to a printed table, got {type(printed).__name__}")
    rows, means = [], []
    for load, t in printed.items():
        if not isinstance(t, Mapping):
            continue
        missing = [k for k in ("readings", "RE1_percent", "RE2_percent", "mean_RE1", "mean_RE2") if k not in t]
        if missing:
            raise ParameterError(f"table {load!r} lacks {', '.join(missing)}", parameter="printed")
        r1 = repeatability(t["readings"], ddof=1)
        r0 = repeatability(t["readings"], ddof=0)
        for i, readings in enumerate(t["readings"]):
            rows.append(PrintedRowCheck(load, i + 1, tuple(readings), t["RE1_percent"][i], float(r1.re1_percent[i]),
                                        t["RE2_percent"][i], float(r1.re2_percent[i]), float(r0.re2_percent[i])))
        means.append(PrintedRowCheck(load, None, None, t["mean_RE1"], float(np.mean(r1.re1_percent)), t["mean_RE2"],
                                     float(np.mean(r1.re2_percent)), float(np.mean(r0.re2_percent))))
    return PrintedTableCheck(rows=tuple(rows), means=tuple(means))


@dataclass(frozen=True)
class DdofFinding:
    """How many printed values each divisor of RE2 reproduces (docs/errata.md, M1).

    Parameters
    ----------
    rows : int
        Printed rows compared (sensors and means).
    re2_match_n_minus_1 : int
        RE2 values reproduced with divisor n − 1.
    re2_match_n : int
        RE2 values reproduced with divisor n (eq. 39 as printed).
    re1_match : int
        RE1 values reproduced.
    """

    rows: int
    re2_match_n_minus_1: int
    re2_match_n: int
    re1_match: int

    def to_dict(self) -> dict:
        """The four counts by name."""
        return {"rows": self.rows, "re2_match_n_minus_1": self.re2_match_n_minus_1,
                "re2_match_n": self.re2_match_n, "re1_match": self.re1_match}


def ddof_finding(tables: Sequence[PrintedTableCheck]) -> DdofFinding:
    """Count the printed RE1 and RE2 values each divisor reproduces over several recomputed tables.

    Parameters
    ----------
    tables : sequence of PrintedTableCheck
        E.g. Tables 4 and 5 from :func:`recompute_printed_table`.

    Returns
    -------
    DdofFinding
    """
    if isinstance(tables, (str, bytes)) or not isinstance(tables, Sequence) or \
            not all(isinstance(t, PrintedTableCheck) for t in tables):
        raise TypeError("tables: must be a sequence of PrintedTableCheck (recompute_printed_table), "
                        f"got {tables!r:.80}")
    entries = [r for t in tables for r in t.rows + t.means]
    return DdofFinding(rows=len(entries), re2_match_n_minus_1=sum(r.re2_n_minus_1_match for r in entries),
                       re2_match_n=sum(r.re2_n_match for r in entries), re1_match=sum(r.re1_match for r in entries))


@dataclass(frozen=True)
class ForceRepeatability:
    """Repeatability of a readout expressed in force terms, from readings at two loads.

    Parameters
    ----------
    elasticity : ndarray
        ``d ln X / d ln F`` of each sensor between the two loads. [1]
    re2_readout_percent : dict
        Load label → RE2 of each sensor in readout terms (eq. 39). [%]
    """

    elasticity: np.ndarray
    re2_readout_percent: dict

    @property
    def re2_force_percent(self) -> dict:
        """Load label → RE2 of each sensor in force terms, ``RE2_X / (d ln X / d ln F)``. [%]"""
        return {load: v / self.elasticity for load, v in self.re2_readout_percent.items()}

    def to_dict(self) -> dict:
        """``elasticity`` per sensor and the mean over sensors of RE2 per load, in readout and force terms."""
        return {"elasticity": self.elasticity.tolist(),
                "re2_readout_mean": {k: float(np.mean(v)) for k, v in self.re2_readout_percent.items()},
                "re2_force_mean": {k: float(np.mean(v)) for k, v in self.re2_force_percent.items()}}


def force_repeatability(readings: Mapping, forces: Mapping, ddof: int = 1) -> ForceRepeatability:
    """RE2 of a readout converted into force terms through its sensitivity between two loads.

    Parameters
    ----------
    readings : mapping
        Two load labels → readings of shape (sensors, n), the same sensors at both loads, e.g. the
        200 g and 400 g rows of the paper's Table 4 or 5. [any unit]
    forces : mapping
        The same two labels → the load each stands for; only their ratio matters. [any unit]
    ddof : {1, 0}
        See :func:`repeatability`.

    Returns
    -------
    ForceRepeatability

    Raises
    ------
    ValueError
        If there are not exactly two loads, the labels of ``readings`` and ``forces`` differ, the two
        forces are equal or not positive, or the sensors differ in number.

    Notes
    -----
    A relative spread of a reading X is a relative spread of force only after dividing by the
    readout's sensitivity ``d ln X / d ln F``, estimated here as a power law through the two loads'
    mean readings: ``ln(X̄_2/X̄_1)/ln(F_2/F_1)``. A two-point estimate, an approximation; an extension
    beyond the paper, which compares RE in percent of each readout (docs/errata.md, M2).
    """
    for name, value in (("readings", readings), ("forces", forces)):
        if not isinstance(value, Mapping):
            raise TypeError(f"{name}: must be a mapping of two load labels, got {type(value).__name__}")
    if len(readings) != 2:
        raise ParameterError(f"must hold two loads, got {list(readings)}", parameter="readings")
    for load, force in forces.items():
        if isinstance(force, bool) or not isinstance(force, (int, float, np.number)):
            raise TypeError(f"forces: the load of {load!r} must be a number, got {type(force).__name__}")
    if set(readings) != set(forces):
        raise ParameterError(f"must have the same two load labels as readings, got {list(forces)} "
                             f"and {list(readings)}", parameter="forces")
    lo, hi = sorted(readings, key=lambda k: forces[k])
    if not 0 < forces[lo] < forces[hi]:
        raise ParameterError(f"must be two different positive loads, got {dict(forces)!r}", parameter="forces")
    r = {load: repeatability(readings[load], ddof=ddof) for load in (lo, hi)}
    if np.shape(r[lo].mean) != np.shape(r[hi].mean):
        raise ParameterError("both loads must hold the same sensors", parameter="readings")
    e = np.log(r[hi].mean / r[lo].mean) / np.log(forces[hi] / forces[lo])  # d ln X / d ln F
    return ForceRepeatability(elasticity=e, re2_readout_percent={load: r[load].re2_percent for load in (lo, hi)})


@dataclass(frozen=True)
class GroupRepeatability:
    """RE1/RE2 of one (load, sensor) group.

    Parameters
    ----------
    load, sensor : str or float
        Group labels as given.
    re1_percent, re2_percent : float
        Eq. (39). [%]
    mean : float
        Mean reading. [unit of the readings]
    n : int
        Number of readings.
    """

    load: Any
    sensor: Any
    re1_percent: float
    re2_percent: float
    mean: float
    n: int


@dataclass(frozen=True)
class LoadMean:
    """Mean of the groups' RE1 and RE2 at one load (the tables' "Average errors" rows).

    Parameters
    ----------
    load : str or float
        Load label.
    re1_percent, re2_percent : float
        Arithmetic mean over the sensors of that load of the unrounded RE1, RE2. [%]
    sensors : int
        Number of sensors averaged.
    """

    load: Any
    re1_percent: float
    re2_percent: float
    sensors: int


@dataclass(frozen=True)
class GroupedRepeatability:
    """Result of :func:`grouped_repeatability`.

    Parameters
    ----------
    groups : list of GroupRepeatability
        One entry per (load, sensor), in order of first appearance.
    means : list of LoadMean
        One entry per load.
    ddof : int
        As in :func:`repeatability`.
    """

    groups: list[GroupRepeatability]
    means: list[LoadMean]
    ddof: int

    def to_dict(self) -> dict:
        """The CLI's JSON shape: ``groups`` and ``means`` lists."""
        return {
            "groups": [{"load": g.load, "sensor": g.sensor, "re1_percent": g.re1_percent,
                        "re2_percent": g.re2_percent} for g in self.groups],
            "means": [{"load": m.load, "re1_percent": m.re1_percent, "re2_percent": m.re2_percent}
                      for m in self.means],
        }


def grouped_repeatability(load: Sequence, sensor: Sequence, reading, ddof: int = 1) -> GroupedRepeatability:
    """RE1/RE2 per (load, sensor) group and their mean per load, as in Tables 4 and 5.

    Parameters
    ----------
    load : sequence
        Load label of each reading (e.g. ``"200g"`` or 1.962 [N]).
    sensor : sequence
        Sensor label of each reading.
    reading : array_like
        The readings. [any unit]
    ddof : {1, 0}
        See :func:`repeatability`.

    Returns
    -------
    GroupedRepeatability

    Raises
    ------
    ValueError
        If the three sequences differ in length, or a group has fewer than 2 readings.
    """
    ddof = _check_ddof(ddof)
    x = float_array("reading", reading)
    if x.ndim != 1:
        raise ParameterError(f"must be a 1-D array, got shape {x.shape}", parameter="reading")
    for name, labels in (("load", load), ("sensor", sensor)):
        if isinstance(labels, (str, bytes, dict)) or not isinstance(labels, Sequence | np.ndarray):
            raise TypeError(f"{name}: must be a sequence of labels, one per reading, got {type(labels).__name__}")
        if len(labels) != x.size:
            raise ParameterError(f"must hold one label per reading ({x.size}), got {len(labels)}", parameter=name)
    load, sensor = list(load), list(sensor)
    order: dict[tuple, list[int]] = {}
    for i, key in enumerate(zip(load, sensor, strict=True)):
        order.setdefault(key, []).append(i)
    groups = []
    for (ld, sn), idx in order.items():
        if len(idx) < 2:
            raise ParameterError(f"group load={ld!r} sensor={sn!r} has {len(idx)} reading; at least 2 are needed",
                                 parameter="reading")
        try:
            r = repeatability(x[idx], ddof=ddof)
        except ParameterError as exc:  # the group it is about, not only "a set"
            raise ParameterError(f"group load={ld!r} sensor={sn!r}: {exc.reason}", parameter="reading") from None
        groups.append(GroupRepeatability(ld, sn, float(r.re1_percent), float(r.re2_percent), float(r.mean), len(idx)))
    means = []
    for ld in dict.fromkeys(g.load for g in groups):
        gs = [g for g in groups if g.load == ld]
        means.append(LoadMean(ld, float(np.mean([g.re1_percent for g in gs])),
                              float(np.mean([g.re2_percent for g in gs])), len(gs)))
    return GroupedRepeatability(groups=groups, means=means, ddof=ddof)
