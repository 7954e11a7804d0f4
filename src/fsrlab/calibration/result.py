"""The one calibration result, :class:`Calibration`: estimate a run, step readings, save, plot.

**Extension beyond the paper.** What :func:`fsrlab.calibrate` (:func:`fsrlab.calibration.runs.calibrate_runs`)
returns and :func:`fsrlab.load_calibration` reads. One contract for every calibration, whatever its
curve, memory and readout variable:

* :meth:`Calibration.estimate` -- a run with ``<reference>_estimate``, ``<reference>_uncertainty`` and
  ``in_range``; the memory takes every reading in row order, ``margin`` only decides which estimates are
  reported, so no estimate inside the calibrated range depends on it;
* :meth:`Calibration.estimator` -- the same numbers one reading at a time (``fsrlab measure``, ``live``);
* :meth:`Calibration.to_dict` / :meth:`Calibration.from_dict` -- the file (``"version": 2``; files of
  version 1 in either earlier layout are read and applied, read-only: :mod:`fsrlab.calibration.legacy`);
* :meth:`Calibration.plot` -- the curve, its ±2u band and the data (matplotlib, imported when called).

Examples
--------
::

    import fsrlab as fl
    cal = fl.calibrate("examples/bench.csv", compensate=True)
    cal                                   # Calibration(stress_pa(frequency_hz): monotone-..., held-out RMSE ...)
    out = cal.estimate(fl.load_run("examples/other.csv"))   # stress_pa_estimate, stress_pa_uncertainty, in_range
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fsrlab.calibration.legacy import LegacyModel, is_legacy
from fsrlab.calibration.model import HeldoutCalibration
from fsrlab.calibration.selection import Selection
from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.io.calibration_file import CALIBRATION_FORMAT, CALIBRATION_VERSION
from fsrlab.io.recorded import RecordedWith
from fsrlab.io.runformat import C_FSR, Run, RunFormatError, as_run

__all__ = ["METHOD", "MARGIN", "Calibration", "Estimator", "as_margin", "require_calibration"]

#: The ``method`` of a calibration file written by this fsrlab.
METHOD = "held-out"
#: Default margin beyond the calibrated readout range, a fraction of its span, within which an
#: estimate is reported (flagged ``in_range`` 0): every reading, since the curve extrapolates linearly
#: and the uncertainty grows by half the extrapolated amount. [1]
MARGIN = float("inf")
_FILE_KEYS = ("complete", "rows", "closed", "created", "format", "version", "columns")


def as_margin(margin) -> float:
    """``margin`` as a fraction ≥ 0 of the calibrated span (None: :data:`MARGIN`); a number, not a string.

    Parameters
    ----------
    margin : float or None
        How far beyond the calibrated readout range an estimate is reported, a fraction of its span. [1]

    Raises
    ------
    ParameterError
        Negative, NaN, or not a number (``"10%"`` is for the command line; give 0.1).
    """
    if margin is None:
        return MARGIN
    if isinstance(margin, bool) or not isinstance(margin, (int, float, np.integer, np.floating)):
        raise ParameterError(f"must be a number, a fraction >= 0 of the calibrated span such as 0.1 for 10 %, "
                             f"got {margin!r}", parameter="margin")
    if not float(margin) >= 0:
        raise ParameterError(f"must be a fraction >= 0 of the calibrated span, got {margin!r}", parameter="margin")
    return float(margin)


def require_calibration(cal, parameter: str = "cal") -> Calibration:
    """``cal`` itself when it is a :class:`Calibration`; anything else is refused naming ``parameter``.

    Parameters
    ----------
    cal : Calibration
        The value given.
    parameter : str
        The parameter's name, for the error.

    Returns
    -------
    Calibration

    Raises
    ------
    ParameterError
        Not a :class:`Calibration` (a path: load it with :func:`fsrlab.load_calibration` first).
    """
    if not isinstance(cal, Calibration):
        hint = "; load the file with fsrlab.load_calibration first" if isinstance(cal, (str, Path)) else ""
        raise ParameterError(f"must be a Calibration (fsrlab.calibrate, fsrlab.load_calibration), got "
                             f"{type(cal).__name__}{hint}", parameter=parameter)
    return cal


@dataclass(repr=False)
class Calibration:
    """A calibration of a readout to its reference, ready to apply, step, save and plot.

    Parameters
    ----------
    model : HeldoutCalibration or LegacyModel
        The curve, memory and uncertainty (a :class:`~fsrlab.calibration.legacy.LegacyModel` for a
        file of the earlier cross-validated layout).
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
    created : str
        UTC time, ISO 8601.
    path : Path or None
        The file it was read from.
    r2 : float
        Coefficient of determination of the estimate on the readings fitted (in sample). [1]
    circuit : LM555Circuit or None
        The circuit C_FSR was decoded through (``x_name`` ``c_fsr_farad``), used again when applied.
    lag_s : float
        Lag of the readout behind the reference the calibration was fitted with. [s]
    """

    model: HeldoutCalibration | LegacyModel
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
    circuit: LM555Circuit | None = None
    lag_s: float = 0.0

    @property
    def read_only(self) -> bool:
        """Whether it comes from a file of the earlier cross-validated layout (applied, never written anew)."""
        return isinstance(self.model, LegacyModel)

    @property
    def x_range(self) -> tuple[float, float]:
        """Calibrated readout range (lowest, highest). [unit of x]"""
        return self.model.x_range if self.read_only else self.model.curve.x_range

    @property
    def full_scale(self) -> float:
        return self.model.full_scale

    @property
    def model_name(self) -> str:
        """``monotone-readout-4+hysteresis+creep``, ``polynomial-3`` (a read-only file's), ..."""
        return _model_name(self.model)

    def __repr__(self) -> str:
        lo, hi = self.x_range
        rmse = self.selection.heldout_rmse
        score = ("read-only (an earlier fsrlab's file)" if self.read_only else
                 f"held-out RMSE {rmse:.4g} {self.y_unit}".rstrip() if math.isfinite(rmse) else None)
        runs = f"{self.n} readings of {len(self.sources)} run{'s' if len(self.sources) != 1 else ''}"
        parts = [self.model_name, score, f"readout {lo:.6g} … {hi:.6g}{' ' + self.x_unit if self.x_unit else ''}", runs]
        return f"Calibration({self.y_name}({self.x_name}): {', '.join(p for p in parts if p)})"

    # ---------------------------------------------------------------------------------- the file
    def to_dict(self) -> dict:
        """The calibration file's content (``"version": 2``; a read-only one: its file as it was)."""
        if self.read_only:
            return self.model.to_dict()
        return {"format": CALIBRATION_FORMAT, "version": CALIBRATION_VERSION, "method": METHOD,
                "model": self.model_name, "x": self.x_name, "y": self.y_name,
                "units": {"x": self.x_unit, "y": self.y_unit}, "readout_range": list(self.x_range),
                "lag_s": self.lag_s, "n": self.n, "r2": self.r2 if math.isfinite(self.r2) else None,
                "created": self.created, "sources": list(self.sources),
                "recorded_with": None if self.recorded_with is None else self.recorded_with.to_dict(),
                "circuit": None if self.circuit is None else self.circuit.to_dict(),
                "selection": self.selection.to_dict(), "calibration": self.model.to_dict()}

    @classmethod
    def from_dict(cls, d: dict, path: Path | None = None) -> Calibration:
        """Inverse of :meth:`to_dict`, for version 2 and both layouts of version 1.

        Raises
        ------
        KeyError, TypeError, ValueError
            An entry missing or malformed.
        """
        rw = d.get("recorded_with")
        rw = None if rw is None else RecordedWith.from_dict(rw)
        units = d.get("units") or {}
        parts = d.get("circuit") if "circuit" in d else d.get("decode")
        circuit = None if not parts else LM555Circuit.from_dict(parts)
        lag = d.get("lag_s")
        if lag is not None and (isinstance(lag, bool) or not isinstance(lag, (int, float)) or not math.isfinite(lag)):
            raise FileFormatError(f"lag_s must be a finite number of seconds or null, got {lag!r}")
        lag = 0.0 if lag is None else float(lag)
        common = dict(x_name=str(d["x"]), y_name=str(d["y"]), x_unit=str(units.get("x", "")),
                      y_unit=str(units.get("y", "")), recorded_with=rw, created=str(d.get("created", "")), path=path,
                      circuit=circuit, lag_s=lag)
        if is_legacy(d):
            met = d.get("metrics") or {}
            rmse = d.get("cv_rmse") if d.get("cv_rmse") is not None else met.get("rmse", math.nan)
            sel = Selection("grouped cross-validation inside one run (an earlier fsrlab)", heldout_rmse=float(rmse),
                            heldout_rmse_plain=float(met.get("rmse", math.nan)))
            return cls(LegacyModel(d), sel, sources=[str(d.get("source", ""))], n=int(met.get("n", 0)),
                       r2=float(met.get("r2", math.nan)), **common)
        s = d.get("selection") or {}
        sel = Selection(str(s.get("scheme", "")), list(s.get("candidates", [])), list(s.get("steps", [])),
                        int(s.get("lag_rows", 0)), float(s.get("heldout_rmse", math.nan)),
                        float(s.get("heldout_rmse_plain", math.nan)), s.get("gain_spread"))
        sel.readout = dict(s.get("readout") or {})  # which readout variables were tried and used, and why
        return cls(HeldoutCalibration.from_dict(d["calibration"]), sel, sources=list(d.get("sources", [])),
                   n=int(d.get("n", 0)), r2=float(d.get("r2") if d.get("r2") is not None else math.nan), **common)

    # ---------------------------------------------------------------------------------- applying
    def estimator(self, margin: float | None = None, compensation: bool = True) -> Estimator:
        """A causal estimator: ``step(reading, t=None) -> (estimate, uncertainty, in_range)``, equal to
        :meth:`estimate` row by row."""
        return Estimator(self, margin, compensation)

    def readout(self, run: Run, circuit: LM555Circuit | None = None) -> np.ndarray:
        """The calibration's readout of a run: its column, or C_FSR decoded through ``circuit`` (default:
        the calibration's, else the run's). [unit of x]"""
        run = as_run(run)
        if self.x_name not in run and self.x_name != C_FSR:
            raise RunFormatError(f"{run.path}: column {self.x_name!r} (the calibration's readout) missing "
                                 f"(columns: {', '.join(run.columns)})")
        values, _ = run.readout_values(self.x_name, circuit if circuit is not None else self.circuit)
        return np.asarray(values, dtype=float)

    def estimate(self, run: Run, margin: float | None = None, compensation: bool = True,
                 circuit: LM555Circuit | None = None, forced: list | None = None) -> Run:
        """The run with ``<reference>_estimate``, ``<reference>_uncertainty`` and ``in_range``.

        Parameters
        ----------
        run : Run
            The run (it needs the readout column, or ``frequency_hz`` and ``duty_cycle`` for ``c_fsr_farad``).
        margin : float, optional
            Beyond the calibrated readout range by more than this fraction of its span, no estimate is
            reported (default :data:`MARGIN`: every reading). Every reading feeds the memory, in row
            order, whatever the margin. [1]
        compensation : bool
            Use the memory terms when the calibration has them (False: the static curve alone).
        circuit : LM555Circuit, optional
            The circuit C_FSR is decoded through, when not the calibration's.
        forced : list of str, optional
            Provenance differences ignored by :func:`fsrlab.calibration.apply.apply_calibration`, kept
            in the metadata. No provenance check here.

        Returns
        -------
        Run
            The input columns and the three new ones; metadata with their units and a ``calibration``
            entry (``counts``: ``estimated``, ``in_range``, ``out_of_range``, ``extrapolated``,
            ``missing``, ``no_readout``, ``not_decodable``, ``beyond_margin``, ``below_activation``).
        """
        margin = as_margin(margin)
        run = as_run(run)
        if forced is not None and not (isinstance(forced, (list, tuple)) and all(isinstance(f, str) for f in forced)):
            raise TypeError(f"forced: must be a list of provenance differences (str), got {forced!r}")
        x = self.readout(run, circuit)
        t = np.asarray(run["time_s"], dtype=float) if "time_s" in run else np.arange(x.size) * self.model.row_s
        model = self.model if compensation else self.model.without_memory()
        est, d = model.run(t, x)
        given = np.isfinite(x)
        lo, hi = self.x_range
        span = hi - lo
        with np.errstate(invalid="ignore"):
            inside = given & (x >= lo) & (x <= hi)
            kept = given & (x >= lo - margin * span) & (x <= hi + margin * span) if math.isfinite(margin) else given
        extra = model.extrapolated(x, lo, hi) if (given & ~inside).any() else None
        u = model.uncertainty(est, d, extra) if model.uncertainty is not None else np.full(x.shape, np.nan)
        ycol, ucol = f"{self.y_name}_estimate", f"{self.y_name}_uncertainty"
        columns = dict(run.columns)
        columns[ycol] = np.where(kept, est, np.nan)
        columns[ucol] = np.where(kept & np.isfinite(est), u, np.nan)
        columns["in_range"] = np.where(given, inside.astype(float), np.nan)
        meta = {k: v for k, v in run.metadata.items() if k not in _FILE_KEYS}
        meta["units"] = dict(run.units, **{ycol: self.y_unit, ucol: self.y_unit, "in_range": "1"})
        meta["calibration"] = {**({} if self.path is None else {"file": str(self.path)}), "x": self.x_name,
                               "reference": self.y_name, "model": _model_name(model),
                               "method": "cross-validated (an earlier fsrlab's file, "
                                       "read-only)" if self.read_only else METHOD, "lag_s": self.lag_s,
                               "created": self.created, "readout_range": [lo, hi],
                               "margin": margin if math.isfinite(margin) else None,
                               "counts": _counts(run, self.x_name, columns[ycol], given, inside, kept, est)}
        if forced:
            meta["calibration"]["forced"] = list(forced)
        return Run(path=run.path, columns=columns, metadata=meta)

    # ---------------------------------------------------------------------------------- drawing
    def plot(self, ax=None, run: Run | None = None, points: int = 200):
        """Draw the static curve over the calibrated readout range with its ±2u band, and a run's data.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).
        run : Run, optional
            A run with the readout and the reference, drawn as points.
        points : int
            Points of the drawn curve.

        Returns
        -------
        matplotlib.axes.Axes
        """
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots()
        lo, hi = self.x_range
        grid = np.linspace(lo, hi, int(points))
        static = self.model.without_memory()
        y = static.curve_estimate(grid)
        if run is not None:
            ax.plot(self.readout(run), np.asarray(run[self.y_name], dtype=float), ".", ms=3, alpha=0.5, label="data")
        if static.uncertainty is not None:
            u = static.uncertainty(y, np.zeros(grid.size, dtype=int))
            ax.fill_between(grid, y - 2 * u, y + 2 * u, color="0.85", label="±2u")
        ax.plot(grid, y, "-", color="k", label=static.static_name)
        ax.set_xlabel(f"{self.x_name} [{self.x_unit or '1'}]")
        ax.set_ylabel(f"{self.y_name} [{self.y_unit}]")
        ax.set_title(repr(self), fontsize=7)
        ax.legend()
        return ax


def _model_name(m) -> str:
    if isinstance(m, LegacyModel):
        return m.static_name + ("+hysteresis" if m.has_memory else "")
    mem = (("+hysteresis" + ("·level" if m.scaled else "")) if m.thresholds else "") + \
        ("+creep" if m.time_constants else "")
    return f"monotone-{m.static_name}{mem}"


def _counts(run: Run, x_name: str, estimate, given, inside, kept, raw) -> dict:
    """Rows estimated, in and out of range, and without an estimate by reason."""
    not_decodable = np.zeros(given.shape, bool)
    if x_name == C_FSR and C_FSR not in run:
        parts = np.isfinite(run["frequency_hz"]) & np.isfinite(run["duty_cycle"])
        not_decodable = ~given & parts
    below = given & kept & ~np.isfinite(raw)
    return {"estimated": int(np.isfinite(estimate).sum()), "in_range": int(inside.sum()),
            "out_of_range": int((given & ~inside).sum()), "extrapolated": int((np.isfinite(estimate) & ~inside).sum()),
            "missing": int((~np.isfinite(estimate)).sum()), "no_readout": int((~given & ~not_decodable).sum()),
            "not_decodable": int(not_decodable.sum()), "beyond_margin": int((given & ~kept).sum()),
            "below_activation": int(below.sum())}


class Estimator:
    """The estimates of :meth:`Calibration.estimate`, one reading at a time (``fsrlab measure``, ``fsrlab live``).

    Parameters
    ----------
    cal : Calibration
        The calibration.
    margin : float, optional
        Beyond the calibrated readout range by more than this fraction of its span, no estimate is
        reported (the memory still takes the reading). [1]
    compensation : bool
        Use the memory terms when the calibration has them.

    Notes
    -----
    ``step(readout, t=None)`` returns ``(estimate or None, standard uncertainty or None, in_range)``;
    ``reference`` and ``x`` name the quantities. A missing reading leaves the memory as it is.
    """

    def __init__(self, cal: Calibration, margin: float | None = None, compensation: bool = True):
        if not isinstance(cal, Calibration):
            raise TypeError(f"cal: must be a Calibration (fsrlab.calibrate, fsrlab.load_calibration), got "
                            f"{type(cal).__name__}")
        margin = as_margin(margin)
        self.cal = cal
        self.model = cal.model if compensation else cal.model.without_memory()
        self.reference, self.x = cal.y_name, cal.x_name
        self.stepper = self.model.stepper()
        self.lo, self.hi = cal.x_range
        span = self.hi - self.lo
        self.kept = ((self.lo - margin * span, self.hi + margin * span) if math.isfinite(margin)
                     else (-math.inf, math.inf))
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
        if est is None or not math.isfinite(est) or not self.kept[0] <= x <= self.kept[1]:
            return None, None, inside
        u = None
        m = self.model
        if m.uncertainty is not None:
            extra = None if inside else m.extrapolated(np.array([x]), self.lo, self.hi)
            u = float(m.uncertainty(np.array([est]), np.array([d]), extra)[0])
        return est, u, inside
