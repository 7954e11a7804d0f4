"""The paper's fixed polynomials of Figure 17: σ(f) fitted by least squares, linear or cubic.

Not a calibration (that is :func:`fsrlab.calibrate`): the paper fits σ on f with one polynomial of a
fixed degree over both branches and prints its R² (Figure 17a linear, 17b cubic). fsrlab reproduces
those fits, and their R², with :func:`fit_polynomial`.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, Figure 17.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import chebyshev

from fsrlab.errors import ParameterError

__all__ = ["PolynomialFit", "fit_polynomial"]


@dataclass(frozen=True)
class PolynomialFit:
    """A least-squares polynomial y(x) and its in-sample quality.

    Parameters
    ----------
    coefficients : ndarray
        Chebyshev coefficients in the mapped variable ``(x − center)/half_width``.
    center, half_width : float
        The mapping of the fitted readings' range onto [−1, 1]. [unit of x]
    r2 : float
        Coefficient of determination. [1]
    rmse : float
        Root-mean-square residual. [unit of y]
    max_error_percent_fs : float
        Largest absolute residual in percent of the reference's span. [%]
    """

    coefficients: np.ndarray
    center: float
    half_width: float
    r2: float
    rmse: float
    max_error_percent_fs: float

    @property
    def degree(self) -> int:
        return int(self.coefficients.size - 1)

    def __call__(self, x) -> np.ndarray:
        """y at readings ``x``. [unit of y]"""
        return chebyshev.chebval((np.asarray(x, dtype=float) - self.center) / self.half_width, self.coefficients)


def fit_polynomial(x, y, degree: int) -> PolynomialFit:
    """Least-squares polynomial of y on x of a fixed degree (the Chebyshev basis keeps it well conditioned).

    Parameters
    ----------
    x, y : array_like
        Readout (frequency [Hz], C_FSR [F], ...) and reference (stress [Pa]); rows where either is NaN
        are left out.
    degree : int
        1 to 5.

    Returns
    -------
    PolynomialFit

    Raises
    ------
    ParameterError
        A degree outside 1–5, arrays of different lengths, too few readings or a readout that does not vary.
    """
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or not 1 <= degree <= 5:
        raise ParameterError(f"must be an integer from 1 to 5, got {degree!r}", parameter="degree")
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ParameterError(f"x and y must have the same length, got {x.size} and {y.size}", parameter="y")
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size <= degree:
        raise ParameterError(f"{degree} needs more than {degree} readings with both values, got {x.size}",
                             parameter="degree")
    lo, hi = float(x.min()), float(x.max())
    if not hi > lo:
        raise ParameterError("the readout does not vary", parameter="x")
    center, half = (lo + hi) / 2, (hi - lo) / 2
    vander = chebyshev.chebvander((x - center) / half, int(degree))
    q, r = np.linalg.qr(vander)
    coef = np.linalg.solve(r, q.T @ y)
    res = y - vander @ coef
    ss_res, ss_tot, fs = float(res @ res), float(((y - y.mean()) ** 2).sum()), float(y.max() - y.min())
    return PolynomialFit(coef, center, half, 1 - ss_res / ss_tot if ss_tot > 0 else float("nan"),
                         float(np.sqrt(ss_res / y.size)),
                         100 * float(np.abs(res).max()) / fs if fs > 0 else float("nan"))
