"""Creep and drift of a readout under a held load: hold segments, drift per decade of time, time constant.

**Beyond the paper.** The paper measures the hysteresis (eq. 13) and repeatability (eq. 39) of its
sensors, not their creep. FSR datasheets state creep as the drift of the reading under a constant
load per decade of time ("< 5 % per log10(time)"); ISO 376 states it as the difference of two
readings, 30 s and 300 s after applying the largest force (:mod:`fsrlab.metrics.iso376`, ``c``).
This module finds the holds of a run (the reference steady) and measures, in each, what the
readout does meanwhile:

* a **hold** (:func:`find_holds`): a stretch of at least ``min_hold_s`` over which the reference,
  after a running median over 5 of its readings (spikes and HX711 noise), stays within a band of
  ±``band`` of full scale (its peak-to-peak spread ≤ 2·band·FS, FS = the largest \\|reference\\| of
  the run); the stretches are maximal and found left to right. Empty reference cells (a load cell
  sampled slower than the readout) are left out of the test; the hold runs from the first to the
  last reference reading in its band, and every readout reading in that time belongs to it;
* t0, the hold's start: its first reference reading in the band. The first ``settle_s`` after t0
  (default 0.5 s, five 100 ms windows, at most a fifth of ``min_hold_s``) are left out of the fits: the load is still
  settling, and
  with a slow reference the true start lies up to one reference interval before t0;
* **drift per decade**: the least-squares line r(t) = a + b·log10(t − t0) through the readings of
  the hold; b [readout unit per decade], and ``100·b/|a|`` [% per decade], a = the line's value at
  t0 + 1 s (the datasheets' normalisation: drift relative to the reading just after loading). Signed:
  a readout that falls under load reports a negative drift;
* **time constant**: the least-squares first-order step r(t) = r∞ − Δ·exp(−(t − t0)/τ), by a
  closed-form search (r∞ and Δ are linear for each τ; τ on a logarithmic grid, then golden-section
  refinement in log τ). τ is reported only when the data determine it: not beyond the hold's
  length (a longer τ is indistinguishable from a line over the hold), not shorter than the
  readings' spacing (a step), and Δ beyond three standard errors (a change, not noise); otherwise
  it is "not determined" with the reason, never a number;
* **total drift**: ``100·(r_end − r_start)/|r_start|`` [%], r_start and r_end the medians of the
  first and last tenth (1 to 5 readings) of the readings after settling.

Holds whose band holds zero (\\|level\\| ≤ band·FS) are unloaded rests, not creep: :func:`creep`
leaves them out and counts them.

References
----------
Interlink Electronics, "FSR 400 Series Data Sheet" (drift under constant load, % per log10(time)).
ISO 376:2011, clause on creep (readings at 30 s and 300 s), see :mod:`fsrlab.metrics.iso376`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.metrics.holds import Hold, find_holds
from fsrlab.physics.params import check_between, check_positive, paired_series

__all__ = ["Hold", "find_holds", "LogDrift", "log_drift", "FirstOrder", "first_order_fit", "HoldCreep",
           "RunCreep", "creep", "creep_of_run", "REFERENCES"]

#: Reference columns a hold is found on, in order of preference when the run has both.
REFERENCES = ("force_n", "stress_pa")


@dataclass(frozen=True)
class LogDrift:
    """Least-squares line r = a + b·log10(t − t0) through a hold's readings.

    Parameters
    ----------
    a : float
        The line at t − t0 = 1 s. [readout unit]
    b : float
        Drift per decade of time. [readout unit per decade]
    b_stderr : float
        Standard error of b (0 for 3 readings on a line). [readout unit per decade]
    percent_per_decade : float
        ``100·b/|a|`` (NaN when a = 0 or the line is not determined). [% per decade]
    percent_per_decade_stderr : float
        ``100·b_stderr/|a|``. [% per decade]
    n : int
        Readings fitted.
    note : str
        Why the line is not determined (empty when it is).
    """

    a: float
    b: float
    b_stderr: float
    percent_per_decade: float
    percent_per_decade_stderr: float
    n: int
    note: str = ""


def log_drift(elapsed_s, readout) -> LogDrift:
    """Fit r = a + b·log10(elapsed) by least squares; drift per decade of time b, and 100·b/|a| in %.

    Parameters
    ----------
    elapsed_s : array_like
        Time since the hold's start, t − t0, > 0 (readings at 0 or before are left out). [s]
    readout : array_like
        Readout at those times; NaN readings are left out. [readout unit]

    Returns
    -------
    LogDrift
        NaN numbers and a note when fewer than 3 readings, or a single distinct time, remain.
    """
    s, r = paired_series("elapsed_s", elapsed_s, "readout", readout)
    keep = np.isfinite(s) & np.isfinite(r) & (s > 0)
    s, r = s[keep], r[keep]
    nan = float("nan")
    if s.size < 3 or np.unique(s).size < 2:
        return LogDrift(nan, nan, nan, nan, nan, int(s.size), f"{s.size} reading(s) after settling; 3 at 2 or more "
                        "distinct times needed")
    x = np.log10(s)
    xm, rm = x.mean(), r.mean()
    sxx = np.sum((x - xm) ** 2)
    b = float(np.sum((x - xm) * (r - rm)) / sxx)
    a = float(rm - b * xm)
    resid = r - (a + b * x)
    b_se = float(np.sqrt(np.sum(resid ** 2) / (s.size - 2) / sxx))
    with np.errstate(divide="ignore", invalid="ignore"):
        pct = 100 * b / abs(a) if a != 0 else nan
        pct_se = 100 * b_se / abs(a) if a != 0 else nan
    return LogDrift(a, b, b_se, float(pct), float(pct_se), int(s.size),
                    "" if a != 0 else "the line is 0 at 1 s: no % of reading")


@dataclass(frozen=True)
class FirstOrder:
    """Least-squares first-order step r = r∞ − Δ·exp(−(t − t0)/τ).

    Parameters
    ----------
    tau_s : float
        Time constant; NaN when not determined. [s]
    tau_stderr_s : float
        Its standard error (linearised); NaN when not determined. [s]
    r_inf : float
        Final value; NaN when not determined. [readout unit]
    delta : float
        Size of the step, r∞ − r(t0), signed; NaN when not determined. [readout unit]
    note : str
        Why τ is not determined (empty when it is).
    """

    tau_s: float
    tau_stderr_s: float
    r_inf: float
    delta: float
    note: str = ""

    @property
    def determined(self) -> bool:
        """Whether the data determine τ."""
        return not self.note


def _sse(s: np.ndarray, r: np.ndarray, tau: np.ndarray):
    """For each τ: (SSE, r∞, Δ) of the linear least squares of r on [1, −exp(−s/τ)].

    From the sums (SSE = Σr'² − β·Xᵀr', r' = r − mean r against cancellation), in blocks of τ so
    that no more than ~2·10⁶ exponentials are held at once.
    """
    n = s.size
    mean = r.mean()
    rc = r - mean
    srr = float(rc @ rc)
    out = np.empty((3, tau.size))
    step = max(1, 2_000_000 // max(n, 1))
    for k in range(0, tau.size, step):
        e = np.exp(-s[:, None] / tau[None, k:k + step])
        se, see, sre = e.sum(axis=0), np.einsum("ij,ij->j", e, e), rc @ e
        det = n * see - se * se
        with np.errstate(divide="ignore", invalid="ignore"):
            r_inf = (see * 0.0 - se * sre) / det  # Σr' = 0
            delta = -(n * sre) / det
            sse = srr - (-delta * sre)  # β·Xᵀr' with Xᵀr' = [0, −Σr'e]
        ok = np.isfinite(sse) & (det > 1e-12 * n * n)
        out[0, k:k + step] = np.where(ok, np.maximum(sse, 0.0), np.inf)
        out[1, k:k + step] = r_inf + mean
        out[2, k:k + step] = delta
    return out[0], out[1], out[2]


def first_order_fit(elapsed_s, readout, hold_s: float | None = None) -> FirstOrder:
    """Fit r = r∞ − Δ·exp(−elapsed/τ) by a closed-form search in τ; τ only where the data determine it.

    Parameters
    ----------
    elapsed_s : array_like
        Time since the hold's start, t − t0 (NaN readings are left out). [s]
    readout : array_like
        Readout at those times. [readout unit]
    hold_s : float, optional
        Length of the hold from t0 [s]; default the largest elapsed time. A τ beyond it is not
        determined.

    Returns
    -------
    FirstOrder

    Notes
    -----
    For a fixed τ the model is linear in r∞ and Δ, so their least squares is closed form; τ is
    searched on 121 logarithmic steps from half the readings' median spacing to 10·hold_s, then
    refined by golden-section search in log τ between the neighbours of the best step. The standard
    errors come from the linearised model (Jacobian in r∞, Δ, τ) and the residual variance.
    τ is "not determined" when the best τ exceeds ``hold_s``, is shorter than the readings'
    spacing, or \\|Δ\\| is within three standard errors of zero.
    """
    s, r = paired_series("elapsed_s", elapsed_s, "readout", readout)
    if hold_s is not None:
        check_positive("hold_s", hold_s, "s", scalar=True)
    keep = np.isfinite(s) & np.isfinite(r)
    s, r = s[keep], r[keep]
    nan = float("nan")
    if s.size < 5 or np.ptp(s) == 0:
        return FirstOrder(nan, nan, nan, nan, f"{s.size} readings after settling; 5 needed")
    span = float(s.max()) if hold_s is None else float(hold_s)
    spacing = float(np.median(np.diff(np.unique(s))))
    if np.ptp(r) == 0:
        return FirstOrder(nan, nan, nan, nan, "the readout does not change over the hold")
    grid = np.logspace(np.log10(spacing / 2), np.log10(10 * span), 121)
    sse, _, _ = _sse(s, r, grid)
    k = int(np.argmin(sse))
    if not np.isfinite(sse[k]):
        return FirstOrder(nan, nan, nan, nan, "no first-order curve fits the readings")
    lo, hi = np.log10(grid[max(k - 1, 0)]), np.log10(grid[min(k + 1, grid.size - 1)])
    g = (np.sqrt(5) - 1) / 2
    for _ in range(40):  # golden section in log τ: the bracket shrinks to 0.618⁴⁰ ≈ 4e-9 of two grid steps
        c, d = hi - g * (hi - lo), lo + g * (hi - lo)
        fc, fd = _sse(s, r, np.array([10 ** c, 10 ** d]))[0]
        if fc <= fd:
            hi = d
        else:
            lo = c
    tau = float(10 ** ((lo + hi) / 2))
    err, r_inf, delta = (float(v[0]) for v in _sse(s, r, np.array([tau])))
    if tau > span:
        return FirstOrder(nan, nan, nan, nan, f"τ beyond the hold ({span:.3g} s): the readout is still changing "
                                              "at its end as it would along a line")
    if tau < spacing:
        return FirstOrder(nan, nan, nan, nan, f"τ shorter than the readings' spacing ({spacing:.3g} s): a step")
    e = np.exp(-s / tau)
    jac = np.column_stack([np.ones_like(s), -e, -delta * e * s / tau ** 2])
    dof = s.size - 3
    try:
        cov = np.linalg.inv(jac.T @ jac) * (err / dof)
    except np.linalg.LinAlgError:
        return FirstOrder(nan, nan, nan, nan, "the first-order curve is degenerate on these readings")
    se_delta, se_tau = (float(np.sqrt(max(cov[i, i], 0.0))) for i in (1, 2))
    if not abs(delta) > 3 * se_delta or not np.isfinite(se_tau):
        return FirstOrder(nan, nan, nan, nan, "no first-order change beyond the noise (|Δ| within 3 standard errors)")
    return FirstOrder(tau, se_tau, r_inf, delta)


@dataclass(frozen=True)
class HoldCreep:
    """The readout's creep over one hold.

    Parameters
    ----------
    hold : Hold
        The hold (times [s], reference level [reference unit]).
    settle_s : float
        Time after the hold's start left out of the fits. [s]
    readout_start : float
        Median of the first tenth (1–5) of the readings after settling. [readout unit]
    readout_end : float
        Median of the last tenth (1–5) of the readings. [readout unit]
    total_drift_percent : float
        ``100·(readout_end − readout_start)/|readout_start|`` (NaN with fewer than 3 readings). [%]
    log : LogDrift
        The drift per decade of time.
    first_order : FirstOrder
        The time constant.
    n_readout : int
        Readout readings after settling.
    """

    hold: Hold
    settle_s: float
    readout_start: float
    readout_end: float
    total_drift_percent: float
    log: LogDrift
    first_order: FirstOrder
    n_readout: int

    @property
    def drift_percent_per_decade(self) -> float:
        """Signed drift per decade of time, % of the reading at t0 + 1 s. [% per decade]"""
        return self.log.percent_per_decade

    @property
    def tau_s(self) -> float:
        """Time constant, NaN when not determined. [s]"""
        return self.first_order.tau_s


def _hold_creep(t: np.ndarray, x: np.ndarray, hold: Hold, settle_s: float) -> HoldCreep:
    inside = (t >= hold.start_s + settle_s) & (t <= hold.end_s) & np.isfinite(x)
    elapsed = t[inside] - hold.start_s
    r = x[inside]
    nan = float("nan")
    if r.size >= 3:
        k = int(min(5, max(1, r.size // 10)))
        start, end = float(np.median(r[:k])), float(np.median(r[-k:]))
        total = 100 * (end - start) / abs(start) if start != 0 else nan
    else:
        start = end = total = nan
    return HoldCreep(hold=hold, settle_s=settle_s, readout_start=start, readout_end=end,
                     total_drift_percent=float(total), log=log_drift(elapsed, r),
                     first_order=first_order_fit(elapsed, r, hold_s=hold.duration_s), n_readout=int(r.size))


@dataclass
class RunCreep:
    """Creep of a readout over every loaded hold of a run.

    Parameters
    ----------
    holds : list of HoldCreep
        One per loaded hold, in time order.
    x : str
        Readout column.
    x_unit : str
        Its unit.
    reference : str
        Reference column.
    reference_unit : str
        Its unit.
    full_scale : float
        Largest \\|reference\\| of the run. [reference unit]
    band : float
        Half-width of the hold band, fraction of full scale. [1]
    min_hold_s : float
        Shortest hold. [s]
    settle_s : float
        Time after each hold's start left out of the fits. [s]
    unloaded : int
        Holds left out because their band holds zero (rests, not creep).
    elapsed : list of ndarray
        Per hold, t − t0 of the readings fitted. [s]
    readings : list of ndarray
        Per hold, those readings. [readout unit]
    """

    holds: list
    x: str
    x_unit: str
    reference: str
    reference_unit: str
    full_scale: float
    band: float
    min_hold_s: float
    settle_s: float
    unloaded: int = 0
    elapsed: list = field(default_factory=list, repr=False)
    readings: list = field(default_factory=list, repr=False)

    def to_dict(self) -> dict:
        """The numbers, units named in the keys (NaN where not determined; ``emit_json`` writes null)."""
        ru, xu = self.reference_unit or "1", self.x_unit or "1"
        rows = []
        for h in self.holds:
            rows.append({
                "start_s": h.hold.start_s, "end_s": h.hold.end_s, "duration_s": h.hold.duration_s,
                f"level_{ru}": h.hold.level, "level_percent_fs": 100 * h.hold.level / self.full_scale,
                f"readout_start_{xu}": h.readout_start, f"readout_end_{xu}": h.readout_end,
                f"readout_at_1s_{xu}": h.log.a,
                f"drift_per_decade_{xu}": h.log.b, "drift_percent_per_decade": h.log.percent_per_decade,
                "drift_percent_per_decade_stderr": h.log.percent_per_decade_stderr,
                "tau_s": h.first_order.tau_s, "tau_stderr_s": h.first_order.tau_stderr_s,
                "tau_note": h.first_order.note or None,
                "total_drift_percent": h.total_drift_percent, "readings": h.n_readout,
                "drift_note": h.log.note or None,
            })
        return {"x": self.x, "x_unit": self.x_unit, "reference": self.reference,
                "reference_unit": self.reference_unit, f"full_scale_{ru}": self.full_scale,
                "band_percent_fs": 100 * self.band, "min_hold_s": self.min_hold_s, "settle_s": self.settle_s,
                "unloaded_holds": self.unloaded, "holds": rows}

    def plot(self, ax=None):
        """Draw each hold's readout against log time since its start, with its log line and first-order curve.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).

        Returns
        -------
        matplotlib.axes.Axes
            Per hold, in order: the readings, the log line, and the first-order curve when τ is
            determined; y in % of the hold's reading at t0 + 1 s (holds at different loads side by
            side), x = t − t0 on a log axis [s].
        """
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots()
        for k, (h, s, r) in enumerate(zip(self.holds, self.elapsed, self.readings, strict=True)):
            a = h.log.a
            if not (np.isfinite(a) and a != 0 and s.size):
                continue
            color = f"C{k % 10}"

            def pct(v, a=a):
                return 100 * (v - a) / abs(a)

            ax.plot(s, pct(r), ".", color=color, ms=3,
                    label=f"hold {k + 1}: {h.hold.level:.4g} {self.reference_unit}, "
                          f"{h.log.percent_per_decade:+.2f} %/decade")
            grid = np.geomspace(s.min(), s.max(), 100)
            ax.plot(grid, pct(h.log.a + h.log.b * np.log10(grid)), "-", color=color)
            fo = h.first_order
            if fo.determined:
                ax.plot(grid, pct(fo.r_inf - fo.delta * np.exp(-grid / fo.tau_s)), "--", color=color,
                        label=f"τ = {fo.tau_s:.3g} s")
        ax.set_xscale("log")
        ax.set_xlabel("t − t0 [s]")
        ax.set_ylabel(f"{self.x}: change from the reading at t0 + 1 s [%]")
        ax.set_title(f"creep of {self.x} under held {self.reference}")
        if ax.lines:
            ax.legend(fontsize="small")
        return ax


def creep(time_s, readout, reference, band: float = 0.02, min_hold_s: float = 5.0, settle_s: float | None = None,
          x: str = "readout", x_unit: str = "", reference_name: str = "reference",
          reference_unit: str = "") -> RunCreep:
    """Drift per decade of time, time constant and total drift of a readout over each loaded hold.

    Parameters
    ----------
    time_s : array_like
        Time of each row, non-decreasing. [s]
    readout : array_like
        Readout per row (NaN where missing). [readout unit]
    reference : array_like
        Reference force or stress per row (NaN where missing). [reference unit]
    band : float
        Half-width of the hold band, a fraction of full scale in (0, 0.5). [1]
    min_hold_s : float
        Shortest hold, > 0. [s]
    settle_s : float, optional
        Time after each hold's start left out of the fits, in [0, min_hold_s); default 0.5 s, at
        most a fifth of ``min_hold_s``. [s]
    x, x_unit : str
        Name and unit of the readout, for the result.
    reference_name, reference_unit : str
        Name and unit of the reference, for the result.

    Returns
    -------
    RunCreep

    Raises
    ------
    fsrlab.errors.ParameterError
        A parameter out of range; a readout without readings; no loaded hold (the message says how
        many holds were found and why none counts), naming the parameter.
    TypeError
        An array that is not numbers.
    """
    t, xr = paired_series("time_s", time_s, "readout", readout)
    _, ref = paired_series("time_s", t, "reference", reference)
    check_positive("min_hold_s", min_hold_s, "s", scalar=True)
    if settle_s is None:
        settle_s = min(0.5, min_hold_s / 5)
    check_between("settle_s", settle_s, 0.0, min_hold_s, "s (min_hold_s)", upper_open=True, scalar=True)
    if not np.isfinite(xr).any():
        raise ParameterError(f"{x}: no readings (every cell is empty)", parameter="readout")
    holds = find_holds(t, ref, band=band, min_hold_s=min_hold_s)
    fs = float(np.nanmax(np.abs(ref)))
    loaded = [h for h in holds if abs(h.level) > band * fs]
    if not loaded:
        why = (f"{len(holds)} hold(s), all unloaded (the band holds zero)" if holds else
               f"the reference never stays within ±{100 * band:g} % of full scale ({fs:.6g} {reference_unit}) "
               f"for {min_hold_s:g} s")
        raise ParameterError(f"{reference_name}: no loaded hold found: {why}", parameter="reference")
    res = RunCreep(holds=[], x=x, x_unit=x_unit, reference=reference_name, reference_unit=reference_unit,
                   full_scale=fs, band=band, min_hold_s=min_hold_s, settle_s=settle_s,
                   unloaded=len(holds) - len(loaded))
    for h in loaded:
        hc = _hold_creep(t, xr, h, settle_s)
        res.holds.append(hc)
        inside = (t >= h.start_s + settle_s) & (t <= h.end_s) & np.isfinite(xr) & (t > h.start_s)
        res.elapsed.append(t[inside] - h.start_s)
        res.readings.append(xr[inside])
    return res


def creep_of_run(run, x: str = "frequency_hz", reference: str | None = None, band: float = 0.02,
                 min_hold_s: float = 5.0, settle_s: float | None = None) -> RunCreep:
    """:func:`creep` on a run's columns: ``time_s``, the readout ``x`` and the reference.

    Parameters
    ----------
    run : fsrlab.io.runformat.Run
        The run (docs/data-format.md); it needs ``time_s``.
    x : str
        Readout column (any numeric column: frequency_hz, duty_cycle, voltage_v, ...).
    reference : {"force_n", "stress_pa"}, optional
        Reference column; default the run's ``force_n`` if it has one, else ``stress_pa``.
    band : float
        Half-width of the hold band, a fraction of full scale in (0, 0.5). [1]
    min_hold_s : float
        Shortest hold, > 0. [s]
    settle_s : float, optional
        Time after each hold's start left out of the fits; default 0.5 s, at most a fifth of
        ``min_hold_s``. [s]

    Returns
    -------
    RunCreep

    Raises
    ------
    fsrlab.errors.ParameterError
        A missing column (named with the file), and what :func:`creep` raises.
    TypeError
        ``run`` neither a run nor its path, ``x`` not a column name.
    """
    from fsrlab.io.runformat import as_run

    run = as_run(run)
    if not isinstance(x, str):
        raise TypeError(f"x: must be a column's name (str), got {type(x).__name__}")
    if reference is None:
        reference = next((c for c in REFERENCES if c in run), None)
        if reference is None:
            raise ParameterError(f"{run.path}: no reference column (force_n or stress_pa): creep needs a held load",
                                 parameter="run")
    elif reference not in REFERENCES:
        raise ParameterError(f"must be one of {', '.join(REFERENCES)}, got {reference!r}", parameter="reference")
    for name, what, parameter in (("time_s", "the time of each reading", "run"),
                                  (reference, "the reference", "reference"),
                                  (x, "the readout", "x")):
        if name not in run:
            raise ParameterError(f"{run.path}: column {name!r} missing ({what}; columns: {', '.join(run.columns)})",
                                 parameter=parameter)
    if x in ("time_s", reference):
        raise ParameterError(f"must be a readout column, not {x!r}", parameter="x")
    if not np.isfinite(run[x]).any():
        raise ParameterError(f"{run.path}: column {x!r} has no readings (every cell is empty)", parameter="x")
    if not np.isfinite(run[reference]).any():
        raise ParameterError(f"{run.path}: column {reference!r} has no readings (every cell is empty)",
                             parameter="reference")
    units = run.units
    try:
        return creep(run["time_s"], run[x], run[reference], band=band, min_hold_s=min_hold_s, settle_s=settle_s,
                     x=x, x_unit=units.get(x, ""), reference_name=reference,
                     reference_unit=units.get(reference, ""))
    except ParameterError as exc:
        if exc.parameter == "reference" and exc.reason.startswith(f"{reference}: "):
            raise ParameterError(f"{run.path}: {exc.reason}", parameter="reference") from None
        raise
