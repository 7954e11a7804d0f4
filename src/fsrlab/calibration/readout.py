"""What a recorded run holds for a calibration: its readout (C_FSR decoded through its circuit), its provenance.

The calibration reads a run through these functions (:mod:`fsrlab.calibration.runs`,
:mod:`fsrlab.calibration.result`, :mod:`fsrlab.calibration.apply`); they pass the run's columns and
sidecar to the computations on arrays.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, eq. (13).
"""

from __future__ import annotations

import numpy as np

from fsrlab.calibration.provenance import recorded_with
from fsrlab.circuits.circuit import LM555Circuit, decode_capacitance, readout_from_metadata
from fsrlab.errors import ParameterError
from fsrlab.io.runformat import Run, RunFormatError, as_run
from fsrlab.physics.params import float_array

__all__ = ["C_FSR", "run_circuit", "run_readout", "reference_reversed", "run_recorded_with"]

#: The decoded-capacitance variable of the physics-informed calibration. [F]
C_FSR = "c_fsr_farad"


def run_circuit(run: Run, circuit: LM555Circuit | None = None) -> LM555Circuit:
    """The LM555 circuit a run was recorded with.

    Parameters
    ----------
    run : Run
        A loaded run.
    circuit : LM555Circuit, optional
        Returned as is when given.

    Returns
    -------
    LM555Circuit
        ``circuit``, else the sidecar's (:func:`fsrlab.circuits.circuit.readout_from_metadata`),
        else :data:`fsrlab.circuits.circuit.PAPER_CIRCUIT` (R = 10 kΩ, ideal D1, no C_off).
    """
    run = as_run(run)
    if circuit is not None:
        if not isinstance(circuit, LM555Circuit):
            raise TypeError(f"circuit: must be an LM555Circuit, got {type(circuit).__name__}")
        return circuit
    found, _ = readout_from_metadata(run.metadata)
    if found is not None:
        return found
    from fsrlab.circuits.circuit import PAPER_CIRCUIT

    return PAPER_CIRCUIT


def run_readout(run: Run, x: str, circuit: LM555Circuit | None = None) -> tuple[np.ndarray, LM555Circuit | None]:
    """The calibration variable of a run: a column, or C_FSR decoded through the run's circuit.

    Parameters
    ----------
    run : Run
        A loaded run.
    x : str
        A column (``frequency_hz``, ``duty_cycle``, ``voltage_v``, ...), or ``c_fsr_farad``: C_FSR
        decoded from ``frequency_hz`` and ``duty_cycle`` (when the run has no such column),
        honouring the ``range`` column.
    circuit : LM555Circuit, optional
        Circuit for the decoding (default: :func:`run_circuit`).

    Returns
    -------
    values : ndarray
        One value per reading (NaN where missing or not decodable).
    circuit : LM555Circuit or None
        The circuit decoded through, or None for a column.

    Raises
    ------
    RunFormatError
        A column the run lacks.
    """
    run = as_run(run)
    if not isinstance(x, str):
        raise TypeError(f"x: must be the name of a column, got {type(x).__name__}")
    if x != C_FSR and x not in run:
        raise ParameterError(f"{run.path} has no column {x!r} (columns: {', '.join(run.columns)})", parameter="x")
    if x == C_FSR and x not in run:
        run.require("frequency_hz", "duty_cycle")
        circ = run_circuit(run, circuit)
        return decode_capacitance(run["frequency_hz"], run["duty_cycle"], circ, run.columns.get("range")), circ
    return run[x], None


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


def run_recorded_with(run: Run, used=None):
    """What a run was recorded with: its sidecar's circuits and the ranges of its readings.

    Parameters
    ----------
    run : Run
        A loaded run.
    used : array_like of bool, optional
        The readings that count (default all).

    Returns
    -------
    RecordedWith
        See :func:`fsrlab.calibration.provenance.recorded_with`.
    """
    run = as_run(run)
    try:
        return recorded_with(run.metadata, run.columns.get("range"), used)
    except ValueError as exc:
        raise RunFormatError(f"{run.path}: its sidecar's circuit: {exc}") from None
