"""Interparticle separation s(σ) of a conductive polymer composite, with hysteresis (paper §2).

Loading follows eq. (1), unloading eq. (9). :func:`separation_history` extends the paper (which
models one cycle only) to any stress history with a turning-point memory rule.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eqs. (1)–(9).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import PAPER, check_at_least, check_finite, check_positive, float_array, plain

__all__ = [
    "separation_loading",
    "separation_unloading",
    "separation_history",
    "SeparationHistory",
]


def _check_material(s0_m: float, modulus_pa: float) -> None:
    check_positive("s0_m", s0_m, "m", scalar=True)
    check_positive("modulus_pa", modulus_pa, "Pa", scalar=True)


def _check_cycle(sigma_f_pa: float, modulus_pa: float, k: float) -> None:
    check_positive("sigma_f_pa", sigma_f_pa, "Pa", scalar=True)
    check_at_least("k", k, 1.0, scalar=True)
    if not np.all(np.asarray(modulus_pa) > sigma_f_pa):
        raise ParameterError(f"must be > sigma_f_pa ({plain(sigma_f_pa)} Pa), got {plain(modulus_pa)}",
                             parameter="modulus_pa")


def _loading(stress, s0_m, modulus_pa):
    """Eq. (1) without checks or domain mask, in place on one new array (the Table 2 kernel's core)."""
    s = np.divide(stress, modulus_pa, out=np.empty(np.shape(stress)))
    np.subtract(1.0, s, out=s)
    s *= s0_m  # Eq. (1)
    return s


def _unloading(stress, sigma_f_pa, s0_m, modulus_pa, k):
    """Eq. (9), simplified, for stresses in [0, σf]; no checks, in place on one new array."""
    s_f = s0_m * (1.0 - sigma_f_pa / modulus_pa)  # Eq. (3)
    s = np.divide(stress, sigma_f_pa, out=np.empty(np.shape(stress)))
    np.subtract(1.0, s, out=s)
    s **= k  # numpy's x**2 is x·x, as in the expression it replaces
    s *= s0_m - s_f
    s += s_f  # Eq. (9), simplified
    return s


def separation_loading(stress_pa, s0_m: float = PAPER.s0_m, modulus_pa: float = PAPER.modulus_pa):
    """Interparticle separation while the stress rises.

    Parameters
    ----------
    stress_pa : float or array_like
        Stress σ = F / A_FSR. [Pa]
    s0_m : float
        Separation at zero stress s0. [m]
    modulus_pa : float
        Material stiffness M. [Pa]

    Returns
    -------
    float or ndarray
        Separation s_l(σ), same shape as ``stress_pa``; NaN where σ < 0 or σ ≥ M. [m]

    Notes
    -----
    Eq. (1): ``s_l(σ) = s0 (1 − σ/M)``.

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    """
    _check_material(s0_m, modulus_pa)
    stress = float_array("stress_pa", stress_pa)
    s = np.where((stress >= 0) & (stress < modulus_pa), _loading(stress, s0_m, modulus_pa), np.nan)  # Eq. (1)
    return s if s.ndim else float(s)


def separation_unloading(
    stress_pa,
    sigma_f_pa: float = PAPER.sigma_f_pa,
    s0_m: float = PAPER.s0_m,
    modulus_pa: float = PAPER.modulus_pa,
    k: float = PAPER.k,
):
    """Interparticle separation while the stress falls from σf back to zero.

    Parameters
    ----------
    stress_pa : float or array_like
        Stress σ, 0 ≤ σ ≤ σf. [Pa]
    sigma_f_pa : float
        Final stress σf where loading stopped. [Pa]
    s0_m : float
        Separation at zero stress s0. [m]
    modulus_pa : float
        Material stiffness M, > σf. [Pa]
    k : float
        Unloading exponent, k ≥ 1 (the paper takes k even; this form is real for any k ≥ 1). [-]

    Returns
    -------
    float or ndarray
        Separation s_u(σ), same shape as ``stress_pa``; NaN outside [0, σf]. [m]

    Notes
    -----
    Eq. (9), ``s_u(σ) = s_f (1 + a (σ − b)^k / M)`` with ``s_f = s0 (1 − σf/M)`` (eq. 3),
    ``b = σf`` (eq. 7) and ``a = M σf^(1−k) / (M − σf)`` (eq. 8), simplifies exactly to
    ``s_u(σ) = s_f + (s0 − s_f)(1 − σ/σf)^k``, which is what is computed: it is real for any k ≥ 1
    on [0, σf] where the printed form needs k even, and it meets eq. (1) at σ = 0 and σ = σf (eq. 5).

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    """
    _check_material(s0_m, modulus_pa)
    _check_cycle(sigma_f_pa, modulus_pa, k)
    stress = float_array("stress_pa", stress_pa)
    inside = (stress >= 0) & (stress <= sigma_f_pa)
    s = _unloading(np.where(inside, stress, 0.0), sigma_f_pa, s0_m, modulus_pa, k)  # Eq. (9), simplified
    s = np.where(inside, s, np.nan)
    return s if s.ndim else float(s)


@dataclass
class SeparationHistory:
    """Separation along a stress history, with the branch each sample lies on.

    Parameters
    ----------
    stress_pa : ndarray
        The stress history. [Pa]
    separation_m : ndarray
        Separation at each sample. [m]
    direction : ndarray of int
        +1 on a loading branch, −1 on an unloading branch, 0 before the stress first moves.
    turning_points : list of tuple
        ``(index, stress_pa, separation_m)`` of every reversal of the stress direction.
    """

    stress_pa: np.ndarray
    separation_m: np.ndarray
    direction: np.ndarray
    turning_points: list


def separation_history(
    stress_pa,
    s0_m: float = PAPER.s0_m,
    modulus_pa: float = PAPER.modulus_pa,
    k: float = PAPER.k,
) -> SeparationHistory:
    """Separation under an arbitrary stress history: partial unloads, reloads, minor loops.

    **Extension beyond the paper**, which models a single loading–unloading cycle (eqs. 1, 9) and
    notes that real composites have memory.

    Parameters
    ----------
    stress_pa : array_like
        Stress samples in time order, 0 ≤ σ < M. A history that starts above zero is taken as
        reached by first loading from zero. [Pa]
    s0_m : float
        Separation at zero stress s0. [m]
    modulus_pa : float
        Material stiffness M. [Pa]
    k : float
        Unloading exponent, k ≥ 1. [-]

    Returns
    -------
    SeparationHistory

    Notes
    -----
    The memory rule is a turning-point (Madelung) rule with return-point memory and wiping out:

    1. The state keeps a stack of reversal points, starting with (0, s0).
    2. First loading, with no upper reversal in memory, follows eq. (1).
    3. Loading that started at a lower reversal (σL, sL) heads for the last upper reversal
       (σU, sU) along the straight line between them (the shape of eq. 1).
    4. Unloading that started at an upper reversal (σU, sU) heads for the last lower reversal
       (σL, sL), or (0, s0), along the shape of eq. (9):
       ``s = sU + (sL − sU) ((σU − σ)/(σU − σL))^k``.
    5. When the stress passes the reversal a branch heads for, that reversal and the one the
       branch started from are wiped out, and the older branch continues: minor loops close.

    For one full cycle 0 → σf → 0 this is exactly eq. (1) then eq. (9). It does not model creep
    or cycle-to-cycle drift, which the paper reports for real composites.

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
    """
    _check_material(s0_m, modulus_pa)
    check_at_least("k", k, 1.0, scalar=True)
    stress = float_array("stress_pa", stress_pa).ravel()
    check_finite("stress_pa", stress)
    if stress.size and (stress.min() < 0 or stress.max() >= modulus_pa):
        raise ParameterError(f"must lie in [0, modulus_pa={modulus_pa:g}) Pa", parameter="stress_pa")

    s = np.empty_like(stress)
    direction = np.zeros(stress.size, dtype=np.int8)
    stack = [(0.0, s0_m)]  # reversal points (σ, s), alternating lower/upper, oldest first
    turning: list[tuple[int, float, float]] = []

    def virgin(x):
        return s0_m * (1.0 - x / modulus_pa)  # Eq. (1)

    def branch(x, d):
        """Separation on the current branch in direction d at stresses x (within its range)."""
        if d > 0:
            sig_l, s_l = stack[-1]
            if len(stack) < 2:
                return virgin(x)
            sig_u, s_u = stack[-2]
            return s_l + (s_u - s_l) * (x - sig_l) / (sig_u - sig_l)
        sig_u, s_u = stack[-1]
        sig_l, s_l = stack[-2]
        return s_u + (s_l - s_u) * ((sig_u - x) / (sig_u - sig_l)) ** k

    d = 0
    current = (0.0, s0_m)
    i = 0
    n = stress.size
    while i < n:
        x0 = stress[i]
        step = x0 - current[0]
        if step == 0:
            s[i] = current[1]
            direction[i] = d
            i += 1
            continue
        new_d = 1 if step > 0 else -1
        if d != 0 and new_d != d:  # a reversal: remember where it happened
            stack.append(current)
            turning.append((i - 1, current[0], current[1]))
        d = new_d
        # the monotone run starting at i
        j = i + 1
        while j < n and (stress[j] - stress[j - 1]) * d >= 0:
            j += 1
        run = stress[i:j]
        start = 0
        while start < run.size:
            # the stress this branch heads for; beyond it the memory is wiped out
            if d > 0:
                limit = stack[-2][0] if len(stack) >= 2 else np.inf
                stop = start + int(np.searchsorted(run[start:], limit, side="right"))
            else:
                limit = stack[-2][0]
                stop = start + int(np.searchsorted(-run[start:], -limit, side="right"))
            s[i + start:i + stop] = branch(run[start:stop], d)
            start = stop
            if start < run.size:  # passed the reversal it headed for: wipe out the pair
                del stack[-2:]
        direction[i:j] = d
        current = (run[-1], s[j - 1])
        i = j
    return SeparationHistory(stress_pa=stress, separation_m=s, direction=direction, turning_points=turning)
