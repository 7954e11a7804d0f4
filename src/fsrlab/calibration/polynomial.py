"""The calibration polynomial: readout -> stress (or the inverse) of degree 1 to 5, chosen by grouped cross-validation.

The paper fits stress against frequency with a straight line (R² = 0.9432) and a cubic
(R² = 0.9974) (§5, Figure 17). fsrlab fits degrees 1 to 5 and chooses the degree by
cross-validation in which whole loading-unloading cycles stay together (grouped folds), so a
degree is judged on cycles it has not seen; it reports R², RMSE and the largest error in percent of
full scale. This module holds the computation on arrays; the calibration file is
:mod:`fsrlab.calibration.document`, and calibrating a recorded run (its cycles, its circuit,
the compensation) and applying the result to another run is :mod:`fsrlab.calibration.fit`.

Numerics: the readout is mapped onto [-1, 1] and the polynomial is written in Chebyshev
polynomials T_k, which keeps the least-squares problem well conditioned up to degree 5. Cross-
validation needs no refits on the data: since ``T_i T_j = (T_{i+j} + T_{|i-j|}) / 2``, the normal
equations of every degree and every fold follow from per-group sums of ``T_0 .. T_10``, of
``T_k y`` and of ``y²``, computed in one pass (``np.bincount``). The final model is fitted by QR
least squares (``numpy.linalg.lstsq``) on all readings.

A physics-informed option calibrates on C_FSR decoded from frequency and duty cycle
(:func:`fsrlab.calibration.readout.decode_capacitance`) instead of on raw frequency.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, Figure 17.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.polynomial import chebyshev as C

__all__ = [
    "MAX_DEGREE",
    "PolynomialModel",
    "fit_polynomial",
    "CrossValidation",
    "cross_validate_degrees",
    "default_groups",
    "fit_metrics",
    "fingerprint",
]

#: Highest polynomial degree offered.
MAX_DEGREE = 5


@dataclass(frozen=True)
class PolynomialModel:
    """y = Σ c_k T_k(z), z = (x − center) / half_width, with Chebyshev polynomials T_k.

    Parameters
    ----------
    coefficients : ndarray
        Chebyshev coefficients c_0..c_degree. [unit of y]
    center, half_width : float
        Mapping of x onto z ∈ [-1, 1] over the calibration data. [unit of x]
    """

    coefficients: np.ndarray
    center: float
    half_width: float

    @property
    def degree(self) -> int:
        """Polynomial degree."""
        return len(self.coefficients) - 1

    def __call__(self, x) -> np.ndarray:
        """Evaluate the polynomial at readout ``x``."""
        z = (np.asarray(x, dtype=float) - self.center) / self.half_width
        return C.chebval(z, self.coefficients)

    def power_coefficients(self) -> np.ndarray:
        """Coefficients a_0..a_degree of ``y = Σ a_k x^k`` in the raw readout x (ascending powers)."""
        p = C.cheb2poly(self.coefficients)  # in z
        # z = (x - c)/h -> compose polynomial
        out = np.zeros(len(p))
        lin = np.array([-self.center / self.half_width, 1.0 / self.half_width])
        term = np.array([1.0])
        for a in p:
            out[: len(term)] += a * term
            term = np.convolve(term, lin)
        return out


def _prepare(x, y) -> tuple[np.ndarray, np.ndarray]:
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"x and y must have the same length, got {x.size} and {y.size}")
    return x, y


def _check_degree(degree: int) -> int:
    if not (isinstance(degree, (int, np.integer)) and 1 <= degree <= MAX_DEGREE):
        raise ValueError(f"degree must be an integer from 1 to {MAX_DEGREE} or 'auto', got {degree!r}")
    return int(degree)


def _scaling(x: np.ndarray) -> tuple[float, float]:
    lo, hi = float(x.min()), float(x.max())
    if not hi > lo:
        raise ValueError("x: the readout does not vary; a calibration needs at least two distinct readings")
    return (lo + hi) / 2, (hi - lo) / 2


def fit_polynomial(x, y, degree: int, center: float | None = None, half_width: float | None = None) -> PolynomialModel:
    """Least-squares polynomial y(x) of a given degree (QR on the Chebyshev Vandermonde matrix).

    Parameters
    ----------
    x : array_like
        Readout (frequency [Hz], C_FSR [F], voltage [V], ...). Finite values only.
    y : array_like
        Reference (stress [Pa], or the readout for an inverse model).
    degree : int
        1 to 5.
    center, half_width : float, optional
        Mapping of x onto [-1, 1] (default: the data's range).

    Returns
    -------
    PolynomialModel
    """
    degree = _check_degree(degree)
    x, y = _prepare(x, y)
    if x.size <= degree:
        raise ValueError(f"degree: {degree} needs more than {degree} readings with both values, got {x.size}")
    if center is None or half_width is None:
        center, half_width = _scaling(x)
    z = (x - center) / half_width
    coef, *_ = np.linalg.lstsq(C.chebvander(z, degree), y, rcond=None)
    return PolynomialModel(coefficients=coef, center=float(center), half_width=float(half_width))


@dataclass(frozen=True)
class CrossValidation:
    """Grouped k-fold cross-validation of polynomial degrees.

    Parameters
    ----------
    degrees : list of int
        Degrees tried.
    rmse : list of float
        Pooled out-of-fold RMSE of each degree. [unit of y]
    folds : int
        Number of folds.
    groups : int
        Number of groups (cycles) distributed over the folds.
    best_degree : int
        Chosen degree: the lowest whose out-of-fold RMSE is within ``tolerance`` of the smallest.
    moments : tuple of ndarray, optional
        Whole-data sums (Σ T_0..T_2d, Σ T_k y) in the Chebyshev basis, reused for the final fit.
    untried : list of int
        Degrees asked for but not tried: a training fold has too few (distinct) readings for them.
    """

    degrees: list[int]
    rmse: list[float]
    folds: int
    groups: int
    best_degree: int
    moments: tuple | None = field(default=None, repr=False, compare=False)
    untried: list[int] = field(default_factory=list)

    def full_fit(self, degree: int) -> np.ndarray:
        """Chebyshev coefficients of the least-squares fit on all readings, from the stored sums."""
        mt, tyt = self.moments
        return np.linalg.solve(_gram(mt, degree), tyt[: degree + 1])


def _gram(mom: np.ndarray, d: int) -> np.ndarray:
    """Gram matrix Σ T_i T_j = (Σ T_{i+j} + Σ T_{|i-j|}) / 2 of the Chebyshev basis up to degree d."""
    i = np.arange(d + 1)
    return 0.5 * (mom[i[:, None] + i[None, :]] + mom[np.abs(i[:, None] - i[None, :])])


def default_groups(n: int, cycle=None, folds: int = 5) -> np.ndarray:
    """Groups for cross-validation: the ``cycle`` column if it has ≥ 2 values, else contiguous blocks.

    Parameters
    ----------
    n : int
        Number of readings.
    cycle : array_like, optional
        Cycle number of each reading (NaN allowed: treated as its own group).
    folds : int
        Blocks to cut the run into when there are no cycles.

    Returns
    -------
    ndarray of int
        Group label 0..G-1 of each reading.
    """
    if cycle is not None:
        c = np.asarray(cycle, dtype=float)
        c = np.where(np.isnan(c), -1.0, c)
        _, g = np.unique(c, return_inverse=True)
        if g.max(initial=0) >= 1:
            return g.astype(np.intp)
    # Contiguous blocks in time order keep neighbouring (correlated) readings together.
    return (np.arange(n) * folds // max(n, 1)).astype(np.intp)


def cross_validate_degrees(x, y, groups, degrees: Sequence[int] = range(1, MAX_DEGREE + 1), folds: int = 5,
                           center: float | None = None, half_width: float | None = None,
                           tolerance: float = 0.01) -> CrossValidation:
    """Out-of-fold RMSE of each degree, with whole groups held out together.

    Parameters
    ----------
    x, y : array_like
        Readout and reference.
    groups : array_like of int
        Group of each reading (e.g. cycle number); a group is never split across folds.
    degrees : sequence of int
        Degrees to try (1..5).
    folds : int
        Number of folds, ≥ 2; reduced to the number of groups if there are fewer.
    center, half_width : float, optional
        Mapping of x onto [-1, 1] (default: the data's range).
    tolerance : float
        Parsimony: the chosen degree is the lowest whose out-of-fold RMSE is at most
        ``(1 + tolerance)`` times the smallest (0: plain argmin). [1]

    Returns
    -------
    CrossValidation
        Over the degrees that every training fold can determine (more readings than the degree,
        a regular system); the others are listed in ``untried``.

    Raises
    ------
    ValueError
        No degree can be tried (message starting ``"degree:"``), fewer than 2 groups, bad options.

    Notes
    -----
    Group g goes to fold ``g mod k`` (groups in order of their labels). For each fold the training
    normal equations ``G β = b`` are assembled from the per-group sums of Chebyshev moments
    (total minus the fold's), and the held-out squared error follows from the fold's own sums:
    ``SSE = Σy² − 2 βᵀb_f + βᵀ G_f β``. This is exact algebra, not an approximation.
    """
    degrees = [_check_degree(d) for d in degrees]
    x, y = _prepare(x, y)
    g = np.asarray(groups)
    if g.shape != x.shape:
        raise ValueError("groups must have one label per reading")
    _, g = np.unique(g, return_inverse=True)
    n_groups = int(g.max()) + 1
    if folds < 2:
        raise ValueError(f"folds must be >= 2, got {folds!r}")
    k = min(folds, n_groups)
    if k < 2:
        raise ValueError("groups: cross-validation needs at least 2 groups (cycles or blocks)")
    dmax = max(degrees)
    if center is None or half_width is None:
        center, half_width = _scaling(x)
    z = (x - center) / half_width
    fold_of_group = np.arange(n_groups) % k
    fold = fold_of_group[g]
    # Per-fold sums of T_0..T_2d (moments), T_0..T_d times y, y², counts: one pass each.
    m = np.empty((2 * dmax + 1, k))
    t_prev, t_cur = np.ones_like(z), z
    m[0] = np.bincount(fold, minlength=k).astype(float)
    ty = np.empty((dmax + 1, k))
    ty[0] = np.bincount(fold, weights=y, minlength=k)
    if 2 * dmax >= 1:
        m[1] = np.bincount(fold, weights=z, minlength=k)
        ty[1] = np.bincount(fold, weights=z * y, minlength=k)
    for j in range(2, 2 * dmax + 1):
        t_prev, t_cur = t_cur, 2 * z * t_cur - t_prev  # Chebyshev recurrence
        m[j] = np.bincount(fold, weights=t_cur, minlength=k)
        if j <= dmax:
            ty[j] = np.bincount(fold, weights=t_cur * y, minlength=k)
    yy = np.bincount(fold, weights=y * y, minlength=k)
    mt, tyt, n_tot = m.sum(axis=1), ty.sum(axis=1), m[0].sum()

    if not tolerance >= 0:
        raise ValueError(f"tolerance must be >= 0, got {tolerance!r}")
    # A training fold of n readings determines a polynomial of degree n - 1 at most: the degrees
    # it cannot determine (small runs) are left out rather than failing the whole selection.
    smallest = int(n_tot - m[0].max())
    tried, rmse = [], []
    for d in degrees:
        if d >= smallest:
            continue
        sse = 0.0
        try:
            for f in range(k):
                beta = np.linalg.solve(_gram(mt - m[:, f], d), (tyt - ty[:, f])[: d + 1])
                sse += yy[f] - 2 * beta @ ty[: d + 1, f] + beta @ _gram(m[:, f], d) @ beta
        except np.linalg.LinAlgError:  # too few distinct readings in a training fold for degree d
            continue
        tried.append(d)
        rmse.append(float(np.sqrt(max(sse, 0.0) / n_tot)))
    if not tried:
        raise ValueError(f"degree: cannot be chosen by cross-validation: the smallest training fold holds {smallest} "
                         f"readings ({int(n_tot)} readings in {k} folds of {n_groups} groups), too few for degree "
                         f"{min(degrees)}; give the degree, or more readings")
    best = min(d for d, e in zip(tried, rmse) if e <= (1 + tolerance) * min(rmse))
    return CrossValidation(degrees=tried, rmse=rmse, folds=k, groups=n_groups, best_degree=best, moments=(mt, tyt),
                           untried=[d for d in degrees if d not in tried])


def fit_metrics(y, y_hat) -> dict[str, float]:
    """R², RMSE and the largest absolute error in percent of full scale.

    Parameters
    ----------
    y, y_hat : array_like
        Reference and estimate. [unit of y]

    Returns
    -------
    dict
        ``r2``, ``rmse`` [unit of y], ``max_error`` [unit of y], ``full_scale`` (``max y − min y``)
        and ``max_error_percent_fs`` [%].
    """
    y, yh = _prepare(y, y_hat)
    res = y - yh
    ss_res = float(res @ res)
    ss_tot = float(((y - y.mean()) ** 2).sum())
    fs = float(y.max() - y.min())
    mx = float(np.abs(res).max())
    return {"r2": 1 - ss_res / ss_tot if ss_tot > 0 else float("nan"), "rmse": float(np.sqrt(ss_res / y.size)),
            "max_error": mx, "full_scale": fs, "max_error_percent_fs": 100 * mx / fs if fs > 0 else float("nan")}


def fingerprint(x, y) -> str:
    """SHA-256 (first 16 hex digits) of the calibration data as float64 bytes.

    Parameters
    ----------
    x, y : array_like
        Readout and reference used for the fit.

    Returns
    -------
    str
        ``"sha256:"`` followed by 16 hex digits.
    """
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(x, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(y, dtype=np.float64).tobytes())
    return "sha256:" + h.hexdigest()[:16]
