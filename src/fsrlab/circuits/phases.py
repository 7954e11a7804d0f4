"""The two RC phases of the FSR-timed LM555 astable: what the timing capacitor sees, and for how long.

In each phase the timing capacitor ``C = C_FSR + C_off`` sees a driving network shunted by
``R_FSR``; its Thevenin equivalent is a source ``V∞`` (where C heads) behind ``R_th`` (so that
``τ = R_th·C``). :func:`thevenin` derives both phases once; the closed forms
(:mod:`fsrlab.circuits.lm555`), the decoding (:mod:`fsrlab.circuits.decode`), the event-driven
transient (:mod:`fsrlab.circuits.transient`) and the period estimate of the ngspice runs
(:mod:`fsrlab.circuits.spice`) all use it. :func:`timing_per_rc` turns the two equivalents into
the phase durations per ``R·C`` as functions of ``N = R_FSR/R``. The ngspice netlist itself does
not use these forms: it is the independent check.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, eqs. (20)–(26), (33)–(34).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsrlab.circuits.checks import broadcast, check_fractions, check_lm555, check_r_fsr, check_supply
from fsrlab.physics.params import check_at_least, float_array

__all__ = ["Thevenin", "thevenin", "timing_per_rc"]


@dataclass(frozen=True)
class Thevenin:
    """The network the timing capacitor sees during one phase, as a source behind a resistance.

    Attributes
    ----------
    source_v : float or ndarray
        ``V∞``: the voltage across C's terminals with C removed, i.e. where C heads. [V]
    resistance_ohm : float or ndarray
        ``R_th``: the resistance seen by C, so that the phase's time constant is ``R_th·C``
        (``inf``: C holds its charge). [Ω]
    drive_v : float or ndarray
        The driving network's own source, before ``R_FSR`` shunts it. [V]
    drive_ohm : float or ndarray
        The driving network's resistance (``inf``: no path, e.g. D1 blocking R_B). [Ω]
    """

    source_v: np.ndarray | float
    resistance_ohm: np.ndarray | float
    drive_v: np.ndarray | float
    drive_ohm: np.ndarray | float


def _out(a, shape):
    a = np.array(a, dtype=float)  # a copy: never the caller's array
    if a.shape != shape:
        a = np.array(np.broadcast_to(a, shape))
    return a[()] if a.ndim == 0 else a


def _shunted(drive_v, drive_ohm, x, inf, xx):
    """(V∞, R_th, drive_v, drive_ohm) of a source behind ``drive_ohm`` with ``x`` across it (inf: open)."""
    return (np.where(inf, drive_v, drive_v * xx / (drive_ohm + xx)),
            np.where(inf, drive_ohm, drive_ohm * xx / (drive_ohm + xx)), drive_v, drive_ohm)


def _phases(r, x, diode, diode_drop_v, vcc_v, rd):
    """Unchecked core of :func:`thevenin`: two tuples (V∞, R_th, drive_v, drive_ohm), not broadcast."""
    inf = np.isinf(x)
    xx = np.where(inf, 1.0, x)
    charge = _shunted(vcc_v - diode_drop_v, 2.0 * r, x, inf, xx)                      # Eq. (21)
    if diode:
        discharge = (0.0, x, 0.0, math.inf)  # D1 blocks R_B: R_FSR alone, toward 0 V       # Eq. (33)
    else:
        # Pin 7 is V_T = Vcc·R_d/(R + R_d) behind R_T = R ∥ R_d (R_d = 0: ground).           # Eq. (24)
        rd_rel = rd / r
        discharge = _shunted(vcc_v * rd_rel / (1.0 + rd_rel), r * (1.0 + rd_rel / (1.0 + rd_rel)), x, inf, xx)
    return charge, discharge


def thevenin(r_ohm, r_fsr_ohm, diode: bool = False, diode_drop_v: float = 0.0, vcc_v: float = 5.0,
             discharge_ohm=0.0, *, c_off_farad=0.0, lower_fraction: float = 1 / 3,
             upper_fraction: float = 2 / 3) -> tuple[Thevenin, Thevenin]:
    """Thevenin equivalents seen by the timing capacitor in the charge and the discharge phase.

    Parameters
    ----------
    r_ohm : float or array_like
        R_A = R_B = R (> 0). [Ω]
    r_fsr_ohm : float or array_like
        FSR resistance (> 0; ``inf``: an ideal capacitor; NaN gives NaN). [Ω]
    diode : bool
        D1 in series with R_B (paper Figs. 13 and 16).
    diode_drop_v : float
        Constant forward drop of D1 during the charge (needs ``diode``). [V]
    vcc_v : float
        Supply (> 0). [V]
    discharge_ohm : float or array_like
        Discharge-transistor on-resistance (≥ 0; 0: the paper's ideal switch). [Ω]
    c_off_farad : float or array_like
        Offset capacitor (≥ 0). It does not enter the equivalents (it adds to C); accepted and
        checked so that ``thevenin(r_fsr_ohm=..., **circuit.kwargs())`` works. [F]
    lower_fraction, upper_fraction : float
        Comparator thresholds as fractions of Vcc. They do not enter the equivalents (they decide
        when a phase ends); accepted and checked like ``c_off_farad``. [1]

    Returns
    -------
    (Thevenin, Thevenin)
        The charge phase (output high) and the discharge phase (output low), broadcast over the
        array inputs; scalars when every input is scalar.

    Raises
    ------
    ParameterError
        A parameter out of range (its ``parameter`` names it).
    TypeError
        A part that is not a number (the message names it).

    Notes
    -----
    With ``Vs = Vcc − V_D``, ``x = R_FSR`` and ``a ∥ b = a·b/(a + b)``::

        charge:               drive Vs behind 2R;   V∞ = Vs·x/(2R + x),  R_th = 2R ∥ x    # Eq. (21)
        discharge, no D1:     drive 0 behind R;     V∞ = 0,              R_th = R ∥ x     # Eq. (24)
        discharge, with D1:   no drive (D1 off);    V∞ = 0,              R_th = x         # Eq. (33)

    With a discharge on-resistance R_d and no diode (an extension), pin 7 is a source
    ``V_T = Vcc·R_d/(R + R_d)`` behind ``R_T = R ∥ R_d``, so the discharge drive is ``V_T`` behind
    ``R + R_T``. The forms are homogeneous in the resistances: with ``r_ohm = 1`` and
    ``r_fsr_ohm = N`` they come out in units of R (as :func:`timing_per_rc` uses them).
    """
    check_lm555(r_ohm, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, discharge_ohm)
    r = float_array("r_ohm", r_ohm)
    check_r_fsr(r_fsr_ohm)
    x = float_array("r_fsr_ohm", r_fsr_ohm)
    rd = float_array("discharge_ohm", discharge_ohm)
    shape = broadcast(("r_ohm", r), ("r_fsr_ohm", x), ("discharge_ohm", rd))[0].shape
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        phases = _phases(r, x, diode, diode_drop_v, vcc_v, rd)
    charge, discharge = (Thevenin(*(_out(a, shape) for a in phase)) for phase in phases)
    return charge, discharge


def timing_per_rc(n_ratio, diode: bool = False, diode_drop_v: float = 0.0, vcc_v: float = 5.0,
                  lower_fraction: float = 1 / 3, upper_fraction: float = 2 / 3, discharge_ratio=0.0):
    """Charge and discharge times per ``R·C`` as functions of ``N = R_FSR/R`` (independent of R and C).

    Parameters
    ----------
    n_ratio : float or array_like
        ``N = R_FSR/R`` (``inf`` allowed; NaN, and N ≤ 0, give NaN). [1]
    diode : bool
        D1 in series with R_B.
    diode_drop_v : float
        Constant forward drop of D1 (needs ``diode``). [V]
    vcc_v : float
        Supply. [V]
    lower_fraction, upper_fraction : float
        Comparator thresholds as fractions of Vcc. [1]
    discharge_ratio : float or array_like
        Discharge-transistor on-resistance over R, ``R_d/R`` (≥ 0). [1]

    Returns
    -------
    (ndarray, ndarray)
        ``τH/(R·C)`` and ``τL/(R·C)``. ``τH/(R·C)`` is NaN where the charge never reaches the upper
        threshold (``N ≤ N_min``); ``τL/(R·C)`` is ``inf`` where the discharge never reaches the
        lower one (with D1 and ``N = inf``, or a discharge on-resistance too large). [1]

    Notes
    -----
    A phase from ``V_start`` to ``V_end`` toward ``V∞`` lasts ``R_th·C·ln((V∞ − V_start)/(V∞ − V_end))``
    (:func:`thevenin` gives ``V∞`` and ``R_th``)::

        τH = C·R_th,charge·ln((V∞ − ℓVcc)/(V∞ − uVcc))      # Eq. (23) for V_D = 0, ℓ = 1/3, u = 2/3
        τL = C·R_th,discharge·ln(u/ℓ)                         # Eqs. (26), (34): V∞ = 0

    With a discharge on-resistance (no diode), ``τL = C·R_th·ln((uVcc − V∞)/(ℓVcc − V∞))``.
    """
    check_fractions(lower_fraction, upper_fraction)
    check_supply(diode, diode_drop_v, vcc_v)
    check_at_least("discharge_ratio", discharge_ratio, 0.0)
    rd = discharge_ratio if isinstance(discharge_ratio, float) else float_array("discharge_ratio", discharge_ratio)
    n = float_array("n_ratio", n_ratio)
    v_lo, v_hi = lower_fraction * vcc_v, upper_fraction * vcc_v
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        n = np.where(n > 0, n, np.nan)  # N ≤ 0 is no circuit: NaN, like N ≤ N_min
        (v_inf, r_charge, _, _), (v_dis, r_dis, _, _) = _phases(1.0, n, diode, diode_drop_v, vcc_v, rd)
        th = np.where(v_inf > v_hi, r_charge * np.log((v_inf - v_lo) / (v_inf - v_hi)), np.nan)      # Eq. (23)
        if diode or not np.any(rd):
            tl = r_dis * math.log(upper_fraction / lower_fraction)                              # Eqs. (26), (34)
        else:
            tl = np.where(v_dis < v_lo, r_dis * np.log((v_hi - v_dis) / (v_lo - v_dis)), np.inf)
    return th, tl
