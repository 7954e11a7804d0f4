"""Calibration files of the earlier cross-validated layout (``"version": 1`` without ``"method"``), read-only.

Before one calibration engine, ``fsrlab calibrate --method cv`` wrote a polynomial or a conductance or
power-law family chosen by grouped cross-validation, a floor (dead zone), play-operator memory and an
uncertainty table. :class:`LegacyModel` reads such a file, and a
:class:`~fsrlab.calibration.result.Calibration` applies like any other: the static curve, the floor, the
memory (the play operators and creep averages of :mod:`fsrlab.calibration.operators`, stepped one
reading at a time, every reading fed whatever the margin) and the uncertainty by level and direction
(:class:`~fsrlab.calibration.uncertainty.LevelUncertainty`, without the quantization term).
The branch polynomials (``"compensation"``) of those files are not applied: they needed the whole run
(or labels of their own); the static curve is, and :attr:`LegacyModel.note` says so. Nothing here fits.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.polynomial import chebyshev

from fsrlab.calibration.model import Stepper
from fsrlab.calibration.operators import directions, memory_features
from fsrlab.calibration.uncertainty import LevelUncertainty
from fsrlab.errors import FileFormatError

__all__ = ["is_legacy", "LegacyModel"]


def is_legacy(d: dict) -> bool:
    """Whether a calibration document is of the earlier cross-validated layout.

    Parameters
    ----------
    d : dict
        A calibration file's content.
    """
    return isinstance(d, dict) and d.get("version") == 1 and "chebyshev_coefficients" in d and \
        d.get("method") != "held-out"


def _chebyshev(p: dict):
    coef = np.asarray(p["chebyshev_coefficients"], dtype=float)
    center = float(p.get("center", p.get("x_center")))
    half = float(p.get("half_width", p.get("x_half_width")))
    if coef.ndim != 1 or coef.size < 1 or not np.all(np.isfinite(coef)) or not (math.isfinite(center) and half > 0):
        raise FileFormatError("chebyshev_coefficients must be finite numbers, x_half_width > 0")
    return lambda u: chebyshev.chebval((np.asarray(u, dtype=float) - center) / half, coef)


def _variable(fam: dict):
    """The family's variable: the readout, its conductance through the divider or op-amp, or above its origin."""
    tr = fam.get("transform")
    if tr:
        topo, r, vcc = str(tr["topology"]), float(tr.get("r_ohm", math.nan)), float(tr.get("vcc_v", math.nan))
        full = float(tr.get("counts_full_scale", 0.0))
        if topo not in ("divider", "opamp-inverting", "capacitance"):
            raise FileFormatError(f"conductance topology {topo!r} unknown")

        def conductance(x):
            x = np.asarray(x, dtype=float) * (vcc / full if full > 0 else 1.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                g = x / (r * (vcc - x)) if topo == "divider" else -x / (r * vcc) if topo == "opamp-inverting" else x
            return np.where(np.isfinite(g) & (g >= 0), g, np.nan)
        return conductance
    if fam["family"] == "power":
        origin, sign = float(fam.get("origin", 0.0)), float(fam.get("sign", 1.0))
        return lambda x: np.clip(sign * (np.asarray(x, dtype=float) - origin), 0.0, None)
    return lambda x: np.asarray(x, dtype=float)


def _static(d: dict):
    """The file's static curve ŷ₀(x) and its name (``polynomial-3``, ``conductance-power``, ...)."""
    fam = d.get("model_family")
    if fam is None:
        return _chebyshev(d), f"polynomial-{len(d['chebyshev_coefficients']) - 1}"
    if fam["family"] not in ("polynomial", "conductance-polynomial", "conductance-power", "power"):
        raise FileFormatError(f"model family {fam['family']!r} unknown")
    var, p = _variable(fam), fam["params"]
    if "chebyshev_coefficients" in p:
        poly = _chebyshev(p)
        return (lambda x: poly(var(x))), f"{fam['family']}-{len(p['chebyshev_coefficients']) - 1}"
    a, b, c, scale = (float(p[k]) for k in ("a", "b", "c", "scale"))

    def power(x):
        with np.errstate(invalid="ignore", over="ignore"):
            return c + a * (var(x) / scale) ** b
    return power, fam["family"]


class LegacyModel:
    """An earlier file's model, with what :class:`~fsrlab.calibration.result.Calibration` asks of a model.

    Parameters
    ----------
    d : dict
        The calibration document (earlier cross-validated layout), kept as it is.
    memory : bool
        Whether its play-operator memory is used (``without_memory()`` gives one without).
    """

    delay_s = 0.0

    def __init__(self, d: dict, memory: bool = True):
        self.document = d
        self.base, self.static_name = _static(d)
        lo, hi = d.get("readout_range") or (d["x_center"] - d["x_half_width"], d["x_center"] + d["x_half_width"])
        self.x_range = (float(lo), float(hi))
        fl = d.get("floor")
        self.floor = None if fl is None else (float(fl["threshold"]), float(fl["sign"]))
        mem = d.get("memory") if memory else None
        self.memory = mem
        if mem is not None:
            self.coef = np.asarray(mem["coefficients"], dtype=float)
            self.degree = int(mem["degree"])
            self.thresholds = tuple(float(v) for v in mem["thresholds"])
            self.time_constants = tuple(float(v) for v in mem["time_constants_s"])
            if self.coef.size != self.degree + 1 + 2 * len(self.thresholds) + 2 * len(self.time_constants):
                raise FileFormatError("memory coefficients: wrong number")
            self.full_scale, self.row_s = float(mem["full_scale"]), float(mem["row_s"])
        else:
            self.thresholds, self.time_constants = (), ()
            self.full_scale, self.row_s = float(d.get("full_scale") or 1.0), 1.0
        if not (self.full_scale > 0 and self.row_s > 0):
            raise FileFormatError("memory: full_scale and row_s must be > 0")
        has = mem is not None or (d.get("memory") is None and d.get("compensation") is None)
        table = d.get("uncertainty") if has else (d.get("uncertainty_plain") or d.get("uncertainty"))
        self.uncertainty = None if table is None else _uncertainty(table)
        self.note = ("its branch compensation (an earlier fsrlab's) is not applied: the static curve is"
                     if d.get("compensation") else "")

    scaled = False

    @property
    def has_memory(self) -> bool:
        return self.memory is not None

    def without_memory(self) -> LegacyModel:
        return LegacyModel(self.document, memory=False) if self.has_memory else self

    def curve_estimate(self, x) -> np.ndarray:
        with np.errstate(invalid="ignore", over="ignore"):
            return np.asarray(self.base(x), dtype=float)

    def extrapolated(self, x, lo: float, hi: float) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        return np.abs(self.curve_estimate(x) - self.curve_estimate(np.clip(x, lo, hi)))

    def _at_floor(self, x: np.ndarray) -> np.ndarray:
        if self.floor is None:
            return np.zeros(x.shape, bool)
        with np.errstate(invalid="ignore"):
            return np.isfinite(x) & (self.floor[1] * (x - self.floor[0]) <= 0)

    def run(self, t, x) -> tuple[np.ndarray, np.ndarray]:
        """Estimates and directions of a whole recording; ``t`` is not used (this memory counts readings).
        Readings at the floor get no estimate and move the memory to zero load."""
        x = np.asarray(x, dtype=float)
        floor = self._at_floor(x)
        y0 = np.where(floor, np.nan, self.curve_estimate(np.where(np.isfinite(x), x, self.x_range[0])))
        y0 = np.where(np.isfinite(x), y0, np.nan)
        w = np.where(floor, 0.0, y0 / self.full_scale)
        if not self.has_memory:
            return y0, directions(w)
        valid = np.isfinite(w)
        steps = np.cumsum(valid) * self.row_s  # one row step per reading taken, as the memory counted
        f = memory_features(w, steps, self.thresholds, self.time_constants)
        est = self.full_scale * self._combine(w, f)
        return np.where(floor, np.nan, est), directions(w)

    def _combine(self, w, f) -> np.ndarray:
        """Σ a_k w^k + Σ (b_j + c_j·w)(p_j − w) + Σ (e_m + f_m·w)(s̄_m − w), in units of full scale."""
        w = np.asarray(w, dtype=float)
        k, n_p, n_s = self.degree + 1, len(self.thresholds), len(self.time_constants)
        hyst, creep = f[..., :n_p], -f[..., n_p:]  # the creep features are u − ū; the file's terms ū − u
        out = sum(self.coef[i] * w ** i for i in range(k))
        out = out + hyst @ self.coef[k:k + n_p] + (w[..., None] * hyst) @ self.coef[k + n_p:k + 2 * n_p]
        c = self.coef[k + 2 * n_p:]
        return out + creep @ c[:n_s] + (w[..., None] * creep) @ c[n_s:]

    def stepper(self) -> Stepper:
        """The same estimates one reading at a time (:class:`~fsrlab.calibration.model.Stepper`)."""
        return Stepper(self)

    def to_dict(self) -> dict:
        """The document it was read from, as it was (these files are not written any more)."""
        return self.document

    #: The memory counts readings, one row step each (:meth:`run`), not the readings' times.
    timed = False
    creep_start = 1.0

    def level_at(self, x: float) -> float | None:
        """The memory's level of one reading, for :class:`~fsrlab.calibration.model.Stepper`: the static
        estimate over full scale, 0 at the floor, None where the curve gives no number."""
        if self._at_floor(np.array([x]))[0]:
            return 0.0
        w = float(self.curve_estimate(np.array([x]))[0]) / self.full_scale
        return w if math.isfinite(w) else None

    def estimate_at(self, x: float, level: float, feats: list) -> float | None:
        """:meth:`run`'s estimate of one reading from its level and memory features (None at the floor)."""
        if self._at_floor(np.array([x]))[0]:
            return None
        if not self.has_memory:
            return float(self.curve_estimate(np.array([x]))[0])
        return self.full_scale * float(self._combine(np.array(level), np.asarray(feats, dtype=float)))


def _uncertainty(table: dict) -> LevelUncertainty:
    """The earlier table (σ by level and direction) as the one uncertainty model (no relative term)."""
    edges = np.asarray(table["level_edges"], dtype=float)
    sigma = np.asarray(table["sigma"], dtype=float)
    if sigma.ndim != 2 or sigma.shape != (edges.size + 1, 3) or np.any(sigma < 0):
        raise FileFormatError("uncertainty: sigma must be (level bins) x 3 numbers >= 0")
    return LevelUncertainty(edges, sigma, float(sigma.min()), 0.0)
