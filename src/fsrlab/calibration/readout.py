"""What a recorded run holds for a calibration: its readout, its reference, its branches, cycles and circuit.

The calibration reads a run through these functions (:mod:`fsrlab.calibration.heldout_runs`,
:mod:`fsrlab.calibration.result`, :mod:`fsrlab.calibration.apply`); they pass the run's columns and
sidecar to the computations on arrays. The hysteresis error of a run (:func:`hysteresis_of_run`) follows
its ``direction`` and ``cycle`` columns when it has them, else the branches found from the reference.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, eq. (13).
"""

from __future__ import annotations

import numpy as np

from fsrlab.calibration.provenance import recorded_with
from fsrlab.circuits.circuit import LM555Circuit, readout_from_metadata
from fsrlab.io.runformat import Run, RunFormatError, load_run
from fsrlab.metrics.cycles import RunHysteresis, run_hysteresis

__all__ = ["C_FSR", "run_circuit", "decode_capacitance", "run_readout",
           "run_reference", "reference_reversed", "run_recorded_with", "hysteresis_of_run"]

#: The decoded-capacitance variable of the physics-informed calibration. [F]
C_FSR = "c_fsr_farad"


def _as_run(run) -> Run:
    return run if isinstance(run, Run) else load_run(run)


def _recorded(run: Run):
    """The run's own ``direction`` and ``cycle`` columns (None where absent): the only place read."""
    return run.columns.get("direction"), run.columns.get("cycle")


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
    if circuit is not None:
        return circuit
    found, _ = readout_from_metadata(run.metadata)
    if found is not None:
        return found
    from fsrlab.circuits.circuit import PAPER_CIRCUIT

    return PAPER_CIRCUIT


def decode_capacitance(frequency_hz, duty_cycle, circuit: LM555Circuit | None = None, range_=None) -> np.ndarray:
    """C_FSR of every reading, decoded from frequency and duty cycle (physics-informed calibration variable).

    Parameters
    ----------
    frequency_hz, duty_cycle : array_like
        555 readings (NaN where missing).
    circuit : LM555Circuit, optional
        The circuit (default :data:`fsrlab.circuits.circuit.PAPER_CIRCUIT`).
    range_ : array_like, optional
        The run's ``range`` column: 1 where C_off was switched in, 0 where it was out
        (:meth:`LM555Circuit.on_range`). Without it, the circuit's C_off applies to every reading.

    Returns
    -------
    ndarray
        C_FSR [F] by :meth:`LM555Circuit.decode`; NaN where a reading or its range is missing, or
        the reading is impossible for the circuit (e.g. one noisy duty cycle outside the reachable
        range), so that one bad window does not stop a whole run.

    Raises
    ------
    ValueError
        A range other than 0 or 1, or columns of different lengths.
    """
    if circuit is None:
        from fsrlab.circuits.circuit import PAPER_CIRCUIT

        circuit = PAPER_CIRCUIT
    f = np.asarray(frequency_hz, dtype=float)
    d = np.asarray(duty_cycle, dtype=float)
    if f.shape != d.shape:
        raise ValueError("frequency_hz and duty_cycle must have the same length")
    ok = np.isfinite(f) & np.isfinite(d)
    if range_ is None:
        states = [(circuit, ok)]
    else:
        r = np.asarray(range_, dtype=float)
        if r.shape != f.shape:
            raise ValueError("range_ must have one value per reading")
        bad = np.isfinite(r) & ~np.isin(r, (0.0, 1.0))
        if bad.any():
            raise ValueError(f"range_: must be 0 (C_off out) or 1 (C_off in), got {r[bad][0]:g}")
        states = [(circuit.on_range(0), ok & (r == 0)), (circuit.on_range(1), ok & (r == 1))]
    out = np.full(f.shape, np.nan)
    for circ, m in states:
        if m.any():
            out[m] = np.asarray(circ.decode(f[m], d[m], check=False).c_fsr_farad, dtype=float)
    return out


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
    y = np.asarray(y, dtype=float)
    y = y[np.isfinite(y)]
    if y.size == 0:
        return None
    neg = float(np.mean(y < 0))
    if neg > 0.5 and -float(np.min(y)) > float(np.max(y)):
        return (f"the reference is mostly negative ({100 * neg:.0f} % of the readings below 0, down to "
                f"{float(np.min(y)):.4g}, up to {float(np.max(y)):.4g})")
    return None


def run_reference(run: Run, reference: str | None = None) -> tuple[np.ndarray, str, str]:
    """The reference of a run: ``force_n`` [N] or ``stress_pa`` [Pa].

    Parameters
    ----------
    run : Run
        A loaded run.
    reference : {"force_n", "stress_pa"}, optional
        Which one (default: ``stress_pa`` when the run has it, else ``force_n``). ``stress_pa``
        from a run with only ``force_n`` needs the sidecar's sensor area (:meth:`Run.stress_pa`).

    Returns
    -------
    values : ndarray
    name : str
    unit : str
        ``"N"`` or ``"Pa"``.

    Raises
    ------
    ValueError
        ``reference`` not one of the two.
    RunFormatError
        The run has no such reference.
    """
    if reference not in (None, "force_n", "stress_pa"):
        raise ValueError(f"reference: must be force_n or stress_pa, got {reference!r}")
    if reference is None:
        reference = "stress_pa" if "stress_pa" in run else ("force_n" if "force_n" in run else None)
    if reference is None:
        raise RunFormatError(f"{run.path}: no reference: the run has neither 'force_n' nor 'stress_pa' "
                             f"(columns: {', '.join(run.columns)})")
    if reference == "stress_pa":
        return run.stress_pa(), "stress_pa", "Pa"
    return run["force_n"], "force_n", "N"


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
    try:
        return recorded_with(run.metadata, run.columns.get("range"), used)
    except ValueError as exc:
        raise RunFormatError(f"{run.path}: its sidecar's circuit: {exc}") from None


def hysteresis_of_run(run, quantity: str = "frequency_hz", threshold: float = 0.05,
                      reference: str | None = None) -> RunHysteresis:
    """Hysteresis error (eq. 13) of one column of a run, per cycle and overall.

    Parameters
    ----------
    run : Run or path
        A run with ``stress_pa`` (or ``force_n``) and the quantity.
    quantity : str
        Column whose hysteresis is measured (``frequency_hz``, ``voltage_v``, ``stress_pa_estimate``, ...).
    threshold : float
        Reversal threshold as a fraction of the stress span, used without a direction column. [1]
    reference : {"force_n", "stress_pa"}, optional
        The reference the branches follow (default: ``stress_pa`` when the run has it, else
        ``force_n``, which needs no sensor area; the result's "stress" is then a force [N]).

    Returns
    -------
    RunHysteresis
        See :func:`fsrlab.metrics.cycles.run_hysteresis`.

    Raises
    ------
    ValueError
        No complete cycle, or the quantity does not respond to the stress (a dead sensor,
        :func:`fsrlab.metrics.hysteresis.check_response`).
    """
    import dataclasses
    import re

    run = _as_run(run)
    stress, ref_name, ref_unit = run_reference(run, reference)
    if quantity in ("stress_pa", "force_n"):
        raise ValueError(f"quantity: {quantity} is a reference column (the {ref_name} the branches follow, or it "
                         "divided by the area); give a readout such as frequency_hz")
    q = run[quantity]
    # eq. (13)'s functions speak of stresses [Pa]; on a force reference their levels are newtons.
    in_unit = (lambda text: text) if ref_unit == "Pa" else (lambda text: re.sub(r"(\d) Pa\b", r"\1 " + ref_unit, text))
    try:
        res = run_hysteresis(stress, q, *_recorded(run), threshold, name=quantity)
    except RunFormatError:
        raise
    except ValueError as exc:
        raise ValueError(f"{run.path}: {in_unit(str(exc))}") from None
    return res if ref_unit == "Pa" else dataclasses.replace(res, method=in_unit(res.method))
