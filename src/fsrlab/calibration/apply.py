"""From a calibration to the estimate of another run, and the one check that the run was recorded the same way.

:func:`check_readout` compares what a calibration was recorded with (circuit, range, readout column:
:mod:`fsrlab.calibration.provenance`) with a run's sidecar; ``fsrlab apply``, ``fsrlab measure`` and
``fsrlab live`` refuse a calibration through it. :func:`apply_calibration` runs the calibration's
estimator (:mod:`fsrlab.calibration.estimator`) over a run in row order.

Examples
--------
Calibrate one run and estimate the stress of another (``bench.csv`` and ``other.csv`` are runs
in the format of docs/data-format.md)::

    import fsrlab as fl
    cal = fl.calibrate(fl.load_run("bench.csv"), x="frequency_hz", compensate=True)
    est = fl.apply(cal, fl.load_run("other.csv"))["stress_pa_estimate"]
"""

from __future__ import annotations

import numpy as np

from fsrlab.calibration.estimator import MARGIN, _causal_branches, live_estimator
from fsrlab.calibration.heldout_runs import MARGIN as HELD_OUT_MARGIN
from fsrlab.calibration.heldout_runs import RunCalibration
from fsrlab.calibration.provenance import RecordedWith, mismatches
from fsrlab.calibration.readout import C_FSR, _as_run, run_readout, run_recorded_with
from fsrlab.calibration.result import Calibration
from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.errors import ProvenanceError
from fsrlab.io.runformat import Run, RunFormatError

__all__ = ["ESTIMATE_COLUMN", "IN_RANGE_COLUMN", "readout_differences", "check_readout", "apply_calibration"]

#: Column that :func:`apply_calibration` adds: the calibrated stress. [Pa]
ESTIMATE_COLUMN = "stress_pa_estimate"
#: Column that :func:`apply_calibration` adds: 1 where the readout lies in the calibrated readout
#: range, 0 where the estimate is extrapolated or left out, empty where there is no readout. [1]
IN_RANGE_COLUMN = "in_range"

# Sidecar keys that describe a file, not the data; an estimate written from a run drops them.
_FILE_KEYS = ("complete", "rows", "closed", "created", "format", "version", "columns")


def readout_differences(cal: Calibration, recorded: RecordedWith, subject: str,
                        circuit: LM555Circuit | None = None) -> list[str]:
    """The one provenance check: how a readout differs from the one a calibration was recorded with.

    ``fsrlab apply`` (through :func:`check_readout`), ``fsrlab measure`` and ``fsrlab live`` all refuse a
    calibration through this function: the circuit (the LM555's parts, C_off on each range, the op-amp
    readout) and the range the data come from, for the calibration's readout column
    (:func:`fsrlab.calibration.provenance.mismatches`).

    Parameters
    ----------
    cal : Calibration
        The calibration (its ``recorded_with``, readout column and, for C_FSR, its decoding circuit).
    recorded : RecordedWith
        What the data it would be used on are recorded with: a run's
        (:func:`~fsrlab.calibration.readout.run_recorded_with`) or a meter's
        (:func:`~fsrlab.calibration.provenance.recorded_with` of its circuit and range).
    subject : str
        The start of each sentence, naming the data: ``"run.csv was recorded with"``, ``"the meter has"``.
    circuit : LM555Circuit, optional
        The circuit C_FSR is decoded through, when not the calibration's.

    Returns
    -------
    list of str
        One sentence per difference, ``"<subject> <theirs>, <calibration> with <its>"``; empty when nothing
        known differs or when the calibration does not record what it was recorded with.
    """
    if cal.recorded_with is None:
        return []
    name = "the calibration" if cal.path is None else str(cal.path)
    decode = (circuit if circuit is not None else cal.circuit) if cal.x_name == C_FSR else None
    found = mismatches(cal.x_name, cal.recorded_with, recorded, decode)
    return [f"{subject} {a}, {name} with {b}" for a, b in found]


def check_readout(cal: Calibration, run: Run, circuit: LM555Circuit | None = None) -> list[str]:
    """How a run's readout differs from the one a calibration was recorded with (:func:`readout_differences`).

    Parameters
    ----------
    cal : Calibration
        The calibration (its ``recorded_with`` and, for C_FSR, its decoding circuit).
    run : Run
        The run it would be applied to.
    circuit : LM555Circuit, optional
        The circuit C_FSR is decoded through, when not the calibration's.

    Returns
    -------
    list of str
        One sentence per difference naming the run's and the calibration's value (see
        :func:`fsrlab.calibration.provenance.mismatches`); empty when nothing known differs or when
        the calibration does not record what it was recorded with (``cal.recorded_with`` None).
    """
    return readout_differences(cal, run_recorded_with(run), f"{run.path} was recorded with", circuit)


def apply_calibration(cal: Calibration, run, compensation: bool = True, circuit: LM555Circuit | None = None,
                      margin: float | None = None, force: bool = False) -> Run:
    """The run with the stress its calibration estimates, ready for :func:`fsrlab.io.runwriter.write_run`.

    Parameters
    ----------
    cal : Calibration or RunCalibration
        From :func:`calibrate_run`, :func:`fsrlab.calibration.heldout_runs.calibrate_runs` (then
        :meth:`~fsrlab.calibration.heldout_runs.RunCalibration.estimate_run` does the work) or
        :func:`fsrlab.calibration.document.load_calibration`.
    run : Run or path
        The run to convert; it needs the calibration's readout column (or ``frequency_hz`` and
        ``duty_cycle`` for a calibration on ``c_fsr_farad``).
    compensation : bool
        Use the calibration's direction-aware compensation when it holds one (else the polynomial).
    circuit : LM555Circuit, optional
        Circuit for decoding C_FSR (default: the calibration's, else the run's, see :func:`run_circuit`).
    margin : float, optional
        How far beyond the calibrated readout range an estimate is still written, as a fraction
        of the range's span (``inf``: never left empty); beyond it the estimate is left empty.
        Default: :data:`MARGIN` (10 %) for a cross-validated calibration, every reading for a
        held-out one (its curve extrapolates linearly in the readout and its uncertainty grows by
        half the extrapolated amount). [1]
    force : bool
        Apply even where the run's readout differs from the calibration's (:func:`check_readout`).

    Returns
    -------
    Run
        The input columns plus ``stress_pa_estimate`` [Pa] and ``in_range`` (1 inside the
        calibrated readout range, 0 outside, empty without a readout). An estimate is empty where
        the readout is missing, cannot be decoded (C_FSR), or lies beyond the margin. Its metadata
        is the input's without the file keys (``complete``, ``rows``, ...), with the units of the
        new columns and a ``calibration`` entry: file when known, readout, degree, method, data
        fingerprint, creation time, ``readout_range``, ``margin``, ``counts`` (rows ``estimated``,
        ``in_range``, ``out_of_range`` (with a readout outside the range), ``extrapolated``
        (estimated outside the range), ``missing`` (without an estimate) and, per reason,
        ``no_readout``, ``not_decodable``, ``beyond_margin``) and, when forced, ``forced`` (the
        differences). ``path`` is the input run's.

    Raises
    ------
    RunFormatError
        The run lacks the calibration's readout.
    ValueError
        The run's readout differs from the calibration's and ``force`` is false (one line naming
        both), or ``margin`` is negative.

    Notes
    -----
    Readings beyond the margin are treated as missing before the estimate is computed, so that
    one corrupt reading does not bend the compensation's branch detection for the whole run
    (see :meth:`fsrlab.calibration.compensation.DirectionAwareCalibration.predict` for gaps).
    """
    run = _as_run(run)
    if margin is None:
        margin = HELD_OUT_MARGIN if isinstance(cal, RunCalibration) else MARGIN
    if not margin >= 0:
        raise ValueError(f"margin: must be a fraction >= 0 of the calibrated span, got {margin!r}")
    if cal.x_name not in run and cal.x_name != C_FSR:
        raise RunFormatError(f"{run.path}: column {cal.x_name!r} (the calibration's readout) missing "
                             f"(columns: {', '.join(run.columns)})")
    differences = check_readout(cal, run, circuit)
    if differences and not force:
        quantity = "force" if cal.y_name == "force_n" else "stress"
        raise ProvenanceError(f"{differences[0]}: the readout means another {quantity}; calibrate on a run recorded "
                              "the same way, or force it")
    if isinstance(cal, RunCalibration):
        return cal.estimate_run(run, margin=margin, compensation=compensation, forced=differences)
    values, _ = run_readout(run, cal.x_name, circuit if circuit is not None else cal.circuit)
    given = np.isfinite(values)
    lo, hi = cal.x_range
    span = hi - lo
    estimate_col, uncertainty_col = f"{cal.y_name}_estimate", f"{cal.y_name}_uncertainty"
    below = np.zeros_like(given)
    if compensation and cal.compensation is not None and cal.memory is None and _causal_branches(cal) is None:
        # An earlier calibration file: the offline branch method (it needs the whole run).
        inside = given & (values >= lo) & (values <= hi)
        kept = given if margin == np.inf else given & (values >= lo - margin * span) & (values <= hi + margin * span)
        est, how = cal.compensation(np.where(kept, values, np.nan)), "direction-aware compensation"
        unc = np.full(values.shape, np.nan)
    else:
        est, unc, inside, reason = live_estimator(cal, margin, compensation).run(values)
        below = reason == 2
        kept = given & (reason != 3)
        how = ("causal play-operator compensation" if compensation and cal.memory is not None
               else "causal branch compensation (loading/unloading polynomials, turning-point memory)"
               if compensation and _causal_branches(cal) is not None
               else f"{cal.model_name}" if cal.family is not None else f"polynomial of degree {cal.degree}")
    no_readout = ~given
    not_decodable = np.zeros_like(given)
    if cal.x_name == C_FSR and C_FSR not in run:
        parts = np.isfinite(run["frequency_hz"]) & np.isfinite(run["duty_cycle"])
        no_readout, not_decodable = ~given & ~parts, ~given & parts
    columns = dict(run.columns)
    columns[estimate_col] = est
    columns[uncertainty_col] = unc
    columns[IN_RANGE_COLUMN] = np.where(given, inside.astype(float), np.nan)
    counts = {"estimated": int(np.isfinite(est).sum()), "in_range": int(inside.sum()),
              "out_of_range": int((given & ~inside).sum()), "extrapolated": int((np.isfinite(est) & ~inside).sum()),
              "missing": int((~np.isfinite(est)).sum()),
              "no_readout": int(no_readout.sum()), "not_decodable": int(not_decodable.sum()),
              "beyond_margin": int((given & ~kept & ~below).sum()), "below_activation": int(below.sum())}
    meta = {k: v for k, v in run.metadata.items() if k not in _FILE_KEYS}
    meta["units"] = dict(run.units, **{estimate_col: cal.y_unit, uncertainty_col: cal.y_unit, IN_RANGE_COLUMN: "1"})
    source = {} if cal.path is None else {"file": str(cal.path)}
    meta["calibration"] = {**source, "x": cal.x_name, "reference": cal.y_name, "model": cal.model_name,
                           "degree": cal.degree, "method": how, "lag_s": cal.lag_s,
                           "data_fingerprint": cal.data_fingerprint, "created": cal.created,
                           "readout_range": [lo, hi], "margin": margin, "counts": counts}
    if differences:
        meta["calibration"]["forced"] = differences
    return Run(path=run.path, columns=columns, metadata=meta)
