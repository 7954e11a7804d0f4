"""Calibration chosen on held-out recordings: a monotone curve, then memory only where it generalises.

**Extension beyond the paper.** :func:`calibrate_recordings` takes one or more recordings (time,
readout, reference) and returns a :class:`HeldoutCalibration`. Every choice is scored by
:mod:`fsrlab.calibration.scoring` (other recordings, or later blocks of one) and taken in order of
complexity:

1. **static curve**: piecewise linear (:mod:`fsrlab.calibration.monotone`), polynomials of degree 2 to 5
   and monotone cubic splines (:mod:`fsrlab.calibration.curves`), simplest first (:data:`STATIC_CANDIDATES`),
   in the readout variables its physics names (:func:`fsrlab.calibration.scoring.readout_variables`); a
   polynomial that falls over the calibrated readings is not tried. The memory is fitted around the
   simplest curve that cannot fall within one standard error of the best; the static estimate is the
   **mean of the candidates within** :data:`MIX_SE` **standard error** (model averaging);
2. **delay** of the reference (:mod:`fsrlab.calibration.delay`): the estimate made from the readout a
   fraction of a reading to 0.5 s earlier, judged with the static curve (an FSR's loop leaves estimates
   behind, so its hysteresis is not taken for a delay);
3. **lag**, only when asked (``lag="auto"``): a shift of whole rows, judged with a hysteresis model;
4. **memory**: hysteresis (play operators) and creep (exponential averages) on the level, alone and
   together (:data:`MEMORY_VARIANTS`), every ridge weight (:data:`RIDGES`), weights of one sign per kind,
   fitted to what the static curve leaves or with the curve refitted (taken only when that wins by more
   than one standard error and :data:`MIN_GAIN`); the best trial's correction enters with the weight in
   [0, 1] that minimises the held-out error of the blend (stacking: D. H. Wolpert, *Neural Networks* 5,
   241, 1992; L. Breiman, *Machine Learning* 24, 49, 1996).

Steps 2 to 4 are kept only when they **win**: the delay and the lag by a held-out MSE lower by more
than one standard error (paired over chunks) and :data:`MIN_GAIN`, lower in most held-out parts and
higher in none; the memory by more than :data:`MEMORY_Z` standard errors (it is the best of many
trials) and :data:`MIN_GAIN`, and higher in no held-out part at all, forward or, for one recording,
backward (:func:`fsrlab.calibration.scoring.backward_splits`). Otherwise the simpler calibration
is kept and the :class:`Selection` says why. What each rule did on real recordings: docs/calibration.md.
The uncertainty (:class:`LevelUncertainty`) comes from the held-out errors of the chosen model, by
level and direction, with a relative term for what changes between recordings.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsrlab.calibration.curves import fit_static, static_system
from fsrlab.calibration.delay import DELAY_ROWS, delay_trials, delayed
from fsrlab.calibration.model import HeldoutCalibration, clip_hysteresis
from fsrlab.calibration.operators import (
    CREEP_START,
    CREEP_TIME_CONSTANTS_S,
    PLAY_THRESHOLDS,
    directions,
    memory_features,
)
from fsrlab.calibration.scoring import (
    Part,
    Recording,
    backward_splits,
    chunk_ids,
    held_out_splits,
    orientation,
    paired_gain,
    readout_rail,
    readout_variables,
    scheme_name,
)
from fsrlab.calibration.uncertainty import RELATIVE_MAX, REPEATABILITY, LevelUncertainty

__all__ = ["STATIC_CANDIDATES", "MIX_SE", "RIDGES", "HeldoutCalibration", "LevelUncertainty", "Selection",
           "calibrate_recordings"]

#: Sizes tried of each static curve family (:data:`fsrlab.calibration.curves.FAMILIES`): segments of the
#: piecewise-linear curve, degrees of the polynomial (degree 1 is the one-segment line), inner knots
#: of the monotone cubic spline. [1]
FAMILY_SIZES = {"piecewise": (1, 2, 4, 8), "polynomial": (2, 3, 4, 5), "spline": (0, 2, 4, 8)}
#: Order of the readout variables among candidates of as many coefficients. [1]
_VARIABLE_ORDER = ("readout", "conductance", "reciprocal", "log")


def _coefficients(family: str, size: int) -> int:
    """Coefficients of a static curve of ``family`` and ``size``: its complexity."""
    return size + 1 if family != "spline" else size + 4


#: Static candidates, simplest first (fewest coefficients, then the piecewise curve before the polynomial
#: before the spline, then :data:`_VARIABLE_ORDER`): (readout variable, family, size). Which variables
#: are tried: :func:`fsrlab.calibration.scoring.readout_variables`. [1]
STATIC_CANDIDATES = tuple(sorted(((v, f, k) for f, sizes in FAMILY_SIZES.items() for k in sizes
                                  for v in _VARIABLE_ORDER),
                                 key=lambda c: (_coefficients(c[1], c[2]), list(FAMILY_SIZES).index(c[1]),
                                                _VARIABLE_ORDER.index(c[0]))))
#: Static candidates whose held-out error is within this many standard errors of the best are averaged
#: (equal weights) into the static estimate: the candidates the one-standard-error rule cannot tell
#: apart, instead of the simplest of them alone (docs/calibration.md). [1]
MIX_SE = 1.0
#: Ridge weights tried for the memory terms (relative to the number of readings). [1]
RIDGES = (1e-3, 1e-2, 1e-1, 1.0)
#: Least held-out MSE a delay, a lag or a memory must save, a fraction of the simpler calibration's
#: (5 %: 2.5 % of its RMSE): a smaller gain held out within one run is not worth terms another recording
#: may not share. [1]
MIN_GAIN = 0.05
#: Standard errors by which a memory's held-out gain must exceed zero to be kept: one-sided 95 %, not one
#: standard error as for the simpler steps -- the best of the :data:`MEMORY_VARIANTS` × :data:`RIDGES`
#: trials, weighted on the same held-out errors, has an optimistic held-out gain. [1]
MEMORY_Z = 1.645
#: The memory models tried, each with every ridge weight: (play thresholds, creep time constants,
#: growing with the level). [1]
MEMORY_VARIANTS = ((PLAY_THRESHOLDS, (), False), (PLAY_THRESHOLDS, (), True), ((), CREEP_TIME_CONSTANTS_S, False),
                   (PLAY_THRESHOLDS, CREEP_TIME_CONSTANTS_S, False), (PLAY_THRESHOLDS, CREEP_TIME_CONSTANTS_S, True))
#: Signs tried for the weights of the play-operator and of the creep features: one sign for all the weights
#: of a kind (a film's loop and creep have one direction, a capacitive film's another). [1]
HYSTERESIS_SIGNS = (1, -1)
CREEP_SIGNS = (1, -1)
#: Ridge weight of the hysteresis model the lag is judged with. [1]
LAG_PROBE_RIDGE = 1e-2
#: Lags tried, in rows of the recording (the reference shifted against the readout). [1]
LAG_ROWS = (-3, -2, -1, 1, 2, 3)
#: Most readings a choice is fitted on while scored (every k-th; the memory and the scoring take every reading): ~20
#: coefficients on 10^5 readings. On 10^6: the same choices, held-out RMSEs within 0.05 %, 31 s instead of 40. [1]
FIT_ROWS = 100_000


@dataclass
class Selection:
    """What was tried and why the calibration is what it is.

    Parameters
    ----------
    scheme : str
        How choices were scored (:func:`fsrlab.calibration.scoring.scheme_name`).
    candidates : list of dict
        Every candidate tried: ``name`` and ``heldout_rmse``. [unit of the reference]
    steps : list of dict
        Each step: ``step``, ``tried``, ``gain``, ``se``, ``heldout_gain_by_part``, ``kept``, ``why``.
    lag_rows : int
        The lag applied. [rows]
    heldout_rmse, heldout_rmse_plain : float
        Held-out RMSE of the calibration chosen and of it without memory (its static curve, with the
        delay or lag kept). [unit of the reference]
    gain_spread : float or None
        RMS relative gain error of the held-out recordings, or of the held-out blocks of one recording
        (None in a file written before blocks were counted). [1]
    readout : dict
        The readout variables: ``variables`` (tried), ``used`` (by the static estimate: its curve's, or
        those of the curves averaged) and ``why`` (the physics of the readout,
        :func:`fsrlab.calibration.scoring.readout_variables`).
    """

    scheme: str
    candidates: list = field(default_factory=list)  # {"name", "heldout_rmse"}
    steps: list = field(default_factory=list)  # {"step", "tried", "gain", "se", "kept", "why"}
    lag_rows: int = 0
    heldout_rmse: float = float("nan")
    heldout_rmse_plain: float = float("nan")
    gain_spread: float | None = None
    readout: dict = field(default_factory=dict)  # {"variables", "used", "why"}

    def to_dict(self) -> dict:
        return dict(self.__dict__)


# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Choice:
    variable: str
    segments: int  # the family's size: segments, degree or inner knots
    thresholds: tuple = ()
    time_constants: tuple = ()
    ridge: float = 1e-3
    lag: int = 0
    scaled: bool = False
    delay: float = 0.0
    held: bool = False  # the memory fitted to what the static curve leaves, the curve held
    family: str = "piecewise"

    @property
    def name(self) -> str:
        mem = (("+hysteresis" + ("·level" if self.scaled else "")) if self.thresholds else "") + \
            ("+creep" if self.time_constants else "")
        lag = (f", lag {self.lag} rows" if self.lag else "") + (f", delay {self.delay:g} rows" if self.delay else "")
        held = "curve held, " if self.held else ""
        return f"{self.static}{mem}" + (f" ({held}ridge {self.ridge:g}{lag})" if mem else
                                                          (f" ({lag[2:]})" if lag else ""))

    @property
    def static(self) -> str:
        """The static curve's name (:attr:`fsrlab.calibration.monotone.StaticCurve.name`)."""
        kind = {"piecewise": "", "polynomial": "poly", "spline": "spline"}[self.family]
        return f"{self.variable}-{kind}{self.segments}"

    def but(self, **kw) -> _Choice:
        d = dict(self.__dict__)
        d.update(kw)
        return _Choice(**d)


class _Cache:
    """Static curves and memory features already computed, per split: every memory variant and ridge
    weight of a split shares its static curve and one matrix of all the features over each recording
    (hysteresis and creep, not scaled, float32), from which a variant takes its columns."""

    def __init__(self):
        self.statics: dict = {}
        self.features: dict = {}
        self.systems: dict = {}

    def static(self, key, make):
        return self.statics[key] if key in self.statics else self.statics.setdefault(key, make())

    def system(self, key, make):
        return self.systems[key] if key in self.systems else self.systems.setdefault(key, make())

    def _full(self, key, rec: Recording, level):
        if key not in self.features:
            u = level(rec.x)
            full = memory_features(u, rec.t, PLAY_THRESHOLDS, CREEP_TIME_CONSTANTS_S, False, CREEP_START)
            self.features[key] = (np.maximum(u, 0.0).astype(np.float32), full.astype(np.float32))
        return self.features[key]

    @staticmethod
    def _columns(ch: _Choice) -> list:
        return ([j for j, r in enumerate(PLAY_THRESHOLDS) if r in ch.thresholds] +
                [len(PLAY_THRESHOLDS) + j for j, v in enumerate(CREEP_TIME_CONSTANTS_S) if v in ch.time_constants])

    def memory(self, key, rec: Recording, level, ch: _Choice) -> np.ndarray:
        """The features of ``ch``'s variant over the whole recording ``rec`` for the level function ``level``."""
        u, full = self._full(key, rec, level)
        f = full[:, self._columns(ch)].astype(float)
        if ch.scaled:
            f *= u.astype(float)[:, None]
        return f

    def memory_term(self, key, rec: Recording, level, ch: _Choice, weights: np.ndarray,
                    hysteresis_range: np.ndarray | None = None) -> np.ndarray:
        """``clip_hysteresis(memory(...), hysteresis_range) @ weights`` in float32."""
        u, full = self._full(key, rec, level)
        f = full[:, self._columns(ch)]
        if ch.scaled:
            f = f * u[:, None]
        f = clip_hysteresis(f, None if hysteresis_range is None else hysteresis_range.astype(np.float32))
        return (f @ weights.astype(np.float32)).astype(float)


def _thinned(parts: list[Part]) -> list[Part]:
    """``parts`` with every k-th of their rows, k the least that leaves at most :data:`FIT_ROWS`."""
    k, out = -(-sum(int(p.rows.sum()) for p in parts) // FIT_ROWS), []
    if k <= 1:
        return parts
    for p in parts:
        out.append(Part(p.rec, np.zeros_like(p.rows)))
        out[-1].rows[np.flatnonzero(p.rows)[::k]] = True
    return out


def _fit(parts: list[Part], ch: _Choice, sign: int, adc, cache: _Cache | None = None,
         split: int = -1) -> HeldoutCalibration:
    """``ch`` fitted on ``parts``; on a held-out split (``split`` ≥ 0) on at most :data:`FIT_ROWS` of their rows."""
    cache = cache or _Cache()
    if split >= 0:
        parts = _thinned(parts)
    x = np.concatenate([p.rec.x[p.rows] for p in parts])
    y = np.concatenate([_shifted(p.rec, ch.lag)[p.rows] for p in parts])
    ok = np.isfinite(y)
    skey = (split, ch.variable, ch.family, ch.segments, ch.lag, ch.delay)
    static, fs = cache.static(skey, lambda: (fit_static(x[ok], y[ok], ch.family, ch.segments, ch.variable, sign, adc),
                                             max(float(np.ptp(y[ok])), 1e-12)))
    # the median step of the recordings' times, once per call (a delayed copy shares its recording's times)
    row_s = cache.static(("row_s",) + tuple(id(p.rec.t) for p in parts), lambda: _row_step([p.rec for p in parts]))
    if not (ch.thresholds or ch.time_constants):
        return HeldoutCalibration(static, static, full_scale=fs, row_s=row_s)
    rest = static.rest
    level = lambda v: (static(v) - rest) / fs  # noqa: E731  (HeldoutCalibration.level)

    def system():  # every choice's memory is a subset of the standard features (MEMORY_VARIANTS, the lag probe)
        feats = np.concatenate([cache.memory(skey + (id(p.rec),), p.rec, level, ch)[p.rows] for p in parts])[ok]
        hyst = feats[:, :len(ch.thresholds)]  # the range of the hysteresis features seen (the creep's is not kept)
        rng = np.array([np.nanmin(hyst, axis=0), np.nanmax(hyst, axis=0)]) if hyst.size else None
        return static_system(x[ok], y[ok], ch.family, ch.segments, ch.variable, sign, adc, extra=feats), rng

    # the normal equations serve every ridge weight and every sign of this split's variant
    msys, hysteresis_range = cache.system(skey + (ch.thresholds, ch.time_constants, ch.scaled), system)
    nh, nc = len(ch.thresholds), len(ch.time_constants)
    best = None
    for sh in (HYSTERESIS_SIGNS if nh else (1,)):
        for sc in (CREEP_SIGNS if nc else (1,)):
            sg = np.array([sh] * nh + [sc] * nc, float)
            if ch.held:
                curve, (w, r) = static, msys.solve_extra(static, ch.ridge, sg)
            else:
                curve, w, r = msys.solve(extra_lower=np.zeros(sg.size), extra_lam=ch.ridge, extra_signs=sg)
            if best is None or r < best[0]:
                best = (r, curve, w)
    _, curve, w = best
    return HeldoutCalibration(static, curve, tuple(ch.thresholds), tuple(ch.time_constants), w, fs, row_s,
                              scaled=ch.scaled, hysteresis_range=hysteresis_range, creep_start=CREEP_START)


def _row_step(recs: list[Recording]) -> float:
    """Median time between readings of ``recs`` (1 when it is not above zero). [s]"""
    steps = np.concatenate([np.diff(r.t) for r in recs if r.t.size > 1] or [np.ones(1)])
    step = float(np.median(steps))
    return step if step > 0 else 1.0


def _shifted(rec: Recording, lag: int) -> np.ndarray:
    """The reference ``lag`` rows later (positive: the readout lags the reference)."""
    if lag == 0:
        return rec.y
    y = np.full_like(rec.y, np.nan)
    if lag > 0:
        y[lag:] = rec.y[:-lag]
    else:
        y[:lag] = rec.y[-lag:]
    return y


def _blend(static: HeldoutCalibration, mem: HeldoutCalibration, alpha: float) -> HeldoutCalibration:
    """``static + alpha·(mem − static)``: the memory's correction shrunk by ``alpha`` (both fitted on the
    same readings, so their curves share the basis, and the blend of two monotone curves is one)."""
    if alpha == 1.0 or not mem.has_memory:
        return mem
    c, k = mem.curve, static.curve
    curve = c.with_coef((1 - alpha) * k.coef + alpha * c.coef)
    return HeldoutCalibration(mem.static, curve, mem.thresholds, mem.time_constants, alpha * mem.weights,
                              mem.full_scale, mem.row_s, scaled=mem.scaled, hysteresis_range=mem.hysteresis_range,
                              creep_start=mem.creep_start)


def _memory_step(sel: Selection, score, scored: dict, cache: _Cache, base: _Choice, plain, backward):
    """The memory trial of lowest held-out error, and the weight ``alpha`` in [0, 1] of its correction
    (trial − base) that minimises the held-out error of ``plain + alpha·(trial − base)`` (stacking);
    (None, 1) unless that blend wins over ``plain`` (:data:`MEMORY_Z`, :data:`MIN_GAIN`, no part worse). The trials with
    the static curve held come first: one with the curve refitted is taken only when it wins over the
    best of them by more than one standard error and :data:`MIN_GAIN`. ``plain``: the held-out
    errors, chunk ids, estimates and parts of the static estimate (``base``'s, or the mean of the
    static candidates); ``backward(trial, alpha)``: its gain in each block scored backward, none worse either
    (:func:`_backward_folds`). Recorded in ``sel``."""
    cache.features.clear()  # the features of the lag step's probes are not needed again
    cache.systems.clear()
    held = [base.but(thresholds=h, time_constants=c, scaled=sc, ridge=r, held=True) for h, c, sc in MEMORY_VARIANTS
            for r in RIDGES]
    # a polynomial refitted with the memory could fall somewhere: only the families that cannot are refitted
    refit = [c.but(held=False) for c in held] if base.family != "polynomial" else []
    e_s, ids, _, parts = plain
    score(base)

    def full(c):  # held-out errors of the static estimate plus c's whole correction
        return scored[c][0] - scored[base][0] + e_s

    def scored_full(c):
        score(c)
        return full(c)

    best_held = _best_of(held, scored_full, scored.pop)
    best_refit = _best_of(refit, scored_full, scored.pop) if refit else best_held
    g_refit, se_refit = paired_gain(full(best_held), full(best_refit), ids)
    refitted = _refit_wins(g_refit, se_refit, float(np.mean(full(best_held) ** 2)))
    best = best_refit if refitted else best_held
    d = scored[best][0] - scored[base][0]
    alpha = float(np.clip(-np.sum(e_s * d) / max(float(np.sum(d * d)), 1e-300), 0.0, 1.0))
    blended = e_s + alpha * d
    gain, se = paired_gain(e_s, blended, ids)
    folds = _fold_gains(plain, (blended, ids, None, parts))
    least = MIN_GAIN * float(np.mean(e_s ** 2))
    worse = sum(f < 0 for f in folds)
    forward = bool(alpha > 0 and gain > MEMORY_Z * se and gain >= least and not worse)
    earlier = backward(best, alpha) if forward else []  # scored backward only when it wins forward
    before = sum(f < 0 for f in earlier)
    kept = forward and not before
    lower = sum(f > 0 for f in folds)
    curve = (f"the curve refitted with it (held-out MSE lower by {g_refit:.4g} ± {se_refit:.4g} than with the curve "
             "held)" if refitted else f"the static curve held (refitting it: {g_refit:.4g} ± {se_refit:.4g})")
    head = (f"{best.name}, {curve}, its correction weighted {alpha:.3g}: held-out MSE lower by {gain:.4g} ± {se:.4g}, "
            f"lower in {lower} of {len(folds)} held-out parts")
    short = (f"not more than {MEMORY_Z:g} standard errors" if not gain > MEMORY_Z * se else
             f"less than {100 * MIN_GAIN:.0f} % of the simpler calibration's" if gain < least else
             f"higher in {worse} held-out part(s)" if worse or not before else
             f"fitted on the later blocks it is higher in {before} of {len(earlier)} earlier ones (a trend through "
             "the run)")
    sel.steps.append({"step": "memory", "tried": best.name, "weight": alpha, "gain": gain, "se": se, "kept": kept,
                      "curve_refitted": refitted, "refit_gain": g_refit, "refit_se": se_refit,
                      "heldout_rmse_at_weight_1": _rmse(e_s + d), "heldout_gain_by_part": folds,
                      "heldout_gain_by_earlier_part": earlier,
                      "why": head + (f" (more than {MEMORY_Z:g} standard errors and {100 * MIN_GAIN:.0f} % of the "
                                     "simpler calibration's, no held-out part worse)" if kept else
                                     f": {short}, so the simpler calibration is kept")})
    for other in held + refit:  # the held-out errors of the trials not kept are no longer needed
        if other is not best or not kept:
            scored.pop(other, None)
    cache.features.clear()
    cache.systems.clear()
    return (best, alpha) if kept else (None, 1.0)


def _backward_folds(search: _Search, cur: _Choice, mixed: list, mem: _Choice, alpha: float) -> list[float]:
    """Relative MSE saved by the memory ``mem`` at ``alpha`` over the static estimate (``cur``'s, or the mean of
    ``mixed``) in each block of a single recording scored backward (``backward_splits``); none with several."""
    splits = backward_splits(search.delayed_recs(cur.delay)[0])
    cache = _Cache()  # its keys name a split by its place: not those of the forward splits

    def held(ch):
        return _held_out(splits, ch, search.sign, search.adc, cache)

    if not splits:
        return []
    e_c, ids, _, parts = held(cur)
    e_p = np.mean([held(m)[0] for m in mixed], axis=0) if mixed else e_c
    return _fold_gains((e_p, ids, None, parts), (e_p + alpha * (held(mem)[0] - e_c), ids, None, parts))


def _best_of(trials, errors, let_go):
    """The trial of least RMS ``errors(trial)`` (held-out errors), scoring them in turn; ``let_go(trial)`` is
    called on each one beaten as soon as it is, so only the best so far keeps its held-out errors."""
    best = None
    for t in trials:
        if best is None or _rmse(errors(t)) < _rmse(errors(best)):
            best, beaten = t, best
        else:
            beaten = t
        if beaten is not None:
            let_go(beaten)
    return best


def _refit_wins(gain: float, se: float, mse_held: float) -> bool:
    """Whether the memory with the curve refitted is taken over the one with the curve held: its held-out
    MSE lower by ``gain`` (± ``se``) than the held one's ``mse_held``, by more than one standard error
    and :data:`MIN_GAIN`."""
    return bool(gain > se and gain >= MIN_GAIN * mse_held)


def _mix(parts: list[Part], mixed: list, sign: int, adc) -> tuple:
    """The static curves of ``mixed`` fitted on ``parts`` (:attr:`HeldoutCalibration.mix`), but a polynomial
    that falls somewhere over these readings (it rose over the undelayed ones it was chosen on)."""
    curves = (_fit(parts, m, sign, adc).static for m in mixed)
    return tuple(c for c in curves if c.is_monotone())


def _gain_spread(splits, static: _Choice, ch: _Choice, alpha: float, sign: int, adc, mixed=()) -> float:
    """RMS relative gain error of the held-out recordings or blocks (least-squares gain of reference on
    estimate, over each part's rows above 5 % of full scale), each part's at most :data:`RELATIVE_MAX`: a
    Velostat film read at 1 N drifted to gains of 4 to 7 between the blocks of one run, which the term must
    show, while an estimate that collapsed (near zero, or of the wrong sign, where the readout left the
    calibrated range: a gain of -76 on a real run) is no measurement at all and counts as the largest."""
    g = []
    for fit_parts, test_parts in splits:
        cal = _fit(fit_parts, ch, sign, adc)
        if static != ch:
            cal = _blend(_fit(fit_parts, static, sign, adc), cal, alpha)
        cal.mix = _mix(fit_parts, mixed, sign, adc)
        for p in test_parts:
            e, _ = cal.run(p.rec.t, p.rec.x)
            y = _shifted(p.rec, ch.lag)
            k = p.rows & np.isfinite(y) & (y > 0.05 * cal.full_scale)
            if k.sum() >= 10 and np.sum(e[k] ** 2) > 0:
                g.append(float(np.sum(e[k] * y[k]) / np.sum(e[k] ** 2)))
    rel = np.where(np.asarray(g) > 0, np.abs(np.asarray(g) - 1.0), RELATIVE_MAX) if g else np.zeros(1)
    return float(np.sqrt(np.mean(np.minimum(rel, RELATIVE_MAX) ** 2)))


def _held_out(splits, ch: _Choice, sign: int, adc, cache: _Cache):
    """Held-out errors, chunk ids, estimates and the held-out parts' slices; the first and last rows of every
    held-out part within the largest lag tried are left out for every choice, so all choices are scored on
    the same rows."""
    errs, est = [], []
    trim = max(abs(k) for k in LAG_ROWS)
    for i, (fit_parts, test_parts) in enumerate(splits):
        cal = _fit(fit_parts, ch, sign, adc, cache, i)
        for p in test_parts:
            key = (i, ch.variable, ch.family, ch.segments, ch.lag, ch.delay, id(p.rec))
            # with the curve held, its values on the part are the static curve's, the same for every trial
            x = p.rec.x
            e = cache.static(("values",) + key, lambda c=cal, x=x: c.curve(x)) if ch.held else cal.curve(x)
            if cal.has_memory:
                e = e + cache.memory_term(key, p.rec, cal.level, ch, cal.weights, cal.hysteresis_range)
            y = _shifted(p.rec, ch.lag)
            idx = np.flatnonzero(p.rows)
            rows = p.rows.copy()
            if idx.size > 2 * trim:
                rows[idx[:trim]] = rows[idx[-trim:]] = False
            y = np.where(rows, y, np.nan)
            rows &= np.isfinite(y)
            errs.append(e[rows] - y[rows])
            est.append(e[rows])
    err = np.concatenate(errs)
    chunks = np.concatenate([chunk_ids(v.size) + (i * 10_000) for i, v in enumerate(errs)])
    _, chunks = np.unique(chunks, return_inverse=True)
    bounds = np.cumsum([0] + [v.size for v in errs])
    parts = [slice(bounds[i], bounds[i + 1]) for i in range(len(errs))]
    return err, chunks, np.concatenate(est), parts


def _fold_gains(a, b):
    """Relative MSE saved in each held-out part (recording or block) by b over a."""
    ea, eb, parts = a[0], b[0], a[3]
    return [float(np.mean(ea[p] ** 2) - np.mean(eb[p] ** 2)) / max(float(np.mean(ea[p] ** 2)), 1e-300)
            for p in parts if p.stop > p.start]


def _rmse(e):
    return float(np.sqrt(np.mean(e ** 2))) if e.size else float("inf")


def rows_have_times(recs: list[Recording]) -> bool:
    """Whether the recordings' rows come in time order (repeated times allowed, as a millisecond clock
    gives at a high rate), so that a delay in seconds means the same on each."""
    return all(r.t.size > 2 and np.all(np.diff(r.t) >= 0) and np.median(np.diff(r.t)) > 0 for r in recs)


class _Search:
    """One calibration's held-out search: the recordings (and their delayed copies) with their splits, the
    held-out errors of the choices scored so far, and the :class:`Selection` being written."""

    def __init__(self, recs: list[Recording], sign: int, adc, sel: Selection):
        self.recs, self.sign, self.adc, self.sel = recs, sign, adc, sel
        self.scored: dict = {}
        self.cache = _Cache()
        self.row_s = _row_step(recs)
        self.by_delay: dict = {}

    def delayed_recs(self, d: float) -> tuple[list[Recording], list]:
        """The recordings with the readout ``d`` rows late, and their held-out splits."""
        if d not in self.by_delay:
            rs = self.recs if d == 0 else [Recording(r.t, delayed(r.t, r.x, d * self.row_s), r.y, r.name)
                                           for r in self.recs]
            self.by_delay[d] = (rs, held_out_splits(rs))
        return self.by_delay[d]

    def score(self, ch: _Choice):
        """Held-out errors, chunk ids, estimates and parts of ``ch`` (:func:`_held_out`), recorded once."""
        if ch not in self.scored:
            self.scored[ch] = _held_out(self.delayed_recs(ch.delay)[1], ch, self.sign, self.adc, self.cache)
            if all(c["name"] != ch.name for c in self.sel.candidates):
                self.sel.candidates.append({"name": ch.name, "heldout_rmse": _rmse(self.scored[ch][0])})
        return self.scored[ch]

    def rmse(self, ch: _Choice) -> float:
        return _rmse(self.scored[ch][0])

    def step(self, name: str, trials: list[_Choice], base: _Choice) -> _Choice | None:
        """The best trial when it wins over ``base`` (see the module's notes), else None; recorded."""
        scored = self.scored
        self.cache.features.clear()  # a step's features serve its own trials only
        self.cache.systems.clear()
        for ch in trials + [base]:
            self.score(ch)
        ch = min(trials, key=self.rmse)
        gain, se = paired_gain(scored[base][0], scored[ch][0], scored[base][1])
        folds = _fold_gains(scored[base], scored[ch])
        # one standard error and MIN_GAIN, and no held-out recording or block made worse, most made better
        least = MIN_GAIN * float(np.mean(scored[base][0] ** 2))
        lower = sum(f > 0 for f in folds)
        wins = gain > se and min(folds) >= 0 and lower > len(folds) / 2
        kept = wins and gain >= least
        said = f"held-out MSE lower by {gain:.4g} ± {se:.4g}, lower in {lower} of {len(folds)} held-out parts"
        if kept:
            why = (f"{said}, higher in none (more than one standard error and {100 * MIN_GAIN:.0f} % of the simpler "
                   "calibration's)")
        elif wins:
            why = (f"{said}: less than {100 * MIN_GAIN:.0f} % of the simpler calibration's, so the simpler "
                   "calibration is kept")
        else:
            why = (f"{said}: not more than one standard error in most parts without a loss in any, so the simpler "
                   "calibration is kept")
        self.sel.steps.append({"step": name, "tried": ch.name, "gain": gain, "se": se, "kept": bool(kept),
                               "heldout_gain_by_part": folds, "why": why})
        for other in trials:  # the held-out errors of the trials not kept are no longer needed
            if other is not ch or not kept:
                scored.pop(other, None)
        return ch if kept else None


def _static_candidates(search: _Search, variables, lag: int) -> tuple[list[_Choice], list[str]]:
    """The static candidates of ``variables`` (:data:`STATIC_CANDIDATES`), without the polynomials that fall
    somewhere over the calibrated readings when fitted on all of them (their names returned apart)."""
    recs = search.recs
    x = np.concatenate([r.x[r.usable] for r in recs])
    y = np.concatenate([r.y[r.usable] for r in recs])
    out, falling = [], []
    for v, family, k in STATIC_CANDIDATES:
        if v not in variables:
            continue
        ch = _Choice(v, k, lag=lag, family=family)
        if family == "polynomial" and not fit_static(x, y, family, k, v, search.sign, search.adc).is_monotone():
            falling.append(ch.name)
            continue
        out.append(ch)
    return out, falling


def _static_step(search: _Search, statics: list[_Choice], falling=()) -> tuple[_Choice, list[_Choice]]:
    """The static curve the memory is fitted around (the simplest within one standard error of the best) and
    the candidates averaged into the static estimate (within :data:`MIX_SE`; empty when only one); recorded,
    with the polynomials not tried because they fall somewhere over the calibrated readings (``falling``)."""
    scored = search.scored
    for ch in statics:
        search.score(ch)
    best = min(statics, key=search.rmse)

    def within(c: _Choice, k: float) -> bool:  # held-out MSE within k standard errors of the best's
        gain, se = paired_gain(scored[c][0], scored[best][0], scored[best][1])
        return c == best or gain <= k * se

    # the memory is fitted around a curve that cannot fall (refitted with it, it still cannot): the simplest
    # of those within one standard error of the best, else the best of them
    rising = [c for c in statics if c.family != "polynomial"] or statics
    cur = next((c for c in rising if within(c, 1.0)), None) or min(rising, key=search.rmse)
    mixed = [c for c in statics if within(c, MIX_SE)]
    mixed = mixed if len(mixed) > 1 or best != cur else []  # a polynomial alone best: the static estimate
    search.sel.steps.append({"step": "static curve", "tried": len(statics), "chosen": cur.name,
                             "averaged": [c.name for c in mixed], "not_monotone": list(falling),
                             "why": "the simplest curve that cannot fall within one standard error of the best "
                                    "held-out error "
                                    f"({search.rmse(best):.4g}, {best.name})"
                                    + (f"; the static estimate the mean of the {len(mixed)} within {MIX_SE:g} "
                                       "standard error" if len(mixed) > 1 else f"; the static estimate {best.name}"
                                       if mixed else "")})
    for other in statics:
        if other != cur:
            scored.pop(other, None)
    return cur, mixed


def _delay_step(search: _Search, cur: _Choice) -> _Choice:
    """``cur`` with the reference's delay when one wins (see the module's notes)."""
    # Judged with the static curve: a delay corrects estimates that run ahead of the reference (a reference
    # that lags); an FSR's loop leaves them behind (it conducts more on unloading), which a delay would make
    # worse, so the sensor's hysteresis is not taken for a delay.
    def let_go(d):  # a delay of the grid beaten: its held-out errors and delayed recordings
        search.scored.pop(cur.but(delay=d))
        search.by_delay.pop(d, None)

    row_s = search.row_s
    coarse = _best_of(delay_trials(row_s), lambda d: search.score(cur.but(delay=d))[0], let_go)
    won = search.step("delay", [cur.but(delay=d) for d in [coarse] + delay_trials(row_s, coarse)], cur)
    if won is not None:
        cur = won
    for d in [d for d in search.by_delay if d != cur.delay]:  # the other delays' recordings are not needed again
        del search.by_delay[d]
    return cur


def _plain(search: _Search, cur: _Choice, mixed: list[_Choice]) -> tuple:
    """Held-out errors, chunk ids, estimates and parts of the static estimate: ``cur``'s, or the mean of
    ``mixed`` (their held-out errors then let go)."""
    e_c, ids, est_c, parts_c = search.score(cur)
    if not mixed:
        return e_c, ids, est_c, parts_c
    plain = (np.mean([search.score(m)[0] for m in mixed], axis=0), ids,
             np.mean([search.scored[m][2] for m in mixed], axis=0), parts_c)
    for m in mixed:
        if m != cur:
            search.scored.pop(m)
    return plain


def calibrate_recordings(recs: list[Recording], compensate: bool = True, lag: int | str = 0,
                         variables=None, rail: float | None = None, between_runs: float | None = None,
                         unit: str = "", name: str = "") -> tuple[HeldoutCalibration, Selection]:
    """Choose and fit a calibration on held-out recordings or blocks (see the module's notes).

    Parameters
    ----------
    recs : list of Recording
        One or more recordings of the same sensor and readout, each in time order.
    compensate : bool
        Try the memory terms (hysteresis, creep); without, only the static curve (and the lag).
    lag : int or "auto"
        Rows the readout lags the reference (default 0), or ``"auto"``: 0 unless a shift wins.
    variables : sequence of str, optional
        Readout variables tried (default: those the readout's physics names,
        :func:`fsrlab.calibration.scoring.readout_variables`; ``conductance`` only with a rail: ADC counts,
        or ``rail`` given; ``log`` and ``reciprocal`` only when every usable reading is above zero).
    rail : float, optional
        The readout's full scale when it is not ADC counts: a divider's supply voltage for its
        voltage (the conductance ratio is then V/(Vcc − V), or its mirror). [unit of the readout]
    between_runs : float, optional
        The floor of the uncertainty's relative term for what changes from one recording to the next
        (default :data:`~fsrlab.calibration.uncertainty.REPEATABILITY`); the held-out
        recordings' gain spread when it is larger. [1]
    unit, name : str
        The readout's unit and column name, when known (a resistance is calibrated in its conductance).

    Returns
    -------
    HeldoutCalibration, Selection
    """
    delays = lag == 0 and DELAY_ROWS and rows_have_times(recs)
    late = [int(d) for d in delay_trials(_row_step(recs)) if d >= 1 and d == int(d)]
    sign, adc = orientation(recs, late if delays else ())
    adc = readout_rail(recs, rail, adc)
    search = _Search(recs, sign, adc, Selection(scheme_name(len(recs))))
    sel = search.sel
    tried, why = readout_variables(recs, sign, adc, unit, name, variables)
    statics, falling = _static_candidates(search, tried, 0 if lag == "auto" else int(lag))
    cur, mixed = _static_step(search, statics, falling)
    used = sorted({c.variable for c in mixed} or {cur.variable}, key=_VARIABLE_ORDER.index)
    sel.readout = {"variables": list(tried), "used": used, "why": why}
    if delays:  # only when the estimate is of the reference as recorded (a lag aligns the reference instead)
        cur = _delay_step(search, cur)
    if lag == "auto":
        # Judged with a hysteresis model: a shift of the reference narrows a loop, so a static curve alone
        # would take part of the hysteresis for a lag.
        probe = cur.but(thresholds=PLAY_THRESHOLDS, ridge=LAG_PROBE_RIDGE)
        won = search.step("lag", [probe.but(lag=k) for k in LAG_ROWS], probe)
        if won is not None:
            cur = cur.but(lag=won.lag)
            search.score(cur)
    mixed = [m.but(delay=cur.delay, lag=cur.lag) for m in mixed]  # with the delay and lag kept
    plain = _plain(search, cur, mixed)
    sel.heldout_rmse_plain = _rmse(plain[0])  # the calibration the memory is tried on (delay, lag kept)
    alpha, mem = 1.0, None
    if compensate:
        mem, alpha = _memory_step(sel, search.score, search.scored, search.cache, cur, plain,
                                  lambda m, a: _backward_folds(search, cur, mixed, m, a))
    return _final(search, cur, mem, alpha, mixed, plain, between_runs)


def _final(search: _Search, static_cur: _Choice, mem: _Choice | None, alpha: float, mixed: list, plain: tuple,
           between_runs: float | None) -> tuple[HeldoutCalibration, Selection]:
    """The calibration chosen, fitted on every recording, with its uncertainty from the held-out errors."""
    scored, sel, recs, sign, adc = search.scored, search.sel, search.recs, search.sign, search.adc
    cur = static_cur
    e_c, ids, est_c, parts_c = scored[cur]
    if mem is not None:
        e_m, _, est_m, _ = scored[mem]
        scored[mem] = (plain[0] + alpha * (e_m - e_c), ids, plain[2] + alpha * (est_m - est_c), parts_c)
        cur = mem
    else:
        scored[cur] = plain
    sel.lag_rows = cur.lag
    delay_s = float(f"{cur.delay * search.row_s:.10g}")  # without the float noise of the median step
    err, _, est, parts = scored[cur]
    fs_all = max(float(np.ptp(np.concatenate([r.y[r.usable] for r in recs]))), 1e-12)

    def held_out_directions(est, parts):  # loading/unloading of the held-out estimates, part by part
        return np.concatenate([directions(est[p] / fs_all) for p in parts])

    dirs = held_out_directions(est, parts)
    sel.heldout_rmse = _rmse(err)
    drecs, splits = search.delayed_recs(cur.delay)
    whole = [Part(r, r.usable) for r in drecs]
    cal = _blend(_fit(whole, static_cur, sign, adc), _fit(whole, cur, sign, adc), alpha)
    cal.delay_s = delay_s
    cal.mix = _mix(whole, mixed, sign, adc)
    rel = REPEATABILITY if between_runs is None else between_runs
    # the gains of the held-out recordings, or of the held-out blocks of one: a block is a short recording
    # of its own, and a gain that moves within one recording moves at least as much to the next
    sel.gain_spread = _gain_spread(splits, static_cur, cur, alpha, sign, adc, mixed)
    rel = max(rel, sel.gain_spread)
    cal.uncertainty = LevelUncertainty.fit(err, est, dirs, relative=rel)
    if cal.has_memory:
        e0, _, est0, parts0 = plain
        dirs0 = held_out_directions(est0, parts0)
        cal.uncertainty_plain = LevelUncertainty.fit(e0, est0, dirs0, relative=rel)
    return cal, sel
