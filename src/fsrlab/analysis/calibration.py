"""Calibration: readout -> stress (or the inverse) as a polynomial of degree 1 to 5.

The paper fits stress against frequency with a straight line (R² = 0.9432) and a cubic
(R² = 0.9974) (§5, Figure 17). fsrlab fits degrees 1 to 5 and chooses the degree by
cross-validation in which whole loading-unloading cycles stay together (grouped folds), so a
degree is judged on cycles it has not seen; it reports R², RMSE and the largest error in percent of
full scale, saves the calibration to a JSON file and applies it to other runs.

Numerics: the readout is mapped onto [-1, 1] and the polynomial is written in Chebyshev
polynomials T_k, which keeps the least-squares problem well conditioned up to degree 5. Cross-
validation needs no refits on the data: since ``T_i T_j = (T_{i+j} + T_{|i-j|}) / 2``, the normal
equations of every degree and every fold follow from per-group sums of ``T_0 .. T_10``, of
``T_k y`` and of ``y²``, computed in one pass (``np.bincount``). The final model is fitted by QR
least squares (``numpy.linalg.lstsq``) on all readings.

A physics-informed option calibrates on C_FSR decoded from frequency and duty cycle
(:func:`fsrlab.circuits.decode.decode`) instead of on raw frequency.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, Figure 17.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from numpy.polynomial import chebyshev as C

__all__ = [
    "MAX_DEGREE",
    "PolynomialModel",
    "fit_polynomial",
    "CrossValidation",
    "cross_validate_degrees",
    "default_groups",
    "Calibration",
    "calibrate",
    "fit_metrics",
    "save_calibration",
    "load_calibration",
    "fingerprint",
    "CALIBRATION_FORMAT",
]

#: Highest polynomial degree offered.
MAX_DEGREE = 5
#: Value of the calibration file's ``"format"`` key.
CALIBRATION_FORMAT = "fsrlab-calibration"


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
        raise ValueError(f"x: degree {degree} needs more than {degree} readings, got {x.size}")
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
    """

    degrees: list[int]
    rmse: list[float]
    folds: int
    groups: int
    best_degree: int
    moments: tuple | None = field(default=None, repr=False, compare=False)

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

    gram = _gram
    rmse = []
    for d in degrees:
        sse = 0.0
        for f in range(k):
            gtrain = gram(mt - m[:, f], d)
            btrain = (tyt - ty[:, f])[: d + 1]
            if n_tot - m[0, f] <= d:
                raise ValueError(f"degree {d}: a training fold has too few readings")
            beta = np.linalg.solve(gtrain, btrain)
            gf = gram(m[:, f], d)
            sse += yy[f] - 2 * beta @ ty[: d + 1, f] + beta @ gf @ beta
        rmse.append(float(np.sqrt(max(sse, 0.0) / n_tot)))
    if not tolerance >= 0:
        raise ValueError(f"tolerance must be >= 0, got {tolerance!r}")
    best = min(d for d, e in zip(degrees, rmse) if e <= (1 + tolerance) * min(rmse))
    return CrossValidation(degrees=degrees, rmse=rmse, folds=k, groups=n_groups, best_degree=best, moments=(mt, tyt))


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


@dataclass
class Calibration:
    """A fitted calibration, ready to save and apply.

    Parameters
    ----------
    model : PolynomialModel
        y(x).
    x_name, y_name : str
        Columns (``frequency_hz`` -> ``stress_pa``; ``c_fsr_farad`` for the physics-informed option).
    x_unit, y_unit : str
        Units of x and y.
    r2, rmse, max_error_percent_fs : float
        In-sample fit quality on all readings (RMSE in the unit of y).
    cv : CrossValidation or None
        The degree selection, when ``degree="auto"``.
    n : int
        Readings used.
    data_fingerprint : str
        See :func:`fingerprint`.
    created : str
        UTC time, ISO 8601.
    decode : dict or None
        Circuit used to decode C_FSR (physics-informed option).
    source : str
        Where the data came from.
    extra : dict
        Further entries kept in the calibration file (e.g. ``compensation``).
    """

    model: PolynomialModel
    x_name: str
    y_name: str
    x_unit: str
    y_unit: str
    r2: float
    rmse: float
    max_error_percent_fs: float
    n: int
    data_fingerprint: str
    created: str
    cv: CrossValidation | None = None
    decode: dict | None = None
    source: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def degree(self) -> int:
        """Polynomial degree."""
        return self.model.degree

    def __call__(self, x) -> np.ndarray:
        """y estimated from readout ``x``."""
        return self.model(x)

    def inverse(self, y, points: int = 8193) -> np.ndarray:
        """Readout x that the calibration maps to ``y`` (e.g. the frequency expected at a stress).

        Parameters
        ----------
        y : array_like
            Values of the calibrated quantity (stress [Pa]).
        points : int
            Grid points over the calibrated readout range used for the inversion.

        Returns
        -------
        ndarray
            Readout [unit of x]; NaN where ``y`` lies outside the calibrated range.

        Raises
        ------
        ValueError
            If the polynomial is not monotonic over the calibrated range (no unique inverse).

        Notes
        -----
        The polynomial is evaluated on a fine grid of the calibrated readout range and inverted by
        linear interpolation; with 8193 points the interpolation error is below 1e-7 of the range
        for a degree-5 polynomial.
        """
        xs = np.linspace(self.model.center - self.model.half_width, self.model.center + self.model.half_width, points)
        ys = self.model(xs)
        d = np.diff(ys)
        if not (np.all(d > 0) or np.all(d < 0)):
            raise ValueError(f"the degree-{self.degree} calibration is not monotonic over its readout range; "
                             "it has no unique inverse")
        if d[0] < 0:
            xs, ys = xs[::-1], ys[::-1]
        yv = np.asarray(y, dtype=float)
        return np.interp(yv, ys, xs, left=np.nan, right=np.nan)

    def to_dict(self) -> dict[str, Any]:
        """The calibration file's content."""
        d = {
            "format": CALIBRATION_FORMAT,
            "version": 1,
            "model": "polynomial",
            "basis": "chebyshev",
            "x": self.x_name, "y": self.y_name,
            "units": {"x": self.x_unit, "y": self.y_unit},
            "degree": self.degree,
            "chebyshev_coefficients": self.model.coefficients.tolist(),
            "x_center": self.model.center,
            "x_half_width": self.model.half_width,
            "coefficients": self.model.power_coefficients().tolist(),
            "coefficients_note": "y = sum(coefficients[k] * x**k); evaluation uses the Chebyshev form (better conditioned)",
            "metrics": {"r2": self.r2, "rmse": self.rmse, "max_error_percent_fs": self.max_error_percent_fs, "n": self.n},
            "cross_validation": None if self.cv is None else {
                "degrees": self.cv.degrees, "rmse": self.cv.rmse, "folds": self.cv.folds, "groups": self.cv.groups},
            "data_fingerprint": self.data_fingerprint,
            "created": self.created,
            "decode": self.decode,
            "source": self.source,
        }
        d.update(self.extra)
        return d


def _finite_pairs(x, y):
    x, y = _prepare(x, y)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3:
        raise ValueError("x, y: fewer than 3 readings with both values present")
    return ok


def calibrate(x, y, degree: int | str = "auto", groups=None, folds: int = 5, x_name: str = "frequency_hz",
              y_name: str = "stress_pa", x_unit: str = "Hz", y_unit: str = "Pa", source: str = "",
              decode: dict | None = None) -> Calibration:
    """Fit y(x) as a polynomial, choosing the degree by grouped cross-validation.

    Parameters
    ----------
    x : array_like
        Readout (or the reference for an inverse model). Rows where x or y is NaN are skipped.
    y : array_like
        Reference stress [Pa] (or the readout for an inverse model).
    degree : int or "auto"
        1..5, or ``"auto"``: the lowest degree whose out-of-fold RMSE is within 1 % of the
        smallest (grouped cross-validation, see :func:`cross_validate_degrees`).
    groups : array_like, optional
        Group (cycle) of each reading for the folds (see :func:`default_groups`); default:
        contiguous blocks in time order.
    folds : int
        Folds of the cross-validation (≥ 2).
    x_name, y_name, x_unit, y_unit : str
        Names and units recorded in the calibration.
    source : str
        Provenance recorded in the calibration.
    decode : dict, optional
        Circuit used to decode x (physics-informed option), recorded as is.

    Returns
    -------
    Calibration
    """
    x, y = _prepare(x, y)
    ok = _finite_pairs(x, y)
    xs, ys = x[ok], y[ok]
    g = default_groups(x.size, None, folds) if groups is None else np.asarray(groups)
    if g.shape != x.shape:
        raise ValueError("groups must have one label per reading")
    g = g[ok]
    center, half = _scaling(xs)
    cv = None
    if isinstance(degree, str):
        if degree != "auto":
            raise ValueError(f"degree must be an integer from 1 to {MAX_DEGREE} or 'auto', got {degree!r}")
        cv = cross_validate_degrees(xs, ys, g, folds=folds, center=center, half_width=half)
        degree = cv.best_degree
        # Final fit from the same sums (the Chebyshev Gram matrix on [-1, 1] is well conditioned).
        model = PolynomialModel(coefficients=cv.full_fit(degree), center=center, half_width=half)
    else:
        model = fit_polynomial(xs, ys, degree, center, half)
    met = fit_metrics(ys, model(xs))
    return Calibration(model=model, x_name=x_name, y_name=y_name, x_unit=x_unit, y_unit=y_unit, r2=met["r2"],
                       rmse=met["rmse"], max_error_percent_fs=met["max_error_percent_fs"], n=int(xs.size),
                       data_fingerprint=fingerprint(xs, ys),
                       created=datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z"),
                       cv=cv, decode=decode, source=source)


def save_calibration(cal: Calibration, path: str | os.PathLike) -> Path:
    """Write a calibration to a JSON file.

    Parameters
    ----------
    cal : Calibration
    path : str or path-like

    Returns
    -------
    Path
    """
    p = Path(path)
    p.write_text(json.dumps(cal.to_dict(), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return p


def load_calibration(path: str | os.PathLike) -> Calibration:
    """Read a calibration written by :func:`save_calibration`.

    Parameters
    ----------
    path : str or path-like
        The JSON file.

    Returns
    -------
    Calibration

    Raises
    ------
    ValueError
        One line naming the file and what is wrong.
    """
    p = Path(path)
    try:
        d = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{p}: not a JSON calibration file ({exc})") from None
    if not isinstance(d, dict) or d.get("format") != CALIBRATION_FORMAT:
        raise ValueError(f"{p}: not an fsrlab calibration (\"format\" must be {CALIBRATION_FORMAT!r})")
    if d.get("version") != 1:
        raise ValueError(f"{p}: calibration version {d.get('version')!r} not supported (version 1 is)")
    try:
        model = PolynomialModel(np.asarray(d["chebyshev_coefficients"], dtype=float), float(d["x_center"]),
                                float(d["x_half_width"]))
        met = d.get("metrics", {})
        cvd = d.get("cross_validation")
        cv = None if not cvd else CrossValidation(cvd["degrees"], cvd["rmse"], cvd["folds"], cvd["groups"],
                                                  int(d["degree"]))
        known = set(Calibration(model, "", "", "", "", 0, 0, 0, 0, "", "").to_dict())
        extra = {k: v for k, v in d.items() if k not in known}
        return Calibration(model=model, x_name=d["x"], y_name=d["y"], x_unit=d["units"]["x"], y_unit=d["units"]["y"],
                           r2=met.get("r2", float("nan")), rmse=met.get("rmse", float("nan")),
                           max_error_percent_fs=met.get("max_error_percent_fs", float("nan")), n=met.get("n", 0),
                           data_fingerprint=d.get("data_fingerprint", ""), created=d.get("created", ""), cv=cv,
                           decode=d.get("decode"), source=d.get("source", ""), extra=extra)
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{p}: calibration file incomplete or malformed ({type(exc).__name__}: {exc})") from None


def run_groups(stress_pa, cycle=None, direction=None, folds: int = 5, threshold: float = 0.05) -> np.ndarray:
    """Cross-validation groups for a run: its cycles, kept whole.

    Parameters
    ----------
    stress_pa : array_like
        Reference stress in time order. [Pa]
    cycle : array_like, optional
        The run's ``cycle`` column (used when it has ≥ 2 values).
    direction : array_like, optional
        The run's ``direction`` column (else branches come from the stress).
    folds : int
        Contiguous blocks to use when the run has fewer than 2 cycles.
    threshold : float
        Reversal threshold for cycles found from the stress. [1]

    Returns
    -------
    ndarray of int
        Group of each reading: a new group starts at each loading start (unloading → loading).
    """
    from fsrlab.analysis.cycles import branch_directions

    x = np.asarray(stress_pa, dtype=float)
    if cycle is not None and np.unique(np.asarray(cycle, dtype=float)[np.isfinite(cycle)]).size >= 2:
        return default_groups(x.size, cycle, folds)
    if direction is not None:
        lab = np.nan_to_num(np.asarray(direction, dtype=float)).astype(int)
    else:
        ok = np.isfinite(x)
        lab = np.zeros(x.size, dtype=int)
        if ok.sum() >= 2:
            lab[ok] = branch_directions(x[ok], threshold)
    nz = np.flatnonzero(lab != 0)
    starts = np.zeros(x.size, dtype=int)
    if nz.size > 1:
        rise = nz[1:][(lab[nz[1:]] == 1) & (lab[nz[:-1]] == -1)]
        starts[rise] = 1
    g = np.cumsum(starts)
    return g if g.max(initial=0) >= 1 else default_groups(x.size, None, folds)


def decode_capacitance(frequency_hz, duty_cycle, r_ohm: float, c_off_farad: float = 0.0, diode: bool = True,
                       diode_drop_v: float = 0.0) -> np.ndarray:
    """C_FSR decoded from frequency and duty cycle (physics-informed calibration variable).

    Parameters
    ----------
    frequency_hz, duty_cycle : array_like
        555 readings (NaN where missing).
    r_ohm : float
        R of the astable (paper Fig. 16: 10 kΩ). [Ω]
    c_off_farad : float
        Offset capacitor in parallel with the FSR. [F]
    diode : bool
        D1 present (paper Fig. 16).
    diode_drop_v : float
        Forward drop of D1. [V]

    Returns
    -------
    ndarray
        C_FSR [F] by :func:`fsrlab.circuits.decode.decode`; NaN where a reading is missing or is
        impossible for the circuit (e.g. one noisy duty cycle outside the reachable range), so that
        one bad window does not stop a whole run.
    """
    from fsrlab.circuits.decode import decode
    f = np.asarray(frequency_hz, dtype=float)
    d = np.asarray(duty_cycle, dtype=float)
    out = np.full(f.shape, np.nan)
    ok = np.isfinite(f) & np.isfinite(d)
    if ok.any():
        res = decode(f[ok], d[ok], r_ohm, c_off_farad=c_off_farad, diode=diode, diode_drop_v=diode_drop_v, check=False)
        out[ok] = np.asarray(res.c_fsr_farad, dtype=float)
    return out
