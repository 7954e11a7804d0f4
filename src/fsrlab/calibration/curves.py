"""Smooth static curves beside the piecewise-linear one: polynomials and monotone cubic splines.

**Extension beyond the paper.** A smooth, quiet readout (a frequency counted in 62.5 ns ticks) is
followed by eight straight pieces only to within their bend: on a cubic of frequency with 5 Pa of
noise the piecewise curve of :mod:`fsrlab.calibration.monotone` misses by tens of pascals where a
cubic misses by the noise. Two smooth families join it, in the same readout variables
(:func:`fsrlab.calibration.monotone.readout_variable`) and with the same rule beyond the calibrated
readings (flat below, linear per unit of readout above: a polynomial is never extrapolated as one):

* :class:`PolynomialCurve` -- degree 2 to 5 in ``s = (v − centre)/half-width`` (``s`` in −1..1 on the
  calibrated readings; degree 1 is the one-segment line of the piecewise family), the paper's cubic
  of Figure 17b among them. Not monotone by construction: :meth:`PolynomialCurve.is_monotone` checks
  its slope over the calibrated readings, and the calibration keeps only one that never falls there;
* :class:`SplineCurve` -- a cubic spline that never falls: the cubic B-spline basis on knots at
  quantiles of ``v`` summed from each basis function to the last (an I-spline: J. O. Ramsay,
  *Statistical Science* 3, 425, 1988), weights not below zero. With no inner knot it is a monotone
  cubic; each inner knot adds a piece.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from fsrlab.calibration.monotone import (
    CurveSystem,
    MonotoneCurve,
    StaticCurve,
    common_fields,
    curve_system,
    knots_for,
    readout_variable,
)
from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.physics.params import check_at_least, check_finite, check_int, float_array

__all__ = ["FAMILIES", "PolynomialCurve", "SplineCurve", "curve_template", "static_system", "fit_static",
           "curve_from_dict"]

#: The static curve families: piecewise linear (size: segments), polynomial (size: degree), monotone
#: cubic spline (size: inner knots). [1]
FAMILIES = ("piecewise", "polynomial", "spline")
#: Degree of the spline pieces. [1]
SPLINE_DEGREE = 3


@dataclass
class PolynomialCurve(StaticCurve):
    """Force from a readout: a polynomial of its variable inside the calibrated readings.

    Parameters
    ----------
    variable, sign, adc
        See :func:`fsrlab.calibration.monotone.readout_variable`.
    centre, half_width : float
        ``s = (v − centre)/half_width``. [unit of the variable]
    coef : ndarray
        Coefficients of ``s⁰, s¹, …``. [unit of the reference]
    x_range : (float, float)
        Readings the curve was fitted on. [unit of the readout]
    """

    variable: str
    sign: int
    adc: float | None
    centre: float
    half_width: float
    coef: np.ndarray
    x_range: tuple[float, float]
    monotone = False
    family = "polynomial"

    @property
    def degree(self) -> int:
        return int(self.coef.size - 1)

    size = degree

    @property
    def name(self) -> str:
        return f"{self.variable}-poly{self.degree}"

    def _at_v(self, v):
        return np.polynomial.polynomial.polyval((v - self.centre) / self.half_width, self.coef)

    def columns(self, v):
        s = (np.asarray(v, dtype=float) - self.centre) / self.half_width
        return np.vander(s, self.degree + 1, increasing=True)[:, 1:]

    def lower_bounds(self):
        return np.full(self.coef.size, -np.inf)

    def with_coef(self, coef) -> PolynomialCurve:
        return PolynomialCurve(self.variable, self.sign, self.adc, self.centre, self.half_width,
                               np.asarray(coef, dtype=float), self.x_range)

    def is_monotone(self) -> bool:
        """Whether the slope in ``s`` is nowhere below zero on −1..1 (the calibrated readings), to rounding:
        its least value, at an end or where the second derivative is zero."""
        p = np.polynomial.Polynomial(self.coef)
        d1 = p.deriv()
        if self.degree < 2:
            at = np.array([-1.0, 1.0])
        else:
            roots = d1.deriv().roots()
            roots = roots[np.isreal(roots)].real
            at = np.r_[-1.0, 1.0, roots[(roots > -1) & (roots < 1)]]
        least = float(np.min(d1(at)))
        scale = float(np.sum(np.abs(self.coef[1:] * np.arange(1, self.coef.size))))
        return least >= -1e-9 * max(scale, np.finfo(float).tiny)

    def to_dict(self) -> dict:
        return {"family": "polynomial", **self._common_dict(), "centre": self.centre, "half_width": self.half_width}

    @classmethod
    def from_dict(cls, d: dict) -> PolynomialCurve:
        variable, sign, adc, coef, rng = common_fields(d, "polynomial curve")
        centre, half = float(d["centre"]), float(d["half_width"])
        if not (np.isfinite(centre) and half > 0 and np.isfinite(half)) or coef.size > 6:
            raise FileFormatError("polynomial curve: centre finite, half_width > 0, degree at most 5")
        return cls(variable, sign, adc, centre, half, coef, rng)


@dataclass
class SplineCurve(StaticCurve):
    """Force from a readout: a cubic spline of its variable that never falls, inside the calibrated readings.

    Parameters
    ----------
    variable, sign, adc
        See :func:`fsrlab.calibration.monotone.readout_variable`.
    breaks : ndarray
        The spline's ends and inner knots, increasing. [unit of the variable]
    coef : ndarray
        The value at the low end, then the rise of each summed basis function (not below zero). [unit of
        the reference]
    x_range : (float, float)
        Readings the curve was fitted on. [unit of the readout]
    """

    variable: str
    sign: int
    adc: float | None
    breaks: np.ndarray
    coef: np.ndarray
    x_range: tuple[float, float]

    family = "spline"

    @property
    def inner(self) -> int:
        return int(self.breaks.size - 2)

    size = inner

    @property
    def name(self) -> str:
        return f"{self.variable}-spline{self.inner}"

    @cached_property
    def _knots(self) -> np.ndarray:
        k = SPLINE_DEGREE
        return np.r_[[self.breaks[0]] * k, self.breaks, [self.breaks[-1]] * k]

    @cached_property
    def _spline(self):
        from scipy.interpolate import BSpline

        # B-spline coefficients: the low end's value, then each summed basis function's rise added on
        return BSpline(self._knots, self.coef[0] + np.r_[0.0, np.cumsum(self.coef[1:])], SPLINE_DEGREE)

    def _at_v(self, v):
        return self._spline(np.clip(v, self.breaks[0], self.breaks[-1]))

    def columns(self, v):
        from scipy.interpolate import BSpline

        vc = np.clip(np.asarray(v, dtype=float), self.breaks[0], self.breaks[-1])
        b = BSpline(self._knots, np.eye(self.coef.size), SPLINE_DEGREE)(vc)  # each basis function at vc
        return np.cumsum(b[:, ::-1], axis=1)[:, ::-1][:, 1:]  # column i: the sum of basis functions i and after

    def lower_bounds(self):
        return np.r_[-np.inf, np.zeros(self.coef.size - 1)]

    def penalty(self, columns: int, lam: float, n: int) -> np.ndarray:
        """Rows penalising the change of slope between neighbouring basis functions, as the piecewise
        curve's (:func:`fsrlab.calibration.monotone.smoothness_penalty`): the spline's slope is a sum of
        ``3·rise_j/(t_{j+3} − t_j)`` times quadratic B-splines; the rows take the differences of these
        slopes times their mean span, so a large weight pulls the curve towards a straight line in ``v``."""
        k = self.coef.size - 1
        if k < 2 or lam <= 0:
            return np.zeros((0, columns))
        t = self._knots
        span = (t[SPLINE_DEGREE + 1:SPLINE_DEGREE + 1 + k] - t[1:1 + k]) / SPLINE_DEGREE  # of rise j = 1..k
        mean = float(np.mean(span))
        d = np.zeros((k - 1, columns))
        for i in range(k - 1):
            d[i, 1 + i], d[i, 2 + i] = -mean / span[i], mean / span[i + 1]
        return np.sqrt(lam * n) * d

    def with_coef(self, coef) -> SplineCurve:
        return SplineCurve(self.variable, self.sign, self.adc, self.breaks, np.asarray(coef, dtype=float),
                           self.x_range)

    def to_dict(self) -> dict:
        return {"family": "spline", **self._common_dict(), "breaks": self.breaks.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> SplineCurve:
        variable, sign, adc, coef, rng = common_fields(d, "spline curve")
        breaks = np.asarray(d["breaks"], dtype=float)
        if (breaks.ndim != 1 or breaks.size < 2 or np.any(np.diff(breaks) <= 0)
                or coef.size != breaks.size + SPLINE_DEGREE - 1 or np.any(coef[1:] < 0)):
            raise FileFormatError("spline curve: breaks must increase, one coefficient per basis function, the rises "
                    ">= 0")
        return cls(variable, sign, adc, breaks, coef, rng)


def curve_template(x, family: str, size: int, variable: str, sign: int, adc: float | None) -> StaticCurve:
    """A curve of ``family`` and ``size`` for readings ``x`` (basis set, coefficients zero).

    Parameters
    ----------
    x : array_like
        Readings, finite. [unit of the readout]
    family : {"piecewise", "polynomial", "spline"}
        See :data:`FAMILIES`.
    size : int
        Segments, degree or inner knots. [1]
    variable, sign, adc
        See :func:`fsrlab.calibration.monotone.readout_variable`.
    """
    x = float_array("x", x)
    if x.ndim != 1 or x.size < 2 or not np.all(np.isfinite(x)):
        raise ParameterError(f"must be two or more finite readings, got {x.size if x.ndim == 1 else x.shape}",
                             parameter="x")
    check_int("size", size, lower=0 if family == "spline" else 1)
    if family not in FAMILIES:
        raise ParameterError(f"must be one of {', '.join(FAMILIES)}, got {family!r}", parameter="family")
    try:
        v = readout_variable(x, variable, sign, adc)
    except ParameterError as exc:  # its name is this function's variable
        raise ParameterError(exc.reason, parameter="variable" if exc.parameter == "name" else exc.parameter) from None
    rng = (float(x.min()), float(x.max()))
    lo, hi = float(v.min()), float(v.max())
    if family == "piecewise":
        knots = knots_for(v, size)
        return MonotoneCurve(variable, sign, adc, knots, np.zeros(knots.size), rng)
    if family == "polynomial":
        return PolynomialCurve(variable, sign, adc, (lo + hi) / 2, (hi - lo) / 2 if hi > lo else 1.0,
                               np.zeros(size + 1), rng)
    if family == "spline":
        inner = np.unique(np.quantile(v, np.linspace(0.0, 1.0, size + 2)[1:-1])) if size else np.zeros(0)
        inner = inner[(inner > lo) & (inner < hi)]
        breaks = np.r_[lo, inner, hi if hi > lo else lo + 1.0]
        return SplineCurve(variable, sign, adc, breaks, np.zeros(breaks.size + SPLINE_DEGREE - 1), rng)
    raise ParameterError(f"must be one of {', '.join(FAMILIES)}, got {family!r}", parameter="family")


def static_system(x, y, family: str, size: int, variable: str, sign: int, adc: float | None,
                  extra: np.ndarray | None = None) -> CurveSystem:
    """The normal equations of a ``family`` curve (:func:`curve_template`) on readings ``x``, reference ``y``
    and ``extra`` columns (:class:`fsrlab.calibration.monotone.CurveSystem`).

    Parameters
    ----------
    x, y : array_like
        Readings and reference, finite.
    family, size, variable, sign, adc
        See :func:`curve_template`.
    extra : ndarray, optional
        More columns fitted with the curve (a memory's features), one row per reading.
    """
    return curve_system(curve_template(x, family, size, variable, sign, adc), x, y, extra)


def fit_static(x, y, family: str, size: int, variable: str, sign: int, adc: float | None,
               lam: float = 1e-3) -> StaticCurve:
    """A ``family`` curve fitted to readings ``x`` and reference ``y`` by (bounded) least squares.

    Parameters
    ----------
    x, y : array_like
        Readings and reference, finite.
    family, size, variable, sign, adc
        See :func:`curve_template`.
    lam : float
        Ridge weight on the change of slope between segments or basis functions, relative to the number of readings. [1]
    """
    template = curve_template(x, family, size, variable, sign, adc)  # checks x and the curve's arguments
    y = float_array("y", y)
    if y.shape != np.shape(x):
        raise ParameterError(f"must have one value per reading, got shape {y.shape}", parameter="y")
    check_finite("y", y)
    check_at_least("lam", lam, 0.0, scalar=True)
    return curve_system(template, x, y).solve(lam)[0]


def curve_from_dict(d: dict) -> StaticCurve:
    """A static curve from its file form (:meth:`to_dict`); without ``family``: a piecewise curve (older files).

    Parameters
    ----------
    d : dict
        The curve's file form.
    """
    if not isinstance(d, dict):
        raise TypeError(f"d: must be a curve's file form (a dict), got {type(d).__name__}")
    family = d.get("family", "piecewise")
    kinds = {"polynomial": PolynomialCurve, "spline": SplineCurve, "piecewise": MonotoneCurve}
    if family in kinds:
        try:
            return kinds[family].from_dict(d)
        except (KeyError, TypeError) as exc:  # a field missing, or not a number
            raise FileFormatError(f"a static curve's file form without a valid {exc}", parameter="d") from None
    raise FileFormatError(f"static curve: family must be one of {', '.join(FAMILIES)}, got {family!r}")
