"""Calibrate from one or more recorded runs, every choice scored held out: :func:`calibrate_runs`.

**Extension beyond the paper.** The orchestration of :mod:`fsrlab.calibration.selection` on
runs: it checks its arguments, reads each run's readout (a column, or C_FSR decoded through the run's
circuit), reference and times, and returns a :class:`~fsrlab.calibration.result.Calibration`; it
holds no model of its own. ``fsrlab calibrate RUN.csv [RUN2.csv ...]`` and :func:`fsrlab.calibrate` are it.

Examples
--------
::

    import fsrlab as fl
    cal = fl.calibrate(["hand.csv", "motor.csv"], x="reading", reference="force_n", compensate=True)
    out = fl.apply(cal, fl.load_run("other.csv"))   # a Run with force_n_estimate and force_n_uncertainty
"""

from __future__ import annotations

import math
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from fsrlab.calibration.provenance import mismatches, same_unit
from fsrlab.calibration.result import METHOD, Calibration
from fsrlab.calibration.scoring import Recording
from fsrlab.calibration.selection import calibrate_recordings
from fsrlab.errors import ParameterError
from fsrlab.io.recorded import recorded_with
from fsrlab.io.runformat import C_FSR, KNOWN_COLUMNS, Run, as_run
from fsrlab.physics.params import float_array

__all__ = ["METHOD", "MIN_READINGS", "REFERENCES", "calibrate_runs", "check_arguments", "reference_column",
           "reference_reversed"]

#: Fewest readings (readout and reference both present) of each run: held-out scoring cuts one run into
#: 5 blocks and scores 3 of them in 8 chunks. [1]
MIN_READINGS = 20
#: The reference columns a calibration is made against.
REFERENCES = ("force_n", "stress_pa")


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


def _as_runs(runs) -> list[Run]:
    """``runs`` as a list of loaded runs: a Run (a synthetic run is one), a path, or a sequence of them."""
    if isinstance(runs, (Run, str, Path)):
        runs = [runs]
    try:
        runs = list(runs)
    except TypeError:
        raise ParameterError(f"must be a run, a path or a sequence of them, got {type(runs).__name__}",
                             parameter="runs") from None
    if not runs:
        raise ParameterError("at least one run", parameter="runs")
    out = []
    for r in runs:
        if isinstance(r, (str, Path)):
            r = as_run(r, "runs")
        if not isinstance(r, Run):
            raise ParameterError(f"must be runs (fsrlab.load_run) or their paths, got {type(r).__name__}",
                                 parameter="runs")
        out.append(r)
    return out


def _positive(value, parameter: str, what: str) -> float | None:
    """``value`` as a finite number > 0, None as None; anything else a ParameterError."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"must be a number, {what}, got {value!r}", parameter=parameter)
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"must be > 0 ({what}), got {value!r}", parameter=parameter)
    return float(value)


def _check_reference(reference):
    """``reference`` itself when it is None or one of :data:`REFERENCES`, else a ParameterError naming it."""
    if reference is not None and reference not in REFERENCES:
        raise ParameterError(f"must be one of {', '.join(REFERENCES)} (the reference column), got {reference!r}",
                             parameter="reference")
    return reference


def check_arguments(x, reference=None, compensate=False, rail=None, between_runs=None) -> None:
    """The arguments of :func:`calibrate_runs` that do not depend on the runs, checked before any is read.

    Parameters
    ----------
    x : str
        The readout column.
    reference : {"force_n", "stress_pa"} or None
        The reference column (None: the runs' own).
    compensate : bool
        Whether the memory is tried.
    rail : float or None
        The readout's full scale. [unit of the readout]
    between_runs : float or None
        Relative standard uncertainty between recordings, 0 to 1. [1]

    Raises
    ------
    ParameterError
        Naming the parameter: ``x`` not a column name or a reference column, ``reference`` not one of
        :data:`REFERENCES`, ``compensate`` not a bool, ``rail`` not above zero, ``between_runs`` outside 0–1.
    """
    if not isinstance(x, str) or not x:
        raise ParameterError(f"must be the name of the readout column, got {x!r}", parameter="x")
    _check_reference(reference)
    if x in REFERENCES:
        raise ParameterError(f"{x} is a reference column: a calibration of the reference against itself (or against "
                             "itself divided by the area) says nothing; give a readout such as frequency_hz",
                             parameter="x")
    if not isinstance(compensate, (bool, np.bool_)):
        raise ParameterError(f"must be True or False, got {compensate!r}", parameter="compensate")
    _positive(rail, "rail", "the readout's full scale in its unit")
    if between_runs is not None and (isinstance(between_runs, bool) or not isinstance(
            between_runs, (int, float, np.integer, np.floating)) or not 0 <= between_runs <= 1):
        raise ParameterError(f"must be a relative uncertainty from 0 to 1 (0 % to 100 %), got {between_runs!r}",
                             parameter="between_runs")


def reference_column(runs, reference: str | None = None) -> str:
    """The reference column a calibration of ``runs`` is made against (not checked against the runs:
    :func:`calibrate_runs` does that).

    Parameters
    ----------
    runs : Run, path, or a sequence of them
        The runs.
    reference : {"force_n", "stress_pa"} or None
        The column asked for (None: ``stress_pa`` when every run has it, else ``force_n``).

    Returns
    -------
    str
    """
    if _check_reference(reference) is not None:
        return reference
    return "stress_pa" if all("stress_pa" in r for r in _as_runs(runs)) else "force_n"


def _check(runs: list[Run], x, reference, compensate, rail, between_runs) -> str:
    """The arguments of :func:`calibrate_runs` checked (:func:`check_arguments`, then against the runs); the
    reference column returned."""
    check_arguments(x, reference, compensate, rail, between_runs)
    for run in runs:
        if x not in run and not (x == C_FSR and "frequency_hz" in run and "duty_cycle" in run):
            raise ParameterError(f"{run.path}: column {x!r} missing (columns: {', '.join(run.columns)})",
                                 parameter="x")
    ref = reference_column(runs, reference)
    for run in runs:
        if ref not in run:
            missing = f"column {ref!r}" if reference else "column 'force_n' [N] or 'stress_pa' [Pa]"
            raise ParameterError(f"{run.path}: no reference: {missing} missing (columns: {', '.join(run.columns)})",
                                 parameter="reference" if reference else "runs")
    if rail is not None:
        for run in runs:
            v = np.asarray(run[x], dtype=float) if x in run else np.zeros(0)
            if np.isfinite(v).any() and float(np.nanmax(v)) >= rail:
                raise ParameterError(f"{run.path}: {x} reaches {float(np.nanmax(v)):g}, not below the full scale "
                                     f"{rail:g}", parameter="rail")
    return ref


def _lag_rows(lag, runs: list[Run]) -> int | str:
    """``lag`` [s] (or "auto") in whole rows of the first run's median time step (rows without ``time_s``)."""
    if isinstance(lag, str) and lag == "auto":
        return "auto"
    if isinstance(lag, bool) or not isinstance(lag, (int, float, np.integer, np.floating)) or not math.isfinite(lag):
        raise ParameterError(f"must be \"auto\" or a finite lag in seconds such as 0.02, got {lag!r}", parameter="lag")
    first = runs[0]
    t = np.asarray(first["time_s"], dtype=float) if "time_s" in first else np.arange(first.n_rows, dtype=float)
    dt = np.diff(t[np.isfinite(t)])
    step = float(np.median(dt)) if dt.size else 1.0
    return int(round(lag / step)) if step > 0 else 0


def reference_reversed(y) -> str | None:
    """Why a reference looks reversed (a load cell mounted or wired the wrong way round), or None.

    It does when most of its values are below zero **and** its largest excursion is below zero
    (``−min > max``): the presses go negative. A reference whose rest level sits below zero (a load
    cell not tared, an offset that drifted) with presses going positive is mostly negative too, but
    is not reversed: its estimate is of the reference as recorded.

    Parameters
    ----------
    y : array_like
        The reference's values (NaN ignored). [N or Pa]
    """
    y = float_array("y", y)
    y = y[np.isfinite(y)]
    if y.size == 0:
        return None
    neg = float(np.mean(y < 0))
    if neg > 0.5 and -float(np.min(y)) > float(np.max(y)):
        return (f"the reference is mostly negative ({100 * neg:.0f} % of the readings below 0, down to "
                f"{float(np.min(y)):.4g}, up to {float(np.max(y)):.4g})")
    return None


def _recording(run: Run, x: str, ref: str, circuit) -> tuple[Recording, str, str]:
    values, _ = run.readout_values(x, circuit)
    t = np.asarray(run["time_s"], dtype=float) if "time_s" in run else np.arange(run.n_rows, dtype=float)
    rec = Recording(t, np.asarray(values, dtype=float), np.asarray(run[ref], dtype=float), str(run.path))
    xu = run.units.get(x) or KNOWN_COLUMNS.get(x, "") or ("F" if x == C_FSR else "")
    return rec, xu, run.units.get(ref) or KNOWN_COLUMNS.get(ref, "")


def _recordings(runs: list[Run], x: str, ref: str, circuit) -> tuple[list[Recording], str, str, list]:
    """The runs' recordings, the units of ``x`` and ``ref`` and what each run was recorded with; refused when the
    runs' readouts differ, a run has too few readings, or the reference looks reversed."""
    recs, xu, yu = [], "", ""
    for run in runs:
        rec, run_xu, yu = _recording(run, x, ref, circuit)
        if not same_unit(run_xu, xu):
            raise ParameterError(f"{run.path} has {x} in {run_xu}, {runs[0].path} in {xu}: calibrate runs of one "
                                 "readout together", parameter="runs")
        xu = xu or run_xu
        recs.append(rec)
        if int(rec.usable.sum()) < MIN_READINGS:
            raise ParameterError(f"{run.path}: {x} and {ref}: fewer than {MIN_READINGS} readings with both values "
                                 "present (held-out scoring cuts a run into blocks)", parameter="runs")
    y_all = np.concatenate([r.y[r.usable] for r in recs])
    reversed_why = reference_reversed(y_all)
    if reversed_why:
        raise ParameterError(f"{ref}: {reversed_why}: a load cell mounted or wired the wrong way round, or the "
                             "wrong column", parameter="reference")
    rws = [recorded_with(r.metadata, r.columns.get("range"), rec.usable) for r, rec in zip(runs, recs, strict=True)]
    for other, run in zip(rws[1:], runs[1:], strict=True):
        diff = mismatches(x, rws[0], other, circuit)
        if diff:
            raise ParameterError(f"{run.path}: recorded with {diff[0][0]}, {runs[0].path} with {diff[0][1]}: "
                                 "calibrate runs of one readout together", parameter="runs")
    return recs, xu, yu, rws


def calibrate_runs(runs, x: str = "frequency_hz", reference: str | None = None, compensate: bool = False,
                   lag: float | str = 0.0, rail: float | None = None, between_runs: float | None = None) -> Calibration:
    """Calibrate a readout to its reference from one or more runs, every choice scored held out.

    Parameters
    ----------
    runs : Run, path, synthetic run, or a sequence of them
        Recordings of the same sensor and readout.
    x : str
        Readout column, or ``c_fsr_farad``: C_FSR decoded from ``frequency_hz`` and ``duty_cycle``
        through the circuit of the run's sidecar (:meth:`fsrlab.io.runformat.Run.readout_values`). Its unit
        and name pass to the engine: a resistance (a unit in ohms, a column named ``*_ohm``) is calibrated in
        its conductance (:func:`fsrlab.calibration.scoring.readout_variables`). [its unit]
    reference : {"force_n", "stress_pa"}, optional
        Reference column (default: ``stress_pa`` when the runs have it, else ``force_n``).
    compensate : bool
        Try the memory terms (hysteresis and creep, alone and together); the best, its correction
        weighted by the held-out error, is kept only when it beats the simpler calibration on held-out
        recordings or later blocks by more than one standard error and 5 % of its MSE.
    lag : float or "auto"
        Lag of the readout behind the reference (default 0: the estimate is of the reference as
        recorded, and a delay of the reference is tried); ``"auto"``: a shift of whole rows searched,
        kept only when it wins held out. A number is taken in whole rows of the first run's median
        time step. [s]
    rail : float, optional
        The readout's full scale for the conductance variable (a divider's supply for its voltage),
        when the runs' sidecar does not give it; every reading must lie below it. [unit of the readout]
    between_runs : float, optional
        Relative standard uncertainty between recordings, the floor of the uncertainty's term for what
        changes from one recording to the next, in [0, 1]: default
        :data:`~fsrlab.calibration.uncertainty.REPEATABILITY` (15 %); the held-out runs' gain
        spread when it is larger. docs/calibration.md: 1–8 % for a film under a robot, about 20 % for
        an FSR placed by hand from one session to the next. [1]

    Returns
    -------
    Calibration

    Raises
    ------
    ParameterError
        A bad argument (``.parameter`` names it): ``x`` a reference or a column the runs lack, an unknown
        ``reference``, ``rail`` ≤ 0 or reached by a reading, ``between_runs`` outside 0–1, a ``lag``
        that is neither a number nor "auto", no runs.
    ValueError
        Too few readings, a readout that does not follow the reference, runs recorded differently.
    """
    runs = _as_runs(runs)
    ref = _check(runs, x, reference, compensate, rail, between_runs)
    lag_rows = _lag_rows(lag, runs)
    circuit = runs[0].circuit() if x == C_FSR and x not in runs[0] else None
    recs, xu, yu, rws = _recordings(runs, x, ref, circuit)
    y_all = np.concatenate([r.y[r.usable] for r in recs])
    try:
        model, sel = calibrate_recordings(recs, compensate=bool(compensate), lag=lag_rows,
                                          rail=_divider_rail(runs[0], x) if rail is None else float(rail),
                                          between_runs=None if between_runs is None else float(between_runs),
                                          unit=xu, name=x)  # a resistance is calibrated in its conductance
    except ValueError as exc:
        names = ", ".join(str(r.path) for r in runs)
        why = exc.reason if isinstance(exc, ParameterError) else str(exc)
        raise ParameterError(f"{names}: {x} and {ref}: {why}",
                             parameter=getattr(exc, "parameter", None) or "runs") from None
    est = np.concatenate([model.run(r.t, r.x)[0][r.usable] for r in recs])
    r2 = float(1 - np.sum((est - y_all) ** 2) / np.sum((y_all - y_all.mean()) ** 2)) if np.ptp(y_all) > 0 else math.nan
    lag_s = float(f"{sel.lag_rows * model.row_s:.10g}")  # without the float noise of the step
    return Calibration(model, sel, x, ref, xu, yu, [str(r.path) for r in runs], rws[0],
                       int(sum(int(r.usable.sum()) for r in recs)),
                       datetime.now(UTC).isoformat(timespec="seconds"), r2=r2, circuit=circuit, lag_s=lag_s)
