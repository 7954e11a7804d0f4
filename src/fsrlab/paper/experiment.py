"""The paper's experiment (§6) on a virtual bench: spring cycles, dead-weight re-placements, Figure 17 fits.

Any sensor with the ``respond(stress_pa, voltage_v)`` interface runs through the paper's two
readouts and fsrlab's meter model (:func:`fsrlab.virtual.meter.measure`, the Uno's 100 ms
windows and 62.5 ns timer), then through fsrlab's own analysis:

- :func:`spring_cycle`: the stepper-driven spring cycle 0 → 10 kPa → 0 (§6.1; Figure 19a/b), HE of
  both readouts by eq. (13) (:func:`fsrlab.metrics.cycles.run_hysteresis`; Table 3);
- :func:`dead_weights`: five re-placements of a dead weight (§6.2; Tables 4 and 5), RE1/RE2 by
  eq. (39) (:func:`fsrlab.metrics.repeatability.repeatability`); the spread comes from the
  sensor's placement mechanisms and creep (:meth:`fsrlab.physics.paper_sensor.PaperFSR.placement`);
- :func:`figure17_fits`: linear and cubic σ(f) on both branches, on one branch, on the branch means
  (:func:`fsrlab.paper.polyfit.fit_polynomial`);
- :func:`run_experiment`: all of it for a list of sensors, with the paper's printed values beside;
- what the "paper sensor" preset was fitted to, and the fit: :mod:`fsrlab.paper.preset_fit`.

The 555 is the paper's Fig. 16 circuit as fsrlab has it (:data:`fsrlab.circuits.circuit.PAPER_CIRCUIT`:
D1 ideal, R = 10 kΩ, the FSR alone on range 0 since §6 prints no C_off value), R_FSR taken at
Vcc/2; the op-amp readout is eq. (38) with R_F = 20 kΩ and Vcc = −5 V
(:data:`fsrlab.circuits.circuit.PAPER_OPAMP`), R_FSR taken at 5 V.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §6, Figures 17 and 19, Tables 3–5.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsrlab.circuits.circuit import (
    PAPER_CIRCUIT,
    PAPER_OPAMP,
    LM555Circuit,
    OpAmpReadout,
)
from fsrlab.errors import ParameterError
from fsrlab.units import STANDARD_GRAVITY

__all__ = ["SpringCycle", "spring_cycle", "DeadWeights", "dead_weights", "figure17_fits", "Experiment",
           "run_experiment", "MASSES_KG", "figure17_counterexample"]

#: The dead weights of Tables 4 and 5. [kg]
MASSES_KG = {"200g": 0.2, "400g": 0.4}


@dataclass
class SpringCycle:
    """One sensor's spring cycle(s) through both readouts and the meter.

    Parameters
    ----------
    columns : dict of str to ndarray
        The run's columns (:func:`fsrlab.virtual.synthetic.synthetic_run`).
    he_traditional_percent : float
        HE of the op-amp voltage, eq. (13). [%]
    he_proposed_percent : float
        HE of the 555 frequency, eq. (13). [%]
    """

    columns: dict
    he_traditional_percent: float
    he_proposed_percent: float

    def branches(self, key: str):
        """``(σ_load, q_load, σ_unload, q_unload)`` of column ``key`` (loading: direction ≥ 0)."""
        c = self.columns
        load = c["direction"] >= 0
        return c["stress_pa"][load], c[key][load], c["stress_pa"][~load], c[key][~load]


def spring_cycle(sensor, peak_pa: float = 10e3, cycles: int = 1, points_per_ramp: int = 40,
                 circuit: LM555Circuit = PAPER_CIRCUIT, opamp: OpAmpReadout = PAPER_OPAMP, seed: int = 0,
                 frequency_noise: float = 0.002, voltage_noise_v: float = 0.002) -> SpringCycle:
    """The stepper-driven spring cycle 0 → ``peak_pa`` → 0 (paper §6.1) through both readouts and the meter.

    Parameters
    ----------
    sensor : object
        Anything with ``respond(stress_pa, voltage_v)`` and ``area_m2`` (a
        :class:`~fsrlab.physics.paper_sensor.PaperFSR`, a :class:`~fsrlab.physics.sensor.VirtualFSR`).
    peak_pa : float
        Largest stress (10 kPa in Figure 19). [Pa]
    cycles : int
        Loading–unloading cycles.
    points_per_ramp : int
        Stepper positions per ramp (one 100 ms meter window each).
    circuit : LM555Circuit
        The proposed readout.
    opamp : OpAmpReadout
        The traditional readout.
    seed : int
        Seed of the meter's noise.
    frequency_noise : float
        Relative frequency noise per window. [1]
    voltage_noise_v : float
        Op-amp voltage noise before the 10-bit conversion. [V]

    Returns
    -------
    SpringCycle
    """
    from fsrlab.metrics.cycles import run_hysteresis
    from fsrlab.virtual.synthetic import synthetic_run

    run = synthetic_run(cycles=cycles, peak_pa=peak_pa, points_per_ramp=points_per_ramp, circuit=circuit,
                        opamp=opamp, sensor=sensor, seed=seed, frequency_noise=frequency_noise,
                        voltage_noise_v=voltage_noise_v)
    c = run.columns
    he_v = run_hysteresis(c["stress_pa"], c["voltage_v"], c["direction"], c["cycle"], name="V0").percent
    he_f = run_hysteresis(c["stress_pa"], c["frequency_hz"], c["direction"], c["cycle"], name="f").percent
    return SpringCycle(columns=c, he_traditional_percent=float(he_v), he_proposed_percent=float(he_f))


@dataclass
class DeadWeights:
    """Re-placements of one dead weight on one sensor (paper §6.2).

    Parameters
    ----------
    mass_kg : float
        The dead weight. [kg]
    stress_pa : float
        Its nominal stress. [Pa]
    frequency_khz : ndarray
        The 555 frequency per placement (Table 4's unit). [kHz]
    voltage_v : ndarray
        The op-amp voltage per placement (Table 5). [V]
    re_frequency, re_voltage : RepeatabilityResult
        Eq. (39) of each set (sample standard deviation, as the paper's tables).
    """

    mass_kg: float
    stress_pa: float
    frequency_khz: np.ndarray
    voltage_v: np.ndarray
    re_frequency: object
    re_voltage: object


def dead_weights(sensor, mass_kg: float, placements: int = 5, load_area_m2: float | None = None,
                 read_after_s: tuple = (2.0, 10.0), circuit: LM555Circuit = PAPER_CIRCUIT,
                 opamp: OpAmpReadout = PAPER_OPAMP, seed: int = 0, window_s: float = 0.1) -> DeadWeights:
    """Place a dead weight, read both readouts, lift it; ``placements`` times (paper §6.2).

    Parameters
    ----------
    sensor : object
        A sensor with ``respond``; if it has ``placement(rng)`` (a
        :class:`~fsrlab.physics.paper_sensor.PaperFSR`), each placement draws its stress, contact
        and area factors, and ``respond`` gets ``time_s`` for creep; with ``respond_many``, both
        readouts' responses come from one call.
    mass_kg : float
        The dead weight. [kg]
    placements : int
        Re-placements (5 in the paper).
    load_area_m2 : float, optional
        Area the weight loads (default :data:`fsrlab.physics.paper_sensor.DEAD_WEIGHT_AREA_M2`). [m²]
    read_after_s : (float, float)
        The reading is taken a uniform random time in this range after placing (creep). [s]
    circuit, opamp
        The readouts.
    seed : int
        Seed of the placements and the meter's noise.
    window_s : float
        Meter window of the reading. [s]

    Returns
    -------
    DeadWeights
    """
    from fsrlab.metrics.repeatability import repeatability
    from fsrlab.physics.paper_sensor import DEAD_WEIGHT_AREA_M2
    from fsrlab.virtual.meter import measure

    if not (np.isfinite(mass_kg) and mass_kg > 0):
        raise ParameterError(f"must be > 0, got {mass_kg!r}", parameter="mass_kg")
    if placements < 2:
        raise ParameterError(f"must be >= 2, got {placements!r}", parameter="placements")
    area = DEAD_WEIGHT_AREA_M2 if load_area_m2 is None else float(load_area_m2)
    sigma = mass_kg * STANDARD_GRAVITY / area
    rng = np.random.default_rng(seed)
    f_read, v_read = [], []
    for _ in range(placements):
        t_read = rng.uniform(*read_after_s)
        stress = np.array([0.0, sigma, sigma])
        kw = {}
        if hasattr(sensor, "placement"):
            kw = {"time_s": np.array([0.0, 0.0, t_read]), **sensor.placement(rng)}
        asked = [dict(stress_pa=stress, voltage_v=circuit.fsr_voltage_v, **kw),
                 dict(stress_pa=stress, voltage_v=opamp.fsr_voltage_v, **kw)]
        if hasattr(sensor, "respond_many"):  # both readouts in one solve (PaperFSR)
            r555, rop = sensor.respond_many(asked)
        else:
            r555, rop = (sensor.respond(**a) for a in asked)
        osc = circuit.astable(r555.r_fsr_ohm[-1:], r555.c_fsr_farad[-1:])
        volts = opamp.output_v(rop.r_fsr_ohm[-1:])  # Eq. (38)
        # two windows: the first only opens a period after START, the second is the reading
        meter, _ = measure(np.repeat(osc.frequency_hz, 2), np.repeat(osc.duty_cycle, 2), np.repeat(volts, 2),
                           window_s, rng=rng, frequency_noise=0.002, adc_noise_v=0.002)
        f_read.append(meter.frequency_hz[-1] / 1e3)
        v_read.append(meter.voltage_v[-1])
    f_read, v_read = np.array(f_read), np.array(v_read)
    return DeadWeights(mass_kg=float(mass_kg), stress_pa=float(sigma), frequency_khz=f_read, voltage_v=v_read,
                       re_frequency=repeatability(f_read), re_voltage=repeatability(v_read))


def figure17_fits(cycle: SpringCycle) -> dict:
    """R² of linear and cubic σ(f) fits on both branches, each branch, and the branch means (Figure 17).

    Parameters
    ----------
    cycle : SpringCycle
        A spring cycle.

    Returns
    -------
    dict
        ``{"both": {"linear", "cubic"}, "loading": {...}, "unloading": {...}, "means": {...}}`` of R²,
        the fits of σ on f by :func:`fsrlab.paper.polyfit.fit_polynomial`. "means": σ against the
        mean of the loading and unloading frequency at each stepper position.
    """
    from fsrlab.paper.polyfit import fit_polynomial

    sl, fl, su, fu = cycle.branches("frequency_hz")
    fu_at = np.interp(sl, su[::-1], fu[::-1]) if su.size > 1 else fl
    sets = {"both": (np.concatenate([fl, fu]), np.concatenate([sl, su])), "loading": (fl, sl),
            "unloading": (fu, su), "means": (0.5 * (fl + fu_at), sl)}
    return {name: {"linear": float(fit_polynomial(x, y, 1).r2), "cubic": float(fit_polynomial(x, y, 3).r2)}
            for name, (x, y) in sets.items()}


def figure17_counterexample(he_percent: float = 14.2, width: float = 0.03, points: int = 41) -> dict:
    """A loop with Table 3's hysteresis whose σ(f) fits still reach R² ≈ 0.94 (linear) and ≈ 0.997 (cubic).

    Parameters
    ----------
    he_percent : float
        HE of the frequency, eq. (13) (Table 3's smallest HE_PM is 14.23 %). [%]
    width : float
        Width of the gap along the stress, as a fraction of the range: the gap is
        ``x·exp(−x/width)·(1 − x)``, x = σ/10 kPa, scaled to ``he_percent``. [1]
    points : int
        Stresses per branch.

    Returns
    -------
    dict
        ``he_percent`` (recomputed by eq. 13), ``linear``, ``cubic`` (R² of σ on f over both branches).

    Notes
    -----
    Extension (fsrlab), for erratum X1. The loading branch f = 3 kHz + 7 kHz·√(σ/10 kPa) (3–10 kHz over
    0–10 kPa, as Figure 19a) is steep at low stress, where the gap sits: a large frequency gap there
    is a small stress error. A both-branch fit of a loop with a 14 % HE can therefore reach the printed
    R² values; the virtual sensors' gap, spread over the range, cannot.
    """
    from fsrlab.metrics.hysteresis import hysteresis_error
    from fsrlab.paper.polyfit import fit_polynomial

    x = np.linspace(0.0, 1.0, points)
    s = 10e3 * x
    f_load = 3e3 + 7e3 * np.sqrt(x)
    gap = x * np.exp(-x / width) * (1 - x)
    gap /= gap.max()
    unit = hysteresis_error(s, f_load, s[::-1], (f_load + 1e3 * gap)[::-1]).percent
    f_unload = f_load + 1e3 * gap * he_percent / unit
    he = hysteresis_error(s, f_load, s[::-1], f_unload[::-1]).percent
    f_all, s_all = np.concatenate([f_load, f_unload]), np.concatenate([s, s])
    return {"he_percent": float(he), "linear": float(fit_polynomial(f_all, s_all, 1).r2),
            "cubic": float(fit_polynomial(f_all, s_all, 3).r2), "width": width}


@dataclass
class Experiment:
    """The virtual experiment for a list of sensors.

    Parameters
    ----------
    cycles : list of SpringCycle
        One per sensor.
    weights : dict
        Load label ("200g", "400g") → list of :class:`DeadWeights`, one per sensor.
    fig17 : dict
        :func:`figure17_fits` of the first sensor's cycle.
    """

    cycles: list
    weights: dict = field(default_factory=dict)
    fig17: dict = field(default_factory=dict)

    @property
    def he_traditional(self) -> np.ndarray:
        """HE of the op-amp voltage per sensor (Table 3, traditional). [%]"""
        return np.array([c.he_traditional_percent for c in self.cycles])

    @property
    def he_proposed(self) -> np.ndarray:
        """HE of the 555 frequency per sensor (Table 3, proposed). [%]"""
        return np.array([c.he_proposed_percent for c in self.cycles])


def run_experiment(sensors, seed: int = 0, points_per_ramp: int = 40) -> Experiment:
    """Spring cycles, dead weights (200 g, 400 g, five placements) and Figure 17 fits for ``sensors``.

    Parameters
    ----------
    sensors : sequence
        Sensors (e.g. :func:`fsrlab.physics.paper_sensor.paper_sensors`).
    seed : int
        Base seed (sensor i uses ``seed + i``).
    points_per_ramp : int
        Stepper positions per ramp of the spring cycle.

    Returns
    -------
    Experiment
    """
    sensors = list(sensors)
    cycles = [spring_cycle(s, seed=seed + i, points_per_ramp=points_per_ramp) for i, s in enumerate(sensors)]
    weights = {label: [dead_weights(s, m, seed=seed + 100 * (j + 1) + i) for i, s in enumerate(sensors)]
               for j, (label, m) in enumerate(MASSES_KG.items())}
    return Experiment(cycles=cycles, weights=weights, fig17=figure17_fits(cycles[0]))


# --- what the preset is fitted to, and the fit -------------------------------------------------------
