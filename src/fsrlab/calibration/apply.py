"""From a calibration to the estimate of another run, and the one check that the run was recorded the same way.

:func:`check_readout` compares what a calibration was recorded with (circuit, range, readout column:
:mod:`fsrlab.calibration.provenance`) with a run's sidecar; ``fsrlab apply``, ``fsrlab measure`` and
``fsrlab live`` refuse a calibration through it. :func:`apply_calibration` runs the calibration's
estimate (:meth:`fsrlab.calibration.result.Calibration.estimate`) over a run in row order.

Examples
--------
Calibrate one run and estimate the stress of another (``bench.csv`` and ``other.csv`` are runs
in the format of docs/data-format.md)::

    import fsrlab as fl
    cal = fl.calibrate(fl.load_run("bench.csv"), x="frequency_hz", compensate=True)
    est = fl.apply(cal, fl.load_run("other.csv"))["stress_pa_estimate"]
"""

from __future__ import annotations

import os

from fsrlab.calibration.provenance import mismatches, same_unit
from fsrlab.calibration.result import Calibration, as_margin, require_calibration
from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.errors import FsrlabError, ParameterError, ProvenanceError
from fsrlab.io.recorded import RecordedWith
from fsrlab.io.runformat import C_FSR, Run, as_run

__all__ = ["readout_differences", "check_readout", "apply_calibration"]


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
        (:meth:`~fsrlab.io.runformat.Run.recorded_with`) or a meter's
        (:func:`~fsrlab.io.recorded.recorded_with` of its circuit and range).
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
    require_calibration(cal, "cal")
    run = as_run(run)
    found = readout_differences(cal, run.recorded_with(), f"{run.path} was recorded with", circuit)
    unit = run.units.get(cal.x_name, "")
    if cal.x_name in run and not same_unit(unit, cal.x_unit):
        name = "the calibration" if cal.path is None else str(cal.path)
        found.append(f"{run.path} has {cal.x_name} in {unit}, {name} in {cal.x_unit}")
    return found


def apply_calibration(cal, run, compensation: bool = True, circuit: LM555Circuit | None = None,
                      margin: float | None = None, force: bool = False) -> Run:
    """The run with the estimate of its calibration, ready for :func:`fsrlab.io.runwriter.write_run`.

    Parameters
    ----------
    cal : Calibration or path
        From :func:`fsrlab.calibrate`, or a calibration file (read by
        :func:`fsrlab.calibration.document.load_calibration`).
    run : Run or path
        The run to convert; it needs the calibration's readout column (or ``frequency_hz`` and
        ``duty_cycle`` for a calibration on ``c_fsr_farad``).
    compensation : bool
        Use the calibration's memory terms when it has them (False: the static curve alone).
    circuit : LM555Circuit, optional
        Circuit for decoding C_FSR (default: the calibration's, else the run's).
    margin : float, optional
        How far beyond the calibrated readout range an estimate is still written, a fraction of the
        range's span (default: every reading); the memory takes every reading whatever it is. [1]
    force : bool
        Apply even where the run's readout differs from the calibration's (:func:`check_readout`).

    Returns
    -------
    Run
        :meth:`Calibration.estimate`'s: the input columns plus ``<reference>_estimate``,
        ``<reference>_uncertainty`` and ``in_range``, and a ``calibration`` entry in the metadata
        (with ``forced``: the differences ignored).

    Raises
    ------
    ParameterError
        ``cal`` neither a calibration nor a path, a negative ``margin``.
    RunFormatError
        The run lacks the calibration's readout.
    ProvenanceError
        The run's readout differs from the calibration's and ``force`` is false (one line naming both).
    """
    if isinstance(cal, (str, os.PathLike)):
        from fsrlab.calibration.document import load_calibration

        try:
            cal = load_calibration(cal)
        except FsrlabError as exc:  # the file is this function's cal
            raise type(exc)(exc.reason, parameter="cal") from None
    if not isinstance(cal, Calibration):
        raise ParameterError(f"must be a Calibration (fsrlab.calibrate, fsrlab.load_calibration) or the path of a "
                             f"calibration file, got {type(cal).__name__}", parameter="cal")
    margin = as_margin(margin)
    run = as_run(run)
    cal.readout(run, circuit)  # a run without the readout is refused before the provenance is compared
    differences = check_readout(cal, run, circuit)
    if differences and not force:
        quantity = "force" if cal.y_name == "force_n" else "stress"
        raise ProvenanceError(f"{differences[0]}: the readout means another {quantity}; calibrate on a run recorded "
                              "the same way, or force it")
    return cal.estimate(run, margin=margin, compensation=compensation, circuit=circuit, forced=differences)
