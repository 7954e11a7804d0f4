"""Model families of a calibration and their choice by grouped cross-validation.

**Extension beyond the paper.** Besides polynomials in the readout (the paper's
Figure 17, :mod:`fsrlab.calibration.polynomial`), a calibration can go through the FSR's
conductance, where FSRs are close to a power law:

* ``polynomial-k``: ``y = Σ c_j T_j(x)``, k = 1..5, in the readout x;
* ``conductance-power``: ``y = c + a·G^b`` with G the conductance the readout circuit gives
  (voltage divider ``G = V/(R_M·(Vcc − V))``; the paper's op-amp, eq. (38) inverted,
  :meth:`fsrlab.circuits.circuit.OpAmpReadout.conductance_s`; decoded C_FSR for the 555, where the
  capacitance plays the part of G);
* ``conductance-polynomial-k``: a polynomial of degree 1..3 in G;
* ``power``: ``y = c + a·u^b`` with u the readout measured from its floor (no circuit needed).

Readings at the floor (the dead zone: an FSR below its activation force reads the circuit's
floor, e.g. 0 V) are found from the data (:func:`find_floor`) and left out: they map to "below
activation", not to a number.

Cross-validation keeps groups (cycles or time blocks) whole: group g goes to fold g mod k, as in
:func:`fsrlab.calibration.polynomial.cross_validate_degrees`. The power law's exponent is chosen per
training fold from a grid of 61 exponents (0.2 to 5, geometric), the other two parameters by least
squares, from per-fold sums (one pass per exponent).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fsrlab.calibration.polynomial import PolynomialModel, cross_validate_degrees, fit_polynomial

__all__ = ["Floor", "find_floor", "resolution", "ConductanceTransform", "transform_from_metadata", "FamilyModel",
           "Candidate", "FamilySelection", "cross_validate_families", "fit_family", "POWER_EXPONENTS"]

#: Exponents tried by the power law. [1]
POWER_EXPONENTS = np.geomspace(0.2, 5.0, 61)


def resolution(x) -> float:
    """Smallest step between distinct readings (the ADC step for a quantized readout). [unit of x]

    Parameters
    ----------
    x : array_like
        Readings (NaN ignored).

    Returns
    -------
    float
        The smallest positive difference of the sorted distinct values, at least 1e-12 of their
        span (0 when fewer than two distinct readings).
    """
    u = np.unique(np.asarray(x, dtype=float)[np.isfinite(x)])
    if u.size < 2:
        return 0.0
    d = np.diff(u)
    return float(max(d.min(), 1e-12 * (u[-1] - u[0])))


@dataclass(frozen=True)
class Floor:
    """The readout's floor: readings at it mean "below the activation force".

    Parameters
    ----------
    threshold : float
        Readings at or beyond it (towards the floor) are below activation. [unit of x]
    sign : float
        +1 if the readout grows with the reference (floor = lowest readings), −1 if it falls.
    activation : float
        The reference below which the sensor reads its floor (90th percentile of the reference at
        floor readings). [unit of y]
    fraction : float
        Share of the calibration readings at the floor. [1]
    """

    threshold: float
    sign: float
    activation: float
    fraction: float

    def below(self, x) -> np.ndarray:
        """True where a reading is at the floor."""
        return self.sign * (np.asarray(x, dtype=float) - self.threshold) <= 0

    def to_dict(self) -> dict:
        """JSON form."""
        return {"threshold": self.threshold, "sign": self.sign, "activation": self.activation,
                "fraction": self.fraction}

    @classmethod
    def from_dict(cls, d: dict) -> "Floor":
        """Inverse of :meth:`to_dict`."""
        return cls(*(float(d[k]) for k in ("threshold", "sign", "activation", "fraction")))


def find_floor(x, y, min_fraction: float = 0.01) -> Floor | None:
    """The readout's floor, when the data show one (a dead zone).

    Parameters
    ----------
    x, y : array_like
        Readout and reference, finite.
    min_fraction : float
        Least share of readings at the floor for it to count. [1]

    Returns
    -------
    Floor or None
        A floor when at least ``min_fraction`` of the readings (and at least 3, and 5 times as many
        as the median count of a distinct reading) lie within half a resolution step of the
        readout's low-force end (the end where the reference is low) and the reference there lies
        in the lower half of its range; else None.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.size < 10:
        return None
    sign = 1.0 if np.corrcoef(x, y)[0, 1] >= 0 else -1.0
    end = x.min() if sign > 0 else x.max()
    q = resolution(x)
    at = np.abs(x - end) <= 0.5 * q + 1e-12 * max(abs(end), 1.0)
    frac = float(at.mean())
    _, counts = np.unique(x, return_counts=True)
    # A floor is a value the readout sticks at: far more often than a typical reading.
    if frac < min_fraction or at.sum() < max(3, 5 * float(np.median(counts))):
        return None
    lo, hi = np.percentile(y, [1, 99])
    act = float(np.percentile(y[at], 90))
    if act > lo + 0.5 * (hi - lo):
        return None
    return Floor(threshold=float(end + sign * 0.5 * q), sign=sign, activation=act, fraction=frac)


@dataclass(frozen=True)
class ConductanceTransform:
    """Readout → FSR conductance through the readout circuit.

    Parameters
    ----------
    topology : str
        ``"divider"`` (FSR on the high side, R_M to ground), ``"opamp-inverting"`` (eq. 38) or
        ``"capacitance"`` (decoded C_FSR, used as it is).
    r_ohm : float
        R_M of the divider or R_F of the op-amp (unused for capacitance). [Ω]
    vcc_v : float
        Supply of the divider, drive of the op-amp. [V]
    counts_full_scale : float
        For a divider read in ADC counts: the count at Vcc (1023 for a 10-bit ``analogRead``
        referenced to the divider's supply); 0: the readout is in volts. [1]
    """

    topology: str
    r_ohm: float = float("nan")
    vcc_v: float = float("nan")
    counts_full_scale: float = 0.0

    def __call__(self, x) -> np.ndarray:
        """Conductance [S] (capacitance [F] for ``"capacitance"``); NaN where impossible."""
        x = np.asarray(x, dtype=float)
        if self.counts_full_scale > 0:
            x = x * (self.vcc_v / self.counts_full_scale)  # ADC counts -> V (Vcc is the reference)
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.topology == "divider":
                g = x / (self.r_ohm * (self.vcc_v - x))  # V = Vcc·R_M·G/(1 + R_M·G) inverted
            elif self.topology == "opamp-inverting":
                g = -x / (self.r_ohm * self.vcc_v)  # Eq. (38) inverted
            else:
                g = x.copy()
        return np.where(np.isfinite(g) & (g >= 0), g, np.nan)

    def to_dict(self) -> dict:
        """JSON form."""
        return {"topology": self.topology, "r_ohm": self.r_ohm, "vcc_v": self.vcc_v,
                "counts_full_scale": self.counts_full_scale}

    @classmethod
    def from_dict(cls, d: dict) -> "ConductanceTransform":
        """Inverse of :meth:`to_dict`."""
        topo = str(d["topology"])
        if topo not in ("divider", "opamp-inverting", "capacitance"):
            raise ValueError(f"conductance topology must be divider, opamp-inverting or capacitance, got {topo!r}")
        full = float(d.get("counts_full_scale", 0.0))
        if not (np.isfinite(full) and full >= 0):
            raise ValueError("counts_full_scale must be a count >= 0")
        return cls(topo, float(d.get("r_ohm", float("nan"))), float(d.get("vcc_v", float("nan"))), full)


def transform_from_metadata(x_name: str, metadata: dict) -> ConductanceTransform | None:
    """The conductance transform a run's sidecar allows for readout ``x_name``, or None.

    Parameters
    ----------
    x_name : str
        The readout column (``voltage_v`` with a ``divider`` or ``opamp`` sidecar entry; the
        divider's ``column`` when it is read in ADC counts; ``c_fsr_farad``).
    metadata : dict
        The run's sidecar: ``divider`` = ``{"r_m_ohm", "vcc_v"[, "adc_bits", "column"]}`` (a
        readout column named by ``column`` holds ``analogRead`` counts of ``adc_bits`` bits, 10 by
        default, referenced to ``vcc_v``), ``opamp`` (see :class:`fsrlab.circuits.circuit.OpAmpReadout`).

    Returns
    -------
    ConductanceTransform or None
    """
    if x_name == "c_fsr_farad":
        return ConductanceTransform("capacitance")
    div = (metadata or {}).get("divider")
    counts = isinstance(div, dict) and div.get("column") == x_name and x_name != "voltage_v"
    if x_name != "voltage_v" and not counts:
        return None
    if isinstance(div, dict) and "r_m_ohm" in div:
        try:
            r, v = float(div["r_m_ohm"]), float(div.get("vcc_v", 5.0))
            full = float(2 ** int(div.get("adc_bits", 10)) - 1) if counts else 0.0
        except (TypeError, ValueError):
            return None
        if np.isfinite(r) and r > 0 and np.isfinite(v) and v > 0:
            return ConductanceTransform("divider", r, v, full)
    if counts:
        return None
    try:
        from fsrlab.circuits.circuit import readout_from_metadata

        _, opamp = readout_from_metadata(metadata)
    except ValueError:
        return None
    if opamp is not None:
        return ConductanceTransform("opamp-inverting", opamp.r_f_ohm, opamp.vcc_v)
    return None


@dataclass(frozen=True)
class FamilyModel:
    """One fitted member of a model family: y(x).

    Parameters
    ----------
    family : str
        ``"polynomial"``, ``"conductance-polynomial"``, ``"conductance-power"`` or ``"power"``.
    params : dict
        Polynomial: ``chebyshev_coefficients``, ``center``, ``half_width`` (in the family's
        variable); power: ``a``, ``b``, ``c``, ``scale`` (``y = c + a·(u/scale)^b``).
    transform : ConductanceTransform, optional
        For the conductance families.
    origin : float
        For ``"power"``: u = sign·(x − origin). [unit of x]
    sign : float
        For ``"power"``: +1 if the readout grows with y.
    """

    family: str
    params: dict
    transform: ConductanceTransform | None = None
    origin: float = 0.0
    sign: float = 1.0

    @property
    def name(self) -> str:
        """``polynomial-3``, ``conductance-power``, ..."""
        if self.family.endswith("polynomial"):
            return f"{self.family}-{len(self.params['chebyshev_coefficients']) - 1}"
        return self.family

    def variable(self, x) -> np.ndarray:
        """The family's variable: the readout, its conductance, or the readout above its floor."""
        x = np.asarray(x, dtype=float)
        if self.transform is not None:
            return self.transform(x)
        if self.family == "power":
            return np.clip(self.sign * (x - self.origin), 0.0, None)
        return x

    def __call__(self, x) -> np.ndarray:
        """y at readout x."""
        u = self.variable(x)
        p = self.params
        if "chebyshev_coefficients" in p:
            return PolynomialModel(np.asarray(p["chebyshev_coefficients"], float), p["center"], p["half_width"])(u)
        with np.errstate(invalid="ignore", over="ignore"):
            return p["c"] + p["a"] * (u / p["scale"]) ** p["b"]

    def to_dict(self) -> dict:
        """JSON form."""
        params = {k: (list(map(float, v)) if isinstance(v, (list, np.ndarray)) else float(v))
                  for k, v in self.params.items()}
        return {"family": self.family, "params": params,
                "transform": None if self.transform is None else self.transform.to_dict(),
                "origin": self.origin, "sign": self.sign}

    @classmethod
    def from_dict(cls, d: dict) -> "FamilyModel":
        """Inverse of :meth:`to_dict`."""
        fam = str(d["family"])
        if fam not in ("polynomial", "conductance-polynomial", "conductance-power", "power"):
            raise ValueError(f"model family {fam!r} unknown")
        params = {k: (np.asarray(v, float) if isinstance(v, list) else float(v)) for k, v in d["params"].items()}
        for v in params.values():
            if not np.all(np.isfinite(v)):
                raise ValueError("model parameters must be finite")
        tr = d.get("transform")
        return cls(fam, params, None if tr is None else ConductanceTransform.from_dict(tr), float(d.get("origin", 0.0)),
                   float(d.get("sign", 1.0)))


@dataclass(frozen=True)
class Candidate:
    """A candidate model and its cross-validated error.

    Parameters
    ----------
    name : str
        ``polynomial-3``, ``conductance-power``, ...
    cv_rmse : float
        Pooled out-of-fold RMSE. [unit of y]
    n_params : int
        Number of fitted parameters.
    """

    name: str
    cv_rmse: float
    n_params: int

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"model": self.name, "cv_rmse": self.cv_rmse, "parameters": self.n_params}


def _folds(groups: np.ndarray, folds: int) -> tuple[np.ndarray, int]:
    _, g = np.unique(np.asarray(groups), return_inverse=True)
    k = min(folds, int(g.max()) + 1)
    if k < 2:
        raise ValueError("groups: cross-validation needs at least 2 groups (cycles or blocks)")
    return (np.arange(int(g.max()) + 1) % k)[g], k


def _power_cv(u: np.ndarray, y: np.ndarray, fold: np.ndarray, k: int):
    """Out-of-fold RMSE of y = c + a·(u/s)^b (b per training fold from the grid) and the full fit."""
    scale = float(np.max(u))
    v = u / scale
    n = y.size
    yy = np.bincount(fold, weights=y * y, minlength=k)
    sy = np.bincount(fold, weights=y, minlength=k)
    cnt = np.bincount(fold, minlength=k).astype(float)
    sums = []
    for b in POWER_EXPONENTS:
        p = v ** b
        sums.append((np.bincount(fold, weights=p, minlength=k), np.bincount(fold, weights=p * p, minlength=k),
                     np.bincount(fold, weights=p * y, minlength=k)))
    sp = np.array([s[0] for s in sums])  # (B, k)
    spp = np.array([s[1] for s in sums])
    spy = np.array([s[2] for s in sums])

    def solve(n_, s1, s2, sy_, spy_):
        det = n_ * s2 - s1 * s1
        with np.errstate(divide="ignore", invalid="ignore"):
            a = (n_ * spy_ - s1 * sy_) / det
            c = (sy_ - a * s1) / n_
        return a, c

    sse = 0.0
    for f in range(k):
        tr = lambda s: s.sum(axis=-1) - s[..., f]  # noqa: E731
        a, c = solve(tr(cnt), tr(sp), tr(spp), tr(sy), tr(spy))
        # training SSE per exponent: Σy² − 2aΣpy − 2cΣy + a²Σp² + 2acΣp + c²n
        train = (tr(yy) - 2 * a * tr(spy) - 2 * c * tr(sy) + a * a * tr(spp) + 2 * a * c * tr(sp) + c * c * tr(cnt))
        train = np.where(np.isfinite(train), train, np.inf)
        j = int(np.argmin(train))
        aj, cj = a[j], c[j]
        sse += (yy[f] - 2 * aj * spy[j, f] - 2 * cj * sy[f] + aj * aj * spp[j, f] + 2 * aj * cj * sp[j, f]
                + cj * cj * cnt[f])
    a, c = solve(cnt.sum(), sp.sum(1), spp.sum(1), sy.sum(), spy.sum(1))
    train = yy.sum() - 2 * a * spy.sum(1) - 2 * c * sy.sum() + a * a * spp.sum(1) + 2 * a * c * sp.sum(1) + c * c * n
    j = int(np.argmin(np.where(np.isfinite(train), train, np.inf)))
    params = {"a": float(a[j]), "b": float(POWER_EXPONENTS[j]), "c": float(c[j]), "scale": scale}
    return float(np.sqrt(max(sse, 0.0) / n)), params


@dataclass
class FamilySelection:
    """Every candidate's cross-validated error and the chosen model.

    Parameters
    ----------
    candidates : list of Candidate
        In the order tried.
    best : FamilyModel
        The candidate with the smallest out-of-fold RMSE (within 1 %: the one with fewer parameters).
    best_cv_rmse : float
        Its out-of-fold RMSE. [unit of y]
    models : dict
        Every candidate's model fitted on all readings, by name.
    """

    candidates: list
    best: FamilyModel
    best_cv_rmse: float
    models: dict = field(default_factory=dict, repr=False)


def cross_validate_families(x, y, groups, folds: int = 5, transform: ConductanceTransform | None = None,
                            floor: Floor | None = None, families=("polynomial", "conductance-polynomial",
                                                                  "conductance-power", "power"),
                            degree: int | None = None, tolerance: float = 0.01) -> FamilySelection:
    """Fit every candidate family and choose by grouped cross-validation.

    Parameters
    ----------
    x, y : array_like
        Readout and reference (finite, floor readings already left out).
    groups : array_like of int
        Group of each reading; a group is never split across folds.
    folds : int
        Folds (≥ 2).
    transform : ConductanceTransform, optional
        Readout → conductance; without it the conductance families are not tried.
    floor : Floor, optional
        The readout's floor, the origin of the ``power`` family (else the lowest reading's end).
    families : sequence of str
        Families to try.
    degree : int, optional
        Only ``polynomial-<degree>`` (a degree given by the user).
    tolerance : float
        A candidate with fewer parameters is preferred when within ``(1 + tolerance)`` of the best. [1]

    Returns
    -------
    FamilySelection

    Raises
    ------
    ValueError
        Too few readings for any candidate (message starting ``"degree:"``), fewer than 2 groups.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    g = np.asarray(groups)
    cands: list[Candidate] = []
    models: dict[str, FamilyModel] = {}

    def poly_family(name, u, degrees, tr=None):
        cv = cross_validate_degrees(u, y, g, degrees=degrees, folds=folds, tolerance=0.0)
        lo, hi = float(u.min()), float(u.max())
        for d, e in zip(cv.degrees, cv.rmse):
            m = FamilyModel(name, {"chebyshev_coefficients": cv.full_fit(d), "center": (lo + hi) / 2,
                                   "half_width": (hi - lo) / 2}, tr)
            cands.append(Candidate(m.name, e, d + 1))
            models[m.name] = m

    if degree is not None:
        poly_family("polynomial", x, [degree])
        families = ()
    elif "polynomial" in families:
        poly_family("polynomial", x, range(1, 6))
    if transform is not None and families:
        gx = transform(x)
        ok = np.isfinite(gx)
        if ok.all() and np.ptp(gx) > 0:
            if "conductance-polynomial" in families:
                try:
                    poly_family("conductance-polynomial", gx, range(1, 4), transform)
                except ValueError:
                    pass
            if "conductance-power" in families and gx.min() >= 0:
                fold, k = _folds(g, folds)
                e, params = _power_cv(gx, y, fold, k)
                m = FamilyModel("conductance-power", params, transform)
                cands.append(Candidate(m.name, e, 3))
                models[m.name] = m
    if "power" in families:
        sign = floor.sign if floor is not None else (1.0 if np.corrcoef(x, y)[0, 1] >= 0 else -1.0)
        origin = floor.threshold if floor is not None else (x.min() if sign > 0 else x.max())
        u = np.clip(sign * (x - origin), 0.0, None)
        if np.ptp(u) > 0:
            fold, k = _folds(g, folds)
            e, params = _power_cv(u, y, fold, k)
            m = FamilyModel("power", params, None, float(origin), float(sign))
            cands.append(Candidate(m.name, e, 3))
            models[m.name] = m
    if not cands:
        raise ValueError("degree: no model could be fitted: too few readings for cross-validation")
    best_e = min(c.cv_rmse for c in cands)
    fine = [c for c in cands if c.cv_rmse <= (1 + tolerance) * best_e]
    choice = min(fine, key=lambda c: (c.n_params, c.cv_rmse))
    return FamilySelection(cands, models[choice.name], choice.cv_rmse, models)


def fit_family(name: str, x, y, transform: ConductanceTransform | None = None, floor: Floor | None = None) -> FamilyModel:
    """Fit one named candidate on all readings (``polynomial-3``, ``conductance-power``, ...).

    Parameters
    ----------
    name : str
        A candidate name as in :attr:`FamilyModel.name`.
    x, y : array_like
        Readout and reference.
    transform : ConductanceTransform, optional
        Needed by the conductance families.
    floor : Floor, optional
        Origin of the ``power`` family.

    Returns
    -------
    FamilyModel
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if name.startswith("conductance") and transform is None:
        raise ValueError(f"model: {name} needs the readout circuit (a divider or op-amp in the run's sidecar, "
                         "or --x c_fsr_farad)")
    if name in ("power", "conductance-power"):
        groups = np.arange(x.size) % 2
        sel = cross_validate_families(x, y, groups, 2, transform, floor, families=(name,))
        return sel.best
    fam, _, deg = name.rpartition("-")
    if fam not in ("polynomial", "conductance-polynomial") or not deg.isdigit():
        raise ValueError(f"model: unknown model {name!r}")
    u = x if fam == "polynomial" else transform(x)
    pm = fit_polynomial(u, y, int(deg))
    return FamilyModel(fam, {"chebyshev_coefficients": pm.coefficients, "center": pm.center,
                             "half_width": pm.half_width}, None if fam == "polynomial" else transform)

