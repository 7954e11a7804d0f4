"""ISO 376 / EURAMET cg-4 quantities of a force-measuring instrument, and the class they reach.

**Beyond the paper.** The paper judges its sensors by eqs. (13) and (39); force metrology judges a
force-proving instrument by the quantities of ISO 376:2011 and estimates its uncertainty with
EURAMET cg-4. This module computes those quantities from a calibration done the ISO 376 way --
series of increasing (and decreasing) forces at several mounting rotations, zero readings, creep
readings -- and the class (00, 0.5, 1, 2) they reach. An FSR is far from class 2; the numbers say
how far, in the metrologist's terms.

Definitions (ISO 376:2011, clause 7.5; X are deflections, i.e. readings minus the zero reading
of their series; X_N the deflection at the largest force; all in percent)::

    b' = |X_2 − X_1| / X̄_wr · 100,   X̄_wr = (X_1 + X_2)/2       relative repeatability (same mounting)
    b  = (X_max − X_min) / X̄_r · 100, X̄_r = mean over rotations   relative reproducibility (rotated mountings)
    fc = (X̄_r − X_a) / X_a · 100                                  relative interpolation error
                                      (X_a from a polynomial of degree 1..3 of X̄_r against force)
    f0 = (i_f − i_0) / X_N · 100                                   relative zero error
                                      (zero reading after, i_f, and before, i_0, a series)
    v  = |X' − X| / X · 100                                        relative reversibility error
                                      (X' decreasing, X increasing, same series; mean over series)
    c  = |i_300 − i_30| / X_N · 100                                relative creep error
                                      (readings 30 s and 300 s after applying the largest force)

Class limits (ISO 376:2011, table of classification criteria), in percent:

    ========  =====  =====  ======  ======  =====  =====
    class     b      b'     fc      f0      v      c
    ========  =====  =====  ======  ======  =====  =====
    00        0.05   0.025  ±0.025  ±0.012  0.07   0.025
    0.5       0.10   0.05   ±0.05   ±0.025  0.15   0.05
    1         0.20   0.10   ±0.10   ±0.050  0.30   0.10
    2         0.40   0.20   ±0.20   ±0.10   0.50   0.20
    ========  =====  =====  ======  ======  =====  =====

An instrument calibrated for increasing forces only is classified with c instead of v.
The guide could not be checked against the normative text here (ISO documents are not freely
available); the definitions and the table follow the 2011 edition as commonly quoted, and the
lower limit of the calibration range (resolution criterion) is not evaluated.

References
----------
ISO 376:2011, "Metallic materials — Calibration of force-proving instruments used for the
verification of uniaxial testing machines".
EURAMET cg-4, version 2.0 (03/2011), "Uncertainty of Force Measurements".
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901 (the quantities it uses instead).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.io.tables import CalibrationSeries
from fsrlab.physics.params import float_array

__all__ = ["CLASS_LIMITS", "CalibrationSeries", "ISO376Result", "iso376", "class_reached"]

#: ISO 376:2011 class limits [%] for b, b', fc (±), f0 (±), v, c; best class first.
CLASS_LIMITS: dict[str, dict[str, float]] = {
    "00": {"b": 0.05, "b_prime": 0.025, "fc": 0.025, "f0": 0.012, "v": 0.07, "c": 0.025},
    "0.5": {"b": 0.10, "b_prime": 0.05, "fc": 0.05, "f0": 0.025, "v": 0.15, "c": 0.05},
    "1": {"b": 0.20, "b_prime": 0.10, "fc": 0.10, "f0": 0.050, "v": 0.30, "c": 0.10},
    "2": {"b": 0.40, "b_prime": 0.20, "fc": 0.20, "f0": 0.10, "v": 0.50, "c": 0.20},
}

_NAMES = {"b": "relative reproducibility b", "b_prime": "relative repeatability b'",
          "fc": "relative interpolation error fc",
          "f0": "relative zero error f0", "v": "relative reversibility v", "c": "relative creep c"}


@dataclass
class ISO376Result:
    """ISO 376 quantities per force and the class reached.

    Parameters
    ----------
    forces_n : ndarray
        Calibration forces. [N]
    b, b_prime, fc, v : ndarray or None
        Per force, in percent; None when the data lack what the quantity needs.
    f0, c : float or None
        Worst zero error over the series, creep error; percent.
    classes : dict
        Best class each available quantity reaches (``"00"``, ``"0.5"``, ``"1"``, ``"2"`` or
        ``"none"``).
    instrument_class : str
        Class of the instrument: the worst over b, b', fc, f0 and v (or c), or ``"none"``, or
        ``"incomplete"`` when a required quantity is missing.
    missing : dict
        Quantity -> what the data lack to compute it.
    notes : list of str
        Where a quantity was computed from less than ISO 376 asks for (e.g. b from 2 rotations).
    """

    forces_n: np.ndarray
    b: np.ndarray | None
    b_prime: np.ndarray | None
    fc: np.ndarray | None
    f0: float | None
    v: np.ndarray | None
    c: float | None
    classes: dict = field(default_factory=dict)
    instrument_class: str = "incomplete"
    missing: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    def worst(self, name: str) -> float | None:
        """Largest magnitude of a quantity over the forces where it is known [%], or None if missing."""
        val = getattr(self, name)
        if val is None:
            return None
        a = np.abs(np.atleast_1d(np.asarray(val, dtype=float)))
        a = a[~np.isnan(a)]
        return float(a.max()) if a.size else None


def class_reached(name: str, value_percent: float) -> str:
    """Best ISO 376 class whose limit for quantity ``name`` holds ``|value_percent|``.

    Parameters
    ----------
    name : {"b", "b_prime", "fc", "f0", "v", "c"}
    value_percent : float
        The quantity. [%]

    Returns
    -------
    str
        ``"00"``, ``"0.5"``, ``"1"``, ``"2"``, or ``"none"`` beyond class 2.
    """
    if not isinstance(name, str) or name not in CLASS_LIMITS["00"]:
        raise ParameterError(f"must be one of {sorted(CLASS_LIMITS['00'])}, got {name!r}", parameter="name")
    value = float_array("value_percent", value_percent)
    if value.ndim:
        raise ParameterError(f"must be a single number, got an array of shape {value.shape}",
                             parameter="value_percent")
    for cls, lim in CLASS_LIMITS.items():
        if abs(value) <= lim[name] + 1e-12:
            return cls
    return "none"


def iso376(forces_n, series: Sequence[CalibrationSeries], creep_readings: tuple[float, float] | None = None,
           interpolation_degree: int = 3) -> ISO376Result:
    """ISO 376:2011 quantities (b, b', fc, f0, v, c) and the class of a force-measuring instrument.

    Parameters
    ----------
    forces_n : array_like
        Calibration forces, increasing, > 0 (ISO 376 asks for at least 8, spread over 20–100 %). [N]
    series : sequence of CalibrationSeries
        In measurement order. b' uses the first two series at the same rotation; b uses the first
        series at each distinct rotation (ISO 376: 0°, 120°, 240°); v uses every series with
        decreasing readings; f0 every series with both zero readings.
    creep_readings : (float, float), optional
        Readings 30 s and 300 s after applying the largest force (deflections or raw readings with
        the same zero). [reading unit]
    interpolation_degree : int
        Degree 1..3 of the interpolation equation for fc.

    Returns
    -------
    ISO376Result

    Raises
    ------
    fsrlab.errors.ParameterError
        Forces not increasing and positive, a series of the wrong length, a bad degree, creep
        readings that are not finite (naming the parameter).
    TypeError
        Forces or creep readings that are not numbers, series that are not CalibrationSeries.

    Notes
    -----
    No numpy warning reaches the caller: a quantity with no value at a force (no decreasing
    reading there) is NaN at that force, and a quantity with no value at any force is missing.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return _iso376(forces_n, series, creep_readings, interpolation_degree)


def _iso376(forces_n, series, creep_readings, interpolation_degree) -> ISO376Result:
    F = float_array("forces_n", forces_n)
    if isinstance(series, (str, bytes, CalibrationSeries)) or not isinstance(series, Sequence) or \
            not all(isinstance(s, CalibrationSeries) for s in series):
        raise TypeError(f"series: must be a sequence of CalibrationSeries (fsrlab.io.tables), got {series!r:.80}")
    if F.ndim != 1 or F.size < 2 or not np.all(np.isfinite(F)) or np.any(F <= 0) or np.any(np.diff(F) <= 0):
        raise ParameterError("must be at least 2 positive, strictly increasing forces [N]", parameter="forces_n")
    if not isinstance(interpolation_degree, (int, np.integer)) or isinstance(interpolation_degree, bool) or \
            interpolation_degree not in (1, 2, 3):
        raise ParameterError("must be 1, 2 or 3 (ISO 376), got "
                f"{interpolation_degree!r}", parameter="interpolation_degree")
    if not series:
        raise ParameterError("at least one calibration series is needed", parameter="series")
    inc, dec = _deflections(F, series)
    missing: dict[str, str] = {}
    notes: list[str] = []
    x_n = float(np.mean([x[-1] for x in inc]))
    if not np.isfinite(x_n):
        raise ParameterError("the readings at the largest force must be finite", parameter="series")
    if x_n == 0:
        raise ParameterError("zero deflection at the largest force", parameter="series")
    b_prime, b, xr = _repeatability(series, inc, missing, notes)
    fc = _interpolation_error(F, xr, interpolation_degree, missing)
    f0 = _zero_error(series, x_n, missing)
    v = _reversibility(inc, dec, missing)
    c = _creep_error(creep_readings, x_n, missing)
    res = ISO376Result(forces_n=F, b=b, b_prime=b_prime, fc=fc, f0=f0, v=v, c=c, missing=missing, notes=notes)
    _classify(res)
    return res


def _deflections(F: np.ndarray, series) -> tuple[list, list]:
    """Increasing deflections of each series and ``(k, decreasing)`` of those that have them, zero subtracted."""
    inc, dec = [], []
    for k, s in enumerate(series):
        x = np.asarray(s.increasing, dtype=float)
        if x.shape != F.shape:
            raise ParameterError(f"series[{k}].increasing: {x.size} readings for {F.size} forces", parameter="series")
        z = 0.0 if s.zero_before is None else float(s.zero_before)
        inc.append(x - z)
        if s.decreasing is not None:
            d = np.asarray(s.decreasing, dtype=float)
            if d.shape != F.shape:
                raise ParameterError(f"series[{k}].decreasing: {d.size} readings for {F.size} forces",
                                     parameter="series")
            dec.append((k, d - z))
    return inc, dec


def _repeatability(series, inc: list, missing: dict, notes: list):
    """b' (first two series in one mounting position), b (first series at each rotation), and the mean
    deflections ``xr`` the interpolation equation goes through."""
    b_prime = None
    rot = [float(s.rotation_deg) % 360 for s in series]
    pair = next(((i, j) for i in range(len(series)) for j in range(i + 1, len(series)) if rot[i] == rot[j]), None)
    if pair is None:
        missing["b_prime"] = "two series in the same mounting position (ISO 376 series 1 and 2, both at 0°)"
    else:
        x1, x2 = inc[pair[0]], inc[pair[1]]
        b_prime = 100 * np.abs(x2 - x1) / ((x1 + x2) / 2)
    firsts = [inc[rot.index(r)] for r in dict.fromkeys(rot)]
    b = None
    if len(firsts) < 2:
        missing["b"] = "series at 2 or more mounting rotations (ISO 376: 0°, 120°, 240°)"
        xr = inc[0] if b_prime is None else (inc[pair[0]] + inc[pair[1]]) / 2
    else:
        arr = np.array(firsts)
        xr = arr.mean(axis=0)
        b = 100 * (arr.max(axis=0) - arr.min(axis=0)) / np.abs(xr)
        if len(firsts) < 3:
            notes.append("b from 2 mounting rotations (ISO 376 asks for 3)")
    return b_prime, b, xr


def _interpolation_error(F, xr, degree: int, missing: dict):
    """fc: the mean deflections against the interpolation equation X_a(F) of ``degree`` through them."""
    if F.size <= degree + 1:
        missing["fc"] = f"more than {degree + 1} forces for a degree-{degree} interpolation equation"
        return None
    coef = np.polynomial.polynomial.polyfit(F, xr, degree)
    xa = np.polynomial.polynomial.polyval(F, coef)
    return 100 * (xr - xa) / xa


def _zero_error(series, x_n: float, missing: dict):
    """f0: the largest change of the zero reading over a series."""
    zs = [(s.zero_after - s.zero_before) for s in series if s.zero_before is not None and s.zero_after is not None]
    if zs:
        return float(100 * max(zs, key=abs) / x_n)
    missing["f0"] = ("zero readings before and after a series (zero_before, zero_after; in a CSV, force_n = 0 rows "
                     "with direction +1 and -1)")
    return None


def _reversibility(inc: list, dec: list, missing: dict):
    """v: decreasing versus increasing readings within the same series, mean over series."""
    v = None
    if dec:
        vs = np.array([100 * np.abs(d - inc[k]) / np.abs(inc[k]) for k, d in dec])
        taken = ~np.isnan(vs)
        if taken.any():
            # Mean over the series with a decreasing reading at each force; NaN where none has one.
            v = np.where(taken.any(axis=0), np.nansum(vs, axis=0) / np.maximum(taken.sum(axis=0), 1), np.nan)
    if v is None:
        missing["v"] = "a series with decreasing forces (ISO 376 series at 120° and 240°)"
    return v


def _creep_error(creep_readings, x_n: float, missing: dict):
    """c: the change between the readings 30 s and 300 s after the largest force was applied."""
    if creep_readings is None:
        missing["c"] = "readings 30 s and 300 s after applying the largest force"
        return None
    readings = float_array("creep_readings", creep_readings)
    if readings.shape != (2,):
        raise ParameterError(f"must be two readings I30,I300, got {creep_readings!r:.80}", parameter="creep_readings")
    i30, i300 = (float(v_) for v_ in readings)
    c = 100 * abs(i300 - i30) / abs(x_n)
    if not np.isfinite(c):
        raise ParameterError(f"must be two finite readings I30,I300 with a finite difference, "
                             f"got {i30:g}, {i300:g}", parameter="creep_readings")
    return c


def _classify(res: ISO376Result) -> None:
    """Each quantity's class and the instrument's (the worst of those ISO 376 requires)."""
    order = list(CLASS_LIMITS) + ["none"]
    for name in ("b", "b_prime", "fc", "f0", "v", "c"):
        w = res.worst(name)
        if w is not None:
            res.classes[name] = class_reached(name, w)
    required = ["b", "b_prime", "fc", "f0"]
    required.append("v" if res.v is not None or res.c is None else "c")
    if all(r in res.classes for r in required):
        res.instrument_class = max((res.classes[r] for r in required), key=order.index)
    else:
        res.instrument_class = "incomplete"
