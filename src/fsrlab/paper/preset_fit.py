"""The "paper sensor" preset: what it was fitted to and the fit (``scripts/fit_paper_sensor.py``, docs/experiment.md).

:func:`preset_targets` gives the paper's printed values one sensor of the preset is fitted to (HE of
both readouts, the readouts at 0 and 10 kPa, the dead weights' readings); :func:`fit_paper_sensor`
and :func:`fit_paper_preset` fit the parameters of :class:`fsrlab.physics.paper_sensor.PaperFSR` to
them through the experiment of :mod:`fsrlab.paper.experiment`; :func:`fit_placement_spread` and
:func:`re2_design` fit the placement spread that gives the repeatability errors RE1/RE2 (eq. 39).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §6, Tables 3–5.
"""

from __future__ import annotations

import numpy as np

from fsrlab.circuits.circuit import PAPER_CIRCUIT, PAPER_OPAMP, LM555Circuit, OpAmpReadout
from fsrlab.paper.experiment import MASSES_KG
from fsrlab.units import STANDARD_GRAVITY

__all__ = ["preset_targets", "TARGET_SOURCES", "fit_target_list", "HELD_PARAMETERS", "quick_response",
           "fit_paper_sensor", "fit_paper_preset", "fit_placement_spread", "placement_sensitivities", "re2_design",
           "re2_design_per_sensor", "film_regimes", "SPREAD_FIT_PARAMETERS", "SPREADS", "FIT_WEIGHTS",
           "FIT_PARAMETERS", "SHARED_FIT_PARAMETERS"]


#: Weights of the fit residuals (relative residuals for readings, pp/2 for HE).
FIT_WEIGHTS = {"f0": 0.5, "f10": 0.5, "v0": 0.5, "v10": 0.5, "f200": 1.0, "f400": 1.0, "he_tm": 1.0, "he_pm": 1.0}


#: Where each key of :func:`preset_targets` comes from: (source, quantity, unit of the value).
TARGET_SOURCES = {
    "f0": ("Figure 19a", "frequency at 0 kPa (lower end of the axis range)", "Hz"),
    "f10": ("Figure 19a", "frequency at 10 kPa (upper end of the axis range)", "Hz"),
    "v0": ("Figure 19b", "op-amp V0 at 0 kPa (lower end of the axis range)", "V"),
    "v10": ("Figure 19b", "op-amp V0 at 10 kPa (upper end of the axis range)", "V"),
    "f200": ("Table 4", "mean of the five 200 g frequency readings", "Hz"),
    "f400": ("Table 4", "mean of the five 400 g frequency readings", "Hz"),
    "he_tm": ("Table 3", "HE of the traditional readout (op-amp V0), eq. (13)", "%"),
    "he_pm": ("Table 3", "HE of the proposed readout (555 frequency), eq. (13)", "%"),
}

#: Values of the preset held in every fit, and how they were chosen (docs/experiment.md).
HELD_PARAMETERS = {
    "layers": "60 films: chosen after the joint fit against the same targets (fit_paper_preset), bounded to "
              "keep each film inside eq. (11)'s range",
    "contact_ohm": "30 kΩ: chosen with the same targets in view (joint fit), then held",
    "contact_stress_pa": "5 kPa: chosen with the same targets in view (joint fit), then held",
    "area_exponent": "1: chosen with the same targets in view (joint fit), then held",
    "dead_weight_area_m2": "392 mm²: set so that 400 g gives 10 kPa, because Table 4's 400 g mean (10.36 kHz) "
                           "sits at the top of Figure 19a (10 kHz at 10 kPa)",
}


def fit_target_list() -> list:
    """Every printed number the preset's fits use, once each: the fit's own list of targets.

    Returns
    -------
    list of dict
        One entry per printed number (or per printed set, for a sensor's five readings): ``id``
        (unique), ``source``, ``quantity``, ``unit``, ``printed`` (the value the fit aims at, in
        ``unit``), ``printed_values`` (the printed numbers behind it), ``key`` (the fit's residual:
        a key of :data:`FIT_WEIGHTS` or a label of :func:`re2_design`), ``sensors`` (the sensors whose
        fit uses it, 1–4) and ``tunes`` (what it sets).

    Notes
    -----
    Built from :data:`FIT_WEIGHTS`, :func:`preset_targets` and :func:`re2_design`'s rows, so the list
    follows the fit. Figure 19's four axis ends are one printed number each, used by all four sensors.
    The dead-weight area and the held shared values (:data:`HELD_PARAMETERS`) were chosen against
    these same numbers; they appear in ``tunes``.
    """
    from fsrlab.reference import paper_values

    p = paper_values()
    held = "held shared values (" + ", ".join(k for k in HELD_PARAMETERS if k != "dead_weight_area_m2") + ")"
    wants = [preset_targets(i) for i in range(1, 5)]
    out = []
    for key in FIT_WEIGHTS:
        source, quantity, unit = TARGET_SOURCES[key]
        if key in ("f0", "f10", "v0", "v10"):
            tunes = [f"own parameters of sensors 1–4 (weight {FIT_WEIGHTS[key]:g})", held]
            if key == "f10":
                tunes.append("dead_weight_area_m2")
            out.append({"id": f"{source.lower().replace(' ', '')}.{key}", "source": source, "quantity": quantity,
                        "unit": unit, "printed": wants[0][key], "printed_values": [wants[0][key]], "key": key,
                        "sensors": [1, 2, 3, 4], "tunes": tunes})
            continue
        for i, want in enumerate(wants, start=1):
            if key in ("f200", "f400"):
                load = f"{key[1:]}g"
                printed_values = p["table4_repeatability_capacitive_kHz"][load]["readings"][i - 1]
                printed_values = [1e3 * float(v) for v in printed_values]
                ident = f"table4.{load}.sensor{i}.mean_reading"
            else:
                side = "traditional" if key == "he_tm" else "proposed"
                printed_values = [float(p["table3_hysteresis_error_percent"][side][i - 1])]
                ident = f"table3.{side}.sensor{i}"
            tunes = [f"own parameters of sensor {i}", held]
            if key == "f400":
                tunes.append("dead_weight_area_m2")
            out.append({"id": ident, "source": source, "quantity": f"{quantity}, sensor {i}", "unit": unit,
                        "printed": want[key], "printed_values": printed_values, "key": key, "sensors": [i],
                        "tunes": tunes})
    for t_key, name in (("table4_repeatability_capacitive_kHz", "table4"),
                        ("table5_repeatability_traditional_V", "table5")):
        for load in MASSES_KG:
            v = float(p[t_key][load]["mean_RE2"])
            out.append({"id": f"{name}.{load}.mean_RE2", "source": name.replace("table", "Table "),
                        "quantity": f"mean RE2 of the four sensors at {load}, eq. (39)", "unit": "%", "printed": v,
                        "printed_values": [v], "key": f"{name} {load}", "sensors": [1, 2, 3, 4],
                        "tunes": list(SPREADS)})
    return out


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
        (:func:`fsrlab.metrics.hysteresis.hysteresis_error`).
    """
    from fsrlab.metrics.hysteresis import hysteresis_error
    from fsrlab.physics.paper_sensor import DEAD_WEIGHT_AREA_M2

    up = np.linspace(0.0, 10e3, points)
    stress = np.concatenate([up, up[::-1][1:]])
    weights = {key: np.array([0.0, m * STANDARD_GRAVITY / DEAD_WEIGHT_AREA_M2])
               for key, m in (("f200", 0.2), ("f400", 0.4))}
    # Both readouts' cycles and the two weights in one contact solve: the numbers of one respond each.
    r5, r25, *placed = sensor.respond_many(
        [dict(stress_pa=stress, voltage_v=opamp.fsr_voltage_v), dict(stress_pa=stress, voltage_v=circuit.fsr_voltage_v),
         *(dict(stress_pa=s, voltage_v=circuit.fsr_voltage_v) for s in weights.values())])
    f = circuit.astable(r25.r_fsr_ohm, r25.c_fsr_farad, check=False).frequency_hz
    v = opamp.output_v(r5.r_fsr_ohm)
    n = points
    he = {}
    for key, q in (("he_tm", v), ("he_pm", f)):
        he[key] = float(hysteresis_error(up, q[:n], up[::-1], q[n - 1:]).percent)
    out = {"f0": float(f[0]), "f10": float(f[n - 1]), "v0": float(v[0]), "v10": float(v[n - 1]), **he}
    for key, rr in zip(weights, placed, strict=True):
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


def _residuals(got: dict, want: dict, weights: dict | None = None) -> np.ndarray:
    res = []
    for key, w in (FIT_WEIGHTS if weights is None else weights).items():
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
        return {n: float(np.exp(v)) if table[n][2] else float(v) for n, v in zip(names, x, strict=True)}

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
        for s, want in zip(sensors, wants, strict=True):
            # a state on a seam of the piecewise tunnelling equations is not a fit (film_regimes)
            fits = False
            try:
                if film_regimes(s) == {11}:
                    out.append(_residuals(quick_response(s), want))
                    fits = True
            except ValueError:  # a state the sensor model refuses
                pass
            if not fits:
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


def fit_paper_sensor(i: int, start=None, max_nfev: int = 400, weights: dict | None = None):
    """Refit the own parameters of sensor ``i`` alone, the shared ones held (scipy least squares).

    Parameters
    ----------
    i : int
        Sensor number 1–4.
    start : PaperFSR, optional
        Starting point (default: the stored preset sensor).
    max_nfev : int
        Largest number of model evaluations.
    weights : dict, optional
        Residual weights by target key (default :data:`FIT_WEIGHTS`); a key left out is not fitted
        (the held-out fit of :mod:`fsrlab.paper.holdout` leaves out Table 4's readings).

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
    weights = FIT_WEIGHTS if weights is None else dict(weights)
    names = list(FIT_PARAMETERS)
    lo, hi, enc, dec = _codec(names, FIT_PARAMETERS)

    def fun(x):
        try:
            return _residuals(quick_response(base.replace(**dec(x))), want, weights)
        except ValueError:
            return np.full(len(weights), 10.0)

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
    up, dn = np.exp(step), np.exp(-step)
    factors = [{k: x} for k in ("stress_factor", "contact_factor", "area_factor") for x in (up, dn)]
    # Every perturbed placement through both readouts in one solve: the numbers of one respond each.
    resp = iter(sensor.respond_many([dict(stress_pa=s, voltage_v=v, **kw) for kw in factors
                                     for v in (circuit.fsr_voltage_v, opamp.fsr_voltage_v)]))

    def readings(r25, r5):
        f = circuit.astable(r25.r_fsr_ohm[-1], r25.c_fsr_farad[-1], check=False).frequency_hz
        return np.log([f, opamp.output_v(r5.r_fsr_ohm[-1])])

    logs = [readings(next(resp), next(resp)) for _ in factors]
    cols = [(logs[2 * j] - logs[2 * j + 1]) / (2 * step) for j in range(3)]
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
    return {n: float(np.sqrt(v)) for n, v in zip(SPREADS, var, strict=True)}, {
        lab: {"printed_re2": float(r), "predicted_re2": float(q)}
        for lab, r, q in zip(labels, printed, pred, strict=True)}


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
    a, printed, labels, _ = re2_design_per_sensor(sensors)
    return a, printed, labels


def re2_design_per_sensor(sensors) -> tuple[np.ndarray, np.ndarray, list, np.ndarray]:
    """:func:`re2_design` and the same design per sensor (one pass over the sensitivities).

    Parameters
    ----------
    sensors : sequence of PaperFSR
        The sensors, in the order of the tables.

    Returns
    -------
    (ndarray, ndarray, list of str, ndarray)
        :func:`re2_design`'s three values and ``A_i`` of shape (4, n_sensors, 3) [%²]: sensor i's
        expected RE2 is ``sqrt(A_i[row, i] @ sd²)``.
    """
    from fsrlab.reference import paper_values

    p = paper_values()
    sens = {m: np.array([placement_sensitivities(s, m) for s in sensors]) for m in MASSES_KG.values()}
    rows, per, printed, labels = [], [], [], []
    for t_key, row, name in (("table4_repeatability_capacitive_kHz", 0, "table4"),
                             ("table5_repeatability_traditional_V", 1, "table5")):
        for label, m in MASSES_KG.items():
            per.append(sens[m][:, row, :] ** 2 * 1e4)
            rows.append(np.mean(sens[m][:, row, :] ** 2, axis=0) * 1e4)
            printed.append(float(p[t_key][label]["mean_RE2"]))
            labels.append(f"{name} {label}")
    return np.array(rows), np.array(printed), labels, np.array(per)
