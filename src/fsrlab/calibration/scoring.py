"""Held-out scoring of calibration choices: other recordings, or later blocks of one.

**Extension beyond the paper.** Cross-validation with folds interleaved inside one recording
cannot see what changes from one recording to the next -- the loading rate, the placement, the
creep state -- and flatters every added complexity. Here a choice is scored where it will be used:

* with two or more recordings, **leave one recording out**: fit on the others, score on it;
* within a single recording, **forward chaining**: cut it into :data:`BLOCKS` contiguous blocks (equal
  numbers of rows with both readout and reference), fit on the first k and score on block k + 1
  (k = 2..BLOCKS−1), so the score is always on later readings than the fit. A memory must also hold
  **backward** (:func:`backward_splits`: fit on the last blocks, score on the one before them): forward
  alone favours a term that rides a trend through the run -- creep building under a load that stays on,
  a sensor settling -- which the next recording, in another state, does not share.

The memory of a model (play operators, creep averages) runs over the whole recording it is scored
on -- it depends on the readout alone, not on the reference -- and only the rows of the held-out
block count.

**One standard error.** A more complex choice is kept only when its held-out mean squared error is
below the simpler one's by more than the standard error of that difference, paired over contiguous
chunks of the held-out rows (:func:`paired_gain`): a gain smaller than its own noise is not a gain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.calibration.monotone import adc_full_scale
from fsrlab.errors import ParameterError

__all__ = ["BLOCKS", "CHUNKS", "Recording", "Part", "held_out_splits", "backward_splits", "scheme_name",
           "paired_gain", "orientation", "readout_rail", "RESISTANCE_UNITS", "readout_variables"]

#: Contiguous blocks of a single recording for forward chaining. [1]
BLOCKS = 5
#: Contiguous chunks each held-out part is cut into for the paired standard error. [1]
CHUNKS = 8


@dataclass
class Recording:
    """One recording, in time order.

    Parameters
    ----------
    t : ndarray
        Time of each reading. [s]
    x : ndarray
        Readout (NaN where missing). [its unit]
    y : ndarray
        Reference (NaN where missing). [N or Pa]
    name : str
        A name for messages.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    name: str = ""

    @property
    def usable(self) -> np.ndarray:
        return np.isfinite(self.x) & np.isfinite(self.y)


@dataclass
class Part:
    """A recording and the rows of it that count (fitted, or scored).

    Parameters
    ----------
    rec : Recording
        The whole recording (its memory runs over every reading).
    rows : ndarray of bool
        The rows that count.
    """

    rec: Recording
    rows: np.ndarray


def scheme_name(n_recordings: int) -> str:
    """How choices are scored for this many recordings.

    Parameters
    ----------
    n_recordings : int
        Number of recordings calibrated together. [1]
    """
    return ("leave one recording out" if n_recordings >= 2
            else f"forward chaining (fit on earlier blocks, score on the next; {BLOCKS} blocks)")


def held_out_splits(recs: list[Recording]) -> list[tuple[list[Part], list[Part]]]:
    """The (fit, score) splits of :func:`scheme_name`'s scheme.

    Parameters
    ----------
    recs : list of Recording
        The recordings.

    Returns
    -------
    list of (list of Part, list of Part)
        The parts to fit on and the parts to score on, per split.
    """
    if len(recs) >= 2:
        return [([Part(r, r.usable) for j, r in enumerate(recs) if j != i], [Part(recs[i], recs[i].usable)])
                for i in range(len(recs))]
    rec = recs[0]
    inside = _blocks(rec)
    return [([Part(rec, rec.usable & np.logical_or.reduce(inside[:k]))], [Part(rec, rec.usable & inside[k])])
            for k in range(2, BLOCKS)]


def backward_splits(recs: list[Recording]) -> list[tuple[list[Part], list[Part]]]:
    """The mirror of forward chaining within a single recording (as :func:`held_out_splits`): fit on the last k
    blocks, score on the block before them (k = 2..BLOCKS−1), the earliest block first; none with two or more
    recordings (leaving one out runs both ways).

    Parameters
    ----------
    recs : list of Recording
        The recordings.
    """
    if len(recs) >= 2:
        return []
    rec = recs[0]
    inside = _blocks(rec)
    return [([Part(rec, rec.usable & np.logical_or.reduce(inside[k + 1:]))], [Part(rec, rec.usable & inside[k])])
            for k in range(BLOCKS - 2)]


def _blocks(rec: Recording) -> list[np.ndarray]:
    """The rows of each of the :data:`BLOCKS` blocks of ``rec``, at equal counts of usable rows (no empty block)."""
    used = np.flatnonzero(rec.usable)
    if used.size < BLOCKS:
        raise ParameterError(f"fewer than {BLOCKS} readings with both the readout and the reference")
    cut = used[np.linspace(0, used.size, BLOCKS + 1).astype(int)[1:-1]]
    edges = np.r_[0, cut, rec.t.size]
    idx = np.arange(rec.t.size)
    return [(idx >= edges[k]) & (idx < edges[k + 1]) for k in range(BLOCKS)]


def chunk_ids(n: int) -> np.ndarray:
    """Contiguous chunk of each of n held-out rows (:data:`CHUNKS` chunks, at least 10 rows each)."""
    size = max(10, -(-n // CHUNKS))
    return np.arange(n) // size


def paired_gain(err_simple: np.ndarray, err_complex: np.ndarray, chunks: np.ndarray) -> tuple[float, float]:
    """Mean squared error saved by the complex choice, and its standard error, paired over chunks.

    Parameters
    ----------
    err_simple, err_complex : ndarray
        Held-out errors of the simpler and the more complex choice on the same rows. [unit]
    chunks : ndarray of int
        The contiguous chunk of each row (0..k−1).

    Returns
    -------
    gain : float
        Mean over chunks of (MSE simple − MSE complex). [unit²]
    se : float
        Its standard error (inf with fewer than 2 chunks). [unit²]
    """
    k = int(chunks.max()) + 1 if chunks.size else 0
    if k < 2:
        return 0.0, float("inf")
    cnt = np.bincount(chunks, minlength=k)
    d = (np.bincount(chunks, err_simple ** 2, k) - np.bincount(chunks, err_complex ** 2, k))[cnt > 0] / cnt[cnt > 0]
    return float(d.mean()), float(d.std(ddof=1) / np.sqrt(d.size))


#: Rank correlation of readout and reference below which :func:`orientation` also tries the reference
#: shifted (docs/calibration.md). [1]
ALIGNED = 0.6


def _rank_correlation(x: np.ndarray, y: np.ndarray) -> float:
    """Rank correlation on dense ranks (ties share one): enough to tell whether the readout rises or falls."""
    rx = np.unique(x, return_inverse=True)[1].astype(float)  # tied readings share a rank
    ry = np.unique(y, return_inverse=True)[1].astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return float(np.corrcoef(rx, ry)[0, 1])


def orientation(recs: list[Recording], late_rows=()) -> tuple[int, float | None]:
    """+1 when the readout rises with the reference, −1 when it falls, and the ADC full scale of its counts
    (None when it is not ADC counts); a reference or readout that does not change is refused.

    When the readout and the reference of the same row agree poorly (rank correlation below
    :data:`ALIGNED`), the reference is also tried ``late_rows`` readings late and early: a reference
    logged late (or ahead) by a good part of a press agrees with the readout of that many readings
    before (after), not with its own row's, whose correlation can even take the wrong sign; the sign
    is then taken from the least shift that agrees about best, when it agrees clearly better (by 0.2).

    Parameters
    ----------
    recs : list of Recording
        The recordings, their usable rows taken together.
    late_rows : sequence of int
        Whole readings by which the reference may be late (the delays the calibration will try). [1]
    """
    x_all = np.concatenate([r.x[r.usable] for r in recs])
    y_all = np.concatenate([r.y[r.usable] for r in recs])
    if x_all.size > 2 and not np.ptp(y_all) > 0:
        raise ParameterError("the reference does not change: nothing to calibrate against")
    rho = _rank_correlation(x_all, y_all) if x_all.size > 2 else float("nan")
    if np.isfinite(rho) and abs(rho) < ALIGNED and len(late_rows):
        shifted = _shifted_correlations(recs, [k for j in late_rows for k in (j, -j)])
        top = max((abs(v) for v in shifted.values()), default=0.0)
        k = min((k for k, v in shifted.items() if abs(v) >= top - 0.05), key=abs, default=None)  # the least shift
        if k is not None and abs(shifted[k]) > abs(rho) + 0.2:
            rho = shifted[k]
    if not np.isfinite(rho) or abs(rho) < 0.1:
        raise ParameterError("the readout does not respond to the reference" + (
            " (it does not change)" if not np.isfinite(rho) else f" (rank correlation {rho:.2f})"))
    return (1 if rho > 0 else -1), adc_full_scale(x_all)


def _shifted_correlations(recs: list[Recording], shifts) -> dict:
    """Rank correlation of each recording's readout with its reference ``k`` readings later, pooled,
    for each ``k`` of ``shifts`` (negative: earlier); the ranks are taken once over all usable rows."""
    xs = [r.x[r.usable] for r in recs]
    ys = [r.y[r.usable] for r in recs]
    cut = np.cumsum([v.size for v in xs])[:-1]
    rx = np.split(np.unique(np.concatenate(xs), return_inverse=True)[1].astype(float), cut)
    ry = np.split(np.unique(np.concatenate(ys), return_inverse=True)[1].astype(float), cut)
    out = {}
    for k in shifts:
        a = [x[:x.size - k] if k > 0 else x[-k:] for x in rx if x.size > abs(k) + 2]
        b = [y[k:] if k > 0 else y[:y.size + k] for y in ry if y.size > abs(k) + 2]
        if a and sum(v.size for v in a) > 2:
            with np.errstate(invalid="ignore", divide="ignore"):
                c = float(np.corrcoef(np.concatenate(a), np.concatenate(b))[0, 1])
            if np.isfinite(c):
                out[int(k)] = c
    return out


def readout_rail(recs: list[Recording], rail: float | None, adc: float | None) -> float | None:
    """The readout's full scale for the conductance variable: the one given (a divider's supply for
    its voltage), else the ADC's found in the counts; None when neither (or readings beyond it).

    Parameters
    ----------
    recs : list of Recording
        The recordings.
    rail : float or None
        A divider's supply for its voltage readout, when known. [unit of the readout]
    adc : float or None
        The ADC full scale found in the counts (:func:`orientation`). [counts]
    """
    if rail is None:
        return adc
    top = max(float(np.nanmax(r.x)) for r in recs)
    return float(rail) if rail > 0 and top < rail else None


#: Units that declare a resistance (spelled as run files and foreign CSVs give them). [1]
RESISTANCE_UNITS = ("ohm", "ohms", "\u03a9", "\u2126", "kohm", "kohms", "k\u03a9", "k\u2126", "Mohm", "M\u03a9")
#: Least ratio of the largest to the smallest reading for a unitless reading that falls as force rises to
#: be tried in its reciprocal as well: a resistance over the range of an FSR spans decades; a voltage or
#: a count of the same film rarely spans one. [1]
DECADE = 10.0


def readout_variables(recs: list[Recording], sign: int, rail: float | None, unit: str = "", name: str = "",
                      asked=None) -> tuple[tuple, str]:
    """The readout variables a static curve is tried in, and why (the physics of the readout).

    A resistance (``unit`` in :data:`RESISTANCE_UNITS`, a column ``*_ohm``) in its conductance ``1/R`` and
    logarithm; divider counts or a voltage with its rail also in the divider's conductance ratio; a reading
    without a unit that is above zero, spans more than :data:`DECADE` and falls as the force rises (a
    resistance logged without its unit) also in its reciprocal; anything else as it is and in its
    logarithm (log and reciprocal only for readings above zero). Each is scored held out.

    Parameters
    ----------
    recs : list of Recording
        The recordings (their usable rows).
    sign : {1, -1}
        Whether the readout rises with the force (:func:`orientation`).
    rail : float or None
        The readout's full scale for the divider's ratio (:func:`readout_rail`). [unit of the readout]
    unit, name : str
        The readout's unit and column name ("" when unknown).
    asked : sequence of str, optional
        The variables to try instead (those that apply to the readings).

    Returns
    -------
    variables : tuple of str
    why : str
    """
    x = np.concatenate([r.x[r.usable] for r in recs])
    positive = bool(x.size) and float(np.min(x)) > 0
    unit = (unit or "").strip()
    resistance = unit.lower() in {u.lower() for u in RESISTANCE_UNITS} or name.lower().endswith("_ohm")
    if asked is not None:
        tried = tuple(v for v in asked if (v != "conductance" or rail is not None)
                      and (v not in ("log", "reciprocal") or positive))
        return tried, "the variables asked for"
    if resistance and positive:
        return ("reciprocal", "log"), (f"a resistance ({name or 'readout'} in {unit or 'ohm'}): calibrated in its "
                                       "conductance 1/R and its logarithm")
    if rail is not None:
        return ("readout", "conductance") + (("log",) if positive else ()), \
            f"a divider's readout (full scale {rail:g}): also in the divider's conductance ratio"
    span = float(np.max(x) / np.min(x)) if positive else 0.0
    if positive and unit in ("", "1") and sign < 0 and span > DECADE:
        return ("readout", "reciprocal", "log"), (f"a reading without a unit, above zero, spanning {span:.3g}:1 and "
                                                  "falling as the force rises, like a resistance: also in its "
                                                  "reciprocal")
    return ("readout", "log") if positive else ("readout",), \
        "used as it is" + (" and in its logarithm" if positive else " (not above zero: no logarithm)")
