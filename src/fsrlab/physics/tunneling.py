"""Simmons tunnelling current density through the composite's polymer films (paper §3).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eqs. (10)–(12).
J. G. Simmons, "Generalized formula for the electric tunnel effect between similar electrodes
separated by a thin insulating film", J. Appl. Phys. 34, 1793 (1963), doi:10.1063/1.1702682.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.constants import e, h, m_e
from scipy.optimize import brentq

from fsrlab.errors import ParameterError
from fsrlab.physics.params import PAPER, check_finite, check_positive, float_array

__all__ = ["REGIMES", "SMALL_U_FRACTION", "tunneling_regime", "current_density", "voltage_limit"]

#: Regimes by the paper's equation number.
REGIMES = {10: "u ≈ 0 (eq. 10)", 11: "u ≤ φ0/e (eq. 11)", 12: "u > φ0/e (eq. 12)"}

#: The paper gives no number for "u ≈ 0"; fsrlab uses eq. (10) where e·u ≤ this fraction of φ0.
SMALL_U_FRACTION = 0.01


def _check_small_u(small_u_fraction: float) -> None:
    check_finite("small_u_fraction", small_u_fraction, scalar=True)
    if not 0 <= small_u_fraction < 1:
        raise ParameterError(f"must be in [0, 1), got {small_u_fraction!r}", parameter="small_u_fraction")


def tunneling_regime(u_v, phi0_j: float = PAPER.phi0_j, small_u_fraction: float = SMALL_U_FRACTION):
    """Which of the paper's equations applies at voltage ``u_v``: 10, 11 or 12.

    Parameters
    ----------
    u_v : float or array_like
        Voltage across the composite u, > 0. [V]
    phi0_j : float
        Barrier height φ0. [J]
    small_u_fraction : float
        e·u ≤ ``small_u_fraction``·φ0 counts as u ≈ 0 (eq. 10); 0 never selects eq. (10). [-]

    Returns
    -------
    int or ndarray of int
        The equation number for each voltage.

    Notes
    -----
    The paper's thresholds: eq. (10) for u ≈ 0, eq. (11) for u ≤ φ0/e, eq. (12) for u > φ0/e.
    The three do not join continuously. As u → 0, eq. (10)/eq. (11) → (3/2)·c/(c − 2) with
    c = (4πs/h)√(2mφ0) (expanding eq. (11) to first order in u gives
    J11 ≈ (2/3)·J10·(1 − 2/c)): 1.655 at s0 = 4.418 nm and φ0 = 0.223 eV (c = 21.38), 1.667 at
    s_f = 4.117 nm, and 3/2 only in the thick-barrier limit c → ∞. At u = φ0/e eq. (12) is about
    twice eq. (11) (2.15× at s0, 2.06× at s_f).
    """
    check_positive("phi0_j", phi0_j, "J", scalar=True)
    _check_small_u(small_u_fraction)
    regime = _regime(float_array("u_v", u_v), phi0_j, small_u_fraction)
    return regime if regime.ndim else int(regime)


def _regime(u, phi0_j: float, small_u_fraction: float):
    """:func:`tunneling_regime` without its checks: an int array of 10, 11, 12 (0-d for a scalar)."""
    eu = e * u
    return np.where(eu > phi0_j, 12, np.where(eu <= small_u_fraction * phi0_j, 10, 11))


def _eq10(u, s, phi0):
    root = np.sqrt(2 * m_e * phi0)
    return 3 * root / (2 * s) * (e / h) ** 2 * u * np.exp(-(4 * np.pi * s / h) * root)  # Eq. (10)


def _eq11(u, s, phi0):
    lo = phi0 - e * u / 2  # negative beyond u = 2φ0/e: out of domain (NaN)
    hi = phi0 + e * u / 2
    ok = lo >= 0
    lo = np.where(ok, lo, 0.0)
    a = 4 * np.pi * s / h * np.sqrt(2 * m_e)
    j = e / (2 * np.pi * h * s**2) * (lo * np.exp(-a * np.sqrt(lo)) - hi * np.exp(-a * np.sqrt(hi)))  # Eq. (11)
    # Beyond u = 2φ0/e, or where the film is so thin that the second term wins, it no longer applies.
    return np.where(ok & (j >= 0), j, np.nan)


def _eq12(u, s, phi0):
    """Eq. (12) with one exponential per distinct argument, in place: the Table 2 kernel's core too.

    Each operation keeps the order of the printed formula, so the result is the same to the bit as
    evaluating it term by term; temporaries are the size of the broadcast ``u``, ``s`` (the Table 2
    kernel passes chunks of a few 10^4 separations, which stay in cache).
    """
    shape = np.broadcast_shapes(np.shape(u), np.shape(s))
    # −B: rounding is symmetric in sign, so starting from −8π gives exactly −B, without a pass to negate.
    neg_b = np.multiply(-8 * np.pi, s, out=np.empty(shape))
    neg_b *= np.sqrt(2 * m_e)
    neg_b *= phi0**1.5
    neg_b /= 2.96 * h * e * u
    r = 1 + 2 * e * u / phi0
    t = np.multiply(neg_b, np.sqrt(r), out=np.empty(shape))
    exp_b = np.exp(neg_b, out=neg_b)  # exp(−B), once
    np.exp(t, out=t)
    t *= r
    bracket = np.subtract(exp_b, t, out=t)
    j = np.square(s, out=np.empty(shape))
    np.multiply(8 * np.pi * h * phi0, j, out=j)
    np.divide(2.2 * e**3 * u**2, j, out=j)
    j *= bracket  # Eq. (12)
    # Thin films at high voltage (B < ln r / (√r − 1)) turn the bracket negative: outside the formula.
    if not bracket.min(initial=np.inf) > 0:  # one pass; min is NaN if any element is
        bad = ~(bracket > 0)
        j[bad] = np.where(exp_b[bad] == 0, 0.0, np.nan)  # 0 where exp(−B) underflows (tiny u)
    return j if j.ndim else j[()]


def current_density(
    u_v,
    s_m,
    phi0_j: float = PAPER.phi0_j,
    regime: str | int = "auto",
    return_regime: bool = False,
    small_u_fraction: float = SMALL_U_FRACTION,
    validate: bool = True,
):
    """Tunnelling current density J(u, s) across the polymer film between particles.

    Parameters
    ----------
    u_v : float or array_like
        Voltage across the composite u, > 0. [V]
    s_m : float or array_like
        Interparticle separation s, > 0; broadcast with ``u_v``. [m]
    phi0_j : float
        Barrier height φ0. [J]
    regime : {"auto", 10, 11, 12}
        Equation to use; ``"auto"`` picks by the paper's thresholds (see :func:`tunneling_regime`).
    return_regime : bool
        Also return the equation number used for each element.
    small_u_fraction : float
        Threshold of u ≈ 0 for ``"auto"``, as a fraction of φ0/e. [-]
    validate : bool
        True (default): raise :class:`~fsrlab.errors.ParameterError` unless ``u_v``, ``s_m`` and ``phi0_j`` are finite
        and > 0
        (and, with ``"auto"``, ``small_u_fraction`` is in [0, 1)). False: skip those checks, for a
        caller that made them once before calling many times (a root finder's inner loop); the
        numbers are the same.

    Returns
    -------
    J : float or ndarray
        Current density. NaN where eq. (11) is forced beyond its domain (e·u > 2φ0, or a negative
        result on very thin films) and where eq. (12)'s bracket is not positive (thin films at high
        voltage, B < ln r / (√r − 1): Simmons' high-voltage formula no longer describes tunnelling);
        :func:`voltage_limit` gives the voltage where that starts. 0 where eq. (12) underflows
        (forced at tiny u). [A/m²]
    regime : int or ndarray of int
        Only with ``return_regime``: 10, 11 or 12 for each element.

    Notes
    -----
    Eq. (10), u ≈ 0: ``J = 3√(2mφ0)/(2s) (e/h)² u exp(−(4πs/h)√(2mφ0))``.
    Eq. (11), u ≤ φ0/e: ``J = e/(2πhs²) {(φ0 − eu/2) exp(−(4πs/h)√(2m(φ0 − eu/2)))
    − (φ0 + eu/2) exp(−(4πs/h)√(2m(φ0 + eu/2)))}``.
    Eq. (12), u > φ0/e: ``J = 2.2e³u²/(8πhφ0s²) {exp(−B) − r exp(−B√r)}`` with
    ``B = 8πs√(2m)φ0^(3/2)/(2.96 h e u)`` and ``r = 1 + 2eu/φ0``.
    No floating-point warnings are raised for s in [0.5, 20] nm and u in [1e-4, 10] V.

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    Simmons, J. Appl. Phys. 34, 1793 (1963), doi:10.1063/1.1702682.
    """
    if validate:
        check_positive("phi0_j", phi0_j, "J", scalar=True)
        check_positive("u_v", u_v, "V")
        check_positive("s_m", s_m, "m")
    u_in, s_in = float_array("u_v", u_v), float_array("s_m", s_m)
    if isinstance(regime, str) and regime == "auto":
        if validate:
            _check_small_u(small_u_fraction)
        which_u = _regime(u_in, phi0_j, small_u_fraction)  # decided on u alone
    elif not isinstance(regime, bool) and isinstance(regime, (int, np.integer)) and regime in (10, 11, 12):
        which_u = np.full(u_in.shape, int(regime))
    else:
        raise ParameterError(f"must be 'auto', 10, 11 or 12, got {regime!r}", parameter="regime")
    equations = {10: _eq10, 11: _eq11, 12: _eq12}
    first = int(which_u.flat[0]) if which_u.size else 12
    with np.errstate(over="ignore", under="ignore", invalid="ignore", divide="ignore"):
        if not which_u.size or bool(np.all(which_u == first)):  # the usual case: one regime, no masking
            j = equations[first](u_in, s_in, phi0_j)
            which = np.broadcast_to(which_u, j.shape)
        else:
            u, s, which = np.broadcast_arrays(u_in, s_in, which_u)
            j = np.empty(u.shape)
            for eq in np.unique(which_u):
                mask = which == eq
                j[mask] = equations[int(eq)](u[mask], s[mask], phi0_j)
    j = np.asarray(j, dtype=float)
    if j.ndim == 0:
        j, which = float(j), int(which)
    else:
        which = np.array(which)
    return (j, which) if return_regime else j


def _eq12_limit_r(q: float) -> float:
    """r = 1 + 2eu/φ0 at which eq. (12)'s bracket reaches 0: the root of (√r + 1) ln r = q."""
    return brentq(lambda r: (math.sqrt(r) + 1) * math.log(r) - q, 1.0, max(4.0, q * q), xtol=1e-15, rtol=1e-15)


def _eq11_limit_t(c: float, t_lo: float, t_hi: float) -> float:
    """Largest t = eu/(2φ0) in [t_lo, t_hi] with c (√(1+t) − √(1−t)) ≥ ln((1+t)/(1−t)): eq. (11) ≥ 0."""

    def margin(t):
        return c * (math.sqrt(1 + t) - math.sqrt(1 - t)) - math.log((1 + t) / (1 - t))

    if margin(t_hi) >= 0:
        return t_hi
    if t_lo <= 0 or margin(t_lo) < 0:
        return t_lo
    return brentq(margin, t_lo, t_hi, xtol=1e-15, rtol=1e-15)


def voltage_limit(s_m, phi0_j: float = PAPER.phi0_j, small_u_fraction: float = SMALL_U_FRACTION):
    """Largest voltage up to which the paper's equations give a current density at separation ``s_m``.

    Parameters
    ----------
    s_m : float or array_like
        Interparticle separation s, > 0; for a stress cycle, the smallest separation of the cycle. [m]
    phi0_j : float
        Barrier height φ0. [J]
    small_u_fraction : float
        Threshold of u ≈ 0, as in :func:`tunneling_regime`. [-]

    Returns
    -------
    float or ndarray
        u_max: for 0 < u < u_max, :func:`current_density` with ``regime="auto"`` is a number (not NaN)
        at ``s_m`` and at every larger separation; just above u_max it is NaN at ``s_m``. [V]

    Notes
    -----
    With ``r = 1 + 2eu/φ0`` and ``B`` of eq. (12), the bracket ``exp(−B) − r exp(−B√r)`` is positive
    exactly when ``(√r + 1) ln r < 16π s √(2mφ0) / (2.96 h)``; the left side grows with u, the right
    side with s. So eq. (12) holds for u below the root of that equation, at s and every thicker
    film. Eq. (11) stays ≥ 0 while ``c (√(1+t) − √(1−t)) ≥ ln((1+t)/(1−t))`` with ``t = eu/(2φ0)``
    and ``c = (4πs/h)√(2mφ0)``; its right side over ``√(1+t) − √(1−t)`` rises from 2 at t → 0, so
    it fails only on films thinner than about 0.44 nm at φ0 = 0.223 eV. Eq. (10) is always positive.
    The limit is where the first of these fails along u, with the regimes the paper's thresholds pick.

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eqs. (10)–(12).
    Simmons, J. Appl. Phys. 34, 1793 (1963), doi:10.1063/1.1702682.
    """
    check_positive("phi0_j", phi0_j, "J", scalar=True)
    check_positive("s_m", s_m, "m")
    _check_small_u(small_u_fraction)
    root = math.sqrt(2 * m_e * phi0_j)

    def one(s: float) -> float:
        q = 16 * math.pi * s * root / (2.96 * h)
        if q > (math.sqrt(3) + 1) * math.log(3):  # eq. (12) holds just above u = φ0/e
            return (_eq12_limit_r(q) - 1) * phi0_j / (2 * e)
        c = 4 * math.pi * s / h * root
        return 2 * phi0_j / e * _eq11_limit_t(c, small_u_fraction / 2, 0.5)

    s = np.asarray(s_m, dtype=float)
    limits = np.vectorize(one, otypes=[float])(s)
    return float(limits) if limits.ndim == 0 else limits
