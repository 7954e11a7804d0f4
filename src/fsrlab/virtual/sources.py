"""What the virtual meter's inputs carry: signal sources for the virtual device and the digital twin.

A source answers, for one measurement window, what the 555's output, the op-amp's A0 and the load
cell see (:class:`Signal`). :class:`PhysicsSource` drives a sensor (:class:`fsrlab.physics.sensor.VirtualFSR`
or any object with its ``respond`` interface) with a stress profile (:class:`StressProfile`) through an
:class:`~fsrlab.circuits.circuit.LM555Circuit` and an :class:`~fsrlab.circuits.circuit.OpAmpReadout`;
:class:`ConstantSource` holds fixed values, for tests; :class:`fsrlab.virtual.bench_source.BenchSource`
places masses. The virtual device (:mod:`fsrlab.virtual.device`) and the twin (:mod:`fsrlab.virtual.twin`)
take any of them.

References
----------
.. [1] Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901 (§5 Figs. 13–16, §6 eq. 38).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from fsrlab.circuits.circuit import PAPER_CIRCUIT, PAPER_OPAMP, LM555Circuit, OpAmpReadout
from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_at_least, check_positive
from fsrlab.physics.sensor import A201_AREA_M2
from fsrlab.virtual.arguments import check_sensor

__all__ = ["Signal", "SignalSource", "ConstantSource", "StressProfile", "PhysicsSource", "MuxSource",
           "sensor_metadata", "PROFILE_KINDS", "VIRTUAL_CIRCUIT"]

PROFILE_KINDS = ("triangle", "sine", "steps", "hold")
"""Shapes of :class:`StressProfile`."""


@dataclass(frozen=True)
class Signal:
    """What the meter's inputs carry during one window.

    Attributes
    ----------
    frequency_hz : float
        Frequency of the 555 output; NaN or 0 when it does not oscillate. [Hz]
    duty_cycle : float
        High time over period, 0..1. [1]
    voltage_v : float
        Op-amp output on A0. [V]
    stress_pa : float
        The applied stress (reference, not sent on the link; NaN if unknown). [Pa]
    """

    frequency_hz: float
    duty_cycle: float
    voltage_v: float = 0.0
    stress_pa: float = math.nan


class SignalSource(Protocol):
    """Anything that says what the 555 and the op-amp do during a window.

    An object with a method ``window(t0_s, t1_s, range_) -> Signal``; see :class:`ConstantSource`
    and :class:`PhysicsSource`.
    """

    def window(self, t0_s: float, t1_s: float, range_: int) -> Signal:
        """Signal averaged over ``[t0_s, t1_s)`` (time since START [s]) with the C_off switch at ``range_``."""
        ...


@dataclass(frozen=True)
class ConstantSource:
    """A fixed square wave (for protocol tests).

    Parameters
    ----------
    frequency_hz : float
        Frequency of the wave. [Hz]
    duty_cycle : float
        High time over period. [1]
    voltage_v : float
        Voltage on A0. [V]
    stress_pa : float
        Reference stress reported by :meth:`VirtualDevice.reference`. [Pa]
    area_m2 : float
        Sensor area, for the force on the load cell (stress × area; NaN stress: no force). [m²]
    """

    frequency_hz: float = 5000.0
    duty_cycle: float = 0.5
    voltage_v: float = 1.0
    stress_pa: float = math.nan
    area_m2: float = A201_AREA_M2

    def window(self, t0_s: float, t1_s: float, range_: int) -> Signal:
        """The same :class:`Signal` for every window."""
        return Signal(self.frequency_hz, self.duty_cycle, self.voltage_v, self.stress_pa)

    def force_n(self, t_s) -> np.ndarray:
        """Force on the load cell at times ``t_s`` [s]: stress × area, 0 when the stress is unknown. [N]"""
        f = self.stress_pa * self.area_m2 if math.isfinite(self.stress_pa) else 0.0
        return np.full(np.shape(t_s), f)


@dataclass(frozen=True)
class StressProfile:
    """A periodic stress profile σ(t), like the paper's stepper-motor bench (§6.1).

    Parameters
    ----------
    kind : str
        ``triangle`` (linear load and unload), ``sine`` (raised cosine), ``steps`` (5 stairs up, 5
        down) or ``hold`` (constant ``peak_pa``).
    peak_pa : float
        Largest stress (> base_pa). [Pa]
    period_s : float
        Duration of one loading-unloading cycle (> 0). [s]
    base_pa : float
        Smallest stress (≥ 0). [Pa]
    """

    kind: str = "triangle"
    peak_pa: float = 50e3
    period_s: float = 4.0
    base_pa: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in PROFILE_KINDS:
            raise ParameterError(f"must be one of {', '.join(PROFILE_KINDS)}, got {self.kind!r}", parameter="kind")
        check_positive("period_s", self.period_s, "s", scalar=True)
        check_at_least("base_pa", self.base_pa, 0.0, "Pa", scalar=True)
        check_positive("peak_pa", self.peak_pa, "Pa", scalar=True)
        if not self.peak_pa > self.base_pa >= 0:
            raise ParameterError(f"must exceed base_pa >= 0 Pa, got {self.peak_pa!r} and {self.base_pa!r}",
                                 parameter="peak_pa")

    def stress(self, t_s) -> np.ndarray:
        """Stress at time ``t_s`` [s] since START; returns [Pa], same shape."""
        t = np.asarray(t_s, dtype=float)
        x = np.mod(t / self.period_s, 1.0)
        if self.kind == "triangle":
            u = 1.0 - np.abs(2.0 * x - 1.0)
        elif self.kind == "sine":
            u = 0.5 - 0.5 * np.cos(2.0 * np.pi * x)
        elif self.kind == "steps":
            u = np.minimum(np.floor((1.0 - np.abs(2.0 * x - 1.0)) * 5.0 + 1e-9), 5.0) / 5.0
        else:
            u = np.ones_like(x)
        return self.base_pa + (self.peak_pa - self.base_pa) * u


VIRTUAL_CIRCUIT = PAPER_CIRCUIT.replace(c_off_farad=1e-9)
"""The virtual device's 555: the paper's circuit (:data:`~fsrlab.circuits.circuit.PAPER_CIRCUIT`) with a
1 nF C_off that ``RANGE 1`` switches in."""

#: The most samples of the two periods :class:`PhysicsSource` computes ahead (100 000 per period): a long
#: period is sampled more coarsely than ``dt_s`` instead of taking time and memory in proportion to it
#: (a 50 000 s period every 0.5 s, not 2·10⁷ samples every 5 ms). The sensor's response depends on the
#: stress history, not on its rate, and the profile moves by 10⁻⁵ of a period from one sample to the next. [1]
MAX_SAMPLES = 200_000


def sensor_metadata(sensor) -> dict:
    """What a run's sidecar says about a virtual sensor.

    Parameters
    ----------
    sensor : object
        A virtual sensor with ``respond`` and ``area_m2`` (``VirtualFSR``, a paper sensor).

    Returns
    -------
    dict
        ``model`` (class and module; the VirtualFSR is FlexiForce A201-like), ``name`` (when the
        sensor has one, e.g. ``paper-a201-1``) and ``area_m2`` [m²].
    """
    check_sensor("sensor", sensor)
    cls = type(sensor)
    model = f"{cls.__name__} ({cls.__module__})"
    if cls.__name__ == "VirtualFSR":
        model = "VirtualFSR (FlexiForce A201-like, fsrlab.physics.sensor)"
    name = getattr(sensor, "name", None)
    return {"model": model, **({"name": name} if isinstance(name, str) else {}), "area_m2": float(sensor.area_m2)}


class PhysicsSource:
    """Signal from a stress profile through the virtual FSR, the LM555 astable and the op-amp.

    Parameters
    ----------
    profile : StressProfile
        σ(t).
    sensor : VirtualFSR, optional
        Default ``fsrlab.physics.sensor.VirtualFSR()``.
    circuit : LM555Circuit
        The 555 readout; its C_off is in circuit on ``RANGE 1`` only (:meth:`LM555Circuit.on_range`).
        R_FSR is taken at Vcc/2, the middle of the capacitor's swing.
    opamp : OpAmpReadout
        The traditional readout on A0 (eq. 38), with R_FSR taken at its |Vcc|
        (:attr:`OpAmpReadout.fsr_voltage_v`).
    dt_s : float
        Time step on which the stress history is sampled (at most a twentieth of the period, at least
        ``2·period/``:data:`MAX_SAMPLES`). [s]
    mux : Multiplexer, optional
        The sensor sits behind a multiplexer's switch (:mod:`fsrlab.circuits.mux`): its R_on and node
        capacitance enter the timing network (:attr:`circuit` becomes the 555 with ``R + R_on``, and
        :meth:`parts` gives ``R_FSR + R_on``, ``C_FSR + C_node``); the sidecar keeps the circuit as given.

    Notes
    -----
    The hysteresis memory needs the whole stress history, so R_FSR and C_FSR are computed once for
    two periods of the profile; from the second period on the response repeats (a periodic
    profile reaches its steady loop after the first cycle), and later times map into it.
    """

    def __init__(self, profile: StressProfile | None = None, sensor=None, circuit: LM555Circuit = VIRTUAL_CIRCUIT,
                 opamp: OpAmpReadout = PAPER_OPAMP, dt_s: float = 0.005, mux=None) -> None:
        from fsrlab.circuits.mux import Multiplexer
        from fsrlab.physics.sensor import VirtualFSR

        check_positive("dt_s", dt_s, "s", scalar=True)
        for name, obj, cls in (("circuit", circuit, LM555Circuit), ("opamp", opamp, OpAmpReadout)):
            if not isinstance(obj, cls):
                raise TypeError(f"{name}: must be an {cls.__name__}, got {type(obj).__name__}")
        if profile is not None and not isinstance(profile, StressProfile):
            raise TypeError(f"profile: must be a StressProfile, got {type(profile).__name__}")
        if sensor is not None:
            check_sensor("sensor", sensor)
        if mux is not None and not isinstance(mux, Multiplexer):
            raise TypeError(f"mux: must be a Multiplexer (fsrlab.circuits.mux), got {type(mux).__name__}")
        self.profile = profile or StressProfile()
        self.sensor = sensor if sensor is not None else VirtualFSR()
        self.mux = mux
        self.given_circuit = circuit
        self.circuit = circuit if mux is None else mux.timing_circuit(circuit)
        self.opamp = opamp
        period = self.profile.period_s
        self.dt_s = max(min(dt_s, period / 20), 2 * period / MAX_SAMPLES)
        self._t = np.arange(0.0, 2 * period + self.dt_s, self.dt_s)
        stress = self.profile.stress(self._t)
        resp = self.sensor.respond(stress, voltage_v=circuit.fsr_voltage_v)
        self._stress = np.asarray(resp.stress_pa, dtype=float)
        self._r = np.asarray(resp.r_fsr_ohm, dtype=float)
        self._c = np.asarray(resp.c_fsr_farad, dtype=float)
        if mux is not None:
            from fsrlab.circuits.mux import mux_parts

            self._r, self._c = mux_parts(self._r, self._c, mux)
        r_opamp = self.sensor.respond(stress, voltage_v=opamp.fsr_voltage_v).r_fsr_ohm
        self._v = np.asarray(opamp.output_v(r_opamp), dtype=float)  # Eq. (38)

    def metadata(self) -> dict:
        """Sidecar content of a run recorded from this source: ``circuit``, ``opamp``, ``sensor``."""
        meta = {"circuit": self.given_circuit.to_dict(), "opamp": self.opamp.to_dict(),
                "sensor": sensor_metadata(self.sensor)}
        if self.mux is not None:
            meta["mux"] = self.mux.to_dict()
        return meta

    def force_n(self, t_s) -> np.ndarray:
        """Applied force at times ``t_s`` since START [s]: the profile's stress × the sensor's area. [N]"""
        return self.profile.stress(t_s) * self.sensor.area_m2

    def parts(self, t_s):
        """Sensor state at times ``t_s``: the source's own samples (grid ``k·dt_s``, hysteresis memory
        included) held from one sample to the next (zero-order hold).

        Parameters
        ----------
        t_s : array_like
            Times since the start of the profile (≥ 0). [s]

        Returns
        -------
        r_fsr_ohm : ndarray
            R_FSR at the 555's voltage. [Ω]
        c_fsr_farad : ndarray
            C_FSR. [F]
        a0_v : ndarray
            Op-amp output (eq. 38). [V]
        """
        t = np.asarray(t_s, dtype=float)
        idx = self._index(np.floor(t / self.dt_s + 1e-9) * self.dt_s)  # the grid :meth:`window` samples
        return self._r[idx], self._c[idx], self._v[idx]

    def _index(self, t_s: np.ndarray) -> np.ndarray:
        period = self.profile.period_s
        t = np.where(t_s < 2 * period, t_s, period + np.mod(t_s - period, period))
        return np.clip(np.round(t / self.dt_s).astype(int), 0, self._t.size - 1)

    def window(self, t0_s: float, t1_s: float, range_: int) -> Signal:
        """Mean signal over the window (see :class:`SignalSource`)."""
        n = max(2, int(math.ceil((t1_s - t0_s) / self.dt_s)) + 1)
        idx = self._index(np.linspace(max(t0_s, 0.0), max(t1_s, 0.0), n))
        osc = self.circuit.on_range(range_).astable(self._r[idx], self._c[idx], check=False)
        period = np.asarray(osc.tau_high_s) + np.asarray(osc.tau_low_s)
        if not np.all(np.isfinite(period)):
            f = duty = math.nan
        else:
            # The meter measures whole periods: mean frequency = 1/mean period, duty = ΣτH/ΣT.
            f = 1.0 / float(np.mean(period))
            duty = float(np.mean(osc.tau_high_s) / np.mean(period))
        return Signal(f, duty, float(np.mean(self._v[idx])), float(np.mean(self._stress[idx])))


class MuxSource:
    """Several sensors behind the meter's multiplexer, one :class:`PhysicsSource` per channel.

    Parameters
    ----------
    sources : sequence of PhysicsSource or None
        Channel k's source (built with the same ``mux`` and circuit); None: an open channel (no
        sensor: the 555 gives no edges while it is selected). At most 8.
    reference_channel : int
        The channel whose sensor sits on the load cell and on A0's op-amp readout (the reference is
        single-channel).

    Notes
    -----
    Every sensor follows its own profile whether or not it is selected (its hysteresis memory
    included). :meth:`scaled` builds the usual test bench: channel k under the profile at
    ``peak × (k + 1) / n``.
    """

    def __init__(self, sources, reference_channel: int = 0) -> None:
        from fsrlab.errors import ParameterError

        if isinstance(sources, (str, bytes)) or not hasattr(sources, "__iter__"):
            raise TypeError(f"sources: must be a sequence of PhysicsSource or None, one per channel, got "
                            f"{type(sources).__name__}")
        self.sources = tuple(sources)
        if not all(s is None or isinstance(s, PhysicsSource) for s in self.sources):
            raise TypeError("sources: each channel must be a PhysicsSource or None")
        if isinstance(reference_channel, bool) or not isinstance(reference_channel, int):
            raise TypeError(f"reference_channel: must be an int, got {type(reference_channel).__name__}")
        if not 1 <= len(self.sources) <= 8:
            raise ParameterError(f"1..8 channels, got {len(self.sources)}", parameter="sources")
        live = [s for s in self.sources if s is not None]
        if not live:
            raise ParameterError("at least one channel needs a sensor", parameter="sources")
        if any(s.circuit != live[0].circuit for s in live):
            raise ParameterError("every channel shares the meter's one 555 circuit", parameter="sources")
        if not 0 <= reference_channel < len(self.sources) or self.sources[reference_channel] is None:
            raise ParameterError(f"{reference_channel!r} is not a channel with a sensor",
                                 parameter="reference_channel")
        self.reference_channel = reference_channel
        ref = self.sources[reference_channel]
        self.circuit, self.opamp, self.mux = ref.circuit, ref.opamp, ref.mux
        self.dt_s = min(s.dt_s for s in live)
        self.profile = ref.profile
        self.sensor = ref.sensor

    @classmethod
    def scaled(cls, channels: int, profile: StressProfile | None = None, sensor_factory=None,
               circuit: LM555Circuit = VIRTUAL_CIRCUIT, mux=None, dt_s: float = 0.005) -> MuxSource:
        """``channels`` sensors, channel k under ``profile`` with its peak scaled by (k + 1)/channels.

        Parameters
        ----------
        channels : int
            1..8.
        profile : StressProfile, optional
            The full-scale profile (default ``StressProfile()``).
        sensor_factory : callable, optional
            ``sensor_factory(k)`` → channel k's virtual sensor (default a ``VirtualFSR()`` each).
        circuit : LM555Circuit
            The meter's 555.
        mux : Multiplexer, optional
            Default the CD74HC4051 (:data:`fsrlab.circuits.mux.CD74HC4051`).
        dt_s : float
            Time step of the sensors' stress histories. [s]
        """
        from dataclasses import replace

        from fsrlab.circuits.mux import CD74HC4051
        from fsrlab.errors import ParameterError

        if isinstance(channels, bool) or not isinstance(channels, int) or not 1 <= channels <= 8:
            raise ParameterError(f"must be an integer 1..8, got {channels!r}", parameter="channels")
        profile = profile or StressProfile()
        mux = mux or CD74HC4051
        out = []
        for k in range(channels):
            peak = profile.base_pa + (profile.peak_pa - profile.base_pa) * (k + 1) / channels
            sensor = sensor_factory(k) if sensor_factory is not None else None
            out.append(PhysicsSource(replace(profile, peak_pa=peak), sensor, circuit, dt_s=dt_s, mux=mux))
        return cls(out)

    @property
    def channels(self) -> int:
        """Channels behind the switch (with or without a sensor)."""
        return len(self.sources)

    def channel(self, k: int):
        """Channel k's source, or None when it is open (or beyond the channels wired)."""
        return self.sources[k] if 0 <= k < len(self.sources) else None

    def parts(self, t_s):
        """The reference channel's parts (A0's op-amp readout): see :meth:`PhysicsSource.parts`."""
        return self.sources[self.reference_channel].parts(t_s)

    def force_n(self, t_s) -> np.ndarray:
        """Force on the load cell: the reference channel's. [N]"""
        return self.sources[self.reference_channel].force_n(t_s)

    def window(self, t0_s: float, t1_s: float, range_: int, channel: int | None = None) -> Signal:
        """Channel ``channel``'s signal (default the reference channel); an open channel has no frequency."""
        src = self.channel(self.reference_channel if channel is None else channel)
        if src is None:
            return Signal(math.nan, math.nan, 0.0, math.nan)
        return src.window(t0_s, t1_s, range_)

    def metadata(self) -> dict:
        """The reference channel's sidecar content, ``mux``, and ``channels``: per channel its sensor and profile."""
        meta = self.sources[self.reference_channel].metadata()
        chans = []
        for k, s in enumerate(self.sources):
            entry = {"channel": k, "sensor_id": f"fsr{k}", "open": s is None}
            if s is not None:
                p = s.profile
                entry["sensor"] = sensor_metadata(s.sensor)
                entry["profile"] = {"kind": p.kind, "peak_pa": p.peak_pa, "period_s": p.period_s, "base_pa": p.base_pa}
            chans.append(entry)
        meta["channels"] = chans
        meta["reference_channel"] = self.reference_channel
        return meta
