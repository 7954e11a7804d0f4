"""Repeatability errors RE1 and RE2 of grouped readings (paper eq. 39, Tables 4 and 5).

RE1 is the range of a set of repeated readings over its mean, RE2 its standard deviation over its
mean, both in percent. The paper prints eq. (39) with the population standard deviation (divisor
n), but every RE2 printed in its Tables 4 and 5 is reproduced only with the sample standard
deviation (divisor n - 1); fsrlab therefore defaults to ``ddof=1`` and offers ``ddof=0``
(see docs/errata.md, M1).

References
----------
A. Matute et al., "A Novel and Inexpensive Approach for Force Sensing Based on FSR
Piezocapacitance Aimed at Hysteresis Error Reduction", J. Sensors 2018, 6561901,
doi:10.1155/2018/6561901, eq. (39), Tables 4 and 5.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

__all__ = [
    "RepeatabilityResult",
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
    if ddof not in (0, 1):
        raise ValueError(f"ddof must be 0 (divisor n, eq. 39 as printed) or 1 (divisor n - 1), got {ddof!r}")
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
    """
    ddof = _check_ddof(ddof)
    x = np.asarray(readings, dtype=float)
    if x.ndim == 0 or x.shape[-1] < 2:
        raise ValueError("readings must hold at least 2 repeated readings along the last axis")
    if not np.all(np.isfinite(x)):
        raise ValueError("readings must be finite numbers")
    mean = x.mean(axis=-1)
    if np.any(mean == 0):
        raise ValueError("readings: a set has zero mean; RE1 and RE2 are relative to the mean")
    std = x.std(axis=-1, ddof=ddof)
    re1 = 100.0 * (x.max(axis=-1) - x.min(axis=-1)) / np.abs(mean)  # Eq. (39), RE1
    re2 = 100.0 * std / np.abs(mean)  # Eq. (39), RE2
    return RepeatabilityResult(re1_percent=re1, re2_percent=re2, mean=mean, std=std, n=x.shape[-1], ddof=ddof)


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
    x = np.asarray(reading, dtype=float)
    load, sensor = list(load), list(sensor)
    if not (len(load) == len(sensor) == x.shape[0]) or x.ndim != 1:
        raise ValueError("load, sensor and reading must be 1-D and of the same length")
    order: dict[tuple, list[int]] = {}
    for i, key in enumerate(zip(load, sensor)):
        order.setdefault(key, []).append(i)
    groups = []
    for (ld, sn), idx in order.items():
        if len(idx) < 2:
            raise ValueError(f"reading: group load={ld!r} sensor={sn!r} has {len(idx)} reading; at least 2 are needed")
        r = repeatability(x[idx], ddof=ddof)
        groups.append(GroupRepeatability(ld, sn, float(r.re1_percent), float(r.re2_percent), float(r.mean), len(idx)))
    means = []
    for ld in dict.fromkeys(g.load for g in groups):
        gs = [g for g in groups if g.load == ld]
        means.append(LoadMean(ld, float(np.mean([g.re1_percent for g in gs])),
                              float(np.mean([g.re2_percent for g in gs])), len(gs)))
    return GroupedRepeatability(groups=groups, means=means, ddof=ddof)
