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

from contextlib import contextmanager

import numpy as np

from fsrlab.analysis.calibration import Calibration, calibrate, default_groups
from fsrlab.analysis.cycles import RunHysteresis, row_cycles, row_directions, run_hysteresis
from fsrlab.circuits.circuit import LM555Circuit, readout_from_metadata
from fsrlab.runformat import KNOWN_COLUMNS, Run, RunFormatError, load_run

__all__ = [
    "ESTIMATE_COLUMN",
    "IN_RANGE_COLUMN",
    "MARGIN",
    "run_directions",
    "run_cycles",
    "run_groups",
    "run_circuit",
    "decode_capacitance",
    "run_readout",
    "calibrate_run",
    "run_recorded_with",
    "check_readout",
    "apply_calibration",
    "hysteresis_of_run",
]

#: Column that :func:`apply_calibration` adds: the calibrated stress. [Pa]
ESTIMATE_COLUMN = "stress_pa_estimate"
#: Column that :func:`apply_calibration` adds: 1 where the readout lies in the calibrated readout
#: range, 0 where the estimate is extrapolated or left out, empty where there is no readout. [1]
IN_RANGE_COLUMN = "in_range"
#: Default margin beyond the calibrated readout range, as a fraction of its span, within which an
#: estimate is still written (extrapolated, flagged); beyond it the estimate is left empty. [1]
MARGIN = 0.10
#: The decoded-capacitance variable of the physics-informed calibration. [F]
C_FSR = "c_fsr_farad"

# Sidecar keys that describe a file, not the data; an estimate written from a run drops them.
_FILE_KEYS = ("complete", "rows", "closed", "created", "format", "version", "columns")


def _as_run(run) -> Run:
    return run if isinstance(run, Run) else load_run(run)


@contextmanager
def _named(run: Run, x: str):
    """Re-raise a computation's ValueError about its arrays ``x``, ``y`` naming the run's columns."""
    try:
        yield
    except RunFormatError:
        raise
    except ValueError as exc:
        message = str(exc)
        for lead, name in (("x, y: ", f"{x} and stress_pa: "), ("x: ", f"{x}: ")):
            if message.startswith(lead):
                raise ValueError(f"{run.path}: {name}{message[len(lead):]}") from None
        if message.startswith("degree: "):
            raise
        raise ValueError(f"{run.path}: {message}") from None


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
        With ``circuit`` set when C_FSR was decoded, ``compensation`` when asked, and
        ``recorded_with`` (:func:`run_recorded_with` of the readings used).

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
    with _named(run, x):
        cal = calibrate(values, stress, degree=degree, groups=run_groups(run, folds, threshold), folds=folds,
                        x_name=x, y_name="stress_pa", x_unit=unit, y_unit="Pa", source=str(run.path), circuit=used)
    cal.recorded_with = run_recorded_with(run, np.isfinite(values) & np.isfinite(stress))
    if compensate:
        from fsrlab.analysis.compensation import compare_compensation

        direction, cycle = _recorded(run)
        with _named(run, x):
            comp = compare_compensation(values, stress, degree=cal.degree, threshold=threshold, direction=direction,
                                        cycle=cycle, plain=cal)
        cal.compensation = comp.compensated
        cal.compensation_he_percent = (comp.he_before_percent, comp.he_after_percent)
    return cal


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
        See :func:`fsrlab.analysis.provenance.recorded_with`.
    """
    from fsrlab.analysis.provenance import recorded_with

    try:
        return recorded_with(run.metadata, run.columns.get("range"), used)
    except ValueError as exc:
        raise RunFormatError(f"{run.path}: its sidecar's circuit: {exc}") from None


def check_readout(cal: Calibration, run: Run, circuit: LM555Circuit | None = None) -> list[str]:
    """How a run's readout differs from the one a calibration was recorded with.

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
        :func:`fsrlab.analysis.provenance.mismatches`); empty when nothing known differs or when
        the calibration does not record what it was recorded with (``cal.recorded_with`` None).
    """
    from fsrlab.analysis.provenance import mismatches

    if cal.recorded_with is None:
        return []
    name = "the calibration" if cal.path is None else str(cal.path)
    decode = (circuit if circuit is not None else cal.circuit) if cal.x_name == C_FSR else None
    found = mismatches(cal.x_name, cal.recorded_with, run_recorded_with(run), decode)
    return [f"{run.path} was recorded with {a}, {name} with {b}" for a, b in found]


def apply_calibration(cal: Calibration, run, compensation: bool = True, circuit: LM555Circuit | None = None,
                      margin: float = MARGIN, force: bool = False) -> Run:
    """The run with the stress its calibration estimates, ready for :func:`fsrlab.runwriter.write_run`.

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
    margin : float
        How far beyond the calibrated readout range an estimate is still written, as a fraction
        of the range's span (default :data:`MARGIN`, 10 %; ``inf``: never left empty); beyond it
        the estimate is left empty. [1]
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
    (see :meth:`fsrlab.analysis.compensation.DirectionAwareCalibration.predict` for gaps).
    """
    run = _as_run(run)
    if not margin >= 0:
        raise ValueError(f"margin: must be a fraction >= 0 of the calibrated span, got {margin!r}")
    if cal.x_name not in run and cal.x_name != C_FSR:
        raise RunFormatError(f"{run.path}: column {cal.x_name!r} (the calibration's readout) missing "
                             f"(columns: {', '.join(run.columns)})")
    differences = check_readout(cal, run, circuit)
    if differences and not force:
        raise ValueError(f"{differences[0]}: the readout means another stress; calibrate on a run recorded the "
                         "same way, or force it")
    values, _ = run_readout(run, cal.x_name, circuit if circuit is not None else cal.circuit)
    given = np.isfinite(values)
    lo, hi = cal.x_range
    span = hi - lo
    inside = given & (values >= lo) & (values <= hi)
    kept = given if margin == np.inf else given & (values >= lo - margin * span) & (values <= hi + margin * span)
    x = np.where(kept, values, np.nan)
    if compensation and cal.compensation is not None:
        est, how = cal.compensation(x), "direction-aware compensation"
    else:
        est, how = cal(x), f"polynomial of degree {cal.degree}"
    no_readout = ~given
    not_decodable = np.zeros_like(given)
    if cal.x_name == C_FSR and C_FSR not in run:
        parts = np.isfinite(run["frequency_hz"]) & np.isfinite(run["duty_cycle"])
        no_readout, not_decodable = ~given & ~parts, ~given & parts
    columns = dict(run.columns)
    columns[ESTIMATE_COLUMN] = est
    columns[IN_RANGE_COLUMN] = np.where(given, inside.astype(float), np.nan)
    counts = {"estimated": int(np.isfinite(est).sum()), "in_range": int(inside.sum()),
              "out_of_range": int((given & ~inside).sum()), "extrapolated": int((np.isfinite(est) & ~inside).sum()),
              "missing": int((~np.isfinite(est)).sum()),
              "no_readout": int(no_readout.sum()), "not_decodable": int(not_decodable.sum()),
              "beyond_margin": int((given & ~kept).sum())}
    meta = {k: v for k, v in run.metadata.items() if k not in _FILE_KEYS}
    meta["units"] = dict(run.units, **{ESTIMATE_COLUMN: "Pa", IN_RANGE_COLUMN: "1"})
    source = {} if cal.path is None else {"file": str(cal.path)}
    meta["calibration"] = {**source, "x": cal.x_name, "degree": cal.degree, "method": how,
                           "data_fingerprint": cal.data_fingerprint, "created": cal.created,
                           "readout_range": [lo, hi], "margin": margin, "counts": counts}
    if differences:
        meta["calibration"]["forced"] = differences
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

    Raises
    ------
    ValueError
        No complete cycle, or the quantity does not respond to the stress (a dead sensor,
        :func:`fsrlab.analysis.hysteresis.check_response`).
    """
    run = _as_run(run)
    stress, q = run.stress_pa(), run[quantity]
    try:
        return run_hysteresis(stress, q, *_recorded(run), threshold, name=quantity)
    except RunFormatError:
        raise
    except ValueError as exc:
        raise ValueError(f"{run.path}: {exc}") from None
