"""Calibrate from one or more recorded runs by held-out selection, and apply it to another run.

**Extension beyond the paper.** The orchestration of :mod:`fsrlab.calibration.heldout_model` on
runs: it reads a run's readout, reference and times, and holds no model of its own. Its result,
:class:`RunCalibration`, is what ``fsrlab calibrate RUN.csv [RUN2.csv ...]`` writes and what
``fsrlab apply``, ``fsrlab measure`` and ``fsrlab live`` use.

Examples
--------
::

    import fsrlab as fl
    cal = fl.calibrate(["hand.csv", "motor.csv"], x="reading", reference="force_n", compensate=True)
    out = fl.apply(cal, fl.load_run("other.csv"))   # a Run with force_n_estimate and force_n_uncertainty
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from fsrlab.calibration.heldout import Recording
from fsrlab.calibration.heldout_model import HeldoutCalibration, Selection, calibrate_recordings
from fsrlab.calibration.provenance import RecordedWith, mismatches, recorded_with
from fsrlab.calibration.readout import reference_reversed
from fsrlab.io.runformat import KNOWN_COLUMNS, Run, RunFormatError, load_run

__all__ = ["METHOD", "MARGIN", "MIN_READINGS", "RunCalibration", "calibrate_runs", "RunEstimator"]

#: Fewest readings (readout and reference both present) of each run: held-out scoring cuts one run into
#: 5 blocks and scores 3 of them in 8 chunks. [1]
MIN_READINGS = 20
#: The ``method`` of a calibration file written by this module.
METHOD = "held-out"
#: Default margin beyond the calibrated readout range, a fraction of its span, within which an
#: estimate is reported (flagged ``in_range`` 0): every reading, since the curve extrapolates linearly
#: in the readout and the uncertainty grows by half the extrapolated amount; the memory is fed with
#: every reading whatever the margin. [1]
MARGIN = float("inf")
_FILE_KEYS = ("complete", "rows", "closed", "created", "format", "version", "columns")


@dataclass
class RunCalibration:
    """A held-out calibration of a readout column to a reference column.

    Parameters
    ----------
    model : HeldoutCalibration
    selection : Selection
        What was tried, how it was scored, and why the calibration is what it is.
    x_name, y_name, x_unit, y_unit : str
        Readout and reference columns and their units.
    sources : list of str
        The runs it was fitted on.
    recorded_with : RecordedWith or None
        The circuit and range the runs were recorded with (checked when applied).
    n : int
        Readings fitted.
    r2 : float
        Coefficient of determination of the estimate on the readings fitted (in sample). [1]
    created : str
        UTC time, ISO 8601.
    path : Path or None
        The file it was read from.
    """

    model: HeldoutCalibration
    selection: Selection
    x_name: str
    y_name: str
    x_unit: str = ""
    y_unit: str = ""
    sources: list = field(default_factory=list)
    recorded_with: RecordedWith | None = None
    n: int = 0
    created: str = ""
    path: Path | None = None
    r2: float = float("nan")

    @property
    def x_range(self) -> tuple[float, float]:
        return self.model.curve.x_range

    @property
    def full_scale(self) -> float:
        return self.model.full_scale

    @property
    def lag_s(self) -> float:
        return float(f"{self.selection.lag_rows * self.model.row_s:.10g}")  # without the float noise of the step

    @property
    def model_name(self) -> str:
        m = self.model
        mem = (("+hysteresis" + ("·level" if m.scaled else "")) if m.thresholds else "") + \
            ("+creep" if m.time_constants else "")
        return f"monotone-{m.static_name}{mem}"

    def to_dict(self) -> dict:
        return {"format": "fsrlab-calibration", "version": 1, "method": METHOD, "model": self.model_name,
                "x": self.x_name, "y": self.y_name, "units": {"x": self.x_unit, "y": self.y_unit},
                "readout_range": list(self.x_range), "lag_s": self.lag_s, "n": self.n, "r2": self.r2,
                "created": self.created,
                "sources": list(self.sources),
                "recorded_with": None if self.recorded_with is None else self.recorded_with.to_dict(),
                "selection": self.selection.to_dict(), "calibration": self.model.to_dict()}

    @classmethod
    def from_dict(cls, d: dict, path: Path | None = None) -> "RunCalibration":
        s = d.get("selection") or {}
        sel = Selection(str(s.get("scheme", "")), list(s.get("candidates", [])), list(s.get("steps", [])),
                        int(s.get("lag_rows", 0)), float(s.get("heldout_rmse", math.nan)),
                        float(s.get("heldout_rmse_plain", math.nan)))
        rw = d.get("recorded_with")
        units = d.get("units") or {}
        return cls(HeldoutCalibration.from_dict(d["calibration"]), sel, str(d["x"]), str(d["y"]),
                   str(units.get("x", "")), str(units.get("y", "")), list(d.get("sources", [])),
                   None if rw is None else RecordedWith.from_dict(rw), int(d.get("n", 0)), str(d.get("created", "")),
                   path, float(d.get("r2", math.nan)))

    def estimator(self, margin: float = MARGIN, compensation: bool = True) -> "RunEstimator":
        """A causal estimator: ``step(reading, t=None) -> (estimate, uncertainty, in_range)``."""
        return RunEstimator(self, margin, compensation)

    def estimate_run(self, run: Run, margin: float = MARGIN, compensation: bool = True,
                     forced: list | None = None) -> Run:
        """The run with ``<reference>_estimate``, ``<reference>_uncertainty`` and ``in_range``.

        Every reading feeds the memory, in row order; ``margin`` only decides which estimates are
        reported (beyond it: empty). ``compensation=False``: the static curve alone. No provenance
        check here: :func:`fsrlab.calibration.apply.apply_calibration` checks the run first
        (``forced``: the differences it was told to ignore, kept in the metadata).
        """
        if not margin >= 0:
            raise ValueError(f"margin: must be a fraction >= 0 of the calibrated span, got {margin!r}")
        if self.x_name not in run:
            raise RunFormatError(f"{run.path}: column {self.x_name!r} (the calibration's readout) missing "
                                 f"(columns: {', '.join(run.columns)})")
        differences = forced or []
        x = np.asarray(run[self.x_name], dtype=float)
        t = run["time_s"] if "time_s" in run else np.arange(x.size) * self.model.row_s
        model = self.model if compensation else self.model.without_memory()
        est, u, inside, kept = _estimate(model, self.x_range, t, x, margin)
        ycol, ucol = f"{self.y_name}_estimate", f"{self.y_name}_uncertainty"
        given = np.isfinite(x)
        columns = dict(run.columns)
        columns[ycol] = np.where(kept, est, np.nan)
        columns[ucol] = np.where(kept, u, np.nan)
        columns["in_range"] = np.where(given, inside.astype(float), np.nan)
        counts = {"estimated": int(np.isfinite(columns[ycol]).sum()), "in_range": int(inside.sum()),
                  "out_of_range": int((given & ~inside).sum()),
                  "extrapolated": int((np.isfinite(columns[ycol]) & ~inside).sum()),
                  "missing": int((~np.isfinite(columns[ycol])).sum()), "no_readout": int((~given).sum()),
                  "not_decodable": 0, "beyond_margin": int((given & ~kept).sum()), "below_activation": 0}
        meta = {k: v for k, v in run.metadata.items() if k not in _FILE_KEYS}
        meta["units"] = dict(run.units, **{ycol: self.y_unit, ucol: self.y_unit, "in_range": "1"})
        meta["calibration"] = {**({} if self.path is None else {"file": str(self.path)}), "x": self.x_name,
                               "reference": self.y_name, "model": self.model_name if compensation else
                               f"monotone-{self.model.static_name}", "method": METHOD,
                               "lag_s": self.lag_s, "created": self.created, "readout_range": list(self.x_range),
                               "margin": margin if math.isfinite(margin) else None, "counts": counts}
        if differences:
            meta["calibration"]["forced"] = differences
        return Run(path=run.path, columns=columns, metadata=meta)


def _estimate(m: HeldoutCalibration, x_range, t, x, margin):
    est, d = m.run(t, x)
    lo, hi = x_range
    span = hi - lo
    inside = np.isfinite(x) & (x >= lo) & (x <= hi)
    kept = np.isfinite(x) & (x >= lo - margin * span) & (x <= hi + margin * span) if np.isfinite(margin) \
        else np.isfinite(x)
    extra = m.extrapolated(x, lo, hi) if (~inside & np.isfinite(x)).any() else None
    u = m.uncertainty(est, d, extra) if m.uncertainty is not None else np.full(x.shape, np.nan)
    return est, u, inside, kept


class RunEstimator:
    """The estimates of :meth:`RunCalibration.estimate_run`, one reading at a time (``fsrlab measure``, ``fsrlab live``).

    Parameters
    ----------
    cal : RunCalibration
        The calibration.
    margin : float
        Beyond the calibrated readout range by more than this fraction of its span, no estimate is
        reported (the memory still takes the reading). [1]
    compensation : bool
        Use the memory terms when the calibration has them.
    """

    def __init__(self, cal: RunCalibration, margin: float = MARGIN, compensation: bool = True):
        if not margin >= 0:
            raise ValueError(f"margin: must be a fraction >= 0 of the calibrated span, got {margin!r}")
        self.cal = cal
        self.model = cal.model if compensation else cal.model.without_memory()
        self.reference, self.x = cal.y_name, cal.x_name
        self.stepper = self.model.stepper()
        self.lo, self.hi = cal.x_range
        span = self.hi - self.lo
        self.kept = (self.lo - margin * span, self.hi + margin * span) if math.isfinite(margin) else (-math.inf, math.inf)
        self._k = 0

    def step(self, readout: float | None, t: float | None = None) -> tuple[float | None, float | None, bool]:
        """Take one reading (time ``t`` [s], default: the calibration's row step after the last)."""
        if t is None:
            t = self._k * self.model.row_s
        self._k += 1
        if readout is None or not math.isfinite(float(readout)):
            return None, None, False
        x = float(readout)
        est, d = self.stepper.step(x, t)
        inside = self.lo <= x <= self.hi
        if est is None or not self.kept[0] <= x <= self.kept[1]:
            return None, None, inside
        u = None
        m = self.model
        if m.uncertainty is not None:
            extra = None if inside else m.extrapolated(np.array([x]), self.lo, self.hi)
            u = float(m.uncertainty(np.array([est]), np.array([d]), extra)[0])
        return est, u, inside


def _divider_rail(run: Run, x: str) -> float | None:
    """The full scale of a divider's readout from the run's sidecar (``divider``: ``vcc_v``, and the
    ``column`` holding ``adc_bits``-bit counts): the supply for ``voltage_v``, the largest count for
    that column; None otherwise."""
    div = run.metadata.get("divider") if isinstance(run.metadata, dict) else None
    if not isinstance(div, dict):
        return None
    try:
        if x == "voltage_v" and div.get("vcc_v") is not None:
            return float(div["vcc_v"])
        if div.get("column") == x:
            return float(2 ** int(div.get("adc_bits", 10)) - 1)
    except (TypeError, ValueError):
        return None
    return None


def _recording(run: Run, x: str, reference: str | None) -> tuple[Recording, str, str, str]:
    if x not in run:
        raise RunFormatError(f"{run.path}: column {x!r} missing (columns: {', '.join(run.columns)})")
    ref = reference or ("stress_pa" if "stress_pa" in run else "force_n")
    if ref not in run:
        raise RunFormatError(f"{run.path}: no reference column {ref!r} (columns: {', '.join(run.columns)})")
    t = np.asarray(run["time_s"], dtype=float) if "time_s" in run else np.arange(run.n_rows, dtype=float)
    rec = Recording(t, np.asarray(run[x], dtype=float), np.asarray(run[ref], dtype=float), str(run.path))
    return rec, ref, run.units.get(x) or KNOWN_COLUMNS.get(x, ""), run.units.get(ref) or KNOWN_COLUMNS.get(ref, "")


def calibrate_runs(runs, x: str = "frequency_hz", reference: str | None = None, compensate: bool = False,
                   lag: int | str = 0, rail: float | None = None, between_runs: float | None = None) -> RunCalibration:
    """Calibrate a readout to its reference from one or more runs, every choice scored held out.

    Parameters
    ----------
    runs : Run, path, or a sequence of them
        Recordings of the same sensor and readout.
    x : str
        Readout column. [its unit]
    reference : {"force_n", "stress_pa"}, optional
        Reference column (default: ``stress_pa`` when the runs have it, else ``force_n``).
    compensate : bool
        Try the memory terms (hysteresis and creep, alone and together); the best, its correction
        weighted by the held-out error, is kept only when it beats the simpler calibration on held-out
        recordings or later blocks by more than one standard error and 5 % of its MSE.
    lag : int or "auto"
        Rows the readout lags the reference (default 0: the estimate is of the reference as recorded);
        ``"auto"``: searched, and kept only when a shift of whole rows wins held out.
    rail : float, optional
        The readout's full scale for the conductance variable (a divider's supply for its voltage),
        when the runs' sidecar does not give it; readings at or above it leave the variable out. [unit
        of the readout]
    between_runs : float, optional
        Relative standard uncertainty between recordings, the floor of the uncertainty's term for what
        changes from one recording to the next (the sensor re-seated, another loading, another creep
        state), in [0, 1]: default :data:`~fsrlab.calibration.heldout_uncertainty.REPEATABILITY`
        (15 %); the held-out runs' gain spread when it is larger. Set it from the setup:
        docs/calibration.md measured 1–8 % for a film under a robot, about 20 % for an FSR placed by
        hand from one session to the next. [1]

    Returns
    -------
    RunCalibration

    Raises
    ------
    RunFormatError
        A column a run lacks.
    ValueError
        Too few readings, a readout that does not follow the reference, runs of different readouts.
    """
    if between_runs is not None and not 0 <= between_runs <= 1:
        raise ValueError(f"between_runs: must be a relative uncertainty from 0 to 1 (0 % to 100 %), got {between_runs!r}")
    if isinstance(runs, (Run, str, Path)):
        runs = [runs]
    runs = [r if isinstance(r, Run) else load_run(r) for r in runs]
    if not runs:
        raise ValueError("runs: at least one run")
    recs, refs, xu, yu = [], set(), "", ""
    for run in runs:
        rec, ref, xu, yu = _recording(run, x, reference)
        recs.append(rec)
        refs.add(ref)
        if int(rec.usable.sum()) < MIN_READINGS:
            raise ValueError(f"{run.path}: {x} and {ref}: fewer than {MIN_READINGS} readings with both values present "
                             "(held-out scoring; --method cv calibrates fewer)")
    if len(refs) > 1:
        raise ValueError(f"runs: the reference differs between runs ({', '.join(sorted(refs))}); name it")
    ref = refs.pop()
    y_all = np.concatenate([r.y[r.usable] for r in recs])
    reversed_why = reference_reversed(y_all)
    if reversed_why:
        raise ValueError(f"{ref}: {reversed_why}: a load cell mounted or wired the wrong way round, or the wrong "
                         "column")
    rws = [recorded_with(r.metadata, r.columns.get("range"), rec.usable) for r, rec in zip(runs, recs)]
    rw = rws[0]
    for other, run in zip(rws[1:], runs[1:]):
        diff = mismatches(x, rw, other, None)
        if diff:
            raise ValueError(f"{run.path}: recorded with {diff[0][0]}, {runs[0].path} with {diff[0][1]}: "
                             "calibrate runs of one readout together")
    try:
        model, sel = calibrate_recordings(recs, compensate=compensate, lag=lag,
                                          rail=_divider_rail(runs[0], x) if rail is None else rail,
                                          between_runs=between_runs)
    except ValueError as exc:
        names = ", ".join(str(r.path) for r in runs)
        raise ValueError(f"{names}: {x} and {ref}: {exc}") from None
    est = np.concatenate([model.run(r.t, r.x)[0][r.usable] for r in recs])
    y = np.concatenate([r.y[r.usable] for r in recs])
    r2 = float(1 - np.sum((est - y) ** 2) / np.sum((y - y.mean()) ** 2)) if np.ptp(y) > 0 else math.nan
    return RunCalibration(model, sel, x, ref, xu, yu, [str(r.path) for r in runs], rw,
                          int(sum(int(r.usable.sum()) for r in recs)),
                          datetime.now(timezone.utc).isoformat(timespec="seconds"), r2=r2)
