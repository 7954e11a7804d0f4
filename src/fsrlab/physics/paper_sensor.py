"""A sensor model with the mechanisms the paper names and leaves out, and the fitted "paper sensor" preset.

**Extension beyond the paper.** The paper's §6 explains why its measured hysteresis (Table 3) is
far above its simulated one (Table 2) by mechanisms it does not model: the effective conductive area
A(σ) with its own hysteresis (§6.1 (i), after ref. [31]), the contact resistance R_C in series with
the composite (Fig. 3: ``u = V − R_C·I``), the voltage dependence of the tunnelling resistance (§6.2:
the op-amp readout puts |Vcc| = 5 V across the FSR, the 555 about Vcc/2), and the test bench
(§6.1 (ii)). This module writes each as a pure vectorised function (labelled extension, with its
equation) and assembles them in :class:`PaperFSR`, a sensor with the same ``respond`` interface and
``area_m2`` attribute as :class:`fsrlab.physics.sensor.VirtualFSR`, so that synthetic runs, the
virtual device and the bench accept it unchanged. :func:`paper_sensors` returns the four fitted
sensors (FlexiForce A201-1 like; what was fitted to what: ``docs/experiment.md`` and
``scripts/fit_paper_sensor.py``).

The per-film physics is the paper's: separation s(σ) with memory (eqs. 1 and 9,
:func:`fsrlab.physics.separation.separation_history`), resistance per area by tunnelling
(eqs. 10–12 and 16–18), capacitance per area ε/s (eq. 14).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, Fig. 3, §6.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.electrical import capacitance, resistance_per_area
from fsrlab.physics.params import (
    PAPER,
    check_at_least,
    check_between,
    check_finite,
    check_int,
    check_positive,
    float_array,
)
from fsrlab.physics.sensor import A201_AREA_M2, SensorResponse
from fsrlab.physics.separation import separation_history

__all__ = ["contact_resistance", "series_contact", "memory_stress", "creep_factor", "hold_time",
           "conductive_area", "PaperResponse", "PaperFSR", "PAPER_SENSOR_PARAMETERS", "PAPER_SENSOR_NAMES",
           "paper_sensors", "paper_sensor", "DEAD_WEIGHT_AREA_M2"]

#: Area over which the paper's dead weights (Tables 4 and 5) load the sensor, an assumption: the paper
#: prints no fixture. The 400 g mean reading (10.4 kHz, Table 4) sits at the top of Figure 19a
#: (≈ 10 kHz at 10 kPa), so 400 g·g0 is taken to give 10 kPa: A = 0.4·9.80665/10⁴ m² (a ≈ 22 mm disc). [m²]
DEAD_WEIGHT_AREA_M2 = 0.4 * 9.80665 / 10e3


def contact_resistance(stress_pa, r_c0_ohm: float, sigma_c_pa: float):
    """Contact resistance between electrode and composite, falling with stress (extension).

    Parameters
    ----------
    stress_pa : float or array_like
        Stress, ≥ 0. [Pa]
    r_c0_ohm : float
        Contact resistance at zero stress (≥ 0; 0 removes the contact). [Ω]
    sigma_c_pa : float
        Stress at which it has halved (> 0). [Pa]

    Returns
    -------
    float or ndarray
        R_C(σ) = R_C0 · σ_c/(σ_c + σ). [Ω]

    Notes
    -----
    The paper's Fig. 3 puts R_C in series with the composite and leaves it out of the model; a
    contact resistance that falls as the asperities flatten (``∝ 1/(1 + σ/σ_c)``) is the usual
    first-order form for FSR electrode contacts.
    """
    check_at_least("r_c0_ohm", r_c0_ohm, 0.0, "Ω", scalar=True)
    check_positive("sigma_c_pa", sigma_c_pa, "Pa", scalar=True)
    r = r_c0_ohm * sigma_c_pa / (sigma_c_pa + float_array("stress_pa", stress_pa))
    return float(r) if np.ndim(r) == 0 else r


def series_contact(voltage_v, r_contact_ohm, film_resistance, iterations: int = 60):
    """Voltage u across the composite with a contact resistance in series, solved self-consistently.

    Parameters
    ----------
    voltage_v : float or array_like
        Voltage V across the whole sensor, > 0. [V]
    r_contact_ohm : float or array_like
        Series contact resistance R_C ≥ 0 (broadcast with ``voltage_v``). [Ω]
    film_resistance : callable
        ``film_resistance(u)`` → resistance of the composite at voltage u (same shape as u),
        positive and not increasing in u (tunnelling). [Ω]
    iterations : int
        Bisection steps (60 halve the bracket to ~1e-18 of V; it stops sooner once the bracket is
        two adjacent floats, when further steps could not change it).

    Returns
    -------
    (u, r_total) : tuple of ndarray
        Voltage across the composite [V] and the sensor's resistance ``R_C + R(u)`` seen from
        its terminals [Ω].

    Notes
    -----
    Paper Fig. 3 (extension: the paper names R_C and drops it): the current ``I = u/R(u)`` flows
    through R_C, so ``V = u + R_C·u/R(u)``. The right side increases with u when R(u) does not
    (its derivative is ``1 + R_C(1 + e)/R`` with the elasticity ``e = −d ln R/d ln u ≥ 0``), so the
    root in (0, V] is unique and found by bisection. ``R_C = 0`` gives ``u = V`` exactly (the
    paper's model).
    """
    v = float_array("voltage_v", voltage_v)
    rc = float_array("r_contact_ohm", r_contact_ohm)
    check_positive("voltage_v", v, "V")
    check_at_least("r_contact_ohm", rc, 0.0, "Ω")
    if not callable(film_resistance):
        raise TypeError(f"film_resistance: must be a function of the voltage u, got {type(film_resistance).__name__}")
    iterations = check_int("iterations", iterations, 0)
    try:
        v, rc = np.broadcast_arrays(v, rc)
    except ValueError:
        raise ParameterError(f"shape {rc.shape} does not broadcast with voltage_v's {v.shape}",
                             parameter="r_contact_ohm") from None
    lo = np.zeros(v.shape)
    hi = v.astype(float).copy()
    if np.all(rc == 0):
        u = hi
    else:
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            if np.all((mid == lo) | (mid == hi)):  # a fixed point: the remaining steps change nothing
                break
            g = mid + rc * mid / film_resistance(mid) - v  # Fig. 3: V = u + R_C·I
            up = g > 0
            hi = np.where(up, mid, hi)
            lo = np.where(up, lo, mid)
        u = np.where(rc == 0, v, 0.5 * (lo + hi))
    return u, rc + film_resistance(u)


def memory_stress(stress_pa, k: float):
    """A stress with turning-point memory: σ on loading, above σ on unloading (extension).

    Parameters
    ----------
    stress_pa : array_like
        Stress history in time order, ≥ 0. [Pa]
    k : float
        Unloading exponent, ≥ 1 (1: no memory, the stress itself). [-]

    Returns
    -------
    ndarray
        x(σ) [Pa]: on first loading ``x = σ``; unloading from an upper reversal σU towards the
        lower one σL, ``x = σU − (σU − σL)((σU − σ)/(σU − σL))^k`` (the shape of eq. 9); reloading
        on the straight line back to the last upper reversal; minor loops close (wiping out).

    Notes
    -----
    The same memory rule as the separation (:func:`fsrlab.physics.separation.separation_history`,
    which it calls with a linear loading branch, ``x = M(1 − s/s0)`` for any M above the largest
    stress), with its own exponent: the paper (§6.1 (i)) says the effective conductive area
    "presents also additional hysteresis" at unloading, which it does not model. The branches meet
    at every turning point.
    """
    stress = float_array("stress_pa", stress_pa).ravel()
    check_finite("stress_pa", stress)
    scale = 10.0 * max(float(stress.max(initial=0.0)), 1.0)
    hist = separation_history(stress, s0_m=1.0, modulus_pa=scale, k=k)
    return scale * (1.0 - hist.separation_m)


def creep_factor(hold_s, beta: float, tau_s: float):
    """Logarithmic creep of the effective stress under a held load (extension).

    Parameters
    ----------
    hold_s : float or array_like
        Time since the stress last changed, ≥ 0. [s]
    beta : float
        Creep per e-fold of time, ≥ 0. [1]
    tau_s : float
        Time constant where the logarithm starts, > 0. [s]

    Returns
    -------
    float or ndarray
        ``1 + β·ln(1 + t/τ)`` [1]: the factor on the stress that the composite feels.

    Notes
    -----
    Polymer composites under constant stress keep deforming, logarithmically in time (the FSR
    literature's "drift"; the paper mentions creep of CPCs but models none). The factor grows by
    β·ln 10 per decade for t ≫ τ, the form fsrlab's creep analysis fits
    (:mod:`fsrlab.metrics.creep`, log drift).
    """
    check_at_least("beta", beta, 0.0, scalar=True)
    check_positive("tau_s", tau_s, "s", scalar=True)
    t = float_array("hold_s", hold_s)
    if np.any(t < 0):
        raise ParameterError("must be >= 0 s", parameter="hold_s")
    f = 1.0 + beta * np.log1p(t / tau_s)
    return float(f) if np.ndim(f) == 0 else f


def hold_time(time_s, stress_pa, tolerance_pa: float = 1.0):
    """Time since the stress last changed by more than ``tolerance_pa``.

    Parameters
    ----------
    time_s : array_like
        Sample times, non-decreasing. [s]
    stress_pa : array_like
        Stress at those times. [Pa]
    tolerance_pa : float
        A step smaller than this counts as held. [Pa]

    Returns
    -------
    ndarray
        Hold time at each sample (0 where the stress has just changed). [s]
    """
    t = float_array("time_s", time_s).ravel()
    s = float_array("stress_pa", stress_pa).ravel()
    check_at_least("tolerance_pa", tolerance_pa, 0.0, "Pa", scalar=True)
    if t.shape != s.shape:
        raise ParameterError(f"must have time_s's length ({t.size}), got {s.size}", parameter="stress_pa")
    check_finite("time_s", t)
    if t.size > 1 and np.any(np.diff(t) < 0):
        raise ParameterError("must be non-decreasing", parameter="time_s")
    moved = np.concatenate([[True], np.abs(np.diff(s)) > tolerance_pa])
    start = np.maximum.accumulate(np.where(moved, np.arange(t.size), 0))
    return t - t[start]


def conductive_area(x_pa, area_m2: float, fraction_0: float, growth_pa: float, exponent: float = 1.0):
    """Effective conductive area of the sensor (extension, after the paper's ref. [31]).

    Parameters
    ----------
    x_pa : float or array_like
        Stress the area responds to (with memory, :func:`memory_stress`). [Pa]
    area_m2 : float
        Sensing area A_FSR. [m²]
    fraction_0 : float
        Fraction of A_FSR carrying conductive paths at zero stress, in (0, 1]. [1]
    growth_pa : float
        Stress scale of the growth. [Pa]
    exponent : float
        Power of the growth. [1]

    Returns
    -------
    float or ndarray
        ``A(x) = A_FSR·a0·(1 + x/σ_a)^p``, capped at A_FSR. [m²]
    """
    check_positive("area_m2", area_m2, "m²", scalar=True)
    check_positive("growth_pa", growth_pa, "Pa", scalar=True)
    check_between("fraction_0", fraction_0, 0.0, 1.0, lower_open=True, scalar=True)
    check_finite("exponent", exponent, scalar=True)
    a = np.minimum(area_m2 * fraction_0 * (1.0 + float_array("x_pa", x_pa) / growth_pa) ** exponent, area_m2)
    return float(a) if np.ndim(a) == 0 else a


def _factor(name: str, value, shape: tuple, positive: bool = False) -> np.ndarray:
    """A placement factor of :meth:`PaperFSR.respond`: finite, ≥ 0 (> 0 when ``positive``), one value or one
    per stress sample."""
    x = float_array(name, value)
    check_at_least(name, x, 0.0, strict=positive)
    if x.ndim and x.shape != shape:
        raise ParameterError(f"must be one value or one per stress sample {shape}, got shape {x.shape}",
                             parameter=name)
    return x


@dataclass
class PaperResponse(SensorResponse):
    """:class:`~fsrlab.physics.sensor.SensorResponse` plus the extension's internal state.

    Parameters
    ----------
    stress_pa, separation_m, direction, r_fsr_ohm, c_fsr_farad
        As in :class:`~fsrlab.physics.sensor.SensorResponse`.
    effective_stress_pa : ndarray
        Stress the composite feels (placement factor and creep applied). [Pa]
    area_m2 : ndarray
        Effective conductive area A(σ) with its memory. [m²]
    film_voltage_v : ndarray
        Voltage across the composite after the contact resistance, u = V − R_C·I. [V]
    contact_ohm : ndarray
        Contact resistance R_C(σ). [Ω]
    """

    effective_stress_pa: np.ndarray = None
    area_m2: np.ndarray = None
    film_voltage_v: np.ndarray = None
    contact_ohm: np.ndarray = None


@dataclass(frozen=True)
class PaperFSR:
    """A FlexiForce-like sensor with contact resistance, area hysteresis, voltage dependence and creep (extension).

    Parameters
    ----------
    name : str
        Label (e.g. ``"paper-a201-1"``).
    area_m2 : float
        Sensing area A_FSR (force = stress × area). [m²]
    s0_m : float
        Interparticle separation at zero stress (eq. 1). [m]
    modulus_pa : float
        Effective stiffness M of eq. (1). [Pa]
    k : float
        Unloading exponent of the separation (eq. 9), ≥ 1. [-]
    phi0_j : float
        Barrier height φ0. [J]
    eps_r : float
        Relative permittivity. [-]
    layers : float
        Films in series between the electrodes: each sees u/n (sets the voltage dependence). [-]
    area_fraction_0 : float
        Conductive fraction of A_FSR at zero stress. [1]
    area_growth_pa : float
        Stress scale of the area's growth. [Pa]
    area_exponent : float
        Power of the area's growth. [1]
    area_k : float
        Unloading exponent of the area's memory (:func:`memory_stress`), ≥ 1. [-]
    dielectric_ratio : float
        Capacitive over conductive area (the capacitance spans more than the conductive paths). [1]
    parasitic_farad : float
        Stress-independent capacitance in parallel (leads, fringe field), ≥ 0. [F]
    contact_ohm : float
        Contact resistance R_C0 at zero stress (:func:`contact_resistance`), ≥ 0. [Ω]
    contact_stress_pa : float
        Stress at which R_C has halved. [Pa]
    creep_beta : float
        Creep per e-fold of hold time (:func:`creep_factor`), ≥ 0. [1]
    creep_tau_s : float
        Creep time constant. [s]
    placement_stress_sd : float
        Relative standard deviation of the stress a re-placed dead weight exerts (centring, tilt). [1]
    placement_contact_sd : float
        Standard deviation of ln R_C between placements (electrode contact re-made). [1]
    placement_area_sd : float
        Standard deviation of the log of the effective area between placements (how the weight's face
        meets the sensing area: the conductive paths it closes). [1]

    Notes
    -----
    With memory stress x(σ) (:func:`memory_stress`, exponent ``area_k``), σ_e = σ·f_p·creep(t)
    the stress the composite feels (f_p a placement factor, 1 by default):

    - separation s = s(σ_e) with memory, eqs. (1) and (9);
    - conductive area A = :func:`conductive_area` (x(σ_e));
    - composite resistance ``R_b(u) = n·R_A(u/n, s)/A`` (eqs. 16–18 per film, films in series);
    - contact: ``V = u + R_C(σ_e)·u/R_b(u)`` solved for u (:func:`series_contact`, Fig. 3) and
      ``R_FSR = R_C + R_b(u)``;
    - ``C_FSR = ε_r ε0·(d·A)/(n s) + C_p`` (eq. 14 over n films, capacitive area d·A).

    The area multiplies both conductance and capacitance (§5 (i) of the paper), so its hysteresis
    cancels in the 555's R_FSR·C_FSR product (up to C_p and R_C) and stays whole in the op-amp's
    conductance: the mechanism behind Table 3's lower HE for the proposed readout.
    """

    name: str = "paper-fsr"
    area_m2: float = A201_AREA_M2
    s0_m: float = 5.0e-9
    modulus_pa: float = 2.0e5
    k: float = 1.5
    phi0_j: float = PAPER.phi0_j
    eps_r: float = PAPER.eps_r
    layers: float = 60.0
    area_fraction_0: float = 0.02
    area_growth_pa: float = 2e4
    area_exponent: float = 1.0
    area_k: float = 1.5
    dielectric_ratio: float = 4.0
    parasitic_farad: float = 0.0
    contact_ohm: float = 0.0
    contact_stress_pa: float = 5e3
    creep_beta: float = 0.0
    creep_tau_s: float = 1.0
    placement_stress_sd: float = 0.0
    placement_contact_sd: float = 0.0
    placement_area_sd: float = 0.0

    def __post_init__(self) -> None:
        for name in ("area_m2", "s0_m", "modulus_pa", "phi0_j", "eps_r", "layers", "area_fraction_0",
                     "area_growth_pa", "area_exponent", "dielectric_ratio", "contact_stress_pa", "creep_tau_s"):
            check_positive(name, getattr(self, name), scalar=True)
        for name in ("parasitic_farad", "contact_ohm", "creep_beta", "placement_stress_sd", "placement_contact_sd",
                     "placement_area_sd"):
            check_at_least(name, getattr(self, name), 0.0, scalar=True)
        for name in ("k", "area_k"):
            check_at_least(name, getattr(self, name), 1.0, scalar=True)
        check_between("area_fraction_0", self.area_fraction_0, 0.0, 1.0, lower_open=True, scalar=True)

    def replace(self, **changes) -> PaperFSR:
        """A copy with some parameters changed (validated again)."""
        return replace(self, **changes)

    def film_resistance(self, u_v, s_m, area_m2, validate: bool = True):
        """Composite resistance ``n·R_A(u/n, s)/A`` (eqs. 16–18 per film, n films in series). [Ω]

        Parameters
        ----------
        u_v : array_like
            Voltage across the composite. [V]
        s_m : array_like
            Separation. [m]
        area_m2 : array_like
            Conductive area. [m²]
        validate : bool
            False skips the checks of u and s (:func:`fsrlab.physics.electrical.resistance_per_area`):
            :meth:`respond` checks the separation once and calls this in its root finder's loop.
        """
        n = self.layers
        u = float_array("u_v", u_v)
        if validate:
            check_positive("area_m2", area_m2, "m²")
        return n * np.asarray(resistance_per_area(u / n, s_m, self.phi0_j, validate=validate)) / area_m2

    def respond(self, stress_pa, voltage_v: float = 2.5, time_s=None, stress_factor=1.0,
                contact_factor=1.0, area_factor=1.0) -> PaperResponse:
        """Electrical response along a stress history.

        Parameters
        ----------
        stress_pa : array_like
            Stress samples in time order, ≥ 0. [Pa]
        voltage_v : float
            Voltage across the sensor's terminals (LM555: ≈ Vcc/2; op-amp readout: |Vcc|). [V]
        time_s : array_like, optional
            Sample times [s]; given, the stress creeps while held (:func:`hold_time`,
            :func:`creep_factor`). Without it, no creep (a quasi-static history).
        stress_factor : float or array_like
            Factor on the stress the composite feels (a placement's centring; 1: none). [1]
        contact_factor : float or array_like
            Factor on the contact resistance (a placement's electrode contact; 1: none). [1]
        area_factor : float or array_like
            Factor on the effective area, conductive and capacitive alike (a placement's face; 1: none). [1]

        Returns
        -------
        PaperResponse
        """
        return self.respond_many([dict(stress_pa=stress_pa, voltage_v=voltage_v, time_s=time_s,
                                       stress_factor=stress_factor, contact_factor=contact_factor,
                                       area_factor=area_factor)])[0]

    def respond_many(self, requests) -> list:
        """:meth:`respond` for several requests at once, with one contact solve (Fig. 3) for all of them.

        Parameters
        ----------
        requests : iterable of dict
            Keyword arguments of :meth:`respond`, one dict per response (``stress_pa`` in each).

        Returns
        -------
        list of PaperResponse
            One per request, in order, with the numbers :meth:`respond` gives for each: the contact solve
            (:func:`series_contact`) goes element by element, so solving the requests together only
            shares its bisection steps (the readouts' two voltages, a placement's perturbations).
        """
        if isinstance(requests, (str, bytes)) or not isinstance(requests, Iterable):
            raise TypeError("requests: must be an iterable of dicts (respond's arguments), got "
                    f"{type(requests).__name__}")
        requests = list(requests)
        if not all(isinstance(req, Mapping) for req in requests):
            raise TypeError("requests: every request must be a dict of respond's arguments")
        states = [self._state(**req) for req in requests]
        if not states:
            return []
        s, area, rc, v = (np.concatenate([np.ravel(st[key]) for st in states]) for key in ("s", "area", "rc", "v"))
        check_positive("s_m", s, "m")  # once: the root finder's u stays in (0, V]
        u, r = series_contact(v, rc, lambda uu: self.film_resistance(uu, s, area, validate=False))  # Fig. 3
        out, start = [], 0
        for st in states:
            stop = start + st["eff"].size
            out.append(self._response(st, u[start:stop], r[start:stop]))
            start = stop
        return out

    def _state(self, stress_pa, voltage_v: float = 2.5, time_s=None, stress_factor=1.0, contact_factor=1.0,
               area_factor=1.0) -> dict:
        """:meth:`respond` up to the contact solve: the checked inputs, separation, area and contact."""
        check_positive("voltage_v", voltage_v, "V", scalar=True)
        sigma = float_array("stress_pa", stress_pa).ravel()
        check_at_least("stress_pa", sigma, 0.0, "Pa")
        eff = sigma * _factor("stress_factor", stress_factor, sigma.shape)
        if time_s is not None:
            eff = eff * creep_factor(hold_time(time_s, sigma), self.creep_beta, self.creep_tau_s)
        if eff.size and eff.max() >= self.modulus_pa:
            raise ParameterError(f"must stay below modulus_pa = {self.modulus_pa:g} Pa", parameter="stress_pa")
        hist = separation_history(eff, s0_m=self.s0_m, modulus_pa=self.modulus_pa, k=self.k)  # Eqs. (1), (9)
        s = hist.separation_m
        area = conductive_area(memory_stress(eff, self.area_k), self.area_m2, self.area_fraction_0,
                               self.area_growth_pa, self.area_exponent) * _factor("area_factor", area_factor,
                                                                                  eff.shape, positive=True)
        area = np.broadcast_to(area, eff.shape)
        rc = contact_resistance(eff, self.contact_ohm, self.contact_stress_pa) * _factor("contact_factor",
                                                                                        contact_factor, eff.shape)
        rc = np.broadcast_to(rc, eff.shape)
        return {"sigma": sigma, "eff": eff, "hist": hist, "s": s, "area": area, "rc": rc,
                "v": np.full(eff.shape, float(voltage_v))}

    def _response(self, st: dict, u, r) -> PaperResponse:
        s, area = st["s"], st["area"]
        c = capacitance(self.layers * s, self.dielectric_ratio * area, self.eps_r) + self.parasitic_farad  # Eq. (14)
        return PaperResponse(stress_pa=st["sigma"], separation_m=s, direction=st["hist"].direction,
                             r_fsr_ohm=np.asarray(r, dtype=float), c_fsr_farad=np.asarray(c, dtype=float),
                             effective_stress_pa=st["eff"], area_m2=np.asarray(area, dtype=float),
                             film_voltage_v=np.asarray(u, dtype=float), contact_ohm=np.asarray(st["rc"], dtype=float))

    def force_to_stress(self, force_n):
        """Stress σ = F / A_FSR for force ``force_n`` [N]; returns [Pa]."""
        return float_array("force_n", force_n) / self.area_m2

    @property
    def load_area_m2(self) -> float:
        """Area over which the bench's weights load this sensor (:data:`DEAD_WEIGHT_AREA_M2`, an
        assumption: the paper prints no fixture); the virtual bench spreads a placed mass's force over
        it. [m²]"""
        return DEAD_WEIGHT_AREA_M2

    def placement(self, rng) -> dict:
        """One dead-weight placement: the factors it applies, drawn from ``rng``.

        Parameters
        ----------
        rng : numpy.random.Generator
            Three standard normal draws.

        Returns
        -------
        dict
            Keyword arguments of :meth:`respond`: ``stress_factor`` = 1 + sd_σ·z1,
            ``contact_factor`` = exp(sd_c·z2), ``area_factor`` = exp(sd_a·z3).

        Notes
        -----
        Extension. Re-placing a weight changes how it meets the sensor: the stress it exerts
        (centring, tilt), the electrode contact, and the part of the sensing area whose conductive
        paths it closes. The area enters R_FSR and C_FSR alike, so it cancels in the 555's R·C and
        stays whole in the op-amp's conductance (as the area's hysteresis does, Table 3).
        """
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"rng: must be a numpy.random.Generator (numpy.random.default_rng(seed)), "
                            f"got {type(rng).__name__}")
        z = rng.standard_normal(3)
        return {"stress_factor": 1.0 + self.placement_stress_sd * float(z[0]),
                "contact_factor": float(np.exp(self.placement_contact_sd * z[1])),
                "area_factor": float(np.exp(self.placement_area_sd * z[2]))}


#: Parameters shared by the four paper sensors (not fitted; see docs/experiment.md). The separation
#: s0 and the films in series n set the resistance level and its voltage dependence together with φ0.
PAPER_SENSOR_COMMON: dict = {
    "s0_m": 5.0e-9,
    "parasitic_farad": 20e-12,
    "creep_beta": 0.004,
    "creep_tau_s": 1.0,
}

#: Fitted parameters of the four paper sensors, printed by scripts/fit_paper_sensor.py: per sensor the six
#: own parameters (fsrlab.paper.preset_fit.fit_paper_sensor, shared ones held: n = 60 films, so 5 V is
#: 0.083 V per film, inside eq. (11)'s range; R_C0 = 30 kΩ, σ_c = 5 kPa, p = 1), then the three shared
#: placement spreads (fit_placement_spread). area_k (25–30) is ill-determined: the area's memory saturates.
PAPER_SENSOR_PARAMETERS: tuple = (
    {"layers": 60.0, "contact_ohm": 30000.0, "contact_stress_pa": 5000.0, "area_exponent": 1.0,
     "modulus_pa": 239433.9041489569, "k": 2.325537181206501, "area_k": 25.207601813231143,
     "area_fraction_0": 0.022227145154504285, "area_growth_pa": 67132.63480911237,
     "dielectric_ratio": 2.1498174240328027, "placement_stress_sd": 0.00010000000000000026,
     "placement_contact_sd": 0.05545153580258893, "placement_area_sd": 0.05389532144854428},
    {"layers": 60.0, "contact_ohm": 30000.0, "contact_stress_pa": 5000.0, "area_exponent": 1.0,
     "modulus_pa": 245351.70477575826, "k": 2.2705699749860715, "area_k": 29.97499026245073,
     "area_fraction_0": 0.019822254443902343, "area_growth_pa": 22733.111754155692,
     "dielectric_ratio": 2.3133001375390885, "placement_stress_sd": 0.00010000000000000026,
     "placement_contact_sd": 0.05545153580258893, "placement_area_sd": 0.05389532144854428},
    {"layers": 60.0, "contact_ohm": 30000.0, "contact_stress_pa": 5000.0, "area_exponent": 1.0,
     "modulus_pa": 228526.99080902553, "k": 2.2213051493357776, "area_k": 25.206811696277853,
     "area_fraction_0": 0.020571499387966093, "area_growth_pa": 38154.15528958332,
     "dielectric_ratio": 2.189306084223522, "placement_stress_sd": 0.00010000000000000026,
     "placement_contact_sd": 0.05545153580258893, "placement_area_sd": 0.05389532144854428},
    {"layers": 60.0, "contact_ohm": 30000.0, "contact_stress_pa": 5000.0, "area_exponent": 1.0,
     "modulus_pa": 233585.99730698363, "k": 2.8660768830424055, "area_k": 29.795413587965577,
     "area_fraction_0": 0.018777574457736954, "area_growth_pa": 20688.28500217303,
     "dielectric_ratio": 2.5852426717259194, "placement_stress_sd": 0.00010000000000000026,
     "placement_contact_sd": 0.05545153580258893, "placement_area_sd": 0.05389532144854428},
)

#: Preset names, in the order of the paper's sensors 1–4 (Table 3).
PAPER_SENSOR_NAMES: tuple = tuple(f"paper-a201-{i}" for i in range(1, 5))


def paper_sensor(which) -> PaperFSR:
    """One of the four fitted paper sensors.

    Parameters
    ----------
    which : int or str
        1–4 (the paper's sensor number) or a name of :data:`PAPER_SENSOR_NAMES`.

    Returns
    -------
    PaperFSR
    """
    if isinstance(which, str):
        key = which.strip().lower()
        if key not in PAPER_SENSOR_NAMES:
            raise ParameterError(f"must be 1-4 or one of {', '.join(PAPER_SENSOR_NAMES)}, got {which!r}",
                                 parameter="which")
        i = PAPER_SENSOR_NAMES.index(key) + 1
    else:
        i = check_int("which", which)
        if not 1 <= i <= 4:
            raise ParameterError(f"must be 1-4 or one of {', '.join(PAPER_SENSOR_NAMES)}, got {which!r}",
                                 parameter="which")
    return PaperFSR(name=PAPER_SENSOR_NAMES[i - 1], **PAPER_SENSOR_COMMON, **PAPER_SENSOR_PARAMETERS[i - 1])


def paper_sensors() -> list[PaperFSR]:
    """The four fitted paper sensors, sensors 1–4 of Tables 3–5.

    Fitted over the paper's range, 0–10 kPa at 2.5 V and 5 V: use them on the paper's bench; beyond
    10 kPa R_FSR falls fast (sensor 1 at 2.5 V: ≈ 43 kΩ at 20 kPa, ≈ 7 kΩ at 40 kPa, where the
    paper's 555 with R = 10 kΩ no longer oscillates).

    Returns
    -------
    list of PaperFSR
    """
    return [paper_sensor(i) for i in range(1, 5)]
