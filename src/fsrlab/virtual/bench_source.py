"""The virtual bench's hands: a signal source whose force follows placed masses.

:class:`BenchSource` is a signal source for :class:`~fsrlab.virtual.device.VirtualDevice`
whose applied force follows a sequence of placed masses: the virtual bench of ``fsrlab weights
--virtual`` places each mass itself (:meth:`BenchSource.place`), the force ramps to it in
``ramp_s``, and the sensor (:class:`~fsrlab.physics.sensor.VirtualFSR`, with its hysteresis
memory), the 555 and the op-amp answer as with :class:`~fsrlab.virtual.sources.PhysicsSource`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fsrlab.circuits.circuit import PAPER_OPAMP, LM555Circuit, OpAmpReadout
from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_int, check_positive, float_array
from fsrlab.virtual.arguments import check_sensor, random_generator

__all__ = ["BenchSource"]



class BenchSource:
    """Signal source whose applied force follows masses placed one after the other (the virtual bench).

    Parameters
    ----------
    forces_n : sequence of float
        The forces of the planned placements, in order (≥ 0). [N]
    sensor : VirtualFSR, optional
        Default ``VirtualFSR()`` (FlexiForce A201-like).
    circuit : LM555Circuit, optional
        Default the virtual device's circuit (:data:`~fsrlab.virtual.sources.VIRTUAL_CIRCUIT`).
    opamp : OpAmpReadout
        The A0 readout (eq. 38).
    ramp_s : float
        Time the force takes from one mass to the next (a hand lowering it). [s]
    ramp_points : int
        Points of the stress history per placement (the sensor's memory is evaluated on them).
    load_area_m2 : float, optional
        Area the placed force spreads over on the sensor (a fixture's puck): stress = force / this
        area. Default: the sensor's ``load_area_m2`` if it has one (the paper sensors), else its
        ``area_m2``. [m²]
    seed : int, optional
        Seed of the placement draws of a sensor with ``placement(rng)`` (the paper sensors: each
        placement meets the sensor a little differently, Tables 4 and 5).

    Notes
    -----
    The sensor model is rate-independent, so its response to the whole planned sequence is computed
    once; :meth:`place` only sets when each placement happens. Before the first placement the force
    is that of the first one. Creep under a held mass is not modelled here (the response is computed
    before the placement times are known).
    """

    def __init__(self, forces_n: Sequence[float], sensor=None, circuit: LM555Circuit | None = None,
                 opamp: OpAmpReadout = PAPER_OPAMP, ramp_s: float = 0.15, ramp_points: int = 16,
                 load_area_m2: float | None = None, seed: int | None = None) -> None:
        from fsrlab.physics.sensor import VirtualFSR
        from fsrlab.virtual.sources import VIRTUAL_CIRCUIT

        f = float_array("forces_n", forces_n)
        if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f < 0):
            raise ParameterError("must be a non-empty sequence of finite forces >= 0 N", parameter="forces_n")
        check_positive("ramp_s", ramp_s, "s", scalar=True)
        ramp_points = check_int("ramp_points", ramp_points, 2)
        if sensor is not None:
            check_sensor("sensor", sensor)
        for name, obj, cls in (("circuit", circuit, LM555Circuit), ("opamp", opamp, OpAmpReadout)):
            if obj is not None and not isinstance(obj, cls):
                raise TypeError(f"{name}: must be an {cls.__name__}, got {type(obj).__name__}")
        if opamp is None:
            raise TypeError("opamp: must be an OpAmpReadout, got None")
        self.sensor = sensor if sensor is not None else VirtualFSR()
        self.circuit = circuit if circuit is not None else VIRTUAL_CIRCUIT
        self.opamp = opamp
        self.forces_n, self.ramp_s, self._n = f, float(ramp_s), int(ramp_points)
        if load_area_m2 is None:
            load_area_m2 = getattr(self.sensor, "load_area_m2", self.sensor.area_m2)
        check_positive("load_area_m2", load_area_m2, "m²", scalar=True)
        self.load_area_m2 = float(load_area_m2)
        stress = f / self.load_area_m2
        hist = [np.array([stress[0]])] + [np.linspace(stress[k - 1], stress[k], self._n + 1)[1:]
                                          for k in range(1, f.size)]
        sigma = np.concatenate(hist)
        kw = self._placement_draws(f.size, seed)
        resp = self.sensor.respond(sigma, voltage_v=self.circuit.fsr_voltage_v, **kw)
        self._stress = np.asarray(resp.stress_pa, dtype=float)
        self._r = np.asarray(resp.r_fsr_ohm, dtype=float)
        self._c = np.asarray(resp.c_fsr_farad, dtype=float)
        r_op = self.sensor.respond(sigma, voltage_v=opamp.fsr_voltage_v, **kw).r_fsr_ohm
        self._v = np.asarray(opamp.output_v(r_op), dtype=float)  # Eq. (38)
        self._placed = [0.0] + [np.inf] * (f.size - 1)  # when each placement began (time since START) [s]

    def _placement_draws(self, placements: int, seed: int | None) -> dict:
        """Per-sample ``respond`` keywords of the placement draws (empty for a sensor without them):
        placement k's factors hold on its ramp and while it rests."""
        if not hasattr(self.sensor, "placement"):
            return {}
        rng = random_generator("seed", seed)
        draws = [self.sensor.placement(rng) for _ in range(placements)]
        owner = np.concatenate([[0]] + [np.full(self._n, k) for k in range(1, placements)])
        return {key: np.asarray([d[key] for d in draws], dtype=float)[owner] for key in draws[0]}

    @property
    def dt_s(self) -> float:
        """Time between the points of a ramp: the grid on which :meth:`parts` changes. [s]"""
        return self.ramp_s / (self._n - 1)

    def parts(self, t_s):
        """Sensor state at times ``t_s`` since START [s]: ``(r_fsr_ohm, c_fsr_farad, a0_v)`` (see
        :meth:`fsrlab.virtual.sources.PhysicsSource.parts`); placements not yet made hold the
        force of the last one."""
        idx = self._index(np.asarray(t_s, dtype=float))
        return self._r[idx], self._c[idx], self._v[idx]

    def place(self, step: int, t_s: float) -> None:
        """Begin placement ``step`` (0-based, in the planned order) at time ``t_s`` since START [s]."""
        if not 0 <= step < self.forces_n.size:
            raise ParameterError(f"must be in 0..{self.forces_n.size - 1}, got {step!r}", parameter="step")
        if step > 0:
            self._placed[step] = max(float(t_s), self._placed[step - 1])

    def metadata(self) -> dict:
        """Sidecar content: ``circuit``, ``opamp``, ``sensor`` (with the area the masses load)."""
        from fsrlab.virtual.sources import sensor_metadata

        return {"circuit": self.circuit.to_dict(), "opamp": self.opamp.to_dict(),
                "sensor": {**sensor_metadata(self.sensor), "load_area_m2": self.load_area_m2}}

    def _where(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Placement in force at each time, and the fraction of its ramp done."""
        placed = np.asarray(self._placed)
        k = np.searchsorted(placed, t_s, side="right") - 1
        k = np.clip(k, 0, placed.size - 1)
        with np.errstate(invalid="ignore"):
            u = np.clip((t_s - placed[k]) / self.ramp_s, 0.0, 1.0)
        return k, np.where(k == 0, 1.0, u)

    def _index(self, t_s: np.ndarray) -> np.ndarray:
        k, u = self._where(np.asarray(t_s, dtype=float))
        return np.where(k == 0, 0, (k - 1) * self._n + 1 + np.round(u * (self._n - 1)).astype(int))

    def force_n(self, t_s) -> np.ndarray:
        """Applied force at times ``t_s`` since START [s] (linear ramps between placements). [N]"""
        k, u = self._where(np.asarray(t_s, dtype=float))
        before = self.forces_n[np.maximum(k - 1, 0)]
        return before + u * (self.forces_n[k] - before)

    def window(self, t0_s: float, t1_s: float, range_: int):
        """Mean signal over the window (see :class:`~fsrlab.virtual.sources.SignalSource`)."""
        from fsrlab.virtual.sources import Signal

        t = np.linspace(max(t0_s, 0.0), max(t1_s, 0.0), 8)
        idx = self._index(t)
        osc = self.circuit.on_range(range_).astable(self._r[idx], self._c[idx], check=False)
        period = np.asarray(osc.tau_high_s) + np.asarray(osc.tau_low_s)
        if not np.all(np.isfinite(period)):
            f = duty = float("nan")
        else:
            f = 1.0 / float(np.mean(period))
            duty = float(np.mean(osc.tau_high_s) / np.mean(period))
        return Signal(f, duty, float(np.mean(self._v[idx])), float(np.mean(self._stress[idx])))
