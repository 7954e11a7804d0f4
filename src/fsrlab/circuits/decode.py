"""Dual decoding of an LM555 reading: (frequency, duty cycle) → (R_FSR, C_FSR), with its uncertainty.

The duty cycle depends on ``N = R_FSR/R`` alone (paper eqs. 28, 36), so it fixes R_FSR; the
frequency then fixes the timing capacitance. The uncertainty is the Uno's timer quantization
(:data:`fsrlab.hardware.TICK_S`) propagated through the inversion.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, eqs. (27)–(36).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsrlab.circuits.checks import check_lm555, check_single
from fsrlab.circuits.lm555 import NoOscillationError, minimum_n_ratio
from fsrlab.circuits.phases import timing_per_rc
from fsrlab.errors import ParameterError
from fsrlab.hardware import TICK_S
from fsrlab.physics.params import check_at_least, float_array

__all__ = ["DecodeResult", "decode"]


@dataclass(frozen=True)
class DecodeResult:
    """FSR parts recovered from a measured frequency and duty cycle.

    Attributes
    ----------
    r_fsr_ohm : float or ndarray
        FSR resistance (``inf`` when DC sits exactly at the N → ∞ limit). [Ω]
    c_fsr_farad : float or ndarray
        FSR capacitance. [F]
    r_fsr_std_ohm : float or ndarray
        Standard uncertainty of R_FSR from timer quantization. [Ω]
    c_fsr_std_farad : float or ndarray
        Standard uncertainty of C_FSR from timer quantization. [F]
    n_ratio : float or ndarray
        ``N = R_FSR/R``. [1]
    """

    r_fsr_ohm: np.ndarray | float
    c_fsr_farad: np.ndarray | float
    r_fsr_std_ohm: np.ndarray | float
    c_fsr_std_farad: np.ndarray | float
    n_ratio: np.ndarray | float

    def plot(self, ax=None, x=None, xlabel: str | None = None):
        """R_FSR and C_FSR with their ±1σ bands versus ``x`` (default the sample index), C_FSR on a twin y axis.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes for R_FSR (default: a new figure).
        x : array_like, optional
            Abscissa, one value per element of a 1-D result, e.g. the readings' times or the
            reference force (default: the index 0, 1, ...).
        xlabel : str, optional
            Label of the x axis (default: ``"sample"`` for the default ``x``).

        Returns
        -------
        (matplotlib.axes.Axes, matplotlib.axes.Axes)
            The R_FSR axes and the C_FSR axes. NaN (an impossible reading) leaves gaps.
        """
        from fsrlab.circuits.plotting import plot_twin

        if x is None:
            x, xlabel = np.arange(np.size(self.r_fsr_ohm)), "sample" if xlabel is None else xlabel
        return plot_twin(x, (self.r_fsr_ohm, self.r_fsr_std_ohm, "R_FSR", "Ω"),
                         (self.c_fsr_farad, self.c_fsr_std_farad, "C_FSR", "F"), ax=ax, xlabel=xlabel)


def _invert(f, dc, r, c_off, diode, diode_drop_v, vcc_v, lo, hi, rd_rel=0.0):
    """Vectorised inversion; returns (N, C_total) with NaN where (f, DC) is impossible."""
    rho = dc / (1.0 - dc)
    n_min = minimum_n_ratio(diode_drop_v, vcc_v, hi)
    u_hi = 1.0 / n_min  # u = 1/N in (0, 1/N_min); τH/τL rises monotonically with u

    def g(u):
        with np.errstate(divide="ignore"):
            n = np.where(u > 0, 1.0 / np.where(u > 0, u, 1.0), np.inf)
        th, tl = timing_per_rc(n, diode, diode_drop_v, vcc_v, lo, hi, rd_rel)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(u > 0, th / tl, 0.0 if diode else th / tl)

    g0 = g(np.zeros(1))[0]
    a = np.zeros_like(rho)
    b = np.full_like(rho, u_hi)
    for _ in range(64):  # 2^-64 of 1/N_min: N to ~1e-15 relative up to N ~ 1e3·N_min
        m = 0.5 * (a + b)
        below = g(m) < rho
        a = np.where(below, m, a)
        b = np.where(below, b, m)
    u = 0.5 * (a + b)
    with np.errstate(divide="ignore"):
        n = np.where(u > 0, 1.0 / np.where(u > 0, u, 1.0), np.inf)
    possible = rho > g0
    n = np.where(possible, n, np.nan)
    # Impossible pairs (NaN N) are masked by the caller; C is taken at the N → ∞ limit there.
    th, tl = timing_per_rc(np.where(possible, n, np.inf), diode, diode_drop_v, vcc_v, lo, hi, rd_rel)
    c_total = 1.0 / (f * r * (th + tl))
    return n, c_total, float(g0 / (1.0 + g0))


def _broadcast(f, dc, n_per):
    try:
        return np.broadcast_arrays(f, dc, n_per)
    except ValueError:
        raise ParameterError(f"shape {dc.shape} does not broadcast with frequency_hz's {f.shape} (and periods' "
                             f"{n_per.shape})", parameter="duty_cycle") from None


def decode(frequency_hz, duty_cycle, r_ohm: float, c_off_farad: float = 0.0, diode: bool = False,
           diode_drop_v: float = 0.0, vcc_v: float = 5.0, lower_fraction: float = 1 / 3,
           upper_fraction: float = 2 / 3, periods=1, timer_resolution_s: float = TICK_S,
           check: bool = True, discharge_ohm: float = 0.0) -> DecodeResult:
    """Recover R_FSR and C_FSR from a measured frequency and duty cycle (the paper's "dual decoding").

    Parameters
    ----------
    frequency_hz : float or array_like
        Measured output frequency (> 0). [Hz]
    duty_cycle : float or array_like
        Measured output-high fraction, in (0, 1). [1]
    r_ohm : float
        R_A = R_B = R of the circuit. [Ω]
    c_off_farad : float
        Offset capacitor in parallel with the FSR. [F]
    diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction
        The circuit variant, as in :func:`astable`.
    periods : int or array_like
        Number of periods averaged into the measurement (≥ 1), e.g. the ``periods`` field of a
        protocol ``M`` frame.
    timer_resolution_s : float
        Timer tick (62.5 ns for Timer1 of an Uno at 16 MHz, prescaler 1). [s]
    check : bool
        True (default): an impossible (f, DC) pair raises. False: NaN for that element (useful for
        noisy measured series whose duty cycle can dip below the circuit's limit).
    discharge_ohm : float
        Discharge-transistor on-resistance, as in :func:`astable`. [Ω]

    Returns
    -------
    DecodeResult

    Raises
    ------
    ParameterError
        A parameter out of range, or an (f, DC) pair the circuit cannot produce: a duty cycle at or
        below the circuit's infimum (2/3 without the diode for default thresholds, see
        :func:`duty_cycle_limits`), or a frequency so high that C = C_FSR + C_off would be smaller
        than C_off (C_FSR < 0). The message names the pair and the limit.

    Notes
    -----
    DC depends on ``N = R_FSR/R`` alone (eqs. 28, 36) and falls monotonically with N, so N is
    found by bisection on ``1/N``; then ``C = 1/(f·(τH + τL)/C)`` and ``C_FSR = C − C_off``.
    Uncertainty: each captured edge is quantized to one tick (uniform error, standard deviation
    ``q/√12``, independent between edges). Averaged over n periods from n + 1 rising and n falling
    edges, the mean period ``T̄ = (r_n − r_0)/n`` and the mean high time ``H̄ = Σ(f_i − r_i)/n`` have
    ``var T̄ = 2σ²/n²``, ``var H̄ = 2σ²/n``, ``cov = σ²/n²``; these are propagated through the
    inversion with a numerical Jacobian (first order). Independence is an assumption: for a
    555 whose period is a fixed non-integer number of ticks, the errors of one window are tied
    to one clock phase and spread less (a Monte-Carlo with one random phase per window gave 0.6× the
    stated σ for R = 10 kΩ, R_FSR = 200 kΩ, C = 1 nF, 4 periods), so the stated σ is conservative.
    """
    check_single(("r_ohm", r_ohm), ("c_off_farad", c_off_farad), ("discharge_ohm", discharge_ohm))
    check_lm555(r_ohm, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, discharge_ohm)
    check_at_least("timer_resolution_s", timer_resolution_s, 0.0, "s", scalar=True)
    f = float_array("frequency_hz", frequency_hz)
    dc = float_array("duty_cycle", duty_cycle)
    n_per = float_array("periods", periods)
    if np.any(~np.isfinite(f)) or np.any(f <= 0):
        raise ParameterError(f"must be finite and > 0 Hz, got {frequency_hz!r}", parameter="frequency_hz")
    if np.any(~np.isfinite(dc)) or np.any(dc <= 0) or np.any(dc >= 1):
        raise ParameterError(f"must be in (0, 1), got {duty_cycle!r}", parameter="duty_cycle")
    if np.any(~np.isfinite(n_per)) or np.any(n_per < 1):
        raise ParameterError(f"must be >= 1, got {periods!r}", parameter="periods")
    if math.isinf(minimum_n_ratio(diode_drop_v, vcc_v, upper_fraction)):
        raise NoOscillationError.for_diode_drop(diode_drop_v, vcc_v, upper_fraction)
    f, dc, n_per = _broadcast(f, dc, n_per)
    check_at_least("discharge_ohm", discharge_ohm, 0.0, "Ω")
    args = (r_ohm, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, discharge_ohm / r_ohm)
    n, c_total, dc_min = _invert(f, dc, *args)
    bad = np.isnan(n)
    if check and np.any(bad):
        i = np.argwhere(bad)[0]
        raise ParameterError(
            f"{float(dc[tuple(i)]):.6g} cannot come from this circuit "
            f"({'with' if diode else 'without'} diode its duty cycle is always above {dc_min:.6g}, reached only "
            f"as R_FSR → ∞){'' if bad.size == 1 else f' (element {i.tolist()})'}", parameter="duty_cycle")
    c_fsr = c_total - c_off_farad
    # Rounding of the bisection can leave -1e-16-level negatives when C_FSR is truly 0.
    neg = c_fsr < -1e-12 * c_total
    if check and np.any(neg):
        i = tuple(np.argwhere(neg)[0])
        raise ParameterError(
            f"{c_off_farad:.4g} F is more than the whole timing capacitance C = {float(c_total[i]):.4g} F that "
            f"{float(f[i]):.6g} Hz at duty cycle {float(dc[i]):.6g} needs (C_FSR would be negative)",
            parameter="c_off_farad")
    c_fsr = np.where(neg | bad, np.nan, np.maximum(c_fsr, 0.0))
    r_fsr = np.where(neg | bad, np.nan, n * r_ohm)

    # Quantization uncertainty, propagated with a central-difference Jacobian in (T, H).
    sigma = timer_resolution_s / math.sqrt(12.0)
    t_per = 1.0 / f
    h = dc * t_per
    var_t = 2 * sigma**2 / n_per**2
    var_h = 2 * sigma**2 / n_per
    cov = sigma**2 / n_per**2
    step = 1e-7 * t_per

    def parts(tt, hh):
        with np.errstate(invalid="ignore", divide="ignore"):
            nn, cc, _ = _invert(1.0 / tt, hh / tt, *args)
        return nn * r_ohm, cc - c_off_farad

    rp_t, cp_t = parts(t_per + step, h)
    rm_t, cm_t = parts(t_per - step, h)
    rp_h, cp_h = parts(t_per, h + step)
    rm_h, cm_h = parts(t_per, h - step)
    with np.errstate(invalid="ignore"):
        drt, dct = (rp_t - rm_t) / (2 * step), (cp_t - cm_t) / (2 * step)
        drh, dch = (rp_h - rm_h) / (2 * step), (cp_h - cm_h) / (2 * step)
        r_std = np.sqrt(drt**2 * var_t + drh**2 * var_h + 2 * drt * drh * cov)
        c_std = np.sqrt(dct**2 * var_t + dch**2 * var_h + 2 * dct * dch * cov)

    def out(v):
        v = np.asarray(v, dtype=float)
        return v[()] if v.ndim == 0 else v

    return DecodeResult(r_fsr_ohm=out(r_fsr), c_fsr_farad=out(c_fsr), r_fsr_std_ohm=out(r_std),
                        c_fsr_std_farad=out(c_std), n_ratio=out(n))
