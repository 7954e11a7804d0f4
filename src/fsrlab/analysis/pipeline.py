"""From a recorded run to a calibration, and from a calibration to the stress of another run.

The orchestration of the analysis topic: it reads what a run holds (its columns, its sidecar's
circuit) and passes it to the computations on arrays, and holds no model of its own --
polynomials and cross-validation are :mod:`fsrlab.analysis.calibration`, the compensation
:mod:`fsrlab.analysis.compensation`, branches, cycles and eq. (13) :mod:`fsrlab.analysis.cycles`,
C_FSR decoding :mod:`fsrlab.circuits.decode`. The command line (``fsrlab calibrate``,
``fsrlab apply``, ``fsrlab hysteresis``) calls these functions and only renders.

A run's branches and cycles come from one rule (:func:`run_directions`, :func:`run_cycles`: the
``direction`` and ``cycle`` columns when the run has them, else found from the reference stress),
used alike by the calibration's cross-validation groups, by the compensation and by the
hysteresis error.

Examples
--------
Calibrate one run and estimate the stress of another (``bench.csv`` and ``other.csv`` are runs
in the format of docs/data-format.md)::

    from fsrlab.runformat import load_run
    from fsrlab.analysis.pipeline import calibrate_run, apply_calibration
    cal = calibrate_run(load_run("bench.csv"), x="frequency_hz", compensate=True)
    est = apply_calibration(cal, load_run("other.csv"))["stress_pa_estimate"]

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5 (Figure 17), eq. (13).
"""

from __future__ import annotations

import numpy as np

from fsrlab.analysis.calibration import Calibration, calibrate, default_groups
from fsrlab.analysis.cycles import RunHysteresis, row_cycles, row_directions, run_hysteresis
from fsrlab.circuits.circuit import LM555Circuit, readout_from_metadata
from fsrlab.runformat import KNOWN_COLUMNS, Run, RunFormatError, load_run

__all__ = [
    "ESTIMATE_COLUMN",
    "run_directions",
    "run_cycles",
    "run_groups",
    "run_circuit",
    "decode_capacitance",
    "run_readout",
    "calibrate_run",
    "apply_calibration",
    "hysteresis_of_run",
]

#: Column that :func:`apply_calibration` adds: the calibrated stress. [Pa]
ESTIMATE_COLUMN = "stress_pa_estimate"
#: The decoded-capacitance variable of the physics-informed calibration. [F]
C_FSR = "c_fsr_farad"

# Sidecar keys that describe a file, not the data; an estimate written from a run drops them.
_FILE_KEYS = ("complete", "rows", "closed", "created", "format", "version", "columns")


def _as_run(run) -> Run:
    return run if isinstance(run, Run) else load_run(run)


def _recorded(run: Run):
    """The run's own ``direction`` and ``cycle`` columns (None where absent): the only place read."""
    return run.columns.get("direction"), run.columns.get("cycle")


def run_directions(run: Run, threshold: float = 0.05) -> np.ndarray:
    """Direction of every reading: the ``direction`` column, else found from the reference stress.

    Parameters
    ----------
    run : Run
        A loaded run (:func:`fsrlab.runformat.load_run`).
    threshold : float
        Reversal threshold as a fraction of the stress span, used without a direction column. [1]

    Returns
    -------
    ndarray of int
        +1 loading, -1 unloading, 0 hold or unknown (see :func:`fsrlab.analysis.cycles.row_directions`).
    """
    return row_directions(run.stress_pa(), *_recorded(run), threshold)


def run_cycles(run: Run, threshold: float = 0.05) -> np.ndarray:
    """Cycle number of every reading: the ``cycle`` column, else numbered from :func:`run_directions`.

    Parameters
    ----------
    run : Run
        A loaded run.
    threshold : float
        Reversal threshold as a fraction of the stress span. [1]

    Returns
    -------
    ndarray of float
        Cycle numbers (NaN where the cycle column is empty); a new cycle starts where loading
        follows unloading (:func:`fsrlab.analysis.cycles.cycle_numbers`).
    """
    return row_cycles(run.stress_pa(), *_recorded(run), threshold)


def run_groups(run: Run, folds: int = 5, threshold: float = 0.05) -> np.ndarray:
    """Cross-validation groups of a run: its cycles, kept whole.

    Parameters
    ----------
    run : Run
        A loaded run.
    folds : int
        Contiguous blocks to cut the run into when it has fewer than 2 cycles.
    threshold : float
        Reversal threshold for cycles found from the stress. [1]

    Returns
    -------
    ndarray of int
        Group of each reading (:func:`fsrlab.analysis.calibration.default_groups` of :func:`run_cycles`).
    """
    return default_groups(run.n_rows, run_cycles(run, threshold), folds)


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
        else :data:`fsrlab.physics.params.PAPER_CIRCUIT` (R = 10 kΩ, ideal D1, no C_off).
    """
    if circuit is not None:
        return circuit
    found, _ = readout_from_metadata(run.metadata)
    if found is not None:
        return found
    from fsrlab.physics.params import PAPER_CIRCUIT

    return PAPER_CIRCUIT


def decode_capacitance(frequency_hz, duty_cycle, circuit: LM555Circuit | None = None, range_=None) -> np.ndarray:
    """C_FSR of every reading, decoded from frequency and duty cycle (physics-informed calibration variable).

    Parameters
    ----------
    frequency_hz, duty_cycle : array_like
        555 readings (NaN where missing).
    circuit : LM555Circuit, optional
        The circuit (default :data:`fsrlab.physics.params.PAPER_CIRCUIT`).
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
        from fsrlab.physics.params import PAPER_CIRCUIT

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


def calibrate_run(run, x: str = "frequency_hz", degree: int | str = "auto", compensate: bool = False,
                  folds: int = 5, circuit: LM555Circuit | None = None, threshold: float = 0.05) -> Calibration:
    """Calibrate a run's readout to its reference stress.

    Parameters
    ----------
    run : Run or path
        A run with ``stress_pa`` (or ``force_n`` and the sensor area) and the readout.
    x : str
        Readout column, or ``c_fsr_farad`` (physics-informed, see :func:`run_readout`).
    degree : int or "auto"
        Polynomial degree 1..5, or ``"auto"``: chosen by cross-validation keeping the run's
        cycles whole (:func:`run_groups`).
    compensate : bool
        Also fit the direction-aware hysteresis compensation (an extension beyond the paper) and
        record the hysteresis error of the calibrated stress before and after.
    folds : int
        Cross-validation folds (≥ 2).
    circuit : LM555Circuit, optional
        Circuit for ``x="c_fsr_farad"`` (default: the sidecar's, else ``PAPER_CIRCUIT``).
    threshold : float
        Reversal threshold, a fraction of the span, where branches come from the data. [1]

    Returns
    -------
    Calibration
        With ``circuit`` set when C_FSR was decoded, and ``compensation`` when asked.

    Raises
    ------
    RunFormatError
        A column the run lacks.
    ValueError
        A parameter out of range, too few readings, no cycles to compensate.
    """
    run = _as_run(run)
    stress = run.stress_pa()
    values, used = run_readout(run, x, circuit)
    unit = run.units.get(x) or KNOWN_COLUMNS.get(x, "F" if x == C_FSR else "")
    cal = calibrate(values, stress, degree=degree, groups=run_groups(run, folds, threshold), folds=folds,
                    x_name=x, y_name="stress_pa", x_unit=unit, y_unit="Pa", source=str(run.path), circuit=used)
    if compensate:
        from fsrlab.analysis.compensation import compare_compensation

        direction, cycle = _recorded(run)
        comp = compare_compensation(values, stress, degree=cal.degree, threshold=threshold, direction=direction,
                                    cycle=cycle, plain=cal)
        cal.compensation = comp.compensated
        cal.compensation_he_percent = (comp.he_before_percent, comp.he_after_percent)
    return cal


def apply_calibration(cal: Calibration, run, compensation: bool = True, circuit: LM555Circuit | None = None) -> Run:
    """The run with the stress its calibration estimates, ready for :func:`fsrlab.runformat.write_run`.

    Parameters
    ----------
    cal : Calibration
        From :func:`calibrate_run` or :func:`fsrlab.analysis.calibration_io.load_calibration`.
    run : Run or path
        The run to convert; it needs the calibration's readout column (or ``frequency_hz`` and
        ``duty_cycle`` for a calibration on ``c_fsr_farad``).
    compensation : bool
        Use the calibration's direction-aware compensation when it holds one (else the polynomial).
    circuit : LM555Circuit, optional
        Circuit for decoding C_FSR (default: the calibration's, else the run's, see :func:`run_circuit`).

    Returns
    -------
    Run
        The input columns plus ``stress_pa_estimate`` [Pa] (NaN where the readout is missing);
        its metadata is the input's without the file keys (``complete``, ``rows``, ...), with
        the unit of the new column and a ``calibration`` entry (file when known, readout,
        degree, method, data fingerprint, creation time). ``path`` is the input run's.

    Raises
    ------
    RunFormatError
        The run lacks the calibration's readout.
    """
    run = _as_run(run)
    if cal.x_name not in run and cal.x_name != C_FSR:
        raise RunFormatError(f"{run.path}: column {cal.x_name!r} (the calibration's readout) missing "
                             f"(columns: {', '.join(run.columns)})")
    values, _ = run_readout(run, cal.x_name, circuit if circuit is not None else cal.circuit)
    if compensation and cal.compensation is not None:
        est, how = cal.compensation(values), "direction-aware compensation"
    else:
        est, how = cal(values), f"polynomial of degree {cal.degree}"
    columns = dict(run.columns)
    columns[ESTIMATE_COLUMN] = est
    meta = {k: v for k, v in run.metadata.items() if k not in _FILE_KEYS}
    meta["units"] = dict(run.units, **{ESTIMATE_COLUMN: "Pa"})
    source = {} if cal.path is None else {"file": str(cal.path)}
    meta["calibration"] = {**source, "x": cal.x_name, "degree": cal.degree, "method": how,
                           "data_fingerprint": cal.data_fingerprint, "created": cal.created}
    return Run(path=run.path, columns=columns, metadata=meta)


def hysteresis_of_run(run, quantity: str = "frequency_hz", threshold: float = 0.05) -> RunHysteresis:
    """Hysteresis error (eq. 13) of one column of a run, per cycle and overall.

    Parameters
    ----------
    run : Run or path
        A run with ``stress_pa`` (or ``force_n``) and the quantity.
    quantity : str
        Column whose hysteresis is measured (``frequency_hz``, ``voltage_v``, ``stress_pa_estimate``, ...).
    threshold : float
        Reversal threshold as a fraction of the stress span, used without a direction column. [1]

    Returns
    -------
    RunHysteresis
        See :func:`fsrlab.analysis.cycles.run_hysteresis`.
    """
    run = _as_run(run)
    return run_hysteresis(run.stress_pa(), run[quantity], *_recorded(run), threshold)
