"""The traditional resistive readout (paper §6, Fig. 18) and a voltage divider, with their
sensitivity to the FSR's voltage-dependent resistance.

An FSR's resistance depends on the voltage across it (tunnelling, eqs. 10–18): written locally as
``R_FSR = R0(σ)·g(V)`` with the voltage coefficient ``β = ∂ln R_FSR/∂ln V`` (negative: the
resistance falls as the voltage rises). The inverting amplifier of eq. (38) holds the FSR at a fixed
voltage ``|Vcc|`` (its other end is the virtual ground), so β only matters through the supply; a
divider lets the FSR's voltage follow its own resistance, which feeds back on the reading.

β can be given directly, or taken from fsrlab's tunnelling model with
:func:`voltage_coefficient` (``fsrlab.physics.electrical.resistance_per_area``).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §6, eq. (38), Fig. 18.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_between, check_finite, check_positive, float_array, plain

__all__ = ["ReadoutResult", "inverting_amplifier", "voltage_divider", "voltage_coefficient"]


@dataclass(frozen=True)
class ReadoutResult:
    """Output of a resistive readout and its sensitivities.

    Attributes
    ----------
    v_out_v : float or ndarray
        Output voltage. [V]
    v_fsr_v : float or ndarray
        Voltage across the FSR. [V]
    sensitivity_r : float or ndarray
        ``∂ln V_out/∂ln R0``: relative output change per relative change of the FSR's
        stress-driven resistance, including the voltage feedback. [1]
    sensitivity_supply : float or ndarray
        ``∂ln V_out/∂ln |Vcc|``: relative output change per relative supply change. [1]
    """

    v_out_v: np.ndarray | float
    v_fsr_v: np.ndarray | float
    sensitivity_r: np.ndarray | float
    sensitivity_supply: np.ndarray | float


def _out(a):
    a = np.asarray(a, dtype=float)
    return a[()] if a.ndim == 0 else a


def inverting_amplifier(r_fsr_ohm, r_f_ohm: float, vcc_v: float,
                        voltage_coefficient=0.0) -> ReadoutResult:
    """Inverting amplifier with the FSR as input resistor, ``V_out = −(R_F/R_FSR)·Vcc`` (eq. 38).

    Parameters
    ----------
    r_fsr_ohm : float or array_like
        FSR resistance at the voltage ``|Vcc|`` it sees (> 0). [Ω]
    r_f_ohm : float
        Feedback resistor (20 kΩ in the paper). [Ω]
    vcc_v : float
        Drive voltage at the FSR's input (−5 V in the paper, so that V_out > 0); not 0. [V]
    voltage_coefficient : float or array_like
        ``β = ∂ln R_FSR/∂ln V`` at ``|Vcc|`` (0: an ohmic FSR). [1]

    Returns
    -------
    ReadoutResult
        ``sensitivity_r = −1`` (the FSR's voltage is fixed, no feedback);
        ``sensitivity_supply = 1 − β`` (a supply change also moves R_FSR). Op-amp saturation and
        offset are not modelled.
    """
    r = float_array("r_fsr_ohm", r_fsr_ohm)
    if np.any(~(r > 0)):
        raise ParameterError(f"must be > 0 Ω, got {r_fsr_ohm!r}", parameter="r_fsr_ohm")
    check_positive("r_f_ohm", r_f_ohm, "Ω")
    check_finite("vcc_v", vcc_v)
    if np.ndim(vcc_v) or vcc_v == 0:
        raise ParameterError(f"must be a finite non-zero voltage, got {plain(vcc_v)}", parameter="vcc_v")
    beta = float_array("voltage_coefficient", voltage_coefficient)
    check_finite("voltage_coefficient", beta)
    v_out = -(r_f_ohm / r) * vcc_v  # Eq. (38)
    shape = np.broadcast(v_out, beta).shape
    return ReadoutResult(v_out_v=_out(np.broadcast_to(v_out, shape)),
                         v_fsr_v=_out(np.full(shape, abs(vcc_v))),
                         sensitivity_r=_out(np.full(shape, -1.0)),
                         sensitivity_supply=_out(np.broadcast_to(1.0 - beta, shape)))


def voltage_divider(r_fsr_ohm, r_m_ohm: float, vcc_v: float = 5.0, voltage_coefficient=0.0) -> ReadoutResult:
    """FSR on the high side of a divider with measuring resistor R_M to ground.

    Parameters
    ----------
    r_fsr_ohm : float or array_like
        FSR resistance at its operating voltage (> 0; ``inf``: an open FSR, no output). [Ω]
    r_m_ohm : float
        Measuring resistor. [Ω]
    vcc_v : float
        Supply (> 0). [V]
    voltage_coefficient : float or array_like
        ``β = ∂ln R_FSR/∂ln V`` at the operating point. [1]

    Returns
    -------
    ReadoutResult

    Notes
    -----
    ``V_out = Vcc·R_M/(R_M + R_FSR)``, ``V_FSR = Vcc·R_FSR/(R_M + R_FSR)``. With ``x = ln R_FSR``,
    ``p = R_FSR/(R_M + R_FSR)``: ``dx = d ln R0 + β·d ln V_FSR`` and ``d ln V_FSR = (1 − p)·dx`` (at
    fixed supply), so ``dx = d ln R0/(1 − β(1 − p))`` and

        ∂ln V_out/∂ln R0 = −p/(1 − β(1 − p)),
        ∂ln V_out/∂ln Vcc = 1 − p·β/(1 − β(1 − p)).

    With β < 0 (tunnelling), the feedback shrinks the resistive sensitivity.
    """
    r = float_array("r_fsr_ohm", r_fsr_ohm)
    if np.any(~(r > 0)):
        raise ParameterError(f"must be > 0 Ω, got {r_fsr_ohm!r}", parameter="r_fsr_ohm")
    check_positive("r_m_ohm", r_m_ohm, "Ω")
    check_positive("vcc_v", vcc_v, "V")
    beta = float_array("voltage_coefficient", voltage_coefficient)
    check_finite("voltage_coefficient", beta)
    p = 1.0 / (1.0 + r_m_ohm / r)  # R_FSR/(R_M + R_FSR), 1 for an open FSR (inf)
    loop = 1.0 - beta * (1.0 - p)
    if np.any(loop <= 0):
        raise ParameterError("β·R_M/(R_M + R_FSR) must stay below 1 (else the operating point is unstable)",
                             parameter="voltage_coefficient")
    return ReadoutResult(v_out_v=_out(vcc_v * (1.0 - p) + 0 * beta), v_fsr_v=_out(vcc_v * p + 0 * beta),
                         sensitivity_r=_out(-p / loop), sensitivity_supply=_out(1.0 - p * beta / loop))


def voltage_coefficient(u_v, s_m, phi0_j: float | None = None, rel_step: float = 1e-4):
    """``β = ∂ln R_A/∂ln u`` from fsrlab's tunnelling model (``fsrlab.physics.electrical``).

    Parameters
    ----------
    u_v : float or array_like
        Voltage across one composite film (> 0). [V]
    s_m : float or array_like
        Interparticle separation. [m]
    phi0_j : float, optional
        Barrier height (default: Table 1). [J]
    rel_step : float
        Relative step of the central difference in u. [1]

    Returns
    -------
    float or ndarray
        β (negative). The equation of J is held fixed across the difference (the paper's eqs. 10–12
        do not join continuously, see SPEC §2), so β is that regime's local slope. NaN where the
        current underflows at both voltages of the difference (separations far beyond nanometres). [1]
    """
    from fsrlab.physics.electrical import resistance_per_area
    from fsrlab.physics.params import PAPER

    phi0 = PAPER.phi0_j if phi0_j is None else phi0_j
    check_positive("phi0_j", phi0, "J", scalar=True)
    u = float_array("u_v", u_v)
    if np.any(~(u > 0)):
        raise ParameterError(f"must be > 0 V, got {u_v!r}", parameter="u_v")
    check_between("rel_step", rel_step, 0.0, 0.5, lower_open=True, scalar=True)
    _, regime = resistance_per_area(u, s_m, phi0, return_regime=True)
    regime = np.asarray(regime)
    out = np.empty(np.broadcast(u, float_array("s_m", s_m)).shape)
    uu, ss = np.broadcast_arrays(u, float_array("s_m", s_m))
    rr = np.broadcast_to(regime, out.shape)
    for eq in np.unique(rr):
        m = rr == eq
        hi = resistance_per_area(uu[m] * (1 + rel_step), ss[m], phi0, regime=int(eq))
        lo = resistance_per_area(uu[m] * (1 - rel_step), ss[m], phi0, regime=int(eq))
        with np.errstate(invalid="ignore", divide="ignore"):  # no current at both voltages: NaN, as documented
            out[m] = (np.log(hi) - np.log(lo)) / (np.log1p(rel_step) - np.log1p(-rel_step))
    return _out(out)
