"""Designing the LM555 readout for a sensor: R, C_off and the variant that keep its frequencies in a band.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5 (Figs. 13, 16).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from fsrlab.circuits.lm555 import astable, minimum_n_ratio, sensitivity
from fsrlab.errors import ParameterError
from fsrlab.hardware import CAPTURE_MAX_HZ, TICK_S
from fsrlab.physics.params import check_at_least, check_positive, float_array, plain

__all__ = ["E12", "DesignResult", "design"]


#: E12 mantissas (IEC 60063), used for the proposed R and C_off.
E12 = (1.0, 1.2, 1.5, 1.8, 2.2, 2.7, 3.3, 3.9, 4.7, 5.6, 6.8, 8.2)


@dataclass(frozen=True)
class DesignResult:
    """A proposed circuit for a sensor range and a wanted frequency band.

    Attributes
    ----------
    diode : bool
        Variant: D1 in series with R_B or not.
    r_ohm : float
        Proposed R_A = R_B = R (E12 value). [Ω]
    c_off_farad : float
        Proposed offset capacitor (E12 value or 0). [F]
    frequency_range_hz : tuple of float
        Lowest and highest frequency over the sensor range. [Hz]
    duty_cycle_range : tuple of float
        Lowest and highest duty cycle over the sensor range. [1]
    margin : float
        Smallest oscillation margin ``N/N_min − 1`` over the range. [1]
    sensitivity_c_range : tuple of float
        Range of ∂ln f/∂ln C_FSR over the sensor range. [1]
    sensitivity_r_range : tuple of float
        Range of ∂ln f/∂ln R_FSR over the sensor range. [1]
    capacitive_share : float
        Smallest ``|S_C|/(|S_C| + |S_R|)`` over the range: 1 = the frequency reads only C_FSR. [1]
    merit : float
        Smallest ``|S_C| − |S_R|`` over the range (what the design maximises). [1]
    resolution_single_hz : tuple of float
        Frequency step of one timer tick in a single-period measurement at the low and high ends
        of the wanted band, ``f²·q``. [Hz]
    resolution_window_hz : tuple of float
        Frequency step of one tick in the period sum of a window of ``window_s`` at the band ends,
        ``f·q/(n/f)`` with ``n = floor(f·window)`` whole periods. [Hz]
    range_resolution_single_hz, range_resolution_window_hz : tuple of float
        The same at the ends of the proposal's frequency range. [Hz]
    band_hz : tuple of float
        The band the frequencies were kept in: the wanted band, its top lowered to
        ``max_frequency_hz`` where it was above. [Hz]
    window_s : float
        Measurement window assumed for ``resolution_window_hz``. [s]
    alternatives : list of dict
        The best design of each variant that was considered (for comparison).
    max_frequency_hz : float
        Highest frequency the counter captures every edge of, that the design respected. [Hz]
    """

    diode: bool
    r_ohm: float
    c_off_farad: float
    frequency_range_hz: tuple
    duty_cycle_range: tuple
    margin: float
    sensitivity_c_range: tuple
    sensitivity_r_range: tuple
    capacitive_share: float
    resolution_single_hz: tuple
    resolution_window_hz: tuple
    window_s: float
    alternatives: list
    merit: float = math.nan
    range_resolution_single_hz: tuple = (math.nan, math.nan)
    range_resolution_window_hz: tuple = (math.nan, math.nan)
    band_hz: tuple = (math.nan, math.nan)
    max_frequency_hz: float = CAPTURE_MAX_HZ


def _e12(lo: float, hi: float) -> np.ndarray:
    vals = [m * 10.0**e for e in range(-13, 8) for m in E12]
    return np.array([v for v in vals if lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9)])


def design(r_fsr_range_ohm, c_fsr_range_farad, band_hz, variant: str = "auto", diode_drop_v: float = 0.0,
           vcc_v: float = 5.0, min_margin: float = 0.25, window_s: float = 0.1,
           timer_resolution_s: float = TICK_S, max_frequency_hz: float | None = CAPTURE_MAX_HZ) -> DesignResult:
    """Propose R, C_off and the variant that keep the sensor's frequencies inside a band.

    Parameters
    ----------
    r_fsr_range_ohm : (float, float)
        Smallest and largest R_FSR the sensor shows (full load, no load). [Ω]
    c_fsr_range_farad : (float, float)
        Smallest and largest C_FSR. [F]
    band_hz : (float, float)
        Wanted frequency band. [Hz]
    variant : {"auto", "diode", "no-diode"}
        Restrict the variant, or let the design choose.
    diode_drop_v : float
        Forward drop of D1 in the diode variant. [V]
    vcc_v : float
        Supply. [V]
    min_margin : float
        Required oscillation margin ``N/N_min − 1`` at the smallest R_FSR (≥ 0). [1]
    window_s : float
        Measurement window for the stated resolution (protocol default 100 ms). [s]
    timer_resolution_s : float
        Timer tick (62.5 ns on an Uno). [s]
    max_frequency_hz : float or None
        Highest frequency the counter captures every edge of; the band's top is lowered to it.
        Default: the fsrlab meter's firmware, :data:`fsrlab.hardware.CAPTURE_MAX_HZ`
        (50 kHz, measured in simavr). ``None``: no limit (another counter). [Hz]

    Returns
    -------
    DesignResult

    Raises
    ------
    ParameterError
        Bad ranges, a band that lies wholly above ``max_frequency_hz``, or no E12 pair (R in 100 Ω–10 MΩ, C_off 0 or 1
        pF–10 µF) satisfies the band and
        margin; the message says what limits it.

    Notes
    -----
    Every pair is evaluated on a grid of the sensor range (R_FSR log-spaced, both C_FSR ends; f is
    monotone in C and the grid catches the non-monotone R_FSR dependence of the diode variant).
    Among the pairs whose frequencies all lie in the band with the required margin, the design
    maximises the smallest ``|S_C| − |S_R|`` over the range (a frequency that follows C_FSR strongly
    and R_FSR weakly; a large C_off lowers |S_C| = C_FSR/(C_FSR + C_off)), then the margin. Resolution of an Uno
    (Timer1, 62.5 ns): a single
    period resolves ``Δf = f²·q``; a window averaging ``n`` periods resolves ``Δf = f·q/(n·T)``.
    """
    (rlo, rhi), (clo, chi), (flo, fhi), limit = _checked_ranges(r_fsr_range_ohm, c_fsr_range_farad, band_hz,
                                                                max_frequency_hz)
    capped = fhi > limit
    fhi = min(fhi, limit)
    if not isinstance(variant, str) or variant not in ("auto", "diode", "no-diode"):
        raise ParameterError(f"must be 'auto', 'diode' or 'no-diode', got {variant!r}", parameter="variant")
    check_at_least("min_margin", min_margin, 0.0, scalar=True)
    check_positive("window_s", window_s, "s", scalar=True)
    check_positive("vcc_v", vcc_v, "V", scalar=True)
    check_at_least("diode_drop_v", diode_drop_v, 0.0, "V", scalar=True)
    check_at_least("timer_resolution_s", timer_resolution_s, 0.0, "s", scalar=True)
    if diode_drop_v > 0 and variant == "no-diode":
        raise ParameterError("a forward drop needs the diode variant", parameter="diode_drop_v")
    variants = {"auto": (False, True), "diode": (True,), "no-diode": (False,)}[variant]

    rf = np.geomspace(rlo, rhi, 24) if rhi > rlo else np.array([rlo])
    cf = np.array([clo, chi]) if chi > clo else np.array([clo])
    rf_g, cf_g = np.meshgrid(rf, cf, indexing="ij")
    best_per_variant = {}
    reasons = []
    for diode in variants:
        best = _best_pair(diode, diode_drop_v if diode else 0.0, vcc_v, rlo, min_margin, rf_g, cf_g, (flo, fhi))
        if isinstance(best, str):
            reasons.append(best)
        else:
            best_per_variant[diode] = best
    if not best_per_variant:
        cap = f" (its top lowered to max_frequency_hz = {limit:g} Hz)" if capped else ""
        raise ParameterError(f"no design keeps the sensor (R_FSR {rlo:g} … {rhi:g} Ω, C_FSR {clo:g} … {chi:g} F) "
                             f"inside the band{cap}: " + "; ".join(reasons), parameter="band_hz")
    chosen = max(best_per_variant.values(), key=lambda d: (d["merit"], d["margin"]))
    q = timer_resolution_s

    def single(ends):
        return tuple(fe**2 * q for fe in ends)

    def window(ends):
        # n whole periods in the window (at least one); a window too long for floor() holds "infinitely" many.
        periods = [fe * window_s for fe in ends]
        whole = [max(math.floor(n), 1) if math.isfinite(n) else n for n in periods]
        return tuple(fe * q / (w / fe) for fe, w in zip(ends, whole, strict=True))

    rng = chosen["frequency_range_hz"]
    return DesignResult(**chosen, resolution_single_hz=single((flo, fhi)), resolution_window_hz=window((flo, fhi)),
                        range_resolution_single_hz=single(rng), range_resolution_window_hz=window(rng),
                        band_hz=(flo, fhi), window_s=window_s, alternatives=list(best_per_variant.values()),
                        max_frequency_hz=limit)


def _pair(name: str, value) -> tuple[float, float]:
    """A (low, high) pair of numbers, or an error naming ``name``."""
    x = float_array(name, value)
    if x.shape != (2,):
        raise ParameterError(f"must be a (low, high) pair, got {plain(value)}", parameter=name)
    return float(x[0]), float(x[1])


def _checked_ranges(r_fsr_range_ohm, c_fsr_range_farad, band_hz, max_frequency_hz):
    """The sensor's R and C ranges, the band and the counter's limit, checked; ``(r, c, band, limit)``."""
    rlo, rhi = _pair("r_fsr_range_ohm", r_fsr_range_ohm)
    clo, chi = _pair("c_fsr_range_farad", c_fsr_range_farad)
    flo, fhi = _pair("band_hz", band_hz)
    if not (0 < rlo <= rhi and math.isfinite(rhi)):
        raise ParameterError(f"need 0 < min <= max < inf, got {r_fsr_range_ohm!r}", parameter="r_fsr_range_ohm")
    if not (0 < clo <= chi and math.isfinite(chi)):
        raise ParameterError(f"need 0 < min <= max < inf, got {c_fsr_range_farad!r}", parameter="c_fsr_range_farad")
    if not (0 < flo < fhi and math.isfinite(fhi)):
        raise ParameterError(f"need 0 < low < high < inf, got {band_hz!r}", parameter="band_hz")
    if max_frequency_hz is not None:
        check_at_least("max_frequency_hz", max_frequency_hz, 0.0, "Hz", strict=True, scalar=True)
    limit = math.inf if max_frequency_hz is None else float(max_frequency_hz)
    if flo >= limit:
        raise ParameterError(f"{flo:g} … {fhi:g} Hz is beyond what the counter captures: every edge only "
                             f"up to max_frequency_hz = {limit:g} Hz", parameter="band_hz")
    return (rlo, rhi), (clo, chi), (flo, fhi), limit


def _best_pair(diode: bool, vd: float, vcc_v: float, rlo: float, min_margin: float, rf_g, cf_g, band):
    """The best E12 (R, C_off) of one variant over the sensor grid, as DesignResult fields; or why none fits."""
    flo, fhi = band
    name = "diode" if diode else "no-diode"
    n_min = minimum_n_ratio(vd, vcc_v)
    if math.isinf(n_min):
        return "the diode drop leaves no headroom"
    r_max = rlo / (n_min * (1 + min_margin))
    rs = _e12(100.0, min(r_max, 10e6))
    if rs.size == 0:
        return f"{name}: R would have to be below 100 Ω for the margin"
    c_offs = np.concatenate([[0.0], _e12(1e-12, 10e-6)])
    # Pair every (R, C_off) with every sensor grid point (not the full 4-D product of rf, cf).
    R = rs[:, None, None] * np.ones((1, c_offs.size, rf_g.size))
    CO = c_offs[None, :, None] * np.ones_like(R)
    RF = np.broadcast_to(rf_g.ravel()[None, None, :], R.shape)
    CF = np.broadcast_to(cf_g.ravel()[None, None, :], R.shape)
    # Pairs that do not oscillate, and extreme sensor ranges, give NaN or inf here (check=False):
    # they fail the band test below, so numpy's warnings about them say nothing.
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # nanmin/nanmax of an all-NaN row
        res = astable(R, RF, CF, CO, diode=diode, diode_drop_v=vd, vcc_v=vcc_v, check=False)
        sens = sensitivity(R, RF, CF, CO, diode=diode, diode_drop_v=vd, vcc_v=vcc_v, check=False)
        f = res.frequency_hz
        ok = np.all(np.isfinite(f) & (f >= flo) & (f <= fhi), axis=2)
        share = np.min(np.abs(sens.c_fsr) / (np.abs(sens.c_fsr) + np.abs(sens.r_fsr)), axis=2)
        # Capacitive readout quality: the part of ∂ln f that comes from C_FSR, minus the part from R_FSR.
        merit = np.min(np.abs(sens.c_fsr) - np.abs(sens.r_fsr), axis=2)
        span = np.nanmin(np.nanmax(f, axis=2) / np.nanmin(f, axis=2)) if not np.any(ok) else math.nan
    if not np.any(ok):
        why = (f"the sensor's frequencies span at least a factor {span:.3g}, wider than the band's {fhi / flo:.3g}"
               if span > fhi / flo else "no E12 R and C_off place the sensor's frequencies inside the band")
        return f"{name} circuit: {why} (R ≤ {rs.max():.3g} Ω for the margin)"
    margin_rc = rlo / R[:, :, 0] / n_min - 1.0  # the smallest R_FSR is the worst case
    score = np.where(ok, merit + 1e-6 * np.minimum(margin_rc, 100.0), -np.inf)
    i, j = np.unravel_index(np.argmax(score), score.shape)
    fi = f[i, j]
    return dict(
        diode=diode, r_ohm=float(rs[i]), c_off_farad=float(c_offs[j]),
        frequency_range_hz=(float(fi.min()), float(fi.max())),
        duty_cycle_range=(float(res.duty_cycle[i, j].min()), float(res.duty_cycle[i, j].max())),
        margin=float(margin_rc[i, j]),
        sensitivity_c_range=(float(sens.c_fsr[i, j].min()), float(sens.c_fsr[i, j].max())),
        sensitivity_r_range=(float(sens.r_fsr[i, j].min()), float(sens.r_fsr[i, j].max())),
        capacitive_share=float(share[i, j]),
        merit=float(merit[i, j]),
    )
