"""The measurement report of a recorded run, as numbers: what ``fsrlab report`` renders.

For one run (and optionally its dead-weight placements and a calibration) :func:`measure_run`
gathers what the paper judges its sensors by, the capacitive readout (555 frequency) beside the
resistive one (op-amp V0, eq. 38) as in its Table 3:

- the hysteresis error (eq. 13) per cycle and overall of each readout
  (:func:`hysteresis_of_run`);
- RE1 and RE2 (eq. 39) per load from the placements (:func:`fsrlab.metrics.repeatability.grouped_repeatability`),
  each mass reached from below once per cycle as in Tables 4 and 5;
- **extension:** the ISO 376 quantities and class (:func:`fsrlab.metrics.iso376.iso376`) when the
  run holds dead-weight series, and what is missing otherwise;
- **extension:** the creep of each readout over every held load of the run
  (:func:`fsrlab.metrics.creep.creep_of_run`: drift per decade of time, total drift, time constant);
- **extension:** the calibration (every choice scored held out: its model, held-out error, lag, delay and
  uncertainty) and the hysteresis error of the compensated estimate
  (:func:`fsrlab.calibration.runs.calibrate_runs`, :func:`~fsrlab.calibration.apply.apply_calibration`).

Each part that the data do not allow is None with a one-line reason.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fsrlab.errors import ParameterError

if TYPE_CHECKING:
    from fsrlab.metrics.cycles import RunHysteresis

__all__ = ["READOUTS", "ReadoutHysteresis", "PlacementRepeatability", "RunReport", "run_reference", "hysteresis_of_run",
           "placement_means", "placements_repeatability", "iso376_of_placements", "measure_run"]

READOUTS = (("frequency_hz", "capacitive (555 frequency f)", "Hz"), ("voltage_v", "resistive (op-amp V0)", "V"))
"""The two readouts compared: column, name, unit."""


def run_reference(run, reference: str | None = None) -> tuple[np.ndarray, str, str]:
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
    from fsrlab.io.runformat import RunFormatError, as_run

    run = as_run(run)
    if reference not in (None, "force_n", "stress_pa"):
        raise ParameterError(f"must be force_n or stress_pa, got {reference!r}", parameter="reference")
    if reference is None:
        reference = "stress_pa" if "stress_pa" in run else ("force_n" if "force_n" in run else None)
    if reference is None:
        raise RunFormatError(f"{run.path}: no reference: the run has neither 'force_n' nor 'stress_pa' "
                             f"(columns: {', '.join(run.columns)})")
    if reference == "stress_pa":
        return run.stress_pa(), "stress_pa", "Pa"
    return run["force_n"], "force_n", "N"


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

    from fsrlab.io.runformat import RunFormatError, as_run
    from fsrlab.metrics.cycles import run_hysteresis

    run = as_run(run)
    stress, ref_name, ref_unit = run_reference(run, reference)
    if quantity in ("stress_pa", "force_n"):
        raise ParameterError(f"{quantity} is a reference column (the {ref_name} the branches follow, or it "
                             "divided by the area); give a readout such as frequency_hz", parameter="quantity")
    if not isinstance(quantity, str):
        raise TypeError(f"quantity: must be a column's name, got {type(quantity).__name__}")
    if quantity not in run:
        raise ParameterError(f"{run.path} has no column {quantity!r} (columns: {', '.join(run.columns)})",
                             parameter="quantity")
    q = run[quantity]
    # eq. (13)'s functions speak of stresses [Pa]; on a force reference their levels are newtons.
    in_unit = (lambda text: text) if ref_unit == "Pa" else (lambda text: re.sub(r"(\d) Pa\b", r"\1 " + ref_unit, text))
    try:
        res = run_hysteresis(stress, q, run.columns.get("direction"), run.columns.get("cycle"),
                             threshold, name=quantity)
    except RunFormatError:
        raise
    except ValueError as exc:
        raise ParameterError(f"{run.path}: {in_unit(getattr(exc, 'reason', str(exc)))}", parameter="run") from None
    return res if ref_unit == "Pa" else dataclasses.replace(res, method=in_unit(res.method))


@dataclass
class ReadoutHysteresis:
    """Eq. (13) of one column of the run.

    Attributes
    ----------
    quantity : str
        The column.
    label : str
        Its name in the report.
    percent : float or None
        Overall HE (mean branches). [%]
    cycles : list of float
        HE of each cycle. [%]
    reason : str or None
        Why there is no value.
    result : RunHysteresis or None
        The full result (branches, for plots).
    note : str or None
        What limits the value (e.g. the ADC's resolution over the readout's span).
    """

    quantity: str
    label: str
    percent: float | None = None
    cycles: list = field(default_factory=list)
    reason: str | None = None
    result: Any = field(default=None, repr=False)
    note: str | None = None

    def to_dict(self) -> dict:
        """JSON shape."""
        return {"quantity": self.quantity, "label": self.label, "hysteresis_error_percent": self.percent,
                "cycles_percent": self.cycles, "reason": self.reason, "note": self.note}


@dataclass
class PlacementRepeatability:
    """RE1/RE2 (eq. 39) of one readout at one load.

    Attributes
    ----------
    quantity : str
        The readout column.
    load_g : float
        The mass. [g]
    sensor : object
        The sensor's label (placements files may hold several sensors, as Tables 4 and 5).
    n : int
        Placements.
    mean : float
        Mean reading. [unit of the readout]
    re1_percent, re2_percent : float
        Eq. (39), RE2 with the sample standard deviation (``ddof=1``, as the paper's tables). [%]
    readings : list of float
        The placements' mean readings. [unit of the readout]
    """

    quantity: str
    load_g: float
    sensor: Any
    n: int
    mean: float
    re1_percent: float
    re2_percent: float
    readings: list = field(default_factory=list)

    def to_dict(self) -> dict:
        """JSON shape."""
        return {"quantity": self.quantity, "load_g": self.load_g, "sensor": self.sensor, "n": self.n, "mean": self.mean,
                "re1_percent": self.re1_percent, "re2_percent": self.re2_percent, "readings": self.readings}


@dataclass
class RunReport:
    """Everything :func:`measure_run` found.

    Attributes
    ----------
    path : Path
        The run.
    rows : int
        Its rows.
    duration_s : float or None
        Its time span. [s]
    reference : str
        The reference column (``stress_pa`` or ``force_n``) and ``reference_unit`` its unit.
    reference_unit : str
    hysteresis : list of ReadoutHysteresis
        Of each readout present (:data:`READOUTS`).
    repeatability : list of PlacementRepeatability
        Per readout and load > 0; empty with ``repeatability_reason``.
    repeatability_source : str
        Where the placements came from.
    repeatability_reason : str or None
    iso376 : ISO376Result or None
        With ``iso376_reason`` when None, ``iso376_readout`` the column judged.
    iso376_reason : str or None
    iso376_readout : str
    creep : list of dict
        Per readout and loaded hold of at least 5 s: ``quantity``, ``level``, ``reference``,
        ``start_s``, ``duration_s``, ``drift_percent_per_decade``, ``total_drift_percent``, ``tau_s``
        (None when not determined); empty with ``creep_reason``.
    creep_reason : str or None
    calibration : dict or None
        ``model``, ``x``, ``y``, ``y_unit``, ``heldout_rmse``, ``r2``, ``lag_s``, ``delay_s``, ``uncertainty_max``,
        ``uncertainty_median``, ``compensated``, ``source``, ``full_scale``, ``scheme``; None with
        ``calibration_reason``.
    calibration_reason : str or None
    estimate : ReadoutHysteresis or None
        Eq. (13) of the calibrated (compensated) estimate.
    agreement : Agreement or None
        A given calibration's estimate against the run's own reference
        (:func:`fsrlab.metrics.agreement.agreement`); None for a run calibrated on itself or without
        its reference.
    curves : dict
        ``reference``, ``estimate``, ``direction`` arrays for plots (estimate only with a calibration).
    """

    path: Path
    rows: int
    duration_s: float | None
    reference: str
    reference_unit: str
    hysteresis: list = field(default_factory=list)
    repeatability: list = field(default_factory=list)
    repeatability_source: str = ""
    repeatability_reason: str | None = None
    iso376: Any = None
    iso376_reason: str | None = None
    iso376_readout: str = "frequency_hz"
    creep: list = field(default_factory=list)
    creep_reason: str | None = None
    calibration: dict | None = None
    calibration_reason: str | None = None
    estimate: ReadoutHysteresis | None = None
    agreement: Any = None
    curves: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        """JSON shape (numbers and reasons; no arrays)."""
        iso = None
        if self.iso376 is not None:
            r = self.iso376
            iso = {"readout": self.iso376_readout, "forces_n": r.forces_n.tolist(),
                   "instrument_class": r.instrument_class,
                   "classes": r.classes,
                   "worst_percent": {k: r.worst(k) for k in ("b", "b_prime", "fc", "f0", "v", "c")},
                   "missing": r.missing, "notes": r.notes}
        return {"file": str(self.path), "rows": self.rows, "duration_s": self.duration_s,
                "reference": self.reference, "reference_unit": self.reference_unit,
                "hysteresis": [h.to_dict() for h in self.hysteresis],
                "repeatability": [p.to_dict() for p in self.repeatability],
                "repeatability_source": self.repeatability_source, "repeatability_reason": self.repeatability_reason,
                "iso376": iso, "iso376_reason": self.iso376_reason,
                "creep": self.creep, "creep_reason": self.creep_reason,
                "calibration": self.calibration, "calibration_reason": self.calibration_reason,
                "estimate": None if self.estimate is None else self.estimate.to_dict(),
                "agreement": None if self.agreement is None else self.agreement.to_dict()}


def _hysteresis(run, quantity: str, label: str) -> ReadoutHysteresis:

    if quantity not in run or not np.isfinite(run[quantity]).any():
        return ReadoutHysteresis(quantity, label, reason=f"the run has no {quantity} readings")
    try:
        res = hysteresis_of_run(run, quantity)
    except ValueError as exc:
        return ReadoutHysteresis(quantity, label, reason=str(exc).split(": ", 1)[-1])
    note = None
    if quantity == "voltage_v":
        from fsrlab.hardware import ADC_V_PER_COUNT

        v = run[quantity][np.isfinite(run[quantity])]
        counts = (float(v.max()) - float(v.min())) / ADC_V_PER_COUNT
        if counts < 100:
            # Eq. (13) divides a branch difference of whole ADC steps by a span of few steps.
            note = (f"V0 spans {counts:.0f} steps of the 10-bit ADC ({ADC_V_PER_COUNT * 1e3:.2f} mV each): its HE "
                    f"moves in steps of about {100 / max(counts, 1):.1f} percentage points")
    return ReadoutHysteresis(quantity, label, float(res.percent), [float(c.percent) for c in res.cycles], None, res,
                             note)


def placement_means(run, readouts=("frequency_hz", "voltage_v")) -> list[dict]:
    """Mean readouts of each placement of a dead-weight run (``step``, ``load``, ``direction``, ``cycle`` columns).

    Parameters
    ----------
    run : Run
        A run written by ``fsrlab weights`` or ``fsrlab bench weights``.
    readouts : sequence of str
        Columns averaged over each placement's steady windows.

    Returns
    -------
    list of dict
        Per step, in order: ``step``, ``load_g``, ``direction``, ``cycle``, ``force_n`` (mean nominal
        force [N]) and the mean of each readout.

    Raises
    ------
    ValueError
        The run has no ``step`` and ``load`` columns.
    """
    from fsrlab.io.runformat import as_run

    run = as_run(run)
    if isinstance(readouts, str) or not isinstance(readouts, (list, tuple)) or \
            not all(isinstance(q, str) for q in readouts):
        raise TypeError(f"readouts: must be a sequence of column names, got {readouts!r:.80}")
    for col in ("step", "load", "direction", "cycle"):
        if col not in run:
            raise ParameterError(f"{run.path}: no {col} column: not a dead-weight run (fsrlab bench weights)",
                                 parameter="run")
    step = run["step"]
    out = []
    for s in np.unique(step[np.isfinite(step)]):
        k = step == s
        d = {"step": int(s), "load_g": float(np.nanmean(run["load"][k])),
             "direction": int(np.nanmean(run["direction"][k])), "cycle": int(np.nanmean(run["cycle"][k])),
             "force_n": float(np.nanmean(run["force_nominal_n"][k])) if "force_nominal_n" in run else math.nan}
        for q in readouts:
            d[q] = float(np.nanmean(run[q][k])) if q in run and np.isfinite(run[q][k]).any() else math.nan
        out.append(d)
    return out


def _check_placements(placements, quantity, keys=("load_g", "direction")) -> None:
    """A TypeError or ParameterError naming the argument unless ``placements`` are placement rows, ``quantity``
    a name."""
    if not isinstance(quantity, str):
        raise TypeError(f"quantity: must be a readout's name, got {type(quantity).__name__}")
    if not isinstance(placements, (list, tuple)) or not all(isinstance(p, dict) for p in placements):
        raise TypeError(f"placements: must be a list of placement rows (dicts, placement_means), got "
                        f"{type(placements).__name__}")
    for p in placements:
        missing = [k for k in keys if k not in p]
        if missing:
            raise ParameterError(f"a row lacks {', '.join(missing)} (rows of placement_means)", parameter="placements")


def placements_repeatability(placements: list[dict], quantity: str) -> list[PlacementRepeatability]:
    """RE1/RE2 (eq. 39, ``ddof=1``) per load > 0 of the loading placements of one readout.

    Parameters
    ----------
    placements : list of dict
        :func:`placement_means` rows (or rows with ``load_g``, ``direction`` and the readout).
    quantity : str
        The readout.

    Returns
    -------
    list of PlacementRepeatability
        One per load (and sensor, when the rows have ``sensor``) with at least two loading
        placements, in increasing load.

    Notes
    -----
    Only loading placements count (the mass reached from below, as in Tables 4 and 5): an
    unloading placement of the same mass differs by the hysteresis, not by a lack of repeatability.
    The zero load is left out: the paper's tables start at 200 g.
    """
    from fsrlab.metrics.repeatability import repeatability

    _check_placements(placements, quantity)
    groups: dict[tuple, list[float]] = {}
    for p in placements:
        v = p.get(quantity, math.nan)
        if p["direction"] > 0 and p["load_g"] > 0 and v is not None and math.isfinite(v):
            groups.setdefault((p["load_g"], p.get("sensor", 1)), []).append(float(v))
    out = []
    for load, sensor in sorted(groups, key=lambda k: (k[0], str(k[1]))):
        x = groups[(load, sensor)]
        if len(x) < 2:
            continue
        r = repeatability(np.asarray(x), ddof=1)  # Eq. (39)
        out.append(PlacementRepeatability(quantity, load, sensor, len(x), float(r.mean), float(r.re1_percent),
                                          float(r.re2_percent), x))
    return out


def iso376_of_placements(placements: list[dict], quantity: str = "frequency_hz"):
    """ISO 376 quantities of a dead-weight run: one series per cycle (extension beyond the paper).

    Parameters
    ----------
    placements : list of dict
        :func:`placement_means` rows.
    quantity : str
        The readout judged.

    Returns
    -------
    (ISO376Result or None, str or None)
        The result, or None and why the data do not allow it.

    Notes
    -----
    Each cycle of 0 → masses → 0 is one series at the same mounting (rotation 0°): its loading
    placements are the increasing readings, its unloading ones the decreasing readings (NaN at
    the top mass), the loading and unloading zero placements the zero readings before and after.
    With one mounting position b (reproducibility) is missing, hence no class; with two forces
    the interpolation equation is a line through them (degree 1).
    """
    from fsrlab.metrics.iso376 import CalibrationSeries, iso376

    _check_placements(placements, quantity, ("load_g", "direction", "cycle", "force_n"))
    if not any(quantity in p for p in placements):
        raise ParameterError(f"no placement has a reading of {quantity!r}", parameter="quantity")
    loads = sorted({p["load_g"] for p in placements if p["load_g"] > 0})
    if len(loads) < 2:
        return None, f"ISO 376 needs at least 2 forces > 0; the placements have {len(loads)}"
    forces = []
    for ld in loads:
        f = [p["force_n"] for p in placements if p["load_g"] == ld and math.isfinite(p.get("force_n", math.nan))]
        forces.append(float(np.mean(f)) if f else ld * 1e-3 * 9.80665)
    series = []
    for c in sorted({p["cycle"] for p in placements}):
        ps = [p for p in placements if p["cycle"] == c]

        def at(load, direction, ps=ps):  # called in this iteration only
            v = [p[quantity] for p in ps if p["load_g"] == load and p["direction"] == direction]
            return float(v[0]) if v and math.isfinite(v[0]) else math.nan
        inc = [at(ld, +1) for ld in loads]
        if not all(math.isfinite(x) for x in inc):
            continue
        dec = [at(ld, -1) for ld in loads]
        z0, z1 = at(0.0, +1), at(0.0, -1)
        series.append(CalibrationSeries(0.0, inc, dec if any(math.isfinite(x) for x in dec) else None,
                                        z0 if math.isfinite(z0) else None, z1 if math.isfinite(z1) else None))
    if not series:
        return None, "no cycle has a reading at every mass"
    try:
        return iso376(forces, series, interpolation_degree=min(3, len(loads) - 1)), None
    except ValueError as exc:
        return None, str(exc)


def _creep(run, min_hold_s: float = 5.0) -> tuple[list, str | None]:
    """Creep of each readout over the run's loaded holds, or why there is none."""
    from fsrlab.metrics.creep import creep_of_run

    if "time_s" not in run:
        return [], "the run has no time_s column"
    rows = []
    for q, _, _ in READOUTS:
        if q not in run or not np.isfinite(run[q]).any():
            continue
        try:
            rc = creep_of_run(run, x=q, min_hold_s=min_hold_s)
        except ValueError as exc:
            return [], f"{str(exc).split(': ', 1)[-1]} (record a hold with fsrlab bench creep)"
        for h in rc.holds:
            tau = h.tau_s
            rows.append({"quantity": q, "level": h.hold.level, "reference": rc.reference,
                         "reference_unit": rc.reference_unit, "start_s": h.hold.start_s,
                         "duration_s": h.hold.duration_s, "drift_percent_per_decade": h.drift_percent_per_decade,
                         "total_drift_percent": h.total_drift_percent,
                         "tau_s": float(tau) if math.isfinite(tau) else None})
    if not rows:
        return [], f"no held load of {min_hold_s:g} s or more (record one with fsrlab bench creep)"
    return rows, None


def _calibration_summary(cal, source: str) -> dict:
    m = cal.model
    table = np.asarray(getattr(m.uncertainty, "table", []), dtype=float)
    table = table[np.isfinite(table)]
    return {"model": cal.model_name, "x": cal.x_name, "y": cal.y_name, "y_unit": cal.y_unit,
            "heldout_rmse": cal.selection.heldout_rmse, "r2": cal.r2, "lag_s": cal.lag_s, "delay_s": m.delay_s,
            "uncertainty_max": float(table.max()) if table.size else None,
            "uncertainty_median": float(np.median(table)) if table.size else None,
            "compensated": m.has_memory, "full_scale": cal.full_scale,
            "source": source, "scheme": cal.selection.scheme}


def measure_run(run, placements=None, weights_run=None, calibration=None, calibrate: bool = True) -> RunReport:
    """The measurement report's numbers for a recorded run.

    Parameters
    ----------
    run : Run or path
        The run (with ``stress_pa`` or ``force_n`` and the readouts).
    placements : path, optional
        A placements CSV (``load,sensor,reading,cycle,direction``; ``reading`` is the frequency) for
        RE1/RE2 when neither the run nor ``weights_run`` holds placements.
    weights_run : Run or path, optional
        A dead-weight run (``fsrlab bench weights``) for RE1/RE2 of both readouts and ISO 376; the
        run itself when it has a ``step`` column.
    calibration : Calibration or path, optional
        Applied to the run for the estimate. Without one and with ``calibrate``, the run is
        calibrated on itself (:func:`fsrlab.calibrate` with ``compensate=True``).
    calibrate : bool
        Calibrate the run on itself when no calibration is given.

    Returns
    -------
    RunReport

    Raises
    ------
    RunFormatError, ValueError
        An unreadable run, placements file or calibration (the message names the file).
    """
    from fsrlab.io.runformat import as_run, input_file

    run = as_run(run)
    y, y_name, y_unit = run_reference(run)
    t = run["time_s"] if "time_s" in run else None
    rep = RunReport(path=Path(run.path), rows=run.n_rows,
                    duration_s=float(np.nanmax(t) - np.nanmin(t)) if t is not None and t.size else None,
                    reference=y_name, reference_unit=y_unit)
    rep.hysteresis = [_hysteresis(run, q, label) for q, label, _ in READOUTS if q in run]

    # Placements: the run's own, a weights run's, or a placements CSV.
    wr = run if "step" in run and "load" in run else weights_run
    means = None
    if wr is not None:
        wr = as_run(wr, "weights_run")
        means = placement_means(wr)
        rep.repeatability_source = f"dead-weight placements of {Path(wr.path).name}"
    elif placements is not None:
        from fsrlab.io.tables import load_grouped_csv

        loads, sensors, readings = load_grouped_csv(input_file(placements, "placements"))
        from fsrlab.io.tables import read_table

        ix, rows, _ = read_table(placements, ("load", "reading"), hint="header load,sensor,reading needed")
        direction = [1] * len(loads)
        if "direction" in ix:
            direction = [int(float(r[ix["direction"]])) if r[ix["direction"]].strip() else 1 for _, r in rows]
        try:
            load_g = [float(str(ld).lower().removesuffix("g")) for ld in loads]  # 200 or "200g"
        except ValueError:
            raise ParameterError(f"{placements}: load: the mass in g (200 or 200g), got {loads[0]!r}",
                                 parameter="placements") from None
        means = [{"load_g": ld, "sensor": sn, "direction": d, "cycle": 0, "frequency_hz": float(v)}
                 for ld, sn, d, v in zip(load_g, sensors, direction, readings, strict=True)]
        rep.repeatability_source = f"placements file {Path(placements).name} (reading: frequency)"
    if means is None:
        rep.repeatability_reason = ("no dead-weight placements: record them with fsrlab bench weights and pass the run "
                                    "or its .placements.csv")
        rep.iso376_reason = "ISO 376 needs series of dead-weight placements (fsrlab bench weights)"
    else:
        for q, _, _ in READOUTS:
            rep.repeatability += placements_repeatability(means, q)
        if not rep.repeatability:
            rep.repeatability_reason = "no load > 0 was placed at least twice from below"
        if wr is not None:
            rep.iso376, rep.iso376_reason = iso376_of_placements(means, "frequency_hz")
        else:
            rep.iso376_reason = ("a placements file holds the loading readings only: ISO 376 needs the run "
                                 "(zero and unloading readings)")

    rep.creep, rep.creep_reason = _creep(run)
    rep.curves = {"reference": y}
    _calibrated(rep, run, calibration, calibrate)
    return rep


def _calibrated(rep: RunReport, run, calibration, calibrate: bool) -> None:
    """The calibration (given, or fitted on the run itself by :func:`fsrlab.calibrate` with its compensation),
    the estimate it gives on the run, its hysteresis error and, for a given calibration on a run with its
    reference, their agreement: into ``rep``, or the reason why not."""
    from fsrlab.calibration.apply import apply_calibration
    from fsrlab.calibration.runs import calibrate_runs

    cal, source = None, ""
    if calibration is not None:
        from fsrlab.calibration.document import load_calibration
        from fsrlab.calibration.result import Calibration
        from fsrlab.errors import FsrlabError

        if isinstance(calibration, Calibration):
            cal = calibration
        elif isinstance(calibration, (str, os.PathLike)):
            try:
                cal = load_calibration(calibration)
            except FsrlabError as exc:  # the file is this function's calibration
                raise type(exc)(exc.reason, parameter="calibration") from None
        else:
            raise TypeError(f"calibration: must be a Calibration or a calibration file's path, got "
                            f"{type(calibration).__name__}")
        source = f"given ({Path(cal.path).name})" if getattr(cal, "path", None) else "given"
    elif calibrate:
        try:
            cal = calibrate_runs(run, compensate=True)
            source = f"fitted on this run (choices scored by {cal.selection.scheme})"
        except ValueError as exc:
            rep.calibration_reason = f"the run cannot be calibrated on itself: {str(exc).split(': ', 1)[-1]}"
    else:
        rep.calibration_reason = "no calibration given"
    if cal is None:
        return
    rep.calibration = _calibration_summary(cal, source)
    try:
        est = apply_calibration(cal, run)
    except ValueError as exc:
        rep.calibration_reason = f"the calibration does not apply to this run: {exc}"
        return
    col, unc = f"{cal.y_name}_estimate", f"{cal.y_name}_uncertainty"
    rep.estimate = _hysteresis(est, col, "calibrated estimate")
    rep.curves["estimate"] = est[col] if col in est else None
    rep.curves["estimate_reference"] = run_reference(est, cal.y_name)[0]
    rep.curves["estimate_uncertainty"] = est[unc] if unc in est else None
    rep.curves["time"] = est["time_s"] if "time_s" in est else None
    if calibration is not None and cal.y_name in est:  # a validation run: how the calibration holds on it
        from fsrlab.metrics.agreement import agreement

        rep.agreement = agreement(est[cal.y_name], est[col], est[unc] if unc in est else None)
