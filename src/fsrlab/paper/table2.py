"""The paper's Table 2: hysteresis error of R_A and C_A over one model cycle, and the barrier height
that reproduces its printed R_A column.

Table 2 prints the hysteresis error (eq. 13) of the resistance per unit area (eqs. 16–18) and of
the capacitance per unit area (eq. 15) over one cycle 0 → σf → 0 of the separation model (eqs. 1
and 9) at u = 3, 2, 1 V, with Table 1's parameters. With those parameters fsrlab does not reproduce
the R_A column; a barrier height of about 0.2295 eV instead of the printed 0.223 eV does
(docs/errata.md, P1). :func:`cycle_error_table` computes the table, :func:`fit_barrier_height` finds
that barrier height. :func:`voltage_sweep` (extension) follows both errors over u and finds where the
paper's "in all cases" capacitance-below-resistance statement fails (docs/errata.md, P4), and
:func:`current_maximum_voltage` the voltage where eq. (12) stops falling with film thickness.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eqs. (1), (9), (13), (15)–(18),
Tables 1 and 2.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.constants import e, electron_volt, h, m_e
from scipy.optimize import brentq, minimize_scalar

from fsrlab.errors import ParameterError
from fsrlab.metrics.hysteresis import model_cycle_errors
from fsrlab.physics.params import PAPER, PaperParameters, check_positive
from fsrlab.physics.separation import separation_loading
from fsrlab.physics.tunneling import voltage_limit

__all__ = ["simmons_terms", "CycleErrorTable", "cycle_error_table", "BarrierHeightFit", "fit_barrier_height",
           "current_maximum_voltage", "VoltageSweep", "voltage_sweep"]


@dataclass(frozen=True)
class CycleErrorTable:
    """Hysteresis errors of R_A and C_A at several voltages (the layout of the paper's Table 2).

    Parameters
    ----------
    u_v : tuple of float
        Voltages across the composite, in the order given. [V]
    resistance_percent : tuple of float
        HE of R_A (eq. 13 on eqs. 16–18) at each voltage. [%]
    capacitance_percent : tuple of float
        HE of C_A (eq. 13 on eq. 15) at each voltage. [%]
    resistance_stress_at_max_pa : tuple of float
        σd of R_A, the stress of the largest branch difference. [Pa]
    capacitance_stress_at_max_pa : tuple of float
        σd of C_A. [Pa]
    tunneling_equation : tuple of int
        The equation (10, 11 or 12) that gave the current density at each voltage.
    params : PaperParameters
        The parameters used.
    """

    u_v: tuple
    resistance_percent: tuple
    capacitance_percent: tuple
    resistance_stress_at_max_pa: tuple
    capacitance_stress_at_max_pa: tuple
    tunneling_equation: tuple
    params: PaperParameters

    def to_dict(self) -> dict:
        """The columns as lists, keyed as in the report's ``paper.json`` (``table2``)."""
        return {
            "u_V": list(self.u_v),
            "resistance_per_area_percent": list(self.resistance_percent),
            "capacitance_per_area_percent": list(self.capacitance_percent),
            "resistance_stress_at_max_Pa": list(self.resistance_stress_at_max_pa),
            "capacitance_stress_at_max_Pa": list(self.capacitance_stress_at_max_pa),
            "tunneling_equation": list(self.tunneling_equation),
        }


def cycle_error_table(u_v: Sequence[float] = (3, 2, 1), params: PaperParameters = PAPER) -> CycleErrorTable:
    """HE of R_A and C_A over one cycle 0 → σf → 0 at each voltage, as in the paper's Table 2.

    Parameters
    ----------
    u_v : sequence of float
        Voltages across the composite, each > 0 (default: Table 2's 3, 2, 1 V). [V]
    params : PaperParameters
        Material and cycle parameters (default: Table 1 with k = 2).

    Returns
    -------
    CycleErrorTable

    Notes
    -----
    Each row is :func:`fsrlab.metrics.hysteresis.model_cycle_errors`: loading by eq. (1),
    unloading by eq. (9), R_A by eqs. (16)–(18) (the tunnelling regime the voltage selects), C_A by
    eq. (15), HE by eq. (13) with σd refined by a bounded search.
    """
    rows = [model_cycle_errors(u, params) for u in u_v]
    return CycleErrorTable(
        u_v=tuple(u_v),
        resistance_percent=tuple(r.resistance.percent for r in rows),
        capacitance_percent=tuple(r.capacitance.percent for r in rows),
        resistance_stress_at_max_pa=tuple(r.resistance.stress_at_max_pa for r in rows),
        capacitance_stress_at_max_pa=tuple(r.capacitance.stress_at_max_pa for r in rows),
        tunneling_equation=tuple(r.regime for r in rows),
        params=params,
    )


@dataclass(frozen=True)
class BarrierHeightFit:
    """Barrier height whose Table 2 R_A column is closest to a target column.

    Parameters
    ----------
    phi0_ev : float
        The fitted barrier height φ0. [eV]
    table : CycleErrorTable
        Table 2 recomputed with that barrier height (other parameters unchanged).
    """

    phi0_ev: float
    table: CycleErrorTable


def _with_phi0(params: PaperParameters, phi0_ev: float) -> PaperParameters:
    return dataclasses.replace(params, phi0_j=phi0_ev * electron_volt)


def fit_barrier_height(target_percent: Sequence[float], u_v: Sequence[float] = (3, 2, 1),
                       params: PaperParameters = PAPER, bounds_ev: tuple[float, float] = (0.225, 0.235),
                       xatol_ev: float = 1e-6) -> BarrierHeightFit:
    """The barrier height φ0 that brings the HE of R_A closest to ``target_percent`` (least squares).

    Parameters
    ----------
    target_percent : sequence of float
        HE of R_A to reproduce at each voltage, e.g. the paper's printed Table 2 column. [%]
    u_v : sequence of float
        The voltages of ``target_percent`` (default: Table 2's 3, 2, 1 V). [V]
    params : PaperParameters
        All other parameters (default: Table 1 with k = 2); its ``phi0_j`` is replaced.
    bounds_ev : (float, float)
        Search interval for φ0. The default brackets the single minimum for Table 2's printed
        column (the printed 0.223 eV lies below it, see docs/errata.md, P1). [eV]
    xatol_ev : float
        Absolute tolerance of φ0. [eV]

    Returns
    -------
    BarrierHeightFit

    Raises
    ------
    ValueError
        If ``target_percent`` and ``u_v`` differ in length, or the bounds are not 0 < low < high.

    Notes
    -----
    Minimises ``Σ (HE_R(φ0, u) − target(u))²`` over φ0 with a bounded scalar search; HE by
    eq. (13) on R_A from eqs. (16)–(18), as in :func:`cycle_error_table`. C_A does not depend on
    φ0 (eq. 15), so the fit leaves the capacitance column unchanged.
    """
    target = np.asarray(target_percent, dtype=float)
    if target.shape != (len(u_v),):
        raise ParameterError(f"must have one value per voltage ({len(u_v)}), got {target.shape}",
                             parameter="target_percent")
    lo, hi = bounds_ev
    check_positive("bounds_ev", lo, "eV")
    if not hi > lo:
        raise ParameterError(f"must be (low, high) with high > low, got {bounds_ev!r}", parameter="bounds_ev")

    def cost(phi0_ev: float) -> float:
        he = cycle_error_table(u_v, _with_phi0(params, phi0_ev)).resistance_percent
        return float(np.sum((np.array(he) - target) ** 2))

    phi0 = float(minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": xatol_ev}).x)
    return BarrierHeightFit(phi0_ev=phi0, table=cycle_error_table(u_v, _with_phi0(params, phi0)))


def current_maximum_voltage(s_m: float, phi0_j: float = PAPER.phi0_j) -> float:
    """The voltage above which eq. (12)'s J grows with the film thickness at separation ``s_m``.

    Parameters
    ----------
    s_m : float
        Interparticle separation s, > 0. [m]
    phi0_j : float
        Barrier height φ0. [J]

    Returns
    -------
    float
        u* with ∂J/∂s = 0 at ``s_m`` (eq. 12): below u*, J falls as s grows (a thicker barrier
        passes less current), above it J rises with s up to :func:`fsrlab.physics.tunneling.voltage_limit`,
        where eq. (12)'s bracket reaches 0. [V]

    Notes
    -----
    Extension (fsrlab), on eq. (12): ``ln J = const − 2 ln s + ln(exp(−B) − r exp(−B√r))`` with
    ``B = βs`` ∝ s and ``r = 1 + 2eu/φ0``, so ``s ∂ln J/∂s = 0`` where
    ``B (r^(3/2) g − 1) = 2 (1 − r g)``, ``g = exp(−B(√r − 1))``. The left minus the right side is
    negative at u just above φ0/e and positive just below the voltage limit; the root is found by
    Brent's method. For Table 1 (φ0 = 0.223 eV) u* = 3.079 V at s_f = 4.117 nm (σ = σf) and
    3.413 V at s0 = 4.418 nm: between the two, R_A = u/J is not monotonic over the stress cycle.
    """
    check_positive("s_m", s_m, "m")
    check_positive("phi0_j", phi0_j, "J")
    beta = 8 * math.pi * s_m * math.sqrt(2 * m_e) * phi0_j**1.5 / (2.96 * h * e)  # B·u

    def side(u: float) -> float:
        b, r = beta / u, 1 + 2 * e * u / phi0_j
        g = math.exp(-b * (math.sqrt(r) - 1))
        return b * (r**1.5 * g - 1) - 2 * (1 - r * g)

    lo, hi = phi0_j / e * (1 + 1e-9), float(voltage_limit(s_m, phi0_j)) * (1 - 1e-12)
    return float(brentq(side, lo, hi, xtol=1e-12, rtol=1e-12))


def simmons_terms(u_v, s_m, phi0_j: float = PAPER.phi0_j):
    """Eq. (12)'s exponent B and the ratio of its reverse to its forward term.

    Parameters
    ----------
    u_v : float or array_like
        Voltage across the film, > φ0/e. [V]
    s_m : float or array_like
        Interparticle separation. [m]
    phi0_j : float
        Barrier height φ0. [J]

    Returns
    -------
    (ndarray, ndarray)
        ``B = 8π s √(2m) φ0^(3/2) / (2.96 h e u)`` [1] and ``r·exp(−B√r)/exp(−B)`` with
        ``r = 1 + 2eu/φ0`` [1].

    Notes
    -----
    Extension (fsrlab), for erratum P4. Simmons' high-voltage formula is the large-B limit: the
    forward term exp(−B) dominates when B ≫ 1. With B ≈ 1 the reverse term is comparable to the
    forward one and the formula is at the edge of its range.
    """
    u = np.asarray(u_v, dtype=float)
    s = np.asarray(s_m, dtype=float)
    b = 8 * math.pi * s * math.sqrt(2 * m_e) * phi0_j**1.5 / (2.96 * h * e * u)  # Eq. (12)
    r = 1 + 2 * e * u / phi0_j
    return b, r * np.exp(-b * (np.sqrt(r) - 1))


@dataclass(frozen=True)
class VoltageSweep:
    """HE of R_A and C_A over a range of voltages (extension of Table 2), with where they cross.

    Parameters
    ----------
    table : CycleErrorTable
        Both errors at each voltage of the sweep.
    crossings_v : tuple of float
        Voltages where HE(R_A) = HE(C_A), refined between the sweep's points; between the first two,
        capacitance shows *more* hysteresis than resistance. [V]
    minimum_v : float
        Voltage of the smallest HE(R_A) of the sweep, refined. [V]
    minimum_percent : float
        That smallest HE(R_A). [%]
    current_maximum_v : (float, float)
        :func:`current_maximum_voltage` at the cycle's thinnest (σf) and thickest (σ = 0) separation. [V]
    """

    table: CycleErrorTable
    crossings_v: tuple
    minimum_v: float
    minimum_percent: float
    current_maximum_v: tuple

    def to_dict(self) -> dict:
        """The report's JSON shape (``table2_voltage_sweep`` in ``paper.json``)."""
        return {"u_V": list(self.table.u_v), "resistance_per_area_percent": list(self.table.resistance_percent),
                "capacitance_per_area_percent": list(self.table.capacitance_percent),
                "resistance_below_capacitance_between_V": list(self.crossings_v),
                "resistance_minimum_V": self.minimum_v, "resistance_minimum_percent": self.minimum_percent,
                "dJ_ds_zero_at_sf_and_s0_V": list(self.current_maximum_v),
                "phi0_eV": self.table.params.phi0_j / electron_volt}


def voltage_sweep(u_v: Sequence[float] = tuple(np.round(np.arange(1.0, 4.201, 0.05), 3)),
                  params: PaperParameters = PAPER) -> VoltageSweep:
    """HE of R_A and C_A over u (extension): where the paper's "in all cases" C_A < R_A fails.

    Parameters
    ----------
    u_v : sequence of float
        Increasing voltages, each above φ0/e and below the eq. (12) limit at the cycle's thinnest
        separation (4.33 V for Table 1). Default 1–4.2 V in 50 mV steps. [V]
    params : PaperParameters
        Material and cycle parameters (default: Table 1 with k = 2).

    Returns
    -------
    VoltageSweep

    Notes
    -----
    Each point is :func:`cycle_error_table`'s computation. Crossings of HE(R_A) − HE(C_A) are refined
    by Brent's method between neighbouring sweep points of opposite sign, the minimum of HE(R_A) by a
    bounded search between the neighbours of the smallest sweep value. HE(R_A) is not monotonic in u:
    it falls while R_A(s) flattens toward its slope reversal (:func:`current_maximum_voltage`), is
    smallest where the loading/unloading difference changes sign, then grows as R_A(s) reverses and
    diverges toward the limit of eq. (12). All of it lies in eq. (12)'s regime (u > φ0/e), so it is
    not the eq. (11)/(12) switch.
    """
    t = cycle_error_table(u_v, params)
    u = np.asarray(t.u_v, dtype=float)
    diff = np.array(t.resistance_percent) - np.array(t.capacitance_percent)

    def d(x: float) -> float:
        r = model_cycle_errors(x, params)
        return r.resistance.percent - r.capacitance.percent

    crossings = tuple(float(brentq(d, u[i], u[i + 1], xtol=1e-6)) for i in range(len(u) - 1)
                      if diff[i] * diff[i + 1] < 0)
    i = int(np.argmin(t.resistance_percent))
    lo, hi = u[max(i - 1, 0)], u[min(i + 1, len(u) - 1)]
    res = minimize_scalar(lambda x: model_cycle_errors(x, params).resistance.percent, bounds=(lo, hi),
                          method="bounded", options={"xatol": 1e-5})
    s_f = float(separation_loading(params.sigma_f_pa, params.s0_m, params.modulus_pa))
    umax = (current_maximum_voltage(s_f, params.phi0_j), current_maximum_voltage(params.s0_m, params.phi0_j))
    return VoltageSweep(table=t, crossings_v=crossings, minimum_v=float(res.x), minimum_percent=float(res.fun),
                        current_maximum_v=umax)
