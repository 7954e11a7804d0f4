"""The calibration :func:`fsrlab.calibration.selection.calibrate_recordings` writes, and its stepper.

**Extension beyond the paper.** A monotone curve of the readout plus weighted memory features
(hysteresis play operators and creep averages of the level, :mod:`fsrlab.calibration.operators`),
fed with the readout as it was :attr:`HeldoutCalibration.delay_s` earlier
(:mod:`fsrlab.calibration.delay`); :class:`Stepper` gives the same estimates one reading at a time.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsrlab.calibration.curves import curve_from_dict
from fsrlab.calibration.delay import DelayLine, delayed
from fsrlab.calibration.monotone import StaticCurve
from fsrlab.calibration.operators import MemoryState, directions, memory_features
from fsrlab.calibration.uncertainty import LevelUncertainty
from fsrlab.errors import FileFormatError

__all__ = ["HeldoutCalibration", "Stepper", "clip_hysteresis"]


@dataclass
class HeldoutCalibration:
    """Estimate = curve(x) + Σ weight·feature, the features of the level
    ``(static(x) − static.rest)/full_scale`` (the load above rest).

    Parameters
    ----------
    static : StaticCurve
        The curve that feeds the memory (fitted alone): piecewise linear, polynomial or spline
        (:mod:`fsrlab.calibration.curves`).
    curve : StaticCurve
        The curve of the estimate (refitted with the memory; ``static`` itself without memory).
    thresholds, time_constants : tuple of float
        The memory's play thresholds [1] and creep time constants [s] (empty: none).
    weights : ndarray
        One weight per feature. [unit of the reference]
    full_scale : float
        The reference's span on the calibration data. [unit of the reference]
    row_s : float
        Median time between readings of the calibration data (the step a gap is taken as). [s]
    uncertainty : LevelUncertainty or None
        The uncertainty of the estimate.
    scaled : bool
        Whether the memory features grow with the level (:func:`memory_features`).
    uncertainty_plain : LevelUncertainty or None
        The uncertainty of the static curve alone (with memory only).
    delay_s : float
        The reference's delay: every estimate is made from the readout this much earlier
        (:func:`fsrlab.calibration.delay.delayed`). [s]
    hysteresis_range : ndarray or None, shape (2, len(thresholds))
        Least and largest value of each hysteresis feature on the calibration data. A new recording's
        hysteresis features are clipped to it (:func:`clip_hysteresis`), so the loop is corrected only
        on branches like those it was fitted on: a calibration that saw loading alone does not
        extrapolate its hysteresis to an unloading. The creep features are not clipped: a film
        recovers after unloading as it crept under load, so their fit holds for either sign. None: not
        clipped (files written before it). [1]
    mix : tuple of StaticCurve
        Static curves whose mean is the static estimate in place of ``static`` (model averaging, see
        :data:`fsrlab.calibration.selection.MIX_SE`); the memory's level and its correction stay
        those fitted around ``static``. Empty: ``static`` alone.
    creep_start : float
        The creep averages at a recording's first reading, a fraction of its level
        (:data:`fsrlab.calibration.operators.CREEP_START`; 1 in files written before it). [1]
    """

    static: StaticCurve
    curve: StaticCurve
    thresholds: tuple = ()
    time_constants: tuple = ()
    weights: np.ndarray = field(default_factory=lambda: np.zeros(0))
    full_scale: float = 1.0
    row_s: float = 1.0
    uncertainty: LevelUncertainty | None = None
    scaled: bool = False
    uncertainty_plain: LevelUncertainty | None = None
    delay_s: float = 0.0
    hysteresis_range: np.ndarray | None = None
    mix: tuple = ()
    creep_start: float = 1.0

    def without_memory(self) -> HeldoutCalibration:
        """The static curve alone (the estimate before compensation), with its own uncertainty."""
        if not self.has_memory:
            return self
        return HeldoutCalibration(self.static, self.static, full_scale=self.full_scale, row_s=self.row_s,
                                  uncertainty=self.uncertainty_plain or self.uncertainty, delay_s=self.delay_s,
                                  mix=self.mix)

    @property
    def static_name(self) -> str:
        """The static estimate's name: ``readout-4``, ``mean(readout-poly3/log-spline2)`` or, of more than
        three curves, ``mean(5 curves: readout-1…log-8)`` (no comma: progress lines split on commas)."""
        names = [m.name for m in self.mix]
        if len(names) > 3:
            return f"mean({len(names)} curves: {names[0]}…{names[-1]})"
        if names:
            return "mean(" + "/".join(names) + ")" if len(names) > 1 else names[0]
        return self.static.name

    def curve_estimate(self, x) -> np.ndarray:
        """The estimate at readings ``x`` (already delayed) before the memory's features: :attr:`curve`,
        plus what the mean of :attr:`mix` adds to :attr:`static`."""
        est = self.curve(x)
        return est + self.static_estimate(x) - self.static(x) if self.mix else est

    def extrapolated(self, x, lo: float, hi: float) -> np.ndarray:
        """How far the estimate before the memory at readings ``x`` goes beyond its value at the nearest end
        of the calibrated readings ``lo`` … ``hi`` (0 inside; NaN stays NaN). [unit of the reference]"""
        x = np.asarray(x, dtype=float)
        return np.abs(self.curve_estimate(x) - self.curve_estimate(np.clip(x, lo, hi)))

    def static_estimate(self, x) -> np.ndarray:
        """The estimate without memory at readings ``x`` (already delayed): the mean of :attr:`mix`, or
        the static curve."""
        if not self.mix:
            return self.static(x)
        return np.mean([m(x) for m in self.mix], axis=0)

    @property
    def has_memory(self) -> bool:
        return self.weights.size > 0

    def level(self, x) -> np.ndarray:
        return (self.static(x) - self.static.rest) / self.full_scale

    def run(self, t, x) -> tuple[np.ndarray, np.ndarray]:
        """Estimates and directions of a whole recording (readings in time order; NaN gives NaN)."""
        x = delayed(t, x, self.delay_s)
        u = self.level(x)
        return self.estimate(t, x, u), directions(u)

    def estimate(self, t, x, u=None, features=None) -> np.ndarray:
        """The estimates alone of readings ``x`` already delayed (:meth:`run` delays them); ``u`` (the
        level) and ``features`` (its :func:`memory_features`) when already computed."""
        x = np.asarray(x, dtype=float)
        est = self.curve_estimate(x)
        if self.has_memory:
            if features is None:
                u = self.level(x) if u is None else u
                features = memory_features(u, t, self.thresholds, self.time_constants, self.scaled, self.creep_start)
            est = est + clip_hysteresis(features, self.hysteresis_range) @ self.weights
        return est

    def stepper(self) -> Stepper:
        """The same estimates one reading at a time."""
        return Stepper(self)

    #: The memory counts seconds (the readings' times) for :class:`Stepper`.
    timed = True

    def level_at(self, x: float) -> float:
        """:meth:`level` of one reading (already delayed), for :class:`Stepper`."""
        return (self.static.at(x) - self.static.rest) / self.full_scale

    def estimate_at(self, x: float, level: float, feats: list) -> float:
        """:meth:`estimate` of one reading (already delayed) from its memory features, for :class:`Stepper`
        (:meth:`curve_estimate` and :func:`clip_hysteresis` without arrays)."""
        est = self.curve.at(x)
        if self.mix:
            est += sum(m.at(x) for m in self.mix) / len(self.mix) - self.static.at(x)
        if self.has_memory:
            rng = self.hysteresis_range
            for j in range(0 if rng is None else rng.shape[1]):
                feats[j] = min(max(feats[j], float(rng[0, j])), float(rng[1, j]))
            est += sum(f * float(w) for f, w in zip(feats, self.weights, strict=True))
        return est

    def to_dict(self) -> dict:
        return {"static": self.static.to_dict(), "curve": self.curve.to_dict(), "thresholds": list(self.thresholds),
                "time_constants_s": list(self.time_constants), "weights": self.weights.tolist(),
                "full_scale": self.full_scale, "row_s": self.row_s, "level_scaled_hysteresis": self.scaled,
                "uncertainty": None if self.uncertainty is None else self.uncertainty.to_dict(),
                "uncertainty_plain": None if self.uncertainty_plain is None else self.uncertainty_plain.to_dict(),
                "delay_s": self.delay_s,
                "hysteresis_range": None if self.hysteresis_range is None else self.hysteresis_range.tolist(),
                "static_mix": [m.to_dict() for m in self.mix], "creep_start": self.creep_start}

    @classmethod
    def from_dict(cls, d: dict) -> HeldoutCalibration:
        thr = tuple(float(v) for v in d.get("thresholds", ()))
        tau = tuple(float(v) for v in d.get("time_constants_s", ()))
        w = np.asarray(d.get("weights", []), dtype=float)
        if w.size != len(thr) + len(tau):
            raise FileFormatError("weights: one per play threshold and creep time constant")
        if any(not 0 < r < 1 for r in thr) or any(not v > 0 for v in tau):
            raise FileFormatError("thresholds must lie in (0, 1) and time constants be > 0")
        fs, row, delay = float(d["full_scale"]), float(d["row_s"]), float(d.get("delay_s", 0.0))
        if not (fs > 0 and row > 0):
            raise FileFormatError("full_scale and row_s must be > 0")
        if not 0 <= delay < 3600:
            raise FileFormatError("delay_s must lie in [0, 3600) s")
        rng = d.get("hysteresis_range")
        if rng is not None:
            rng = np.asarray(rng, dtype=float)
            if rng.shape != (2, len(thr)) or not np.all(np.isfinite(rng)) or np.any(rng[0] > rng[1]):
                raise FileFormatError("hysteresis_range: two rows (least, largest) of one finite value per play "
                        "threshold, "
                                 "least ≤ largest")
        unc, plain = d.get("uncertainty"), d.get("uncertainty_plain")
        start = float(d.get("creep_start", 1.0))
        if not 0 <= start <= 1:
            raise FileFormatError(f"creep_start: must be a fraction from 0 to 1 of the first level, got {start!r}")
        return cls(curve_from_dict(d["static"]), curve_from_dict(d["curve"]), thr, tau, w, fs, row,
                   None if unc is None else LevelUncertainty.from_dict(unc),
                   bool(d.get("level_scaled_hysteresis", False)),
                   None if plain is None else LevelUncertainty.from_dict(plain), delay, rng,
                   tuple(curve_from_dict(m) for m in d.get("static_mix", ())), start)


def clip_hysteresis(features: np.ndarray, hysteresis_range: np.ndarray | None) -> np.ndarray:
    """Memory features with their first (hysteresis) columns clipped to the range they had on the
    calibration data; the creep columns after them as they are (NaN rows stay NaN).

    Parameters
    ----------
    features : ndarray, shape (n, k) or (k,)
        Memory features (:func:`fsrlab.calibration.operators.memory_features`): the play operators'
        columns first. [1]
    hysteresis_range : ndarray, shape (2, h), or None
        Least and largest value of each of the first h features (None: returned as they are). [1]
    """
    if hysteresis_range is None or hysteresis_range.shape[1] == 0:
        return features
    h = hysteresis_range.shape[1]
    out = np.array(features, copy=True)
    out[..., :h] = np.clip(out[..., :h], hysteresis_range[0], hysteresis_range[1])
    return out


class Stepper:
    """One reading at a time: ``step(x, t) -> (estimate, direction)``; None readings keep the memory.

    The one stepper of every calibration model: it holds the memory's state
    (:class:`~fsrlab.calibration.operators.MemoryState`) and the readout's delay line, and asks the model
    for the level of a reading (:meth:`HeldoutCalibration.level_at`) and for the estimate from that
    reading and its features (:meth:`HeldoutCalibration.estimate_at`). A model whose memory counts
    readings instead of seconds (``timed`` False: an earlier fsrlab's files) takes one row step per reading.

    Parameters
    ----------
    model : HeldoutCalibration or LegacyModel
        The model whose ``run`` this gives reading by reading.
    """

    def __init__(self, model):
        self.model = model
        self.state = MemoryState(model.thresholds, model.time_constants, model.scaled, model.creep_start)
        self.state.dt_default = model.row_s
        self.line = DelayLine(model.delay_s)
        self._t = None

    def step(self, x: float | None, t: float | None = None) -> tuple[float | None, int]:
        if x is None or not np.isfinite(x):
            return None, 0
        m = self.model
        if m.delay_s > 0:
            t = t if t is not None else (0.0 if self._t is None else self._t + m.row_s)
            self._t = t
            x = self.line.push(t, float(x))
        x = float(x)
        level = m.level_at(x)
        if level is None:
            return None, 0
        feats, d = self.state.advance(level, t if m.timed else None)
        return m.estimate_at(x, level, feats), d
