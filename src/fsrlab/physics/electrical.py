"""Resistance and capacitance per unit area of the composite (paper §3–4).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eqs. (14)–(18).
"""

from __future__ import annotations

import numpy as np
from scipy.constants import epsilon_0

from fsrlab.physics.params import PAPER, check_positive
from fsrlab.physics.tunneling import SMALL_U_FRACTION, current_density

__all__ = ["resistance_per_area", "capacitance_per_area", "capacitance"]


def resistance_per_area(
    u_v,
    s_m,
    phi0_j: float = PAPER.phi0_j,
    regime: str | int = "auto",
    return_regime: bool = False,
    small_u_fraction: float = SMALL_U_FRACTION,
    validate: bool = True,
):
    """Resistance per unit area R_A = u / J of the composite.

    Parameters
    ----------
    u_v : float or array_like
        Voltage across the composite u, > 0. [V]
    s_m : float or array_like
        Interparticle separation s, > 0. [m]
    phi0_j : float
        Barrier height φ0. [J]
    regime : {"auto", 10, 11, 12}
        Tunnelling equation (see :func:`fsrlab.physics.tunneling.current_density`); eq. (10) gives
        eq. (16), eq. (11) gives eq. (17), eq. (12) gives eq. (18).
    return_regime : bool
        Also return the equation number of J used for each element.
    small_u_fraction : float
        Threshold of u ≈ 0 for ``"auto"``. [-]
    validate : bool
        False skips the checks of the inputs, as in
        :func:`fsrlab.physics.tunneling.current_density`.

    Returns
    -------
    R_A : float or ndarray
        Resistance per unit area; inf where J underflows to 0 (or below the smallest float), NaN
        where J is NaN (with ``"auto"``, from u = :func:`fsrlab.physics.tunneling.voltage_limit`
        on). [Ω·m²]
    regime : int or ndarray of int
        Only with ``return_regime``.

    Notes
    -----
    Eqs. (16)–(18): ``R_A = u / J(u, s)``.

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    """
    j, which = current_density(u_v, s_m, phi0_j, regime, return_regime=True, small_u_fraction=small_u_fraction,
                               validate=validate)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.divide(np.asarray(u_v, dtype=float), j)  # Eqs. (16)-(18)
    r = float(r) if np.ndim(r) == 0 else r
    return (r, which) if return_regime else r


def capacitance_per_area(s_m, eps_r: float = PAPER.eps_r):
    """Capacitance per unit area C_A = ε_r ε0 / s.

    Parameters
    ----------
    s_m : float or array_like
        Interparticle separation s, > 0. [m]
    eps_r : float
        Relative permittivity of the polymer matrix, > 0. [-]

    Returns
    -------
    float or ndarray
        Capacitance per unit area. [F/m²]

    Notes
    -----
    Eq. (15). ε0 is CODATA's (scipy.constants); Table 1 prints 8.85·10⁻¹² F/m, 0.05 % lower,
    which leaves every hysteresis error unchanged (it cancels in eq. 13).

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    """
    check_positive("eps_r", eps_r, scalar=True)
    check_positive("s_m", s_m, "m")
    c = eps_r * epsilon_0 / np.asarray(s_m, dtype=float)  # Eq. (15)
    return float(c) if c.ndim == 0 else c


def capacitance(s_m, area_m2, eps_r: float = PAPER.eps_r):
    """Whole capacitance C = ε_r ε0 A / s.

    Parameters
    ----------
    s_m : float or array_like
        Interparticle separation s, > 0. [m]
    area_m2 : float or array_like
        Effective area A(σ), > 0; broadcast with ``s_m``. [m²]
    eps_r : float
        Relative permittivity, > 0. [-]

    Returns
    -------
    float or ndarray
        Capacitance. [F]

    Notes
    -----
    Eq. (14).

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    """
    check_positive("area_m2", area_m2, "m²")
    c = capacitance_per_area(s_m, eps_r) * np.asarray(area_m2, dtype=float)  # Eq. (14)
    return float(c) if np.ndim(c) == 0 else c
