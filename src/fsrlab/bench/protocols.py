"""Bench protocols (``fsrlab bench``): the paper's measurements as plans a bench runs and a person can follow.

**Extension.** The paper (§6.1) loads its sensors with a stepper-driven spring (cycles 0 → 10 kPa
→ 0, for Figure 19 and Table 3) and with dead weights placed again and again (200 g and 400 g, five
times, for Tables 4 and 5). fsrlab writes those procedures down as pure plans, and adds a creep hold:

- :class:`SpringPlan`: ``cycles`` triangle cycles from ``base_pa`` to ``peak_pa`` and back, each
  ``period_s`` long. The virtual bench drives it with a
  :class:`~fsrlab.virtual.sources.StressProfile`; with hardware the user starts the motor
  (or loads and unloads by hand) when asked and the run records for ``cycles × period_s``.
- :class:`WeightsPlan`: dead-weight re-placements, each mass reached from below in each of
  ``repeat`` cycles and unloaded to zero in between (:func:`~fsrlab.bench.weights.plan_steps`
  with the unloading, run by :class:`~fsrlab.bench.weights.WeightsProcedure`: the known-weight
  workflow with its stability criterion).
- :class:`CreepPlan`: unloaded for ``before_s``, then one mass held for ``hold_s``, then unloaded
  for ``after_s`` (:mod:`fsrlab.metrics.creep` reads such holds).

:func:`run_protocol` runs a plan on an open meter (a serial port, the Python virtual device or
the digital twin, :func:`open_bench`) into a run file, through
:func:`fsrlab.acquisition.recorder.record`.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fsrlab.bench.weights import Step, plan_steps
from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_at_least, check_positive, float_array
from fsrlab.units import STANDARD_GRAVITY

__all__ = ["PROTOCOLS", "DEVICES", "SPEEDS", "VIRTUAL_SENSORS", "virtual_sensor", "SpringPlan", "WeightsPlan",
           "CreepPlan", "twin_status", "open_bench",
           "ProtocolRun", "run_protocol"]

PROTOCOLS = ("spring", "weights", "creep")
"""The bench protocols, as ``fsrlab bench`` names them."""

DEVICES = ("virtual", "twin", "port")
"""Where a protocol runs: the Python virtual device, the digital twin (firmware in simavr), a serial port."""

SPEEDS = ("realtime", "max")
"""Pacing of a virtual bench: ``realtime`` (as hardware, for a person watching) or ``max`` (as fast as the
machine runs it; the run's time axis stays the simulated one)."""


@dataclass(frozen=True)
class SpringPlan:
    """Spring cycles as on the paper's stepper-motor bench (§6.1): base → peak → base, ``cycles`` times.

    Parameters
    ----------
    peak_pa : float
        Largest stress (> base_pa); the paper's bench reaches 10 kPa. [Pa]
    cycles : int
        Loading-unloading cycles (≥ 1).
    period_s : float
        Duration of one cycle (> 0). [s]
    base_pa : float
        Smallest stress (≥ 0). [Pa]
    """

    peak_pa: float = 10e3
    cycles: int = 3
    period_s: float = 4.0
    base_pa: float = 0.0

    def __post_init__(self) -> None:
        if not (isinstance(self.cycles, int) and 1 <= self.cycles <= 100000):
            raise ParameterError(f"must be an integer from 1 to 100000, got {self.cycles!r}", parameter="cycles")
        check_positive("period_s", self.period_s, "s", scalar=True)
        check_at_least("base_pa", self.base_pa, 0.0, "Pa", scalar=True)
        check_positive("peak_pa", self.peak_pa, "Pa", scalar=True)
        if not (math.isfinite(self.peak_pa) and self.peak_pa > self.base_pa >= 0):
            raise ParameterError(f"must exceed base_pa >= 0 Pa, got {self.peak_pa!r} and {self.base_pa!r}",
                                 parameter="peak_pa")

    @property
    def duration_s(self) -> float:
        """Recording time: the whole cycles. [s]"""
        return self.cycles * self.period_s

    def profile(self):
        """The virtual bench's :class:`~fsrlab.virtual.sources.StressProfile` (triangle)."""
        from fsrlab.virtual.sources import StressProfile

        return StressProfile(kind="triangle", peak_pa=self.peak_pa, period_s=self.period_s, base_pa=self.base_pa)

    def stress(self, t_s):
        """Planned stress at times ``t_s`` since START [s]; the base stress after the last cycle. [Pa]"""
        import numpy as np

        t = np.asarray(t_s, dtype=float)
        return np.where((t >= 0) & (t <= self.duration_s), self.profile().stress(t), self.base_pa)

    def prompt(self) -> str:
        """What a person with hardware is asked to do."""
        return (f"start the spring cycles: {self.cycles} × (from {self.base_pa / 1e3:g} kPa up to "
                f"{self.peak_pa / 1e3:g} kPa and back) in {self.period_s:g} s each (motor, or by hand), then press "
                f"Enter; the run records {self.duration_s:g} s (Ctrl-C ends it early, keeping the rows)")

    def to_dict(self) -> dict:
        """The sidecar's ``protocol``."""
        return {"name": "spring", "peak_pa": self.peak_pa, "base_pa": self.base_pa, "cycles": self.cycles,
                "period_s": self.period_s, "duration_s": self.duration_s}


@dataclass(frozen=True)
class WeightsPlan:
    """Dead-weight re-placements as for the paper's Tables 4 and 5.

    Parameters
    ----------
    masses_kg : tuple of float
        The masses, increasing and > 0 (paper: 200 g and 400 g). [kg]
    repeat : int
        How often each mass is placed again (paper: 5).

    Notes
    -----
    Each cycle is 0 → every mass in increasing order → back down to 0, so every mass is reached
    from below once per cycle (the placements RE1/RE2 of eq. 39 are computed from) and the sensor
    is unloaded between the cycles.
    """

    masses_kg: tuple = (0.2, 0.4)
    repeat: int = 5

    def __post_init__(self) -> None:
        if isinstance(self.masses_kg, (str, bytes, int, float)) or float_array("masses_kg", self.masses_kg).ndim != 1:
            raise TypeError(f"masses_kg: must be a sequence of masses [kg], got {self.masses_kg!r:.80}")
        m = tuple(float(x) for x in self.masses_kg)
        object.__setattr__(self, "masses_kg", m)
        if not m or not all(math.isfinite(x) and x > 0 for x in m):
            raise ParameterError(f"must be finite masses > 0 kg, got {self.masses_kg!r}", parameter="masses_kg")
        if not (isinstance(self.repeat, int) and 1 <= self.repeat <= 1000):
            raise ParameterError(f"must be an integer from 1 to 1000, got {self.repeat!r}", parameter="repeat")
        plan_steps((0.0,) + m, self.repeat, True)  # increasing masses, or the ValueError naming them

    def steps(self) -> list[Step]:
        """The placements: :func:`~fsrlab.bench.weights.plan_steps` of 0 and the masses, with unloading."""
        return plan_steps((0.0,) + self.masses_kg, self.repeat, unload=True)

    def to_dict(self) -> dict:
        """The sidecar's ``protocol``."""
        return {"name": "weights", "masses_kg": list(self.masses_kg), "repeat": self.repeat,
                "steps": len(self.steps())}


@dataclass(frozen=True)
class CreepPlan:
    """A creep hold: unloaded, one mass held for a while, unloaded again.

    Parameters
    ----------
    mass_kg : float
        The mass held (> 0). [kg]
    hold_s : float
        How long it stays on (> 0). [s]
    before_s : float
        Unloaded time before it is placed (≥ 0). [s]
    after_s : float
        Unloaded time recorded after it is removed (recovery, ≥ 0). [s]
    """

    mass_kg: float = 0.2
    hold_s: float = 60.0
    before_s: float = 2.0
    after_s: float = 5.0

    def __post_init__(self) -> None:
        check_positive("mass_kg", self.mass_kg, "kg", scalar=True)
        check_positive("hold_s", self.hold_s, "s", scalar=True)
        for name in ("before_s", "after_s"):
            check_at_least(name, getattr(self, name), 0.0, "s", scalar=True)

    @property
    def duration_s(self) -> float:
        """Recording time. [s]"""
        return self.before_s + self.hold_s + self.after_s

    def segments(self) -> list[tuple[float, float]]:
        """``(start [s], mass [kg])`` of each part of the plan, in order."""
        return [(0.0, 0.0), (self.before_s, self.mass_kg), (self.before_s + self.hold_s, 0.0)]

    def mass_at(self, t_s: float) -> float:
        """The planned mass at time ``t_s`` since START [s]. [kg]"""
        mass = 0.0
        for start, m in self.segments():
            if t_s >= start:
                mass = m
        return mass

    def to_dict(self) -> dict:
        """The sidecar's ``protocol``."""
        return {"name": "creep", "mass_kg": self.mass_kg, "hold_s": self.hold_s, "before_s": self.before_s,
                "after_s": self.after_s, "duration_s": self.duration_s}


VIRTUAL_SENSORS = ("virtual-fsr", "paper-a201-1", "paper-a201-2", "paper-a201-3", "paper-a201-4")
"""Names of the virtual bench's sensors (:func:`virtual_sensor`); a sensor preset's name
(:data:`fsrlab.physics.presets.SENSOR_PRESETS`) gives the virtual FSR that preset's area."""


def virtual_sensor(sensor):
    """The virtual bench's sensor by name.

    Parameters
    ----------
    sensor : str or object
        ``virtual-fsr`` (:class:`~fsrlab.physics.sensor.VirtualFSR`, FlexiForce A201-like),
        ``paper-a201-1`` .. ``paper-a201-4`` (:func:`fsrlab.physics.paper_sensor.paper_sensor`, the
        sensors fitted to the paper's §6), another sensor preset's name (the virtual FSR with that
        sensing area), or a sensor object, returned as is.

    Returns
    -------
    (object, str)
        The sensor (with ``respond`` and ``area_m2``) and its description.

    Raises
    ------
    fsrlab.errors.ParameterError
        An unknown name (parameter ``sensor``).
    TypeError
        An object that is not a sensor model.
    """
    from fsrlab.physics.paper_sensor import PAPER_SENSOR_NAMES, paper_sensor
    from fsrlab.physics.presets import SENSOR_PRESETS
    from fsrlab.physics.sensor import VirtualFSR

    if not isinstance(sensor, str):
        from fsrlab.virtual.arguments import check_sensor

        check_sensor("sensor", sensor)
        return sensor, type(sensor).__name__
    key = sensor.strip().lower()

    if key in PAPER_SENSOR_NAMES:
        return paper_sensor(key), f"{key} (fitted paper sensor, fsrlab.physics.paper_sensor)"
    if key == "virtual-fsr":
        return VirtualFSR(), "VirtualFSR (FlexiForce A201-like, fsrlab.physics.sensor)"
    if key in SENSOR_PRESETS:
        area = SENSOR_PRESETS[key].area_m2
        return VirtualFSR(area_m2=area), f"VirtualFSR on the area of {key} ({area * 1e6:.1f} mm²)"
    raise ParameterError(f"must be virtual-fsr or one of {', '.join(SENSOR_PRESETS)}, got {sensor!r}",
                         parameter="sensor")


def twin_status() -> tuple[bool, str]:
    """Whether the digital twin (``fsrlab.virtual.twin``: the firmware in simavr) can run here, and why not.

    Returns
    -------
    (bool, str)
        ``(True, "")`` or ``(False, reason)``: the module is missing, or its own
        ``twin_available()`` says why not.
    """
    try:
        from fsrlab.virtual.twin import twin_available  # noqa: PLC0415 - optional, built separately
    except ImportError as exc:
        return False, f"the digital twin is not part of this installation (fsrlab.virtual.twin: {exc})"
    try:
        ok, reason = twin_available()
    except Exception as exc:  # noqa: BLE001 - any failure of the probe means: not available
        return False, f"the digital twin's check failed: {type(exc).__name__}: {exc}"
    return bool(ok), "" if ok else str(reason)


def open_bench(device: str, source, seed: int | None = None, speed: str = "realtime"):
    """A virtual meter driven by ``source``, not yet opened: the Python virtual device or the twin.

    Parameters
    ----------
    device : {"virtual", "twin"}
        :class:`~fsrlab.virtual.device.VirtualDevice` (a Python model of the firmware
        on a pty), or ``fsrlab.virtual.twin.Twin`` (the real firmware in simavr on a pty).
    source : SignalSource
        What the sensor and the circuits do (``PhysicsSource``, ``BenchSource``).
    seed : int, optional
        Random seed of the noise.
    speed : {"realtime", "max"}
        Pacing of the simulated time (:data:`SPEEDS`).

    Returns
    -------
    object
        With ``open() -> pty path``, ``close()`` and ``failure``.

    Raises
    ------
    ValueError
        An unknown device or speed, or the twin is not available (the message says why).
    """
    if speed not in SPEEDS:
        raise ParameterError(f"must be one of {', '.join(SPEEDS)}, got {speed!r}", parameter="speed")
    if device == "virtual":
        from fsrlab.virtual.device import VirtualDevice

        return VirtualDevice(source, seed=seed, speed=speed)
    if device == "twin":
        ok, reason = twin_status()
        if not ok:
            raise ParameterError(f"the twin: {reason}", parameter="device")
        from fsrlab.acquisition.loadcell import LoadCellModel
        from fsrlab.virtual.twin import Twin

        # The load cell the Python virtual device emulates by default, on the twin's HX711 model.
        return Twin(source=source, speed=speed, seed=0 if seed is None else seed, loadcell=LoadCellModel())
    raise ParameterError(f"must be virtual or twin, got {device!r}", parameter="device")


@dataclass
class ProtocolRun:
    """What :func:`run_protocol` did.

    Attributes
    ----------
    result : RecordResult
        The recording (rows, drops, how it ended).
    protocol : dict
        The plan (its ``to_dict``), as in the sidecar.
    device : str
        ``virtual``, ``twin`` or the serial port.
    summary : dict
        Per protocol: the weights procedure's ``summary()`` (``weights``), else ``{}``.
    placements : Path or None
        ``NAME.placements.csv`` of a weights run.
    """

    result: object
    protocol: dict
    device: str
    summary: dict = field(default_factory=dict)
    placements: Path | None = None


def _hardware_wait(confirm: Callable[[], str | None], stop: threading.Event) -> None:
    """Block until the person confirms (Enter) or ``stop`` is set."""
    while not stop.is_set() and confirm() is None:
        stop.wait(0.05)


def run_protocol(plan, out, device: str = "virtual", port: str | None = None, sensor=None,
                 area_m2: float | None = None, seed: int | None = None, window_ms: int = 20,
                 loadcell=None, announce: Callable[[str], None] | None = None,
                 confirm: Callable[[], str | None] | None = None, overwrite: bool = False,
                 on_status: Callable | None = None, settle: dict | None = None,
                 gravity_m_s2: float = STANDARD_GRAVITY, metadata: dict | None = None,
                 speed: str = "realtime") -> ProtocolRun:
    """Run a bench protocol into a run file.

    Parameters
    ----------
    plan : SpringPlan, WeightsPlan or CreepPlan
        What to do.
    out : path-like
        The run's CSV (sidecar beside it; a weights run also writes ``NAME.placements.csv``).
    device : {"virtual", "twin", "port"}
        The Python virtual device, the digital twin, or hardware on ``port``.
    port : str, optional
        Serial port for ``device="port"``.
    sensor : VirtualFSR, optional
        The virtual sensor (default ``VirtualFSR()``, or one of ``area_m2``).
    area_m2 : float, optional
        Sensing area for stress = force / area (hardware; the virtual sensor's own area otherwise). [m²]
    seed : int, optional
        Noise seed of a virtual meter.
    window_ms : int
        Measurement window. [ms]
    loadcell : LoadCellCalibration, optional
        Load-cell calibration; a virtual meter uses its emulated load cell's own when None.
    announce : callable, optional
        ``announce(text)``: prompts and notices (default: none).
    confirm : callable, optional
        ``confirm() -> None | "ok" | "skip"``: the person's answer (hardware); the virtual bench
        answers itself.
    overwrite : bool
        Replace an existing run.
    on_status : callable, optional
        The recorder's progress callback (:class:`~fsrlab.acquisition.recorder.RecordStatus`).
    settle : dict, optional
        Weights only: ``settle_windows``, ``max_drift``, ``timeout_s``, ``hold_s``
        (:data:`~fsrlab.bench.weights.STABILITY`).
    gravity_m_s2 : float
        Local gravity for m·g. [m/s²]
    metadata : dict, optional
        More sidecar content.
    speed : {"realtime", "max"}
        A virtual bench's pacing (:data:`SPEEDS`): ``max`` records as fast as the machine runs the
        device, the run's duration and times on the device's simulated clock (``record``'s
        ``clock="device"``); hardware is ``realtime`` only.

    Returns
    -------
    ProtocolRun

    Raises
    ------
    ValueError
        A bad plan or device, the twin not available, a virtual sensor without a response at the
        plan's load.
    FileExistsError, LinkError, OSError
        As :func:`fsrlab.acquisition.recorder.record`.
    """
    from fsrlab.acquisition.recorder import record
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.physics.sensor import VirtualFSR

    _check_device(device, port, speed)
    out = Path(out)
    say = announce or (lambda text: None)
    answer = confirm or (lambda: "ok")
    virtual = device != "port"
    if virtual and sensor is None:
        sensor = VirtualFSR() if area_m2 is None else VirtualFSR(area_m2=area_m2)
    meta = {"protocol": plan.to_dict(), **(metadata or {})}
    stop = threading.Event()
    clock = _DeviceClock()
    hooks = _plan_hooks(plan, virtual, sensor, seed, clock, say, answer, stop, gravity_m_s2, loadcell,
                        area_m2, settle)
    reference = health = None
    if virtual:
        clock.dev = open_bench(device, hooks.source, seed, speed)
        reference, loadcell, area_m2 = _virtual_bench(hooks, clock.dev, plan, device, sensor, meta, metadata,
                                                      loadcell, window_ms)
        health = lambda: clock.dev.failure  # noqa: E731
        port = clock.dev.open()
    try:
        with SerialLink(port) as link:
            if not virtual:
                _ask_to_start(plan, say, answer, stop)
            result = record(link, out, hooks.duration, window_ms=window_ms, metadata=meta, reference=reference,
                            on_status=on_status, stop=stop, health=health, overwrite=overwrite,
                            loadcell=loadcell, area_m2=area_m2 if reference is None else None,
                            on_event=say, clock="device" if speed == "max" else "host", **hooks.record_kwargs())
    finally:
        if clock.dev is not None:
            clock.dev.close()
    summary, placements = _placements(hooks.proc, out)
    return ProtocolRun(result=result, protocol=plan.to_dict(), device=device if virtual else str(port),
                       summary=summary, placements=placements)


def _check_device(device: str, port: str | None, speed: str) -> None:
    if device not in DEVICES:
        raise ParameterError(f"must be one of {', '.join(DEVICES)}, got {device!r}", parameter="device")
    if device == "port" and not port:
        raise ParameterError("a serial port is needed for device='port'", parameter="port")
    if speed not in SPEEDS:
        raise ParameterError(f"must be one of {', '.join(SPEEDS)}, got {speed!r}", parameter="speed")
    if device == "port" and speed != "realtime":
        raise ParameterError("hardware runs in real time; speed='max' is for a virtual bench", parameter="speed")


class _DeviceClock:
    """The bench's time for a placement: the device's clock, else the last row's time. [s]"""

    def __init__(self):
        self.dev = None
        self.last_t = 0.0

    def now(self) -> float:
        t = self.dev.time_since_start() if hasattr(self.dev, "time_since_start") else math.nan
        return t if math.isfinite(t) else self.last_t


@dataclass
class _Hooks:
    """What a protocol adds to the recording: its duration, its virtual source, the row hook."""

    duration: float
    source: object = None
    bench: object = None
    proc: object = None
    on_row: Callable | None = None
    extra_columns: list = field(default_factory=list)
    final_metadata: Callable | None = None

    def record_kwargs(self) -> dict:
        kw: dict = {}
        if self.extra_columns:
            kw["extra_columns"] = self.extra_columns
        if self.on_row is not None:
            kw["on_row"] = self.on_row
        if self.final_metadata is not None:
            kw["final_metadata"] = self.final_metadata
        return kw


def _plan_hooks(plan, virtual, sensor, seed, clock: _DeviceClock, say, answer, stop, gravity_m_s2, loadcell,
                area_m2, settle) -> _Hooks:
    """The hooks of ``plan``; the row hook also keeps ``clock``'s last row time."""
    if isinstance(plan, SpringPlan):
        hooks = _Hooks(duration=plan.duration_s)
        if virtual:
            from fsrlab.virtual.sources import PhysicsSource

            hooks.source = PhysicsSource(plan.profile(), sensor=sensor)
    elif isinstance(plan, WeightsPlan):
        hooks = _weights_hooks(plan, virtual, sensor, seed, clock, say, answer, stop, gravity_m_s2, loadcell,
                               area_m2, settle)
    elif isinstance(plan, CreepPlan):
        hooks = _creep_hooks(plan, virtual, sensor, seed, clock, say, gravity_m_s2)
    else:
        raise ParameterError("must be a SpringPlan, WeightsPlan or CreepPlan, got "
                f"{type(plan).__name__}", parameter="plan")
    if hooks.on_row is not None:
        hook = hooks.on_row

        def on_row(m, row):
            clock.last_t = float(row["time_s"])  # the run's clock, for a device without time_since_start
            return hook(m, row)
        hooks.on_row = on_row
    return hooks


def _weights_hooks(plan, virtual, sensor, seed, clock, say, answer, stop, gravity_m_s2, loadcell, area_m2,
                   settle) -> _Hooks:
    from fsrlab.bench.weights import WeightsProcedure

    hooks = _Hooks(duration=10 * 365 * 86400.0)  # the plan's end (or Ctrl-C) stops it
    steps = plan.steps()
    if virtual:
        from fsrlab.virtual.bench_source import BenchSource

        hooks.source = hooks.bench = BenchSource([s.mass_kg * gravity_m_s2 for s in steps], sensor=sensor, seed=seed)

        def place(step):
            t = clock.now()
            hooks.bench.place(step.index, t)
            return t
    else:
        def place(step):
            return None
    proc = hooks.proc = WeightsProcedure(
        steps, say, answer if not virtual else (lambda: "ok"), place, stop, gravity_m_s2=gravity_m_s2,
        use_loadcell=not virtual and loadcell is not None,
        area_m2=hooks.bench.load_area_m2 if virtual else area_m2, **(settle or {}))
    hooks.extra_columns = ["step", "direction", "cycle", "force_nominal_n", "force_n"] + (
        ["stress_pa"] if (virtual or area_m2) else []) + ["load", "sensor", "reading"]
    hooks.on_row = proc.on_row
    hooks.final_metadata = lambda: {"weights": proc.summary()}
    return hooks


def _creep_hooks(plan, virtual, sensor, seed, clock, say, gravity_m_s2) -> _Hooks:
    hooks = _Hooks(duration=plan.duration_s, extra_columns=["mass_planned_kg"])
    segments = plan.segments()
    if virtual:
        from fsrlab.virtual.bench_source import BenchSource

        hooks.source = hooks.bench = BenchSource([m * gravity_m_s2 for _, m in segments], sensor=sensor, seed=seed)
    done = [0]

    def creep_row(m, row):
        t = float(row["time_s"])
        while done[0] + 1 < len(segments) and t >= segments[done[0] + 1][0]:
            done[0] += 1
            mass = segments[done[0]][1]
            say(f"{'place ' + format(mass * 1e3, 'g') + ' g on the sensor' if mass else 'remove the mass'} now "
                f"(t = {segments[done[0]][0]:g} s)")
            if hooks.bench is not None:
                hooks.bench.place(done[0], clock.now())
        row = dict(row)
        row["mass_planned_kg"] = segments[done[0]][1]
        return row
    hooks.on_row = creep_row
    return hooks


def _virtual_bench(hooks: _Hooks, dev, plan, device, sensor, meta, metadata, loadcell, window_ms):
    """A virtual bench's sidecar, reference and load cell; returns ``(reference, loadcell, area_m2)``."""
    source = hooks.source
    vmeta = source.metadata()
    if metadata and "sensor" in metadata:  # the name given, beside the model that stood for it
        vmeta["sensor"] = {**metadata["sensor"], "virtual_model": vmeta["sensor"]["model"],
                           "area_m2": sensor.area_m2}
    meta.update(vmeta)
    meta["origin"] = (f"fsrlab bench {plan.to_dict()['name']} --{device} (virtual bench -> "
                      f"{type(sensor).__name__} -> LM555 and op-amp -> "
                      + ("meter model -> emulated firmware over a pty)" if device == "virtual" else
                         "the firmware in simavr over a pty)"))
    if loadcell is None and getattr(dev, "load_cell", None) is not None:
        loadcell = dev.load_cell.calibration()
    reference = None
    if hasattr(dev, "reference") and not isinstance(plan, WeightsPlan):
        reference = lambda frame: dev.reference(frame.seq)  # noqa: E731 - the applied stress
    area_m2 = hooks.bench.load_area_m2 if hooks.bench is not None else sensor.area_m2  # stress = force / loaded area
    if reference is None and loadcell is None and not isinstance(plan, WeightsPlan):
        # A device that sends neither the applied stress nor a load cell's reading (a twin without
        # its HX711): the stress the bench's model applied during each window.
        w_s, hook = window_ms / 1000.0, hooks.on_row

        def with_stress(m, row):
            t = float(row["time_s"])
            row = dict(row)
            sig = source.window(max(t - w_s, 0.0), t, int(row.get("range") or 0))
            row["stress_pa"] = sig.stress_pa if math.isfinite(sig.stress_pa) else None
            return hook(m, row) if hook is not None else row
        hooks.on_row = with_stress
        hooks.extra_columns = ["stress_pa", *hooks.extra_columns]
        meta["notes"] = ("stress_pa: the stress the virtual bench's model applied during each window (the device "
                         "sends no reference)")
    return reference, loadcell, area_m2


def _ask_to_start(plan, say, answer, stop) -> None:
    """Hardware, spring or creep: the port is open, ask the person and wait for Enter."""
    if isinstance(plan, SpringPlan):
        say(plan.prompt())
    elif isinstance(plan, CreepPlan):
        say(f"creep hold: {plan.before_s:g} s unloaded, then {plan.mass_kg * 1e3:g} g for "
            f"{plan.hold_s:g} s, then {plan.after_s:g} s unloaded; you are told when to place and "
            "remove the mass. Press Enter to start")
    else:
        return
    _hardware_wait(answer, stop)


def _placements(proc, out: Path) -> tuple[dict, Path | None]:
    """A weights run's summary and its ``NAME.placements.csv``; ``({}, None)`` for other protocols."""
    if proc is None:
        return {}, None
    from fsrlab.bench.weights import placements_table
    from fsrlab.io.outputs import write_text_atomic

    summary = proc.summary()
    placements = out.with_name(out.stem + ".placements.csv")
    write_text_atomic(placements, placements_table(summary, "frequency_hz"))
    return summary, placements
