"""The demo's measurement chain on a virtual bench (``make demo`` / ``fsrlab demo``; the reports:
:mod:`fsrlab.reports.demo`).

:func:`run_chain` does what a user of fsrlab does with a sensor, with no hardware (steps 1 to 4;
:func:`fsrlab.reports.demo.run_demo` then writes the reports and runs several sensors, steps 5 to 8):

1. chooses the bench: the digital twin (the firmware in simavr) when
   :func:`~fsrlab.bench.protocols.twin_status` says it can run, else the Python virtual
   device, and says which;
2. records two spring runs (``fsrlab bench spring``: a calibration run and a test run) and a
   dead-weight run (``fsrlab bench weights``: 200 g and 400 g placed again and again); at
   ``speed="max"`` (the default) the bench runs faster than real time and the three runs are
   recorded at once, each on its own virtual meter (their time axes are the simulated clocks);
3. calibrates on the calibration run against the load cell's force when the meter has one (the
   virtual meter emulates an HX711; else the stress the bench applied), with the causal hysteresis
   compensation, every choice scored held out (:func:`fsrlab.calibrate`), and a known-weight
   calibration by the same engine on the dead-weight run (its readings against m·g);
4. applies the calibration to the test run (the compensated estimate);
5. writes the measurement report of the test run (:func:`fsrlab.reports.run_report.write_run_report`)
   with the dead-weight run's placements;
6. writes the reproduction report (:func:`fsrlab.reports.paper.write_report`);
7. scans 8 sensors behind the multiplexer, calibrates each from the one run and checks the cross-talk
   (:func:`fsrlab.bench.channels.several_sensors`);
8. writes ``index.html`` linking both reports.

The sensor is chosen in one place, :func:`demo_sensor`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fsrlab.errors import ParameterError

__all__ = ["DEMO_SENSOR", "demo_sensor", "DemoSettings", "DemoResult", "DemoSteps", "DemoChain", "run_chain",
           "remove_stale_staging"]

#: Name of the hidden folder a run is recorded in before it is renamed into the output directory:
#: the recording process's id, then a unique part. [1]
STAGING_PREFIX = ".recording-"

DEMO_SENSOR = "paper-a201-1"
"""The sensor the demo runs on (:func:`demo_sensor`): ``paper-a201-1`` (the first of the four sensors
fitted to the paper's §6, :func:`fsrlab.physics.paper_sensor.paper_sensor`; its dead weights load a
22 mm puck, :data:`~fsrlab.physics.paper_sensor.DEAD_WEIGHT_AREA_M2`), another of ``paper-a201-2`` ..
``-4``, or ``virtual-fsr`` (:class:`~fsrlab.physics.sensor.VirtualFSR`, FlexiForce A201-like)."""


def demo_sensor(name=None):
    """The virtual sensor of the demo: the one place where it is chosen.

    Parameters
    ----------
    name : str or object, optional
        A name for :func:`fsrlab.bench.protocols.virtual_sensor` (default :data:`DEMO_SENSOR`),
        or a sensor object, returned as is.

    Returns
    -------
    (object, str)
        The sensor (with ``respond`` and ``area_m2``) and its description.

    Raises
    ------
    ValueError
        An unknown name (see :func:`fsrlab.bench.protocols.virtual_sensor`).
    """
    from fsrlab.bench.protocols import virtual_sensor

    return virtual_sensor(DEMO_SENSOR if name is None else name)


@dataclass(frozen=True)
class DemoSettings:
    """How long the demo's recordings are and how fast the virtual bench runs them.

    Parameters
    ----------
    cycles : int
        Spring cycles per run.
    period_s : float
        Duration of one spring cycle. [s]
    peak_pa : float
        Peak stress of the spring cycles (the paper's bench: 10 kPa). [Pa]
    masses_kg : tuple of float
        Dead weights (the paper: 200 g and 400 g). [kg]
    repeat : int
        Placements of each dead weight (the paper: 5).
    settle_hold_s : float
        Steady time recorded per placement. [s]
    window_ms : int
        Measurement window. [ms]
    seed : int
        Noise seed of the first run (the others use the next ones).
    speed : {"realtime", "max"}
        ``max``: the virtual bench as fast as the machine runs it, the three runs at once;
        ``realtime``: one after the other, as hardware would (:data:`fsrlab.bench.protocols.SPEEDS`).
    """

    cycles: int = 4
    period_s: float = 4.0
    peak_pa: float = 10e3
    masses_kg: tuple = (0.2, 0.4)
    repeat: int = 5
    settle_hold_s: float = 0.5
    window_ms: int = 20
    seed: int = 1
    speed: str = "max"


@dataclass
class DemoResult:
    """What :func:`run_demo` did.

    Attributes
    ----------
    index : Path
        The demo's ``index.html``.
    device : str
        ``twin`` or ``virtual``.
    files : dict
        Name → path of every file written (runs, calibration, reports).
    steps : list of (str, float)
        Each step and its duration. [s]
    numbers : dict
        The headline numbers (HE of f, V0 and the estimate, RE, calibration).
    """

    index: Path
    device: str
    files: dict = field(default_factory=dict)
    steps: list = field(default_factory=list)
    numbers: dict = field(default_factory=dict)

    @property
    def total_s(self) -> float:
        """Total duration. [s]"""
        return float(sum(t for _, t in self.steps))


class DemoSteps:
    """The demo's numbered steps: says each one as it starts and records how long it took.

    Parameters
    ----------
    result : DemoResult
        Where each step's duration is recorded.
    total : int
        Number of steps.
    say : callable
        ``say(line)``: the progress lines.
    """

    def __init__(self, result: DemoResult, total: int, say: Callable[[str], None]):
        self.result, self.total, self.say = result, total, say
        self.t_all = time.monotonic()
        self.k = 0

    def step(self, title: str) -> float:
        """Say the next step's title; return its start time. [s]"""
        self.k += 1
        self.say(f"[{self.k}/{self.total}] {title}")
        return time.monotonic()

    def done(self, title: str, t0: float, text: str = "") -> None:
        """Record a step that started at ``t0`` and say how long it took."""
        dt = time.monotonic() - t0
        self.result.steps.append((title, dt))
        self.say(f"      {text + '; ' if text else ''}{dt:.1f} s (total {time.monotonic() - self.t_all:.1f} s)")


@dataclass
class DemoChain:
    """What the demo's measurement chain produced (steps 1 to 4).

    Attributes
    ----------
    result : DemoResult
        The files and numbers so far.
    calibration : Calibration
        The calibration on the spring run.
    sensor_text : str
        The sensor's description.
    steps : DemoSteps
        The step counter, for the steps that follow.
    """

    result: DemoResult
    calibration: Any
    sensor_text: str
    steps: DemoSteps


def remove_stale_staging(out) -> list[Path]:
    """Remove the hidden folders (``.recording-PID-…``) that a demo killed outright left in ``out``:
    those whose process no longer runs. A demo ended any other way removes its own; one still running
    keeps its. Returns the folders removed.

    Parameters
    ----------
    out : path-like
        The demo's output directory (nothing happens when it does not exist).
    """
    import os
    import shutil

    out = Path(out)
    removed = []
    if not out.is_dir():
        return removed
    for entry in out.iterdir():
        head, _, rest = entry.name.partition(STAGING_PREFIX)
        pid = rest.split("-", 1)[0]
        if head or not entry.is_dir() or not pid.isdigit():
            continue
        try:
            os.kill(int(pid), 0)
            continue  # its process still runs
        except ProcessLookupError:
            pass
        except (PermissionError, OverflowError):
            continue  # another user's, or not a process id: left alone
        shutil.rmtree(entry, ignore_errors=True)
        removed.append(entry)
    return removed


def run_chain(out, settings: DemoSettings, sensor=None, device: str = "auto", total: int = 4,
              say: Callable[[str], None] = lambda line: None,
              after_spring: Callable[[], None] | None = None) -> DemoChain:
    """The demo's measurement chain: bench, spring and dead-weight runs, calibrations, the compensated estimate.

    Parameters
    ----------
    out : path-like
        Output directory (created; files in it are replaced). Each run is recorded in a hidden
        folder inside it and renamed into ``out`` once complete, with its sidecar and placements; the
        folder is removed however the chain ends, so an interrupted demo leaves the old files (or
        none), never half of a run.
    settings : DemoSettings
        Durations and loads.
    sensor : str or object, optional
        :func:`demo_sensor`'s name or a sensor object (default :data:`DEMO_SENSOR`).
    device : {"auto", "twin", "virtual"}
        ``auto``: the twin when available, else the Python virtual device.
    total : int
        Number of steps the whole demo has (for the progress lines).
    say : callable
        ``say(line)``: what the demo does, step by step.
    after_spring : callable, optional
        Called once the two spring runs are recorded, while the dead weights may still be (the demo
        starts its reproduction report there, so that it draws meanwhile).

    Returns
    -------
    DemoChain

    Raises
    ------
    ValueError
        A bad setting or sensor, ``device="twin"`` without the twin.
    RuntimeError
        A recording that failed (the message says which and why).
    """
    import os
    import shutil
    import tempfile
    from concurrent.futures import Future, ThreadPoolExecutor

    from fsrlab.bench.protocols import SpringPlan, WeightsPlan

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    s = settings
    sensor_obj, sensor_text = demo_sensor(sensor)
    bench, reason = _bench_device(device, s.speed)
    result = DemoResult(index=out / "index.html", device=bench)
    steps = DemoSteps(result, total, say)
    step, done = steps.step, steps.done
    rec = None

    # 1. The bench and the spring runs. Faster than real time, the three recordings run at once (each its own
    # meter and time axis): the machine's cores share the simulations.
    spring = SpringPlan(peak_pa=s.peak_pa, cycles=s.cycles, period_s=s.period_s)
    weights = WeightsPlan(masses_kg=tuple(s.masses_kg), repeat=s.repeat)
    at_once = s.speed == "max"
    pool = ThreadPoolExecutor(3, thread_name_prefix="fsrlab-demo-bench") if at_once else None

    def later(*args, **kwargs) -> Future:
        if pool is not None:
            return pool.submit(rec.record, *args, **kwargs)
        f: Future = Future()
        f.set_result(rec.record(*args, **kwargs))
        return f

    pace = "faster than real time, the three runs at once" if at_once else "in real time"
    t0 = step("spring cycles on the "
            f"{'digital twin (firmware in simavr)' if bench == 'twin' else 'Python virtual device'}"
              f"{'' if bench == 'twin' else ' (the twin is not available: ' + reason + ')'}: sensor {sensor_text}; "
              f"{s.cycles} cycles 0 → {s.peak_pa / 1e3:g} kPa → 0 of {s.period_s:g} s, "
              "twice (calibration run, test run); "
              f"{pace}")
    staging = Path(tempfile.mkdtemp(prefix=f"{STAGING_PREFIX}{os.getpid()}-", dir=out))
    rec = _BenchRecorder(out, staging, bench, device, sensor_obj, s, result, say)
    try:
        f1 = later(spring, "calibration-run.csv", s.seed, "calibration run", spring.duration_s)
        f2 = later(spring, "test-run.csv", s.seed + 1, "test run", spring.duration_s)
        fw = later(weights, "weights-run.csv", s.seed + 2, "dead weights", None,
                   settle={"hold_s": s.settle_hold_s}) if at_once else None
        r1, r2 = f1.result(), f2.result()
        done("spring runs", t0, f"{r1.result.frames} + {r2.result.frames} windows on the {rec.bench} bench")
        if after_spring is not None:
            after_spring()

        # 2. Dead weights.
        t0 = step(f"dead weights: {', '.join(format(m * 1e3, 'g') + ' g' for m in weights.masses_kg)}, "
                  f"each placed {s.repeat} times from below, unloaded in between ({len(weights.steps())} placements)")
        if fw is None:
            fw = later(weights, "weights-run.csv", s.seed + 2, "dead weights", None, settle={"hold_s": s.settle_hold_s})
        rw = fw.result()
    finally:
        if pool is not None:
            pool.shutdown(wait=True)
        shutil.rmtree(staging, ignore_errors=True)
    for name in ("calibration-run.csv", "test-run.csv", "weights-run.csv"):  # in the plan's order, however they ended
        result.files[name] = result.files.pop(name)
    result.files["placements"] = rw.placements
    done("dead weights", t0, f"{rw.summary['recorded']} of {len(weights.steps())} placements recorded")

    cal = _calibrate_and_apply(out, result, steps, say)
    return DemoChain(result, cal, sensor_text, steps)


class _BenchRecorder:
    """Records one protocol of the demo aside (in ``staging``) and renames it into ``out`` once complete; when the
    twin fails and it was not asked for by name, says so and records on the Python virtual device instead."""

    def __init__(self, out: Path, staging: Path, bench: str, device: str, sensor, settings: DemoSettings,
                 result: DemoResult, say: Callable[[str], None]):
        self.out, self.staging, self.bench, self.device = out, staging, bench, device
        self.sensor, self.settings, self.result, self.say = sensor, settings, result, say

    def _on_status(self, label: str, total_s: float | None):
        last = [time.monotonic()]

        def on_status(st) -> None:
            now = time.monotonic()
            if now - last[0] >= 3.0:
                last[0] = now
                self.say(f"      {label}: {st.elapsed_s:.0f} s" + (f" of {total_s:.0f} s" if total_s else "")
                         + f", {st.frames} windows")
        return on_status

    def _run(self, plan, path: Path, bench: str, seed: int, label: str, total_s, settle):
        from fsrlab.bench.protocols import run_protocol

        s = self.settings
        return run_protocol(plan, path, device=bench, sensor=self.sensor, seed=seed, window_ms=s.window_ms,
                            overwrite=True, on_status=self._on_status(label, total_s), settle=settle, speed=s.speed)

    def record(self, plan, name: str, seed: int, label: str, total_s: float | None, settle=None):
        import dataclasses
        import os

        from fsrlab.io.outputs import replace_run

        path, final = self.staging / name, self.out / name  # recorded aside, renamed into place when complete
        used = self.bench  # (runs recorded at once: another one may fall back meanwhile)
        try:
            run = self._run(plan, path, used, seed, label, total_s, settle)
        except Exception as exc:  # noqa: BLE001 - the twin failing: say so and use the Python device
            if used != "twin" or self.device == "twin":
                raise
            self.say(f"      {label}: the digital twin failed ({type(exc).__name__}: {exc}); using the Python virtual "
                     "device")
            self.bench = self.result.device = "virtual"
            run = self._run(plan, path, "virtual", seed, label, total_s, settle)
        if run.result.failed or not run.result.frames:
            raise RuntimeError(f"{final}: the recording failed: {run.result.message.replace(str(path), str(final))}")
        replace_run(path, final)  # the sidecar first, naming its CSV: a stop between the two is told when read
        run.result = dataclasses.replace(run.result, file=final)
        if run.placements is not None:
            placed = final.with_name(run.placements.name)
            os.replace(run.placements, placed)
            run.placements = placed
        self.result.files[name] = final
        return run



def _bench_device(device: str, speed: str) -> tuple[str, str]:
    """The bench the demo records on (``twin`` or ``virtual``) and why the twin is not available (or "")."""
    from fsrlab.bench.protocols import SPEEDS, twin_status

    if device not in ("auto", "twin", "virtual"):
        raise ParameterError(f"must be auto, twin or virtual, got {device!r}", parameter="device")
    if speed not in SPEEDS:
        raise ParameterError(f"must be one of {', '.join(SPEEDS)}, got {speed!r}", parameter="speed")
    ok, reason = twin_status()
    if device == "twin" and not ok:
        raise ParameterError(f"the digital twin is not available: {reason}", parameter="device")
    return ("twin" if (device == "twin" or (device == "auto" and ok)) else "virtual"), reason


def _calibrate_and_apply(out: Path, result: DemoResult, steps: DemoSteps, say: Callable[[str], None]):
    """Steps 3 and 4 of the chain: the calibration run calibrated (:func:`fsrlab.calibrate`, compensation tried),
    the dead weights calibrated against m·g by the same engine, and the calibration applied to the test run."""
    import numpy as np

    from fsrlab.calibration.apply import apply_calibration
    from fsrlab.calibration.document import save_calibration
    from fsrlab.calibration.runs import calibrate_runs
    from fsrlab.io.runformat import load_run
    from fsrlab.io.runwriter import write_run

    step, done = steps.step, steps.done
    calrun = load_run(out / "calibration-run.csv")
    # The load cell when the meter has one (the virtual meter emulates an HX711): the reference a bench
    # with hardware has; else the stress the bench applied.
    reference = "force_n" if "force_n" in calrun and np.isfinite(calrun["force_n"]).mean() > 0.5 else "stress_pa"
    what = "the load cell's force (HX711)" if reference == "force_n" else "the applied stress"
    t0 = step(f"calibration: the calibration run against {what}, every choice (curve, delay of the reference, "
              "hysteresis and creep compensation) scored on later blocks of the run and kept only when it wins there; "
              "and a known-weight calibration on the dead weights (m·g)")
    cal = calibrate_runs(calrun, x="frequency_hz", reference=reference, compensate=True)
    refused = [s for s in cal.selection.steps if s["step"] == "memory" and not s["kept"]]
    if refused:
        say(f"      {refused[0]['step']} not kept: {refused[0]['why']}")
    # The demo's files in ``out`` are replaced (its caller checked the directory: the output policy).
    result.files["calibration"] = save_calibration(cal, out / "calibration.json", overwrite=True)
    known = None
    try:
        # The same engine on the dead weights' readings against m·g.
        known = calibrate_runs(out / "weights-run.csv", x="frequency_hz", reference="force_n")
        result.files["known-weight calibration"] = save_calibration(known, out / "known-weight-calibration.json",
                                                                     overwrite=True)
    except ValueError as exc:
        say(f"      known-weight calibration not possible: {exc}")
    for key, c in (("calibration", cal), ("known_weight_calibration", known)):
        if c is not None:
            result.numbers[key] = {"model": c.model_name, "reference": c.y_name,
                                   "heldout_rmse": c.selection.heldout_rmse,
                                   "unit": c.y_unit, "lag_s": c.lag_s, "delay_s": c.model.delay_s,
                                   "scheme": c.selection.scheme}
    done("calibration", t0, f"{cal.model_name}, held-out RMSE {cal.selection.heldout_rmse:.3g} {cal.y_unit}"
         + (f"; known weights: {known.model_name}, held-out RMSE {known.selection.heldout_rmse:.3g} {known.y_unit}"
            if known is not None else ""))

    # 4. Compensation on the test run.
    t0 = step("compensation: the calibration applied to the test run (causal estimate, row by row)")
    est = apply_calibration(cal, out / "test-run.csv")
    result.files["estimate"] = write_run(out / "test-estimate.csv", est.columns, est.metadata, overwrite=True)
    done("compensation", t0, f"{out / 'test-estimate.csv'}")
    return cal


