"""The paper's experiment (§6) on a virtual bench: spring cycles, dead-weight re-placements, Figure 17 fits.

Any sensor with the ``respond(stress_pa, voltage_v)`` interface runs through the paper's two
readouts and fsrlab's meter model (:func:`fsrlab.acquisition.meter.measure`, the Uno's 100 ms
windows and 62.5 ns timer), then through fsrlab's own analysis:

- :func:`spring_cycle`: the stepper-driven spring cycle 0 → 10 kPa → 0 (§6.1; Figure 19a/b), HE of
  both readouts by eq. (13) (:func:`fsrlab.analysis.cycles.run_hysteresis`; Table 3);
- :func:`dead_weights`: five re-placements of a dead weight (§6.2; Tables 4 and 5), RE1/RE2 by
  eq. (39) (:func:`fsrlab.analysis.repeatability.repeatability`); the spread comes from the
  sensor's placement mechanisms and creep (:meth:`fsrlab.physics.paper_sensor.PaperFSR.placement`);
- :func:`figure17_fits`: linear and cubic σ(f) on both branches, on one branch, on the branch means
  (:func:`fsrlab.analysis.calibration.calibrate`);
- :func:`run_experiment`: all of it for a list of sensors, with the paper's printed values beside;
- :func:`preset_targets` and :func:`fit_paper_sensor`: what the "paper sensor" preset was fitted to,
  and the fit (``scripts/fit_paper_sensor.py``).

The 555 is the paper's Fig. 16 circuit as fsrlab has it (:data:`fsrlab.physics.params.PAPER_CIRCUIT`:
D1 ideal, R = 10 kΩ, the FSR alone on range 0 since §6 prints no C_off value), R_FSR taken at
Vcc/2; the op-amp readout is eq. (38) with R_F = 20 kΩ and Vcc = −5 V
(:data:`fsrlab.physics.params.PAPER_OPAMP`), R_FSR taken at 5 V.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §6, Figures 17 and 19, Tables 3–5.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsrlab.circuits.circuit import LM555Circuit, OpAmpReadout
from fsrlab.physics.params import PAPER_CIRCUIT, PAPER_OPAMP
from fsrlab.units import STANDARD_GRAVITY

__all__ = ["SpringCycle", "spring_cycle", "DeadWeights", "dead_weights", "figure17_fits", "Experiment",
           "run_experiment", "preset_targets", "quick_response", "fit_paper_sensor", "fit_paper_preset",
           "fit_placement_spread", "placement_sensitivities", "re2_design", "film_regimes", "SPREAD_FIT_PARAMETERS", "FIT_WEIGHTS", "FIT_PARAMETERS",
           "SHARED_FIT_PARAMETERS", "MASSES_KG"]

#: The dead weights of Tables 4 and 5. [kg]
MASSES_KG = {"200g": 0.2, "400g": 0.4}


@dataclass
class SpringCycle:
    """One sensor's spring cycle(s) through both readouts and the meter.

    Parameters
    ----------
    columns : dict of str to ndarray
        The run's columns (:func:`fsrlab.analysis.synthetic.synthetic_run`).
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
    from fsrlab.analysis.cycles import run_hysteresis
    from fsrlab.analysis.synthetic import synthetic_run

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
        and area factors, and ``respond`` gets ``time_s`` for creep.
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
    from fsrlab.acquisition.meter import measure
    from fsrlab.analysis.repeatability import repeatability
    from fsrlab.physics.paper_sensor import DEAD_WEIGHT_AREA_M2

    if not (np.isfinite(mass_kg) and mass_kg > 0):
        raise ValueError(f"mass_kg must be > 0, got {mass_kg!r}")
    if placements < 2:
        raise ValueError(f"placements must be >= 2, got {placements!r}")
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
        r555 = sensor.respond(stress, voltage_v=circuit.fsr_voltage_v, **kw)
        rop = sensor.respond(stress, voltage_v=opamp.fsr_voltage_v, **kw)
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
        the fits of σ on f by :func:`fsrlab.analysis.calibration.calibrate`. "means": σ against the
        mean of the loading and unloading frequency at each stepper position.
    """
    from fsrlab.analysis.calibration import calibrate

    sl, fl, su, fu = cycle.branches("frequency_hz")
    fu_at = np.interp(sl, su[::-1], fu[::-1]) if su.size > 1 else fl
    sets = {"both": (np.concatenate([fl, fu]), np.concatenate([sl, su])), "loading": (fl, sl),
            "unloading": (fu, su), "means": (0.5 * (fl + fu_at), sl)}
    return {name: {"linear": float(calibrate(x, y, degree=1).r2), "cubic": float(calibrate(x, y, degree=3).r2)}
            for name, (x, y) in sets.items()}


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

#: Weights of the fit residuals (relative residuals for readings, pp/2 for HE).
FIT_WEIGHTS = {"f0": 0.5, "f10": 0.5, "v0": 0.5, "v10": 0.5, "f200": 1.0, "f400": 1.0, "he_tm": 1.0, "he_pm": 1.0}


def preset_targets(i: int) -> dict:
    """The printed numbers sensor ``i`` (1–4) of the preset is fitted to.

    Parameters
    ----------
    i : int
        Sensor number 1–4.

    Returns
    -------
    dict
        ``f0``, ``f10`` [Hz]: Figure 19a's range at 0 and 10 kPa (3 and 10 kHz, read off the axis);
        ``v0``, ``v10`` [V]: Figure 19b's (0.4 and 1 V); ``f200``, ``f400`` [Hz]: Table 4's mean reading
        of the sensor; ``he_tm``, ``he_pm`` [%]: Table 3's row.
    """
    from fsrlab.reference import paper_values

    p = paper_values()
    t3, t4 = p["table3_hysteresis_error_percent"], p["table4_repeatability_capacitive_kHz"]
    return {"f0": 3e3, "f10": 10e3, "v0": 0.4, "v10": 1.0,
            "f200": 1e3 * float(np.mean(t4["200g"]["readings"][i - 1])),
            "f400": 1e3 * float(np.mean(t4["400g"]["readings"][i - 1])),
            "he_tm": float(t3["traditional"][i - 1]), "he_pm": float(t3["proposed"][i - 1])}


def film_regimes(sensor, circuit: LM555Circuit = PAPER_CIRCUIT, opamp: OpAmpReadout = PAPER_OPAMP) -> set:
    """The tunnelling equations (10, 11, 12) the films of ``sensor`` use on the paper's bench.

    Parameters
    ----------
    sensor : PaperFSR
        The sensor.
    circuit, opamp
        The readouts (their voltages across the FSR).

    Returns
    -------
    set of int
        Regimes met over the 0 → 10 kPa → 0 cycle and the dead weights, at both readouts' voltages
        (:func:`fsrlab.physics.tunneling.tunneling_regime` of the per-film voltage u/n). ``{11}`` means
        no state sits on the seams where the paper's piecewise eqs. (10)–(12) jump.
    """
    from fsrlab.physics.paper_sensor import DEAD_WEIGHT_AREA_M2
    from fsrlab.physics.tunneling import tunneling_regime

    up = np.linspace(0.0, 10e3, 21)
    cycle = np.concatenate([up, up[::-1][1:],
                            [m * STANDARD_GRAVITY / DEAD_WEIGHT_AREA_M2 for m in MASSES_KG.values()]])
    out: set = set()
    for v in (circuit.fsr_voltage_v, opamp.fsr_voltage_v):
        u = sensor.respond(cycle, voltage_v=v).film_voltage_v / sensor.layers
        out |= {int(r) for r in np.atleast_1d(tunneling_regime(u, sensor.phi0_j))}
    return out


def quick_response(sensor, points: int = 41, circuit: LM555Circuit = PAPER_CIRCUIT,
                   opamp: OpAmpReadout = PAPER_OPAMP) -> dict:
    """The fitted quantities of a sensor without the meter (closed forms only; the fit's inner loop).

    Parameters
    ----------
    sensor : PaperFSR
        The sensor.
    points : int
        Stress points per ramp of the 0 → 10 kPa → 0 cycle.
    circuit, opamp
        The readouts.

    Returns
    -------
    dict
        Same keys as :func:`preset_targets`; HE by eq. (13) on the two branches at common stresses
        (:func:`fsrlab.analysis.hysteresis.hysteresis_error`).
    """
    from fsrlab.analysis.hysteresis import hysteresis_error
    from fsrlab.physics.paper_sensor import DEAD_WEIGHT_AREA_M2

    up = np.linspace(0.0, 10e3, points)
    stress = np.concatenate([up, up[::-1][1:]])
    r5 = sensor.respond(stress, voltage_v=opamp.fsr_voltage_v)
    r25 = sensor.respond(stress, voltage_v=circuit.fsr_voltage_v)
    f = circuit.astable(r25.r_fsr_ohm, r25.c_fsr_farad, check=False).frequency_hz
    v = opamp.output_v(r5.r_fsr_ohm)
    n = points
    he = {}
    for key, q in (("he_tm", v), ("he_pm", f)):
        he[key] = float(hysteresis_error(up, q[:n], up[::-1], q[n - 1:]).percent)
    out = {"f0": float(f[0]), "f10": float(f[n - 1]), "v0": float(v[0]), "v10": float(v[n - 1]), **he}
    for key, m in (("f200", 0.2), ("f400", 0.4)):
        s = np.array([0.0, m * STANDARD_GRAVITY / DEAD_WEIGHT_AREA_M2])
        rr = sensor.respond(s, voltage_v=circuit.fsr_voltage_v)
        out[key] = float(circuit.astable(rr.r_fsr_ohm[-1], rr.c_fsr_farad[-1], check=False).frequency_hz)
    return out


#: The parameters :func:`fit_paper_sensor` adjusts, with bounds; fitted in log space where marked.
FIT_PARAMETERS = {
    "modulus_pa": (1e5, 1e7, True),
    "k": (1.0, 6.0, False),
    "area_k": (1.0, 40.0, False),
    "area_fraction_0": (1e-6, 1.0, True),
    "area_growth_pa": (5e2, 1e6, True),
    "dielectric_ratio": (1e-2, 1e4, True),
}


def _residuals(got: dict, want: dict) -> np.ndarray:
    res = []
    for key, w in FIT_WEIGHTS.items():
        if key.startswith("he"):
            res.append(w * (got[key] - want[key]) / 2.0)
        else:
            g = got[key]
            res.append(w * (np.log(g / want[key]) if np.isfinite(g) and g > 0 else 10.0))
    return np.array(res)


#: The placement spreads of :class:`~fsrlab.physics.paper_sensor.PaperFSR`, with bounds (log space), shared by
#: the four sensors; :func:`fit_paper_preset` fits them with ``repeatability=True``.
SPREAD_FIT_PARAMETERS = {
    "placement_stress_sd": (1e-4, 0.3, True),
    "placement_contact_sd": (1e-4, 1.0, True),
    "placement_area_sd": (1e-4, 1.0, True),
}
SPREADS = tuple(SPREAD_FIT_PARAMETERS)

#: Parameters shared by the four sensors that :func:`fit_paper_preset` adjusts (same layout as
#: :data:`FIT_PARAMETERS`): the films in series (voltage dependence), the contact and the area's growth law.
#: At least 24 films keep 5 V below φ0/e = 0.223 V per film, inside eq. (11)'s range: the paper's
#: eqs. (10)–(12) do not join (R_A jumps by ≈ 2.4× at u = φ0/e), and a fit left free parks the films
#: on that seam (see :func:`film_regimes`).
SHARED_FIT_PARAMETERS = {
    "layers": (24.0, 400.0, True),
    "contact_ohm": (1e3, 1e7, True),
    "contact_stress_pa": (5e2, 1e5, True),
    "area_exponent": (0.2, 4.0, True),
}


def _codec(names: list, table: dict):
    lo = np.array([np.log(table[n][0]) if table[n][2] else table[n][0] for n in names])
    hi = np.array([np.log(table[n][1]) if table[n][2] else table[n][1] for n in names])

    def enc(sensor):
        return np.array([np.log(getattr(sensor, n)) if table[n][2] else getattr(sensor, n) for n in names])

    def dec(x) -> dict:
        return {n: float(np.exp(v)) if table[n][2] else float(v) for n, v in zip(names, x)}

    return lo, hi, enc, dec


def fit_paper_preset(start=None, max_nfev: int = 300, repeatability: bool = False):
    """Fit the four preset sensors jointly to :func:`preset_targets` (scipy least squares).

    Parameters
    ----------
    start : sequence of PaperFSR, optional
        Starting sensors (default: the stored preset, :func:`fsrlab.physics.paper_sensor.paper_sensors`).
    max_nfev : int
        Largest number of evaluations of the 32 residuals.
    repeatability : bool
        Also fit the three placement spreads (:data:`SPREAD_FIT_PARAMETERS`) to the printed mean RE2
        of Tables 4 and 5 (four more residuals: log ratio of :func:`re2_design`'s prediction).

    Returns
    -------
    (list of PaperFSR, list of dict, list of dict)
        The fitted sensors, their :func:`quick_response` and their targets.

    Notes
    -----
    Residuals per sensor: log ratios of the readings (Figure 19 ranges at weight ½, Table 4 means at
    1) and HE differences in units of 2 pp (Table 3), :data:`FIT_WEIGHTS`; 8 per sensor, 32 in all.
    Adjusted within bounds by ``scipy.optimize.least_squares`` (trust region reflective): the six
    :data:`FIT_PARAMETERS` of each sensor and the four :data:`SHARED_FIT_PARAMETERS` common to the
    four (28 parameters); the rest is :data:`fsrlab.physics.paper_sensor.PAPER_SENSOR_COMMON`.
    """
    from scipy.optimize import least_squares

    from fsrlab.physics.paper_sensor import paper_sensors

    base = list(start) if start is not None else paper_sensors()
    wants = [preset_targets(i) for i in range(1, 5)]
    shared_table = {**SHARED_FIT_PARAMETERS, **(SPREAD_FIT_PARAMETERS if repeatability else {})}
    own, shared = list(FIT_PARAMETERS), list(shared_table)
    lo_o, hi_o, enc_o, dec_o = _codec(own, FIT_PARAMETERS)
    lo_s, hi_s, enc_s, dec_s = _codec(shared, shared_table)
    lo = np.concatenate([lo_s] + [lo_o] * 4)
    hi = np.concatenate([hi_s] + [hi_o] * 4)
    m = len(own)

    def sensors_of(x):
        common = dec_s(x[:len(shared)])
        return [b.replace(**common, **dec_o(x[len(shared) + j * m:len(shared) + (j + 1) * m]))
                for j, b in enumerate(base)]

    def fun(x):
        out = []
        sensors = sensors_of(x)
        for s, want in zip(sensors, wants):
            try:
                # a state on a seam of the piecewise tunnelling equations is not a fit (film_regimes)
                if film_regimes(s) != {11}:
                    raise ValueError("films outside eq. (11)'s range")
                out.append(_residuals(quick_response(s), want))
            except ValueError:
                out.append(np.full(len(FIT_WEIGHTS), 10.0))
        if repeatability:
            try:
                a, printed, _ = re2_design(sensors)
                sd2 = np.array([getattr(sensors[0], n) for n in SPREADS]) ** 2
                out.append(np.log(np.sqrt(a @ sd2) / printed))
            except ValueError:
                out.append(np.full(4, 10.0))
        return np.concatenate(out)

    x0 = np.concatenate([enc_s(base[0])] + [enc_o(b) for b in base])
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    sol = least_squares(fun, x0, bounds=(lo, hi), max_nfev=max_nfev, x_scale="jac")
    best = sensors_of(sol.x)
    return best, [quick_response(s) for s in best], wants


def fit_paper_sensor(i: int, start=None, max_nfev: int = 400):
    """Refit the own parameters of sensor ``i`` alone, the shared ones held (scipy least squares).

    Parameters
    ----------
    i : int
        Sensor number 1–4.
    start : PaperFSR, optional
        Starting point (default: the stored preset sensor).
    max_nfev : int
        Largest number of model evaluations.

    Returns
    -------
    (PaperFSR, dict, dict)
        The fitted sensor, its :func:`quick_response` and the targets.

    Notes
    -----
    The residuals of :func:`fit_paper_preset` for one sensor; only :data:`FIT_PARAMETERS` move.
    """
    from scipy.optimize import least_squares

    from fsrlab.physics.paper_sensor import paper_sensor

    base = start if start is not None else paper_sensor(i)
    want = preset_targets(i)
    names = list(FIT_PARAMETERS)
    lo, hi, enc, dec = _codec(names, FIT_PARAMETERS)

    def fun(x):
        try:
            return _residuals(quick_response(base.replace(**dec(x))), want)
        except ValueError:
            return np.full(len(FIT_WEIGHTS), 10.0)

    x0 = np.clip(enc(base), lo + 1e-9, hi - 1e-9)
    sol = least_squares(fun, x0, bounds=(lo, hi), max_nfev=max_nfev, x_scale="jac")
    best = base.replace(**dec(sol.x))
    return best, quick_response(best), want


def placement_sensitivities(sensor, mass_kg: float, circuit: LM555Circuit = PAPER_CIRCUIT,
                            opamp: OpAmpReadout = PAPER_OPAMP, step: float = 1e-3) -> np.ndarray:
    """d ln(reading)/d ln(factor) of both readouts to a placement's stress and contact factors.

    Parameters
    ----------
    sensor : PaperFSR
        The sensor.
    mass_kg : float
        The dead weight. [kg]
    circuit, opamp
        The readouts.
    step : float
        Relative step of the central differences. [1]

    Returns
    -------
    ndarray, shape (2, 3)
        Rows: frequency, voltage; columns: stress, contact and area factors. [1]
    """
    from fsrlab.physics.paper_sensor import DEAD_WEIGHT_AREA_M2

    s = np.array([0.0, mass_kg * STANDARD_GRAVITY / DEAD_WEIGHT_AREA_M2])

    def readings(**kw):
        r25 = sensor.respond(s, circuit.fsr_voltage_v, **kw)
        r5 = sensor.respond(s, opamp.fsr_voltage_v, **kw)
        f = circuit.astable(r25.r_fsr_ohm[-1], r25.c_fsr_farad[-1], check=False).frequency_hz
        return np.log([f, opamp.output_v(r5.r_fsr_ohm[-1])])

    up, dn = np.exp(step), np.exp(-step)
    cols = [(readings(**{k: up}) - readings(**{k: dn})) / (2 * step)
            for k in ("stress_factor", "contact_factor", "area_factor")]
    return np.column_stack(cols)


def fit_placement_spread(sensors) -> tuple[dict, dict]:
    """The placement spreads (stress, contact, area) from the mean RE2 of Tables 4 and 5 (linearised).

    Parameters
    ----------
    sensors : sequence of PaperFSR
        The sensors, in the order of the tables.

    Returns
    -------
    (dict, dict)
        ``{"placement_stress_sd", "placement_contact_sd", "placement_area_sd"}`` and the predicted and
        printed mean RE2 per table and load.

    Notes
    -----
    For small spreads, ``RE2² ≈ 100²·(a²·sd_σ² + b²·sd_c² + c²·sd_a²)`` with ``a, b, c`` the
    sensitivities of :func:`placement_sensitivities` (averaged in square over the sensors). The three
    spreads are fitted (least squares on the log ratios, each spread within
    :data:`SPREAD_FIT_PARAMETERS`, started from the non-negative least squares on the squares) to
    the printed mean RE2 of Table 4 (frequency) and Table 5 (voltage) at 200 g and 400 g: four
    equations, three unknowns. Creep (a random read time) adds a small term that the fit does not use.
    """
    from scipy.optimize import least_squares, nnls

    a, printed, labels = re2_design(sensors)
    var0, _ = nnls(a, printed**2)
    lo = np.log([SPREAD_FIT_PARAMETERS[n][0] for n in SPREADS])
    hi = np.log([SPREAD_FIT_PARAMETERS[n][1] for n in SPREADS])
    x0 = np.clip(0.5 * np.log(np.maximum(var0, 1e-12)), lo + 1e-9, hi - 1e-9)
    sol = least_squares(lambda x: np.log(np.sqrt(a @ np.exp(2 * x)) / printed), x0, bounds=(lo, hi))
    var = np.exp(2 * sol.x)
    pred = np.sqrt(a @ var)
    return {n: float(np.sqrt(v)) for n, v in zip(SPREADS, var)}, {
        lab: {"printed_re2": float(r), "predicted_re2": float(q)} for lab, r, q in zip(labels, printed, pred)}


def re2_design(sensors) -> tuple[np.ndarray, np.ndarray, list]:
    """The linearised mean RE2 of Tables 4 and 5: ``RE2 ≈ sqrt(A @ sd²)`` per table and load.

    Parameters
    ----------
    sensors : sequence of PaperFSR
        The sensors, in the order of the tables.

    Returns
    -------
    (ndarray, ndarray, list of str)
        ``A`` of shape (4, 3) [%²] (rows: Table 4 at 200 g, 400 g, Table 5 at 200 g, 400 g; columns:
        :data:`SPREADS`), the printed mean RE2 [%] and the rows' labels.

    Notes
    -----
    ``A = 100²·mean over sensors of S²`` with S the sensitivities of :func:`placement_sensitivities`.
    """
    from fsrlab.reference import paper_values

    p = paper_values()
    sens = {m: np.array([placement_sensitivities(s, m) for s in sensors]) for m in MASSES_KG.values()}
    rows, printed, labels = [], [], []
    for t_key, row, name in (("table4_repeatability_capacitive_kHz", 0, "table4"),
                             ("table5_repeatability_traditional_V", 1, "table5")):
        for label, m in MASSES_KG.items():
            rows.append(np.mean(sens[m][:, row, :] ** 2, axis=0) * 1e4)
            printed.append(float(p[t_key][label]["mean_RE2"]))
            labels.append(f"{name} {label}")
    return np.array(rows), np.array(printed), labels
