"""A monotone static calibration curve that extrapolates sanely.

**Extension beyond the paper.** The force of an FSR rises with its conductance, so the curve from
readout to force is monotone; a polynomial fitted to it is not, and between and beyond the readings it
can bend back or shoot off. Here the curve is piecewise linear in a readout variable ``v``
(:func:`readout_variable`: the readout oriented to rise with force, a divider's conductance ratio, a
resistance's reciprocal, or the logarithm, in which a power law's bend is spread evenly over decades)
with knots at quantiles of the calibration readings and non-negative slopes (bounded least squares, a
ridge term on the change of slope between segments). Below the calibrated readings the curve is flat (an
FSR below its activation force reads as no load); above them it continues linearly **per unit of
readout** (a conductance that grows without bound near a divider's rail is not followed), with the mean
slope over the top half of the readings' range (:data:`TOP_SLOPE_SPAN`), not its last segment's.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.physics.params import check_positive, float_array

__all__ = ["VARIABLES", "TOP_SLOPE_SPAN", "adc_full_scale", "readout_variable", "StaticCurve", "MonotoneCurve",
           "bounded_solve", "CurveSystem", "curve_system"]

#: The readout variables a curve can be fitted in. [1]
VARIABLES = ("readout", "conductance", "reciprocal", "log")
#: Beyond the top of its readings a curve continues with its mean slope over this top fraction of the
#: readings' range, per unit of readout (docs/calibration.md). [1]
TOP_SLOPE_SPAN = 0.5
#: ADC full scales recognised in integer readings (10, 12, 16 bits). [1]
_ADC = (1023.0, 4095.0, 65535.0)


def adc_full_scale(x) -> float | None:
    """The full scale of an ADC whose counts ``x`` are (integers in 0..1023, 0..4095 or 0..65535), else None.

    Parameters
    ----------
    x : array_like
        Readings (NaN ignored).
    """
    x = float_array("x", x)
    x = x[np.isfinite(x)]
    if x.size == 0 or x.min() < 0 or not np.all(x == np.round(x)):
        return None
    return next((a for a in _ADC if x.max() <= a), None)


def check_sign(sign) -> None:
    """Raise an error naming ``sign`` unless it is +1 or −1 (whether the readout rises with force)."""
    if isinstance(sign, bool) or not isinstance(sign, (int, float, np.number)) or sign not in (1, -1):
        raise ParameterError(f"must be 1 (the readout rises with force) or -1, got {sign!r}", parameter="sign")


def readout_variable(x, name: str, sign: int, adc: float | None) -> np.ndarray:
    """The curve's variable ``v`` of readings ``x`` (rising with force).

    Parameters
    ----------
    x : array_like
        Readings.
    name : {"readout", "conductance", "reciprocal", "log"}
        ``sign·x``, the divider conductance ratio (needs ``adc``), ``−sign/x`` (a resistance's
        conductance) or ``sign·ln x`` (the last two for readings above zero; ones at or below it are
        taken as the smallest positive float).
    sign : {1, -1}
        +1 when the readout rises with force.
    adc : float or None
        Full scale of the readout: an ADC's largest count, or a divider's supply for its voltage. [unit
        of the readout]
    """
    x = float_array("x", x)
    check_sign(sign)
    if adc is not None and adc is not False:  # None (or False): no full scale
        check_positive("adc", adc, scalar=True)
    if name == "readout":
        return sign * x
    if name == "conductance" and adc:
        eps = adc / 2046.0  # half a count of a 10-bit ADC off each rail: the ratio stays finite
        c = np.clip(x, eps, adc - eps)
        return c / (adc - c) if sign > 0 else (adc - c) / c
    if name == "log":
        return sign * np.log(np.maximum(x, np.finfo(float).tiny))
    if name == "reciprocal":
        return -sign / np.maximum(x, np.finfo(float).tiny)

    raise ParameterError(f"must be one of {', '.join(VARIABLES)} (conductance only for ADC counts), got {name!r}",
                         parameter="name")


def _basis(v: np.ndarray, knots: np.ndarray, extra: int = 0) -> np.ndarray:
    """Columns of the monotone piecewise-linear basis: each segment's share of v (the last unbounded).

    Column-major, with ``extra`` columns left empty after them for the caller to fill."""
    k = knots.size - 1
    out = np.empty((v.size, k + extra), order="F")
    for i in range(k):
        col = out[:, i]
        np.subtract(v, knots[i], out=col)
        np.maximum(col, 0.0, out=col)
        if i < k - 1:
            np.minimum(col, knots[i + 1] - knots[i], out=col)
    return out


def bounded_solve(gram: np.ndarray, atb: np.ndarray, n: int, lower: np.ndarray,
                  penalty: np.ndarray | None = None) -> np.ndarray:
    """Least squares ``a·c ≈ y`` with ``c ≥ lower`` and a ridge ``‖penalty·c‖²``, from its normal equations.

    Columns are scaled to unit root mean square first; the normal equations keep the memory to the
    number of columns squared, whatever the number of readings.

    Parameters
    ----------
    gram : ndarray, shape (k, k)
        ``aᵀa``.
    atb : ndarray, shape (k,)
        ``aᵀy``.
    n : int
        Rows of ``a``. [1]
    lower : ndarray, shape (k,)
        Lower bound of each coefficient (``-inf``: free).
    penalty : ndarray, shape (m, k), optional
        Ridge rows.
    """
    from scipy.optimize import lsq_linear

    scale = np.sqrt(np.diag(gram) / n)
    scale[~(scale > 0)] = 1.0
    ata = gram / np.outer(scale, scale)
    atb = atb / scale
    if penalty is not None and penalty.size:
        p_s = penalty / scale
        ata = ata + p_s.T @ p_s
    k = ata.shape[0]
    ata = ata + 1e-12 * np.trace(ata) / k * np.eye(k)
    chol = np.linalg.cholesky(ata)
    rhs = np.linalg.solve(chol, atb)
    free = np.linalg.solve(chol.T, rhs) / scale
    if np.all(free >= lower):  # no bound reached: the least-squares solution is the bounded one (convex)
        return free
    res = lsq_linear(chol.T, rhs, bounds=(lower * scale, np.inf), method="bvls")
    return res.x / scale


class StaticCurve:
    """What every static curve shares: the readout variable, and the rule beyond the calibrated readings.

    A curve is linear in its coefficients ``coef``: ``coef[0]`` plus the columns of :meth:`columns`
    (of the readout variable ``v``) times the others. Below the calibrated readings it is flat; above them
    it continues linearly per unit of readout with its mean slope over the top half of the readings'
    range (:data:`TOP_SLOPE_SPAN`). A subclass gives :meth:`_at_v` (the curve inside, at ``v``),
    :meth:`columns`, :meth:`lower_bounds`, :attr:`name`, :attr:`monotone` and the file form.
    """

    variable: str
    sign: int
    adc: float | None
    coef: np.ndarray
    x_range: tuple[float, float]
    #: Whether every curve of the family is non-decreasing in force (checked by :meth:`is_monotone` otherwise).
    monotone: bool = True

    def _at_v(self, v: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def columns(self, v: np.ndarray) -> np.ndarray:
        """The family's columns at ``v`` (after the constant): the curve is ``coef[0] + columns(v) @ coef[1:]``."""
        raise NotImplementedError

    def lower_bounds(self) -> np.ndarray:
        """Lower bound of each coefficient in a fit (``-inf``: free)."""
        raise NotImplementedError

    def penalty(self, columns: int, lam: float, n: int) -> np.ndarray:
        """Ridge rows of a fit with ``columns`` columns in all on ``n`` readings (none by default)."""
        return np.zeros((0, columns))

    def with_coef(self, coef) -> StaticCurve:
        """The same curve (variable, basis, range) with other coefficients."""
        raise NotImplementedError

    #: The family (:data:`fsrlab.calibration.curves.FAMILIES`) and its size (segments, degree, inner knots). [1]
    family: str = ""
    size: int = 0

    @property
    def name(self) -> str:
        raise NotImplementedError

    def _inside(self, x: np.ndarray) -> np.ndarray:
        """The curve at readings ``x`` (finite) clipped to the range it was fitted on."""
        lo, hi = self.x_range
        return self._at_v(readout_variable(np.clip(x, lo, hi), self.variable, self.sign, self.adc))

    @cached_property
    def _top(self) -> tuple[float, float]:
        """(The reading at the top of the range, the slope beyond it per unit of readout): the curve's
        mean slope over the top half of the readings' range (:data:`TOP_SLOPE_SPAN`), in readout units."""
        lo, hi = self.x_range
        top = hi if self.sign > 0 else lo
        if not hi > lo:
            return top, 0.0
        start = top - self.sign * TOP_SLOPE_SPAN * (hi - lo)
        f_start, f_top = self._inside(np.array([start, top]))
        return top, max(float(f_top - f_start), 0.0) / (TOP_SLOPE_SPAN * (hi - lo))

    @cached_property
    def rest(self) -> float:
        """The curve's value at the low-force end of its readings: the reference at rest as the curve
        sees it (0 for a tared load cell; another value when it was not tared). [unit of the reference]"""
        lo, hi = self.x_range
        return float(self._inside(np.array([lo if self.sign > 0 else hi]))[0])

    def is_monotone(self) -> bool:
        """Whether the curve never falls as force rises over its calibrated readings."""
        return True

    def _one(self, xc: float) -> float:
        """The curve at one reading within the calibrated range."""
        return float(self._inside(np.array([xc]))[0])

    def at(self, x: float) -> float:
        """The curve at one finite reading ``x``: :meth:`__call__` one reading at a time (a live stream's step)."""
        lo, hi = self.x_range
        out = self._one(lo if x < lo else (hi if x > hi else x))
        top, slope = self._top
        beyond = self.sign * (x - top)
        return out + slope * beyond if beyond > 0 else out

    def __call__(self, x) -> np.ndarray:
        """The curve at readings ``x`` (NaN stays NaN)."""
        x = np.asarray(x, dtype=float)
        ok = np.isfinite(x)
        xs = np.where(ok, x, self.x_range[0])
        top, slope = self._top
        out = self._inside(xs) + slope * np.maximum(self.sign * (xs - top), 0.0)
        return np.where(ok, out, np.nan)

    def _common_dict(self) -> dict:
        return {"variable": self.variable, "sign": int(self.sign), "adc": self.adc,
                "coefficients": self.coef.tolist(), "readout_range": list(self.x_range)}


def common_fields(d: dict, what: str) -> tuple:
    """(variable, sign, adc, coefficients, readout range) of a curve's file form, checked."""
    if str(d["variable"]) not in VARIABLES:
        raise FileFormatError(f"{what}: variable must be one of {', '.join(VARIABLES)}, got {d['variable']!r}")
    if int(d["sign"]) not in (1, -1):
        raise FileFormatError(f"{what}: sign must be 1 or -1, got {d['sign']!r}")
    lo, hi = (float(v) for v in d["readout_range"])
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
        raise FileFormatError(f"{what}: readout_range must be two finite readings, least first")
    coef = np.asarray(d["coefficients"], dtype=float)
    if coef.ndim != 1 or coef.size < 2 or not np.all(np.isfinite(coef)):
        raise FileFormatError(f"{what}: coefficients must be finite numbers, at least two")
    return str(d["variable"]), int(d["sign"]), None if d.get("adc") is None else float(d["adc"]), coef, (lo, hi)


@dataclass
class MonotoneCurve(StaticCurve):
    """Force (or stress) from a readout: non-decreasing in ``v``, flat below, linear in the readout above.

    Parameters
    ----------
    variable : str
        See :func:`readout_variable`.
    sign : int
        +1 when the readout rises with force, −1 when it falls.
    adc : float or None
        ADC full scale for ``variable="conductance"``. [counts]
    knots : ndarray
        Knots in ``v``.
    coef : ndarray
        Intercept, then each segment's slope times its length. [unit of the reference]
    x_range : (float, float)
        Readings the curve was fitted on. [unit of the readout]
    """

    variable: str
    sign: int
    adc: float | None
    knots: np.ndarray
    coef: np.ndarray
    x_range: tuple[float, float]

    @property
    def rest(self) -> float:
        """The curve's least value, at the low-force end of its readings (:attr:`StaticCurve.rest`). [unit
        of the reference]"""
        return float(self._values[0])

    @cached_property
    def _values(self) -> np.ndarray:
        """The curve's values at its knots. [unit of the reference]"""
        c = self.coef
        return c[0] + np.concatenate([[0.0], np.cumsum(c[1:] * np.diff(self.knots))])

    def _at_v(self, v: np.ndarray) -> np.ndarray:
        return np.interp(v, self.knots, self._values)

    def columns(self, v: np.ndarray) -> np.ndarray:
        return _basis(v, self.knots)

    def lower_bounds(self) -> np.ndarray:
        return np.r_[-np.inf, np.zeros(self.segments)]

    def penalty(self, columns: int, lam: float, n: int) -> np.ndarray:
        return smoothness_penalty(self.knots, columns, lam, n)

    def with_coef(self, coef) -> MonotoneCurve:
        return MonotoneCurve(self.variable, self.sign, self.adc, self.knots, np.asarray(coef, dtype=float),
                             self.x_range)

    @property
    def name(self) -> str:
        return f"{self.variable}-{self.segments}"

    @cached_property
    def _table(self) -> tuple:
        """(knots, values at the knots) as Python floats, for :meth:`_one` (the curve is not changed after
        it is made)."""
        return self.knots.tolist(), self._values.tolist()

    def _one(self, xc: float) -> float:
        """The piecewise-linear interpolation of :meth:`_at_v` without arrays."""
        knots, values = self._table
        if self.variable == "readout":
            v = self.sign * xc
        else:
            v = float(readout_variable(np.array([xc]), self.variable, self.sign, self.adc)[0])
        i = bisect_right(knots, v)
        if i <= 0:
            return values[0]
        if i >= len(knots):
            return values[-1]
        k0, k1 = knots[i - 1], knots[i]
        return values[i - 1] + (values[i] - values[i - 1]) * (v - k0) / (k1 - k0)

    @property
    def segments(self) -> int:
        return int(self.knots.size - 1)

    family = "piecewise"
    size = segments

    def to_dict(self) -> dict:
        return {"variable": self.variable, "sign": int(self.sign), "adc": self.adc, "knots": self.knots.tolist(),
                "coefficients": self.coef.tolist(), "readout_range": list(self.x_range)}

    @classmethod
    def from_dict(cls, d: dict) -> MonotoneCurve:
        variable, sign, adc, coef, rng = common_fields(d, "monotone curve")
        knots = np.asarray(d["knots"], dtype=float)
        if knots.size < 2 or coef.size != knots.size or np.any(np.diff(knots) <= 0) or np.any(coef[1:] < 0):
            raise FileFormatError("monotone curve: knots must increase, one coefficient per segment plus the "
                    "intercept, "
                             "the segments' coefficients >= 0")
        return cls(variable, sign, adc, knots, coef, rng)


def knots_for(v: np.ndarray, segments: int) -> np.ndarray:
    """Knots at quantiles of ``v`` (repeated quantiles merged, at least two knots)."""
    k = np.unique(np.quantile(v, np.linspace(0.0, 1.0, segments + 1)))
    if k.size < 2:
        k = np.array([k[0], k[0] + 1.0])
    return k


def smoothness_penalty(knots: np.ndarray, columns: int, lam: float, n: int) -> np.ndarray:
    """Rows penalising the change of slope between neighbouring segments (column 1 is the first segment).

    A segment's coefficient is its slope times its length; the rows take the slopes' differences
    times the mean length, so a large weight pulls the curve towards a straight line in ``v``."""
    segments = knots.size - 1
    if segments < 2 or lam <= 0:
        return np.zeros((0, columns))
    length = np.diff(knots)
    mean = float(np.mean(length))
    d = np.zeros((segments - 1, columns))
    for i in range(segments - 1):
        d[i, 1 + i], d[i, 2 + i] = -mean / length[i], mean / length[i + 1]
    return np.sqrt(lam * n) * d


@dataclass
class CurveSystem:
    """The normal equations of a static curve's design ``[1, the family's columns, extra columns]`` on some
    readings: every ridge weight and every sign of the extra columns is then solved without the readings.

    Parameters
    ----------
    curve : StaticCurve
        The curve's family, variable, basis and range (coefficients not yet fitted).
    gram, atb : ndarray
        ``aᵀa`` and ``aᵀy``.
    yty : float
        ``yᵀy``.
    n : int
        Readings.
    """

    curve: StaticCurve
    gram: np.ndarray
    atb: np.ndarray
    yty: float
    n: int

    @property
    def extra(self) -> int:
        return self.gram.shape[0] - self.curve.coef.size

    def solve(self, lam: float = 1e-3, extra_lower: np.ndarray | None = None, extra_lam: float = 0.0,
              extra_signs: np.ndarray | None = None) -> tuple[StaticCurve, np.ndarray, float]:
        """The curve, the extra columns' weights and the residual sum of squares: ``lam`` the ridge weight
        on the curve's change of slope, ``extra_lower``, ``extra_lam`` the extra columns' lower bounds and
        ridge weight (relative to the number of readings); ``extra_signs``: the extra columns multiplied by these signs
        first (the weights returned are of the
        columns as given)."""
        k = self.curve.coef.size
        m = self.extra
        gram, atb = self.gram, self.atb
        sg = np.ones(gram.shape[0])
        if m and extra_signs is not None:
            sg[k:] = extra_signs
            gram = gram * np.outer(sg, sg)
            atb = atb * sg
        cols = gram.shape[0]
        pen = [self.curve.penalty(cols, lam, self.n)]
        if m and extra_lam > 0:
            r = np.zeros((m, cols))
            r[:, k:] = np.eye(m)
            pen.append(np.sqrt(extra_lam * self.n) * r)
        lower = np.r_[self.curve.lower_bounds(), (extra_lower if extra_lower is not None else np.full(m, -np.inf))
                      if m else np.zeros(0)]
        c = bounded_solve(gram, atb, self.n, lower, np.vstack(pen))
        rss = float(c @ gram @ c - 2 * c @ atb + self.yty)
        return self.curve.with_coef(c[:k]), (c * sg)[k:], max(rss, 0.0)

    def solve_extra(self, curve: StaticCurve, extra_lam: float = 0.0,
                    extra_signs: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        """The extra columns' weights, not below zero (after ``extra_signs``), with the curve held at
        ``curve`` (fitted alone on the same readings, so on this basis), and the residual sum of squares:
        the extra columns fitted to what the curve leaves."""
        k = self.curve.coef.size
        if curve.coef.size != k:
            raise ParameterError("must have the system's knots", parameter="curve")
        g_ff, g_fc = self.gram[k:, k:], self.gram[k:, :k]
        b = self.atb[k:] - g_fc @ curve.coef
        m = b.size
        sg = np.ones(m) if extra_signs is None else np.asarray(extra_signs, dtype=float)
        pen = np.sqrt(extra_lam * self.n) * np.eye(m) if extra_lam > 0 else None
        if pen is None and not np.any(g_ff):  # columns all zero and no ridge: nothing to fit
            w = np.zeros(m)
        else:
            w = bounded_solve(g_ff * np.outer(sg, sg), b * sg, self.n, np.zeros(m), pen) * sg
        c = curve.coef
        rr = self.yty - 2 * c @ self.atb[:k] + c @ self.gram[:k, :k] @ c  # what the curve leaves
        return w, max(float(w @ g_ff @ w - 2 * w @ b + rr), 0.0)


def curve_system(template: StaticCurve, x, y, extra: np.ndarray | None = None) -> CurveSystem:
    """The :class:`CurveSystem` of ``template``'s family on readings ``x``, reference ``y`` and further columns.

    Parameters
    ----------
    template : StaticCurve
        The family, variable and basis (its coefficients are not used).
    x, y : array_like
        Readings and reference, finite.
    extra : ndarray, shape (n, m), optional
        Further columns (memory features) fitted with the curve.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    v = readout_variable(x, template.variable, template.sign, template.adc)
    m = 0 if extra is None else extra.shape[1]
    k = template.coef.size
    # columns: the constant, the family's, the extra columns
    a = np.empty((x.size, k + m), order="F")
    a[:, 0] = 1.0
    a[:, 1:k] = template.columns(v)
    if m:
        a[:, k:] = extra
    return CurveSystem(template, a.T @ a, a.T @ y, float(y @ y), x.size)
