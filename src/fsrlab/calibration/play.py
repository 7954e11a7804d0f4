"""Causal hysteresis compensation with memory: play operators (Prandtl–Ishlinskii), fitted by least squares.

**Extension beyond the paper.** The compensation runs forward in time on the readout
alone, sample by sample, so it works live (``fsrlab measure``) and on any run -- hand-loaded runs
with reversals of every size included -- without finding cycles or branches.

Model. Let ``w = ŷ₀(x)/FS`` be the plain calibration's estimate (:mod:`fsrlab.calibration.models`)
as a fraction of full scale. A play (backlash) operator of threshold r holds a state p that
follows w only when w leaves the band ``[p − r, p + r]``::

    p_t = max(w_t − r, min(w_t + r, p_{t−1}))

so ``p − w`` lies in ``[−r, r]`` and remembers the last reversal larger than 2r: a set of
operators with thresholds from 0.5 % to 32 % of full scale remembers the turning points of every
size (the wiping-out and congruency of Preisach models hold for this class). The estimate is::

    y/FS = Σ_k a_k w^k + Σ_j (b_j + c_j·w)·(p_j − w) + Σ_m (e_m + f_m·w)·(s_m − w)

with ``k ≤ 3`` (the shape left over by the plain model), the hysteresis terms of the play
operators (their weight allowed to grow with the level), and, where cross-validation supports it,
creep terms: exponential averages ``s_m`` of w with time constants of 2 s and 20 s, their weight
also allowed to grow with the level (FSR creep is stated in % of the reading). All weights
come from one linear least-squares fit (a small ridge term keeps it regular); the operators'
memory is computed once, so grouped cross-validation only refits the weights.

Noise: an operator does not move while w stays inside its band, so readout noise smaller than the
smallest threshold (0.5 % of full scale) causes no false reversal; larger noise enters each
operator as a small, bounded wobble, not as a switched branch (the "backwards slips" that break
cycle detection). Why this model: on the hand-loaded runs of :mod:`fsrlab.virtual.handloaded`
(a Bouc–Wen sensor, i.e. not this model) the earlier branch polynomials with turning-point memory
(:mod:`fsrlab.calibration.compensation`) cannot be fitted at all (no whole cycles) and make a slow
motor cycle worse (HE 13.7 → 22.2 %), while play operators need no cycles and bring the
cross-validated error from 3.1 % to 1.4 % of full scale (0.9 % with the creep terms) and that
cycle's HE to 2.3 % (docs/calibration.md).

The uncertainty table is :mod:`fsrlab.calibration.uncertainty`; the estimator that steps the compensation one
reading at a time is :mod:`fsrlab.calibration.estimator`.

References
----------
M. Brokate, J. Sprekels, *Hysteresis and Phase Transitions*, Springer 1996, ch. 2 (play
operators, Prandtl–Ishlinskii). A. Matute et al., J. Sensors 2018, doi:10.1155/2018/6561901, eq. (13).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["THRESHOLDS", "THRESHOLDS_WIDE", "CREEP_TIME_CONSTANTS_S", "DIRECTION_THRESHOLD", "CausalState", "MemoryModel",
           "MemoryFit", "causal_features", "fold_assignment", "fit_memory"]

#: Play-operator thresholds, fractions of full scale. [1]
THRESHOLDS = (0.005, 0.01, 0.02, 0.04, 0.08, 0.16, 0.32)
#: The wider set, also tried: an operator of threshold 0.5 remembers reversals of the whole range. [1]
THRESHOLDS_WIDE = THRESHOLDS + (0.5,)
#: Time constants of the creep terms. [s]
CREEP_TIME_CONSTANTS_S = (2.0, 20.0)
#: Threshold of the play operator that tells the direction (loading, unloading, still). [1]
DIRECTION_THRESHOLD = 0.01
#: Relative ridge term of the least-squares fit. [1]
RIDGE = 1e-8


class CausalState:
    """The memory of the causal model: play operators, exponential averages, the direction.

    Parameters
    ----------
    thresholds : sequence of float
        Play thresholds (fractions of full scale). [1]
    alphas : sequence of float
        Smoothing factor per row of each exponential average (``1 − exp(−Δt/τ)``). [1]
    """

    def __init__(self, thresholds, alphas):
        self.r = [float(v) for v in thresholds]
        self.alphas = [float(a) for a in alphas]
        self.p: list[float] | None = None
        self.s: list[float] = []
        self.pd = 0.0
        self.direction = 0

    def advance(self, w: float) -> None:
        """Take one reading ``w`` (a fraction of full scale, finite) into the memory."""
        if self.p is None:
            # The sensor starts from rest (w = 0): each operator starts as if loaded from 0 to w.
            self.p = [w - r if w - r > 0.0 else 0.0 for r in self.r]
            self.s = [w for _ in self.alphas]
            self.pd = w - DIRECTION_THRESHOLD if w - DIRECTION_THRESHOLD > 0.0 else 0.0
            self.direction = 1 if w > DIRECTION_THRESHOLD else 0
            return
        p = self.p
        for j, r in enumerate(self.r):
            lo, hi = w - r, w + r
            q = p[j]
            p[j] = lo if lo > q else (hi if hi < q else q)
        s = self.s
        for m, a in enumerate(self.alphas):
            s[m] = s[m] + a * (w - s[m])
        lo, hi = w - DIRECTION_THRESHOLD, w + DIRECTION_THRESHOLD
        if lo > self.pd:
            self.pd, self.direction = lo, 1
        elif hi < self.pd:
            self.pd, self.direction = hi, -1
        else:
            self.direction = 0


def causal_features(w, thresholds, alphas) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Play-operator states, exponential averages and directions along a sequence, in row order.

    Parameters
    ----------
    w : array_like
        The plain estimate as a fraction of full scale, in time order; NaN rows are skipped (the
        memory is kept across them) and give NaN.
    thresholds, alphas : sequence of float
        See :class:`CausalState`.

    Returns
    -------
    p : ndarray, shape (n, len(thresholds))
    s : ndarray, shape (n, len(alphas))
    direction : ndarray of int, shape (n,)
        +1 loading, −1 unloading, 0 still or missing.
    """
    w = np.asarray(w, dtype=float)
    n = w.size
    thresholds = [float(v) for v in thresholds]
    alphas = [float(a) for a in alphas]
    p = np.full((n, len(thresholds)), np.nan)
    s = np.full((n, len(alphas)), np.nan)
    d = np.zeros(n, dtype=int)
    rows = np.flatnonzero(np.isfinite(w))  # NaN rows are gaps: skipped, the memory kept
    if rows.size == 0:
        return p, s, d
    wl = w[rows].tolist()
    w0 = wl[0]
    # The same arithmetic as CausalState.advance, one operator at a time (fast in pure Python).
    for j, r in enumerate(thresholds):
        q = w0 - r if w0 - r > 0.0 else 0.0
        out = [q]
        for wi in wl[1:]:
            lo, hi = wi - r, wi + r
            q = lo if lo > q else (hi if hi < q else q)
            out.append(q)
        p[rows, j] = out
    for m, a in enumerate(alphas):
        q = w0
        out = [q]
        for wi in wl[1:]:
            q = q + a * (wi - q)
            out.append(q)
        s[rows, m] = out
    r = DIRECTION_THRESHOLD
    q = w0 - r if w0 - r > 0.0 else 0.0
    dirs = [1 if w0 > r else 0]
    for wi in wl[1:]:
        lo, hi = wi - r, wi + r
        if lo > q:
            q = lo
            dirs.append(1)
        elif hi < q:
            q = hi
            dirs.append(-1)
        else:
            dirs.append(0)
    d[rows] = dirs
    return p, s, d


def _design(w: np.ndarray, p: np.ndarray, s: np.ndarray, degree: int) -> np.ndarray:
    """Columns w^0..w^degree, (p_j − w), w·(p_j − w), (s_m − w), w·(s_m − w)."""
    w = np.asarray(w, dtype=float)
    cols = [w ** k for k in range(degree + 1)]
    hyst = p - w[:, None]
    creep = s - w[:, None]
    return np.column_stack(cols + [hyst, w[:, None] * hyst, creep, w[:, None] * creep])


@dataclass(frozen=True)
class MemoryModel:
    """The fitted causal compensation (see the module's docstring).

    Parameters
    ----------
    full_scale : float
        FS: w = ŷ₀/FS. [unit of y]
    thresholds : tuple of float
        Play thresholds. [1]
    time_constants_s : tuple of float
        Creep time constants (empty: no creep term). [s]
    row_s : float
        Row period the exponential averages assume. [s]
    degree : int
        Degree of the polynomial in w.
    coefficients : ndarray
        Weights of the design columns. [1]
    """

    full_scale: float
    thresholds: tuple
    time_constants_s: tuple
    row_s: float
    degree: int
    coefficients: np.ndarray

    @property
    def alphas(self) -> tuple:
        """Exponential-average factor per row of each creep term. [1]"""
        return tuple(1.0 - math.exp(-self.row_s / tau) for tau in self.time_constants_s)

    def estimate(self, w, p, s) -> np.ndarray:
        """y from w and the operator states (arrays in row order). [unit of y]"""
        return self.full_scale * (_design(w, p, s, self.degree) @ self.coefficients)

    def step_estimate(self, w: float, state: CausalState) -> float:
        """y of one reading after ``state.advance(w)``, in plain Python (the live path). [unit of y]"""
        c = self.coefficients.tolist()
        total, wk = 0.0, 1.0
        for k in range(self.degree + 1):
            total += c[k] * wk
            wk *= w
        i = self.degree + 1
        n = len(state.p)
        for j, pj in enumerate(state.p):
            h = pj - w
            total += c[i + j] * h + c[i + n + j] * (w * h)
        i += 2 * n
        n = len(state.s)
        for m, sm in enumerate(state.s):
            h = sm - w
            total += c[i + m] * h + c[i + n + m] * (w * h)
        return self.full_scale * total

    def to_dict(self) -> dict:
        """JSON form."""
        return {"model": "play operators (Prandtl-Ishlinskii), causal, least squares (fsrlab extension)",
                "full_scale": self.full_scale, "thresholds": list(self.thresholds),
                "time_constants_s": list(self.time_constants_s), "row_s": self.row_s, "degree": self.degree,
                "coefficients": self.coefficients.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> "MemoryModel":
        """Inverse of :meth:`to_dict`."""
        coef = np.asarray(d["coefficients"], dtype=float)
        thr = tuple(float(v) for v in d["thresholds"])
        taus = tuple(float(v) for v in d["time_constants_s"])
        fs, row_s, deg = float(d["full_scale"]), float(d["row_s"]), int(d["degree"])
        if coef.size != deg + 1 + 2 * len(thr) + 2 * len(taus) or not np.all(np.isfinite(coef)):
            raise ValueError("memory coefficients: wrong number or not finite")
        if not (fs > 0 and row_s > 0 and all(r > 0 for r in thr) and all(t > 0 for t in taus)):
            raise ValueError("memory: full_scale, row_s, thresholds and time constants must be > 0")
        return cls(fs, thr, taus, row_s, deg, coef)


def _solve(ata: np.ndarray, atb: np.ndarray) -> np.ndarray:
    """Ridge-regularised normal equations (the ridge relative to the Gram matrix's mean diagonal)."""
    lam = RIDGE * np.trace(ata) / ata.shape[0]
    return np.linalg.solve(ata + lam * np.eye(ata.shape[0]), atb)


def _lstsq(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return _solve(a.T @ a, a.T @ b)


@dataclass
class MemoryFit:
    """The compensation chosen by cross-validation, and every variant's error.

    Parameters
    ----------
    model : MemoryModel or None
        The chosen compensation (None: the plain model was best).
    candidates : dict
        Cross-validated RMSE of ``plain`` and of each variant: play operators to 32 % or to 50 % of
        full scale, each with or without the creep terms. [unit of y]
    oof : ndarray
        Out-of-fold estimate of every row (of the chosen variant). [unit of y]
    direction : ndarray of int
        Direction of every row (see :func:`causal_features`).
    fitted : ndarray
        In-sample estimate of the rows fitted (NaN elsewhere). [unit of y]
    """

    model: MemoryModel | None
    candidates: dict
    oof: np.ndarray
    direction: np.ndarray = field(repr=False, default=None)
    fitted: np.ndarray = field(repr=False, default=None)


def fold_assignment(groups, use, folds: int) -> tuple[np.ndarray, int]:
    """The folds of the grouped cross-validation: whole groups, dealt round-robin in group order.

    Parameters
    ----------
    groups : array_like of int
        Group of every row (whole cycles or time blocks).
    use : array_like of bool
        Rows that take part.
    folds : int
        Folds wanted.

    Returns
    -------
    fold : ndarray of int
        Fold of each used row (in row order of ``use``).
    k : int
        Folds made, ``min(folds, groups among the used rows)``.

    Raises
    ------
    ValueError
        Fewer than 2 groups among the used rows.
    """
    _, gi = np.unique(np.asarray(groups)[np.asarray(use, bool)], return_inverse=True)
    k = min(folds, int(gi.max(initial=0)) + 1)
    if k < 2:
        raise ValueError("groups: cross-validation needs at least 2 groups (cycles or blocks)")
    return (np.arange(int(gi.max()) + 1) % k)[gi], k


def fit_memory(w, y, usable, groups, full_scale: float, row_s: float, folds: int = 5, degree: int = 3,
               plain_oof=None, force: bool = True) -> MemoryFit:
    """Fit the causal compensation on a run (any run with a reference) and choose its variant by CV.

    Parameters
    ----------
    w : array_like
        Plain estimate / FS for every row in time order (0 at the floor, NaN where missing).
    y : array_like
        The (aligned) reference. [unit of y]
    usable : array_like of bool
        Rows that enter the fit (finite, not at the floor).
    groups : array_like of int
        Cross-validation groups (whole cycles or time blocks).
    full_scale : float
        FS. [unit of y]
    row_s : float
        Row period. [s]
    folds : int
        Folds.
    degree : int
        Degree of the polynomial in w.
    plain_oof : array_like, optional
        Out-of-fold estimate of the plain model (its ``plain`` candidate).
    force : bool
        Keep the play-operator model even where the plain one cross-validates better.

    Returns
    -------
    MemoryFit
    """
    w = np.asarray(w, dtype=float)
    y = np.asarray(y, dtype=float)
    use = np.asarray(usable, bool) & np.isfinite(w) & np.isfinite(y)
    variants = {"play operators": (THRESHOLDS, ()), "play operators + creep": (THRESHOLDS, CREEP_TIME_CONSTANTS_S),
                "play operators to 50 %": (THRESHOLDS_WIDE, ()),
                "play operators to 50 % + creep": (THRESHOLDS_WIDE, CREEP_TIME_CONSTANTS_S)}
    alphas = tuple(1.0 - math.exp(-row_s / tau) for tau in CREEP_TIME_CONSTANTS_S)
    p_all, s, direction = causal_features(w, THRESHOLDS_WIDE, alphas)
    fold, k = fold_assignment(groups, use, folds)
    cands = {}
    if plain_oof is not None:
        po = np.asarray(plain_oof, float)[use]
        cands["plain"] = float(np.sqrt(np.mean((po - y[use]) ** 2)))
    best = None
    for name, (thr, taus) in variants.items():
        ss = s if taus else s[:, :0]
        p = p_all[:, : len(thr)]
        a = _design(w[use], p[use], ss[use], degree)
        b = y[use] / full_scale
        oof = np.empty(b.size)
        # Per-fold sums once: each training fold's normal equations are the total minus its own.
        parts = [fold == f for f in range(k)]
        grams = [a[m].T @ a[m] for m in parts]
        rhs = [a[m].T @ b[m] for m in parts]
        gram_all, rhs_all = sum(grams), sum(rhs)
        for f, m in enumerate(parts):
            oof[m] = a[m] @ _solve(gram_all - grams[f], rhs_all - rhs[f])
        e = float(full_scale * np.sqrt(np.mean((oof - b) ** 2)))
        cands[name] = e
        if best is None or e < best[1]:
            best = (name, e, thr, taus, a, b, oof * full_scale)
    name, e, thr, taus, a, b, oof_u = best
    oof_all = np.full(w.size, np.nan)
    if not force and "plain" in cands and cands["plain"] <= e:
        oof_all[use] = np.asarray(plain_oof, float)[use]
        return MemoryFit(None, cands, oof_all, direction)
    coef = _lstsq(a, b)
    oof_all[use] = oof_u
    model = MemoryModel(float(full_scale), tuple(thr), tuple(taus), float(row_s), degree, coef)
    fitted = np.full(w.size, np.nan)
    fitted[use] = full_scale * (a @ coef)
    return MemoryFit(model, cands, oof_all, direction, fitted)
