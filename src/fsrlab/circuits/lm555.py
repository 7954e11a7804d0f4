"""LM555 astable with the FSR as timing element: closed forms, oscillation condition, sensitivity.

Decoding a reading back to R_FSR and C_FSR is :mod:`fsrlab.circuits.decode`; proposing a circuit for
a sensor is :mod:`fsrlab.circuits.design`; the Thevenin equivalents of the two phases, which every
model here builds on, are :mod:`fsrlab.circuits.phases`.

:func:`astable` and :func:`sensitivity` take every part of an
:class:`~fsrlab.circuits.circuit.LM555Circuit` as keywords (``astable(r_fsr_ohm=..., c_fsr_farad=...,
**circuit.kwargs())``); the functions of N alone (:func:`tau_ratio`, :func:`duty_cycle_limits`,
:func:`minimum_n_ratio`, :func:`oscillation_margin`) take only the parts they depend on.

The FSR is electrically ``R_FSR ∥ C_FSR``; it replaces the timing capacitor of a 555 astable with
``R_A = R_B = R`` (paper Fig. 9b), an offset capacitor ``C_off`` sits in parallel (Fig. 16), and
optionally a diode D1 is in series with ``R_B`` (Figs. 13, 16). The timing capacitance is
``C = C_FSR + C_off``.

Model (what is kept, what is neglected)
---------------------------------------
* Comparator thresholds at ``lower_fraction·Vcc`` and ``upper_fraction·Vcc`` (1/3 and 2/3 for the
  internal divider; a voltage on the control pin moves both).
* Charge (output high, discharge transistor off): Vcc → R_A → (D1) → R_B → C, with R_FSR across C.
  Thevenin: source ``Vs·R_FSR/(2R + R_FSR)`` behind ``2R ∥ R_FSR``, where ``Vs = Vcc − V_D`` with a
  diode of constant forward drop ``V_D`` (``V_D = 0``: ideal diode or no diode).
* Discharge (output low, pin 7 at ground): without the diode C discharges through ``R ∥ R_FSR``;
  with the diode D1 blocks R_B and C discharges through R_FSR alone. The diode drop does not enter
  the discharge: D1 is reverse biased.
* Optional (``discharge_ohm``, an extension): the discharge transistor's on-resistance; it only
  matters without D1 (a 50 Ω on-resistance lowers f by ~0.45 % at R = 10 kΩ).
* Neglected: discharge-transistor offset voltage, comparator delay and offset,
  output edge times, threshold/trigger input currents, diode reverse leakage, the diode's
  current-dependent drop (a constant drop is used), leakage of C_off.

References
----------
A. Matute, L. Paredes-Madrid, G. Moreno, F. Cárdenas, C. A. Palacio, "A Novel and Inexpensive
Approach for Force Sensing Based on FSR Piezocapacitance Aimed at Hysteresis Error Reduction",
Journal of Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, eqs. (19)–(37).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsrlab.circuits.checks import (
    broadcast,
    check_drop,
    check_fraction,
    check_fractions,
    check_lm555,
    check_r_fsr,
    check_supply,
    check_vcc,
)
from fsrlab.circuits.phases import thevenin, timing_per_rc
from fsrlab.errors import FsrlabError, ParameterError
from fsrlab.physics.params import check_positive, float_array

__all__ = [
    "NoOscillationError",
    "AstableResult",
    "astable",
    "minimum_n_ratio",
    "oscillation_margin",
    "tau_ratio",
    "duty_cycle_limits",
    "thresholds_from_control",
    "Sensitivity",
    "sensitivity",
]

class NoOscillationError(FsrlabError, ValueError):
    """The circuit does not oscillate; the message names the failed condition and by how much.

    Parameters
    ----------
    message : str
        One line: which condition failed and by how much.
    condition, shortfall
        See Attributes.
    parameter : str, optional
        The part to change (``r_fsr_ohm``, ``diode_drop_v``, ``discharge_ohm``); the message then reads
        ``"<parameter>: no oscillation: ..."``.

    Attributes
    ----------
    condition : str
        ``"charge"`` (the charge target stays below the upper threshold, N ≤ N_min),
        ``"diode_drop"`` (the supply minus the diode drop cannot reach the upper threshold) or
        ``"discharge"`` (diode variant with R_FSR = ∞: no discharge path).
    shortfall : float
        Relative amount by which the condition is missed (e.g. ``1 − N/N_min``). [1]
    """

    def __init__(self, message: str, condition: str, shortfall: float, parameter: str | None = None):
        super().__init__(message, parameter)
        self.condition = condition
        self.shortfall = shortfall

    @classmethod
    def for_diode_drop(cls, diode_drop_v: float, vcc_v: float, upper_fraction: float,
                       where: str = "") -> NoOscillationError:
        """The error for a diode drop that leaves the charge no headroom (condition ``"diode_drop"``).

        Parameters
        ----------
        diode_drop_v : float
            Forward drop of D1. [V]
        vcc_v : float
            Supply. [V]
        upper_fraction : float
            Upper threshold as a fraction of Vcc. [1]
        where : str
            Appended to the message (e.g. which array elements).

        Returns
        -------
        NoOscillationError
            To be raised when ``Vcc − V_D ≤ u·Vcc`` (:func:`minimum_n_ratio` is ``inf``).
        """
        return cls(f"no oscillation: the diode drop {diode_drop_v:.4g} V leaves Vcc − V_D = "
                   f"{vcc_v - diode_drop_v:.4g} V, not above the upper threshold {upper_fraction * vcc_v:.4g} V; "
                   f"the drop must stay below {(1 - upper_fraction) * vcc_v:.4g} V{where}", "diode_drop",
                   diode_drop_v / ((1 - upper_fraction) * vcc_v) - 1.0, "diode_drop_v")


@dataclass(frozen=True)
class AstableResult:
    """Steady-state timing of the astable.

    Attributes
    ----------
    frequency_hz : float or ndarray
        Output frequency ``1/(τH + τL)``; NaN where the circuit does not oscillate. [Hz]
    duty_cycle : float or ndarray
        ``τH/(τH + τL)`` (output high fraction, 0–1); NaN where it does not oscillate. [1]
    tau_high_s : float or ndarray
        Output-high (charge) time τH. [s]
    tau_low_s : float or ndarray
        Output-low (discharge) time τL. [s]
    n_ratio : float or ndarray
        ``N = R_FSR / R``. [1]
    oscillates : bool or ndarray
        Whether every oscillation condition holds.
    """

    frequency_hz: np.ndarray | float
    duty_cycle: np.ndarray | float
    tau_high_s: np.ndarray | float
    tau_low_s: np.ndarray | float
    n_ratio: np.ndarray | float
    oscillates: np.ndarray | bool

    @property
    def period_s(self):
        """Period ``τH + τL``. [s]"""
        return self.tau_high_s + self.tau_low_s

    @property
    def ratio(self):
        """τH/τL (the quantity of the paper's eqs. 32 and 37). [1]"""
        return self.tau_high_s / self.tau_low_s

    def plot(self, ax=None, x=None, xlabel: str | None = None):
        """Frequency and duty cycle versus ``x`` (default N), the duty cycle on a twin y axis.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes for the frequency (default: a new figure).
        x : array_like, optional
            Abscissa, one value per element of a 1-D result (default: :attr:`n_ratio`).
        xlabel : str, optional
            Label of the x axis (default: ``"N = R_FSR/R"`` for the default ``x``).

        Returns
        -------
        (matplotlib.axes.Axes, matplotlib.axes.Axes)
            The frequency axes and the duty-cycle axes. NaN (no oscillation) leaves gaps.
        """
        from fsrlab.circuits.plotting import plot_twin

        if x is None:
            x, xlabel = self.n_ratio, "N = R_FSR/R" if xlabel is None else xlabel
        return plot_twin(x, (self.frequency_hz, None, "frequency", "Hz"), (self.duty_cycle, None, "duty cycle", "%"),
                         ax=ax, xlabel=xlabel)


def _is_number(x) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) and math.isfinite(x)


def thresholds_from_control(control_v: float, vcc_v: float = 5.0) -> tuple[float, float]:
    """Threshold fractions when the control pin (5) is driven to ``control_v``.

    Parameters
    ----------
    control_v : float
        Voltage on the control pin, 0 < control_v < vcc_v (open pin: 2/3·Vcc). [V]
    vcc_v : float
        Supply. [V]

    Returns
    -------
    (lower_fraction, upper_fraction) : (float, float)
        The threshold comparator trips at ``control_v`` and the trigger comparator at half of it
        (the LM555's internal divider), as fractions of Vcc. [1]
    """
    check_vcc(vcc_v)
    if not (_is_number(control_v) and 0 < control_v < vcc_v):
        raise ParameterError(f"must be between 0 and Vcc = {vcc_v:g} V, got {control_v!r}", parameter="control_v")
    upper = control_v / vcc_v
    return upper / 2, upper


def minimum_n_ratio(diode_drop_v: float = 0.0, vcc_v: float = 5.0, upper_fraction: float = 2 / 3) -> float:
    """Smallest ``N = R_FSR/R`` for which the charge phase reaches the upper threshold.

    Parameters
    ----------
    diode_drop_v : float
        Forward drop of D1 in the charge path (0 without diode or with an ideal diode). [V]
    vcc_v : float
        Supply voltage. [V]
    upper_fraction : float
        Upper threshold as a fraction of Vcc (2/3 by default). [1]

    Returns
    -------
    float
        ``N_min = 2·u·Vcc / (Vcc − V_D − u·Vcc)``; ``inf`` when ``V_D ≥ (1 − u)·Vcc`` (the charge
        can never reach the threshold). [1]

    Notes
    -----
    The charge target ``(Vcc − V_D)·N/(N + 2)`` must exceed ``u·Vcc``. With ``V_D = 0`` and
    ``u = 2/3`` this is the paper's eq. (30), ``R < R_FSR/4`` (N > 4).
    """
    check_drop(diode_drop_v)
    check_vcc(vcc_v)
    check_fraction("upper_fraction", upper_fraction)
    headroom = vcc_v - diode_drop_v - upper_fraction * vcc_v
    if headroom <= 0:
        return math.inf
    return 2.0 * upper_fraction * vcc_v / headroom


def tau_ratio(n_ratio, diode: bool = False, diode_drop_v: float = 0.0, vcc_v: float = 5.0,
              lower_fraction: float = 1 / 3, upper_fraction: float = 2 / 3):
    """τH/τL as a function of ``N = R_FSR/R`` (independent of R and C).

    Parameters
    ----------
    n_ratio : float or array_like
        ``N = R_FSR / R``. [1]
    diode : bool
        With D1 in series with R_B (paper Fig. 13).
    diode_drop_v : float
        Constant forward drop of D1 (needs ``diode=True``). [V]
    vcc_v : float
        Supply. [V]
    lower_fraction, upper_fraction : float
        Comparator thresholds as fractions of Vcc. [1]

    Returns
    -------
    float or ndarray
        τH/τL; NaN where ``N ≤ N_min`` (no oscillation). [1]

    Notes
    -----
    Without the diode and with the default thresholds this is eq. (32) as eqs. (23) and (26) give
    it (the printed eq. (32) has an extra factor N, see docs/errata.md, O1),
    ``τH/τL = ln((2N − 2)/(N − 4))·2(N + 1)/((N + 2)·ln 2)``, which falls monotonically from ∞ at
    N = 4 to 2 as N → ∞. With an ideal diode it is ``2·ln((2N − 2)/(N − 4))/((N + 2)·ln 2)``,
    which falls to 0; the paper's printed eq. (37) has an extra factor N (see docs/errata.md, O2).
    """
    th, tl = timing_per_rc(n_ratio, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = th / tl
    return out[()] if np.ndim(out) == 0 else out


def duty_cycle_limits(diode: bool = False, diode_drop_v: float = 0.0, vcc_v: float = 5.0,
                      lower_fraction: float = 1 / 3, upper_fraction: float = 2 / 3) -> tuple[float, float]:
    """Range of duty cycles the circuit can produce over all ``N > N_min`` (open interval).

    Parameters
    ----------
    diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction
        As in :func:`astable`.

    Returns
    -------
    (float, float)
        ``(inf DC, sup DC)``: the supremum is 1 (N → N_min); the infimum is reached as N → ∞:
        ``ρ∞/(1 + ρ∞)`` with ``ρ∞ = 2·ln((Vs − ℓVcc)/(Vs − uVcc))/ln(u/ℓ)`` without the diode
        (2/3 for the default thresholds) and 0 with the diode (τL = ln(u/ℓ)·R_FSR·C grows without
        bound while τH stays finite). Neither limit is attained. [1]
    """
    check_fractions(lower_fraction, upper_fraction)
    check_supply(diode, diode_drop_v, vcc_v)
    if math.isinf(minimum_n_ratio(diode_drop_v, vcc_v, upper_fraction)):
        raise NoOscillationError.for_diode_drop(diode_drop_v, vcc_v, upper_fraction)
    if diode:
        return 0.0, 1.0
    vs = vcc_v - diode_drop_v
    rho = 2.0 * math.log((vs - lower_fraction * vcc_v) / (vs - upper_fraction * vcc_v)) / math.log(
        upper_fraction / lower_fraction)
    return rho / (1.0 + rho), 1.0


def oscillation_margin(r_ohm, r_fsr_ohm, diode_drop_v: float = 0.0, vcc_v: float = 5.0,
                       upper_fraction: float = 2 / 3):
    """Relative margin of the charge condition, ``N/N_min − 1`` (> 0: oscillates).

    Parameters
    ----------
    r_ohm : float or array_like
        R_A = R_B = R. [Ω]
    r_fsr_ohm : float or array_like
        FSR resistance (``inf`` allowed). [Ω]
    diode_drop_v, vcc_v, upper_fraction
        As in :func:`astable`.

    Returns
    -------
    float or ndarray
        ``N/N_min − 1``; ``-1`` when the diode drop leaves no headroom at all. [1]
    """
    check_positive("r_ohm", r_ohm, "Ω")
    check_r_fsr(r_fsr_ohm)
    n = float_array("r_fsr_ohm", r_fsr_ohm) / float_array("r_ohm", r_ohm)
    n_min = minimum_n_ratio(diode_drop_v, vcc_v, upper_fraction)
    out = np.full(np.shape(n), -1.0) if math.isinf(n_min) else n / n_min - 1.0
    return out[()] if np.ndim(out) == 0 else out


def astable(r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad=0.0, diode: bool = False, diode_drop_v: float = 0.0,
            vcc_v: float = 5.0, lower_fraction: float = 1 / 3, upper_fraction: float = 2 / 3,
            check: bool = True, discharge_ohm=0.0) -> AstableResult:
    """Closed-form steady-state τH, τL, frequency and duty cycle of the FSR-timed LM555 astable.

    Parameters
    ----------
    r_ohm : float or array_like
        R_A = R_B = R (> 0). [Ω]
    r_fsr_ohm : float or array_like
        FSR resistance R_FSR (> 0; ``inf`` for an ideal capacitor, which gives the classic 555). [Ω]
    c_fsr_farad : float or array_like
        FSR capacitance C_FSR (≥ 0). [F]
    c_off_farad : float or array_like
        Offset capacitor in parallel with the FSR (≥ 0); C = C_FSR + C_off must be > 0. [F]
    diode : bool
        D1 in series with R_B (paper Figs. 13 and 16).
    diode_drop_v : float
        Constant forward drop of D1 during the charge; 0 is the paper's ideal diode. Needs
        ``diode=True``. [V]
    vcc_v : float
        Supply voltage. [V]
    lower_fraction, upper_fraction : float
        Trigger and threshold levels as fractions of Vcc (1/3 and 2/3 by default; the control pin
        moves them). Must satisfy 0 < lower < upper < 1. [1]
    check : bool
        True (default): raise :class:`NoOscillationError` if any element does not oscillate.
        False: return NaN for frequency and duty cycle (and for the affected τ) where the circuit
        does not oscillate, with ``oscillates`` False there.
    discharge_ohm : float or array_like
        On-resistance of the discharge transistor (pin 7), ≥ 0; 0 (default) is the paper's ideal
        switch. An extension: it only matters without D1 (with D1 the diode blocks R_B during the
        discharge). A real LM555 saturates at some tens of ohms at sub-mA currents. [Ω]

    Returns
    -------
    AstableResult
        Scalars when every input is scalar, otherwise broadcast arrays.

    Raises
    ------
    ParameterError
        A parameter out of range (its ``parameter`` names it).
    TypeError
        A part that is not a number (the message names it).
    NoOscillationError
        ``check=True`` and the circuit does not oscillate for some element: the message names the
        condition (charge target below the upper threshold, diode drop too large, or no discharge
        path) and the shortfall.

    Notes
    -----
    With ``N = R_FSR/R``, ``Vs = Vcc − V_D``, ``V∞ = Vs·N/(N + 2)``, thresholds ``V_ℓ = ℓ·Vcc`` and
    ``V_u = u·Vcc`` (ideal discharge switch)::

        τH = C·(2R ∥ R_FSR)·ln((V∞ − V_ℓ)/(V∞ − V_u))     # Eq. (23) for V_D = 0, ℓ = 1/3, u = 2/3
        τL = C·(R ∥ R_FSR)·ln(u/ℓ)                         # Eq. (26), no diode
        τL = C·R_FSR·ln(u/ℓ)                               # Eq. (34), with D1
        f = 1/(τH + τL),  DC = τH/(τH + τL)                 # Eqs. (27), (28), (35), (36)

    Oscillation needs ``V∞ > V_u``, i.e. ``N > N_min = 2uVcc/(Vs − uVcc)`` (eq. 30: N > 4), which
    in turn needs ``V_D < (1 − u)·Vcc``; with D1, R_FSR must be finite (else C never discharges).
    As ``R_FSR → ∞`` without diode this tends to the classic ``f = 1/(3 ln 2·R·C) ≈ 1.44/(3RC)``
    (eq. 19 with R_A = R_B = R).

    With a discharge on-resistance R_d and no diode, pin 7 is a source ``V_T = Vcc·R_d/(R + R_d)``
    behind ``R_T = R ∥ R_d``; C discharges toward ``V_T·R_FSR/(R + R_T + R_FSR)`` through
    ``(R + R_T) ∥ R_FSR``, ``τL = C·((R + R_T) ∥ R_FSR)·ln((V_u − V∞,dis)/(V_ℓ − V∞,dis))``, and the
    discharge must end below the lower threshold (``V∞,dis < V_ℓ``).

    References
    ----------
    Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.

    Examples
    --------
    The paper's circuit (R = 10 kΩ, ideal D1) with R_FSR = 200 kΩ and C_FSR = 1 nF:

    >>> r = astable(10e3, 200e3, 1e-9, diode=True)
    >>> print(f"{r.frequency_hz:.1f} Hz, duty cycle {r.duty_cycle:.4f}")
    6478.5 Hz, duty cycle 0.1019

    Without D1 and with R_FSR → ∞, the classic ``f = 1/(3 ln 2·R·C)`` (48089.8 Hz here):

    >>> print(f"{astable(10e3, 1e12, 1e-9).frequency_hz:.1f} Hz")
    48089.8 Hz
    """
    check_lm555(r_ohm, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, discharge_ohm)
    r = float_array("r_ohm", r_ohm)
    rf = float_array("r_fsr_ohm", r_fsr_ohm)
    cf = float_array("c_fsr_farad", c_fsr_farad)
    co = float_array("c_off_farad", c_off_farad)
    rd = float_array("discharge_ohm", discharge_ohm)
    if np.any(np.isnan(rf)) or np.any(rf <= 0):
        raise ParameterError(f"must be > 0 Ω (inf allowed), got {r_fsr_ohm!r}", parameter="r_fsr_ohm")
    if np.any(~np.isfinite(cf)) or np.any(cf < 0):
        raise ParameterError(f"must be finite and >= 0 F, got {c_fsr_farad!r}", parameter="c_fsr_farad")
    c = cf + co
    if np.any(c <= 0):
        raise ParameterError("the timing capacitance C_FSR + C_off must be > 0 F", parameter="c_fsr_farad")
    r, rf, c, rd = broadcast(("r_ohm", r), ("r_fsr_ohm", rf), ("c_fsr_farad", c), ("discharge_ohm", rd))
    n = rf / r
    n_min = minimum_n_ratio(diode_drop_v, vcc_v, upper_fraction)
    th_rc, tl_rc = timing_per_rc(n, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, rd / r)
    # A relative guard of 1e-12 keeps N = N_min (e.g. exactly 4, eq. 30) on the non-oscillating side
    # despite rounding of the thresholds; there τH would be infinite anyway.
    ok_charge = (n > n_min * (1.0 + 1e-12)) & np.isfinite(th_rc)
    ok_discharge = np.isfinite(tl_rc)
    ok = ok_charge & ok_discharge
    if check and not np.all(ok):
        _raise_no_oscillation(n, n_min, ok_charge, ok_discharge, diode_drop_v, vcc_v, upper_fraction, diode,
                              lower_fraction)
    rc = r * c
    with np.errstate(invalid="ignore"):
        th = np.where(ok_charge, th_rc * rc, np.nan)
        tl = np.where(ok_discharge, tl_rc * rc, np.nan)
        period = np.where(ok, th + tl, np.nan)
        f = 1.0 / period
        dc = th / period

    def out(a):
        return a[()] if a.ndim == 0 else a

    return AstableResult(frequency_hz=out(f), duty_cycle=out(dc), tau_high_s=out(th), tau_low_s=out(tl),
                         n_ratio=out(n), oscillates=out(ok))


def _raise_no_oscillation(n, n_min, ok_charge, ok_discharge, diode_drop_v, vcc_v, upper_fraction, diode=True,
                          lower_fraction=1 / 3):
    bad = ~(ok_charge & ok_discharge)
    count, total = int(np.count_nonzero(bad)), int(bad.size)
    where = "" if total == 1 else f" ({count} of {total} elements; first at index {np.argwhere(bad)[0].tolist()})"
    if math.isinf(n_min):
        raise NoOscillationError.for_diode_drop(diode_drop_v, vcc_v, upper_fraction, where)
    if not np.all(ok_charge):
        idx = np.unravel_index(np.argmin(np.where(ok_charge, np.inf, n)), n.shape)
        worst = float(n[idx])
        short = 1.0 - worst / n_min
        raise NoOscillationError(
            f"no oscillation: the charge target stays below the upper threshold {upper_fraction * vcc_v:.4g} V; "
            f"N = R_FSR/R = {worst:.4g} must exceed {n_min:.4g} (short by {100 * short:.3g} %; "
            f"make R < R_FSR/{n_min:.4g}){where}", "charge", short, "r_fsr_ohm")
    if diode:
        raise NoOscillationError(
            f"no oscillation: with the diode C can discharge only through R_FSR, which is infinite{where}",
            "discharge", math.inf, "r_fsr_ohm")
    raise NoOscillationError(
        f"no oscillation: the discharge transistor's resistance holds the capacitor above the lower threshold "
        f"{lower_fraction * vcc_v:.4g} V{where}", "discharge", math.nan, "discharge_ohm")


# --------------------------------------------------------------------------------------------------
# Sensitivities
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Sensitivity:
    """Logarithmic sensitivities of the output to the FSR's two parts.

    Attributes
    ----------
    c_fsr : float or ndarray
        ``∂ln f/∂ln C_FSR = −C_FSR/(C_FSR + C_off)``. [1]
    r_fsr : float or ndarray
        ``∂ln f/∂ln R_FSR`` (0 for an ideal capacitor; → −1 for the diode variant at large N,
        where ``f ≈ 1/(ln 2·R_FSR·C)``). [1]
    duty_r_fsr : float or ndarray
        ``∂ln DC/∂ln R_FSR`` (DC does not depend on C). [1]
    """

    c_fsr: np.ndarray | float
    r_fsr: np.ndarray | float
    duty_r_fsr: np.ndarray | float


def sensitivity(r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad=0.0, diode: bool = False, diode_drop_v: float = 0.0,
                vcc_v: float = 5.0, lower_fraction: float = 1 / 3, upper_fraction: float = 2 / 3,
                check: bool = True, discharge_ohm=0.0) -> Sensitivity:
    """How much of a frequency change comes from C_FSR and how much from R_FSR.

    Parameters
    ----------
    r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, check
        As in :func:`astable`. [Ω, Ω, F, F, -, V, V, 1, 1, -]
    discharge_ohm : float or array_like
        Discharge-transistor on-resistance, as in :func:`astable`. [Ω]

    Returns
    -------
    Sensitivity

    Notes
    -----
    With ``x = R_FSR``, ``a = 2R∥x``, ``V∞ = Vs·x/(2R + x)`` and ``Λ = ln((V∞ − V_ℓ)/(V∞ − V_u))``
    (so τH = C·a·Λ, eq. 23)::

        x ∂τH/∂x = τH·2R/(2R + x) + C·a·V∞·(2R/(2R + x))·(V_ℓ − V_u)/((V∞ − V_ℓ)(V∞ − V_u))
        x ∂τL/∂x = τL·R/(R + x)   (no diode, eq. 26);   = τL   (diode, eq. 34)
        with R_d > 0 and no diode (b = R + R_T, V∞d = V_T·x/(b + x), R_th = b∥x):
        x ∂τL/∂x = τL·b/(b + x) + C·R_th·V∞d·(b/(b + x))·(V_u − V_ℓ)/((V_u − V∞d)(V_ℓ − V∞d))
        ∂ln f/∂ln x = −(x ∂τH/∂x + x ∂τL/∂x)/(τH + τL)

    f is proportional to 1/C with ``C = C_FSR + C_off``, hence ``∂ln f/∂ln C_FSR = −C_FSR/C``.
    """
    res = astable(r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction,
                  upper_fraction, check=check, discharge_ohm=discharge_ohm)
    x = float_array("r_fsr_ohm", r_fsr_ohm)
    cf = float_array("c_fsr_farad", c_fsr_farad)
    c = cf + float_array("c_off_farad", c_off_farad)
    th, tl = np.asarray(res.tau_high_s), np.asarray(res.tau_low_s)
    charge, discharge = thevenin(r_ohm, x, diode, diode_drop_v, vcc_v, discharge_ohm)
    v_lo, v_hi = lower_fraction * vcc_v, upper_fraction * vcc_v
    with np.errstate(invalid="ignore", divide="ignore"):
        finite = np.isfinite(x)
        xf = np.where(finite, x, 1.0)
        # x·∂V∞/∂x = V∞·w and x·∂R_th/∂x = R_th·w with w = R_drive/(R_drive + x) (0 when x = inf).
        w2 = np.where(finite, charge.drive_ohm / (charge.drive_ohm + xf), 0.0)
        a, vinf = charge.resistance_ohm, charge.source_v
        dth = th * w2 + c * a * vinf * w2 * (v_lo - v_hi) / ((vinf - v_lo) * (vinf - v_hi))
        if diode:
            dtl = tl
        else:
            b = discharge.drive_ohm  # R_B + R_T [Ω]
            wb = np.where(finite, b / (b + xf), 0.0)
            r_th, v_d = discharge.resistance_ohm, discharge.source_v
            dtl = tl * wb + c * r_th * v_d * wb * (v_hi - v_lo) / ((v_hi - v_d) * (v_lo - v_d))
        s_r = -(dth + dtl) / (th + tl)
        s_dc = dth / th - (dth + dtl) / (th + tl)
        s_c = -cf / c

    def out(v):
        v = np.asarray(v, dtype=float)
        return v[()] if v.ndim == 0 else v

    return Sensitivity(c_fsr=out(np.broadcast_to(s_c, np.shape(s_r))), r_fsr=out(s_r), duty_r_fsr=out(s_dc))
