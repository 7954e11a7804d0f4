"""The guided known-weight calibration (``fsrlab weights``): the plan of placements and the procedure.

:func:`plan_steps` lays out the placements: the masses in increasing order (``direction`` +1), then,
with ``unload``, back down in reverse (−1) without placing the top mass twice, all of it ``repeat``
times (``cycle`` 0, 1, ...), as the paper's dead-weight measurements of Tables 4 and 5.

:class:`WeightsProcedure` runs it, window by window, as the recorder's ``on_row`` hook
(:func:`fsrlab.acquisition.recorder.record`): for each step it asks for the mass (``announce``; the
virtual bench places it itself through ``place``), waits for the confirmation (``confirmed``), waits
until the readout is stable (:data:`STABILITY`), then keeps ``hold_s`` seconds of steady windows as
rows of the run, with ``step``, ``direction``, ``cycle``, ``force_nominal_n`` (m·g) and ``force_n``
(the nominal force, or the load cell's reading when a load-cell calibration is used), and the
``load``/``sensor``/``reading`` columns that ``fsrlab repeatability`` reads. It is driven by the
windows' own times (``time_s``), so it can be tested without a clock.

Stability criterion: over the last ``settle_windows`` windows (all with a readout), the relative
drift of the readout — the difference between the mean of the second half and the mean of the
first half, over the mean of all — is at most ``max_drift``. An FSR creeps after a load change;
this waits until the creep has slowed below the threshold. If it is not reached within
``timeout_s`` the user is asked again (Enter waits once more, ``s`` skips); a second timeout
skips the step, saying so. The virtual bench answers every question itself.
"""

from __future__ import annotations

import math
import threading
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from fsrlab.acquisition.loadcell import STANDARD_GRAVITY
from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_int, float_array

__all__ = ["STABILITY", "Step", "plan_steps", "WeightsProcedure", "READOUTS", "placements_table"]

STABILITY = {"settle_windows": 10, "max_drift": 0.005, "timeout_s": 30.0, "hold_s": 1.0}
"""Defaults of the stability criterion (see the module's docstring): windows compared [1],
largest relative drift of the readout [1], time before asking again [s], steady time kept [s]."""

READOUTS = ("frequency_hz", "duty_cycle", "voltage_v")
"""Readouts the stability is judged on (and written as ``reading``)."""


@dataclass(frozen=True)
class Step:
    """One placement.

    Attributes
    ----------
    index : int
        Order of the placement (0-based), the run's ``step`` column.
    mass_kg : float
        The total mass on the sensor. [kg]
    direction : int
        +1 loading (the masses increase to this one), −1 unloading.
    cycle : int
        Repeat number (0-based).
    """

    index: int
    mass_kg: float
    direction: int
    cycle: int


def plan_steps(masses_kg: Sequence[float], repeat: int = 1, unload: bool = False) -> list[Step]:
    """The placements of a known-weight calibration.

    Parameters
    ----------
    masses_kg : sequence of float
        Strictly increasing masses ≥ 0 (at least two). [kg]
    repeat : int
        Number of cycles (≥ 1).
    unload : bool
        Also go back down in reverse after the largest mass (for hysteresis).

    Returns
    -------
    list of Step

    Raises
    ------
    ValueError
        Masses not increasing, negative, fewer than two, or ``repeat`` < 1.
    """
    m = list(float_array("masses_kg", masses_kg).ravel()) if not isinstance(masses_kg, (int, float)) else None
    if m is None or np.ndim(masses_kg) != 1:
        raise TypeError(f"masses_kg: must be a sequence of masses [kg], got {masses_kg!r:.80}")
    if len(m) < 2:
        raise ParameterError(f"at least two are needed (e.g. 0,100g), got {len(m)}", parameter="masses_kg")
    for a, b in zip(m, m[1:], strict=False):  # consecutive pairs: the second list is one shorter
        if not b > a:
            raise ParameterError(f"must increase, got {b * 1e3:g} g after {a * 1e3:g} g", parameter="masses_kg")
    if m[0] < 0 or not all(math.isfinite(x) for x in m):
        raise ParameterError("must be finite and >= 0 kg", parameter="masses_kg")
    repeat = check_int("repeat", repeat, 1)
    steps: list[Step] = []
    for cycle in range(repeat):
        for mass in m:
            steps.append(Step(len(steps), mass, +1, cycle))
        if unload:
            for mass in reversed(m[:-1]):
                steps.append(Step(len(steps), mass, -1, cycle))
    return steps


class WeightsProcedure:
    """The guided calibration as a state machine fed with the run's windows (the recorder's ``on_row``).

    Parameters
    ----------
    steps : list of Step
        The plan (:func:`plan_steps`).
    announce : callable
        ``announce(text)``: tells the user (a prompt or a notice).
    confirmed : callable
        ``confirmed() -> None | "ok" | "skip"``: polled while waiting for the user; None: not yet.
    place : callable, optional
        ``place(step)``: called when a mass is asked for (the virtual bench places it). It may return
        the time of the placement on the run's clock [s]: windows that ended before it are not
        taken for the new mass (a host behind the device still reads windows of the old one).
    stop : threading.Event, optional
        Set when the plan is done (ends the recording).
    x : str
        Readout judged for stability and written as ``reading``: one of :data:`READOUTS`.
    gravity_m_s2 : float
        For the nominal force m·g. [m/s²]
    use_loadcell : bool
        ``force_n`` from the load cell (the row's own ``force_n``) instead of m·g.
    area_m2 : float, optional
        Sensor area: ``stress_pa = force_n / area``. [m²]
    settle_windows, max_drift, timeout_s, hold_s
        The stability criterion (:data:`STABILITY`). [1], [1], [s], [s]
    sensor_label : int
        The ``sensor`` column's value (repeatability groups by load and sensor).
    """

    def __init__(self, steps: list[Step], announce: Callable[[str], None], confirmed: Callable[[], str | None],
                 place: Callable[[Step], None] | None = None, stop: threading.Event | None = None,
                 x: str = "frequency_hz", gravity_m_s2: float = STANDARD_GRAVITY, use_loadcell: bool = False,
                 area_m2: float | None = None, settle_windows: int = STABILITY["settle_windows"],
                 max_drift: float = STABILITY["max_drift"], timeout_s: float = STABILITY["timeout_s"],
                 hold_s: float = STABILITY["hold_s"], sensor_label: int = 1) -> None:
        if x not in READOUTS:
            raise ParameterError(f"must be one of {', '.join(READOUTS)}, got {x!r}", parameter="x")
        if settle_windows < 2:
            raise ParameterError(f"must be >= 2, got {settle_windows}", parameter="settle_windows")
        for name, v in (("max_drift", max_drift), ("timeout_s", timeout_s), ("hold_s", hold_s)):
            if not (math.isfinite(v) and v > 0):
                raise ParameterError(f"must be > 0, got {v!r}", parameter=name)
        self.steps, self.announce, self.confirmed = steps, announce, confirmed
        self.place, self.stop = place, stop
        self.x, self.g, self.use_loadcell, self.area_m2 = x, gravity_m_s2, use_loadcell, area_m2
        self.settle_windows, self.max_drift, self.timeout_s, self.hold_s = settle_windows, max_drift, timeout_s, hold_s
        self.sensor_label = sensor_label
        self.k = 0
        self.state = "prompt" if steps else "done"
        self._buf: deque = deque(maxlen=settle_windows)
        self._t_settle = self._t_hold = 0.0
        self._retried = False
        self._not_before = -math.inf
        self.results: list[dict] = [{"step": s.index, "mass_kg": s.mass_kg, "direction": s.direction,
                                     "cycle": s.cycle, "status": "pending", "rows": 0} for s in steps]
        self._values: list[list[float]] = [[] for _ in steps]

    @property
    def done(self) -> bool:
        """Whether every step is recorded or skipped."""
        return self.state == "done"

    def drift(self) -> float:
        """Relative drift of the readout over the last windows (NaN until there are enough). [1]"""
        if len(self._buf) < self.settle_windows:
            return math.nan
        v = np.asarray(self._buf, dtype=float)
        if not np.all(np.isfinite(v)):
            return math.nan
        h = v.size // 2
        mean = float(np.mean(v))
        return abs(float(np.mean(v[h:]) - np.mean(v[:h]))) / abs(mean) if mean else math.inf

    def _next(self, status: str) -> None:
        self.results[self.k]["status"] = status
        self.k += 1
        self._retried = False
        if self.k >= len(self.steps):
            self.state = "done"
            if self.stop is not None:
                self.stop.set()
        else:
            self.state = "prompt"

    def _prompt(self) -> None:
        s = self.steps[self.k]
        way = "loading" if s.direction > 0 else "unloading"
        self.announce(f"step {s.index + 1}/{len(self.steps)} (cycle {s.cycle + 1}, {way}): place {s.mass_kg * 1e3:g} g "
                      "in all on the sensor, then press Enter (s and Enter skips the step)")
        if self.place is not None:
            when = self.place(s)
            if isinstance(when, (int, float)) and math.isfinite(when):
                self._not_before = float(when)
        self.state = "wait"

    def on_row(self, m, row: dict) -> dict | None:
        """The recorder's hook: the row to write (a steady window of the current step), or None."""
        if self.state == "done":
            return None
        t = float(row["time_s"])
        if self.state == "prompt":
            self._prompt()
        if self.state == "wait":
            if t <= self._not_before:
                return None  # a window of the old mass, read late
            answer = self.confirmed()
            if answer is None:
                return None
            if answer == "skip":
                self.announce(f"step {self.k + 1} skipped")
                self._next("skipped")
                return None
            self.state, self._t_settle = "settle", t
            self._buf.clear()
        if self.state == "settle":
            value = row.get(self.x)
            self._buf.append(value if value is not None else math.nan)
            drift = self.drift()
            if drift <= self.max_drift:
                self.state, self._t_hold = "hold", t
                self.results[self.k]["settle_s"] = round(t - self._t_settle, 3)
                return None  # the steady windows from the next one on are kept
            if t - self._t_settle >= self.timeout_s:
                said = ("no readout in some windows" if math.isnan(drift) else
                        f"the readout drifts {drift:.2%} over the last {self.settle_windows} windows, more than "
                        f"{self.max_drift:.2%}")
                if not self._retried:
                    self._retried = True
                    self.announce(f"step {self.k + 1}: not stable after {self.timeout_s:g} s ({said}); check that the "
                                  "mass sits still, then press Enter to wait again, or s and Enter to skip the step")
                    self.state = "wait"
                else:
                    self.announce(f"step {self.k + 1} skipped: not stable after a second {self.timeout_s:g} s ({said})")
                    self._next("skipped: unstable")
            return None
        # hold: a steady window of this step
        if t - self._t_hold > self.hold_s + 1e-9:
            self._next("recorded")
            return self.on_row(m, row) if self.state == "prompt" else None
        s = self.steps[self.k]
        nominal = s.mass_kg * self.g
        force = row.get("force_n") if self.use_loadcell else nominal
        row = dict(row)
        row.update({"step": s.index, "direction": s.direction, "cycle": s.cycle, "force_nominal_n": nominal,
                    "force_n": force, "load": round(s.mass_kg * 1e3, 6), "sensor": self.sensor_label,
                    "reading": row.get(self.x)})
        if self.area_m2 is not None:
            row["stress_pa"] = force / self.area_m2 if force is not None else None
        self.results[self.k]["rows"] += 1
        if row.get(self.x) is not None and math.isfinite(row[self.x]):
            self._values[self.k].append(float(row[self.x]))
        return row

    def summary(self) -> dict:
        """The sidecar's ``weights.steps``: per step its mass, direction, cycle, status, rows, time to
        settle [s] and the mean readout of its steady windows."""
        out = []
        for r, v in zip(self.results, self._values, strict=True):
            out.append({**r, "mean_reading": float(np.mean(v)) if v else None})
        return {"steps": out, "recorded": sum(r["status"] == "recorded" for r in self.results),
                "skipped": sum(r["status"].startswith("skipped") for r in self.results),
                "completed": self.done}


def placements_table(summary: dict, x: str, sensor_label: int = 1) -> str:
    """CSV ``load,sensor,reading,cycle,direction,step`` with one row per recorded loading placement
    (the mean of its steady windows): the input of ``fsrlab repeatability`` as in the paper's Tables
    4 and 5, the same load reached again from below in each cycle. Unloading placements are left out:
    at the same mass they differ by the hysteresis, which is not a lack of repeatability.

    Parameters
    ----------
    summary : dict
        :meth:`WeightsProcedure.summary`.
    x : str
        The readout (for the header comment in the docs; the column is ``reading``).
    sensor_label : int
        The ``sensor`` column.

    Returns
    -------
    str
        The CSV text.
    """
    lines = ["load,sensor,reading,cycle,direction,step"]
    for s in summary["steps"]:
        if s["status"] == "recorded" and s["mean_reading"] is not None and s["direction"] > 0:
            lines.append(f"{s['mass_kg'] * 1e3:g},{sensor_label},{s['mean_reading']!r},{s['cycle']},{s['direction']},"
                         f"{s['step']}")
    return "\n".join(lines) + "\n"
