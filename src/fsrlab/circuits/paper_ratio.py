"""τH/τL versus N = R_FSR/R as the paper prints it and as its own equations give it (errata O1–O3).

The paper's §5 derives τH/τL of the FSR-timed LM555 without the diode, eq. (32), and with the diode
D1, eq. (37). Both printed equations carry an extra factor N over the ratio that follows from the
paper's own τH and τL (eqs. 23 with 26, and 23 with 34), as if τL had been divided by N. The quoted
minimum 24.37 (DC ≥ 0.96) and Figure 12 follow from eq. (32) as printed; the circuit's ratio falls
monotonically toward 2 and has no minimum. This module gives the printed forms, the minimum of the
printed eq. (32), the corrected columns over N (via :func:`fsrlab.circuits.lm555.tau_ratio`) and an
ngspice check of them (docs/errata.md, O1–O3).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eqs. (23), (26), (32), (34),
(37), Figures 12 and 15.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fsrlab.circuits.lm555 import tau_ratio
from fsrlab.circuits.spice import simulate_spice_many, start_spice_many
from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_finite, check_positive, float_array, plain

__all__ = [
    "tau_ratio_eq32_as_printed",
    "tau_ratio_eq37_as_printed",
    "tau_ratio_times_n",
    "RatioMinimum",
    "minimum_eq32_as_printed",
    "n_where_ratio_equals",
    "TauRatioTable",
    "tau_ratio_table",
    "SimulatedRatios",
    "simulate_tau_ratios",
    "TauRatioRuns",
    "start_tau_ratios",
]


def tau_ratio_eq32_as_printed(n_ratio):
    """The paper's eq. (32) as printed: ``ln((2 − 2N)/(4 − N))·2N(N + 1)/(ln 2·(N + 2))``.

    Parameters
    ----------
    n_ratio : float or array_like
        ``N = R_FSR / R``, > 4 for a real value. [1]

    Returns
    -------
    float or ndarray
        The printed expression; NaN for 1 < N ≤ 4 where the logarithm's argument is negative. [1]

    Notes
    -----
    The extracted text reads "ln 2 − 2N / 4 −N 2N N + 1 / ln 2 N + 2", the same layout as eq. (37)
    ("ln 2 − 2N / 4 −N 2N / ln 2 N + 2") with the factor ``N + 1`` added, so the numerator is
    ``2N·(N + 1)``. This is N times the ratio that follows from eqs. (23) and (26),
    ``2·ln((2N − 2)/(N − 4))·(N + 1)/(ln 2·(N + 2))`` (:func:`fsrlab.circuits.lm555.tau_ratio`):
    the same extra factor N as eq. (37). Its minimum over N > 4 is the paper's 24.37
    (:func:`minimum_eq32_as_printed`; docs/errata.md, O1).
    """
    n = float_array("n_ratio", n_ratio)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.log((2 - 2 * n) / (4 - n)) * 2 * n * (n + 1) / (math.log(2) * (n + 2))  # Eq. (32) as printed
    return out[()] if out.ndim == 0 else out


def tau_ratio_eq37_as_printed(n_ratio):
    """The paper's eq. (37) exactly as printed: ``ln((2 − 2N)/(4 − N))·2N/(ln 2·(N + 2))``.

    Parameters
    ----------
    n_ratio : float or array_like
        ``N = R_FSR / R``, > 4 for a real value. [1]

    Returns
    -------
    float or ndarray
        The printed expression; NaN for 1 < N ≤ 4 where the logarithm's argument is negative. [1]

    Notes
    -----
    This is N times the ratio that follows from eqs. (23) and (34),
    ``2·ln((2N − 2)/(N − 4))/(ln 2·(N + 2))``; the printed form tends to 2 as N → ∞, the
    corrected one to 0 (docs/errata.md, O2).
    """
    n = float_array("n_ratio", n_ratio)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.log((2 - 2 * n) / (4 - n)) * 2 * n / (math.log(2) * (n + 2))  # Eq. (37) as printed
    return out[()] if out.ndim == 0 else out


def tau_ratio_times_n(n_ratio, diode: bool = False):
    """``N × τH/τL``: the paper's printed eqs. (32) and (37), from the circuit's ratio.

    Parameters
    ----------
    n_ratio : float or array_like
        ``N = R_FSR / R``. [1]
    diode : bool
        With the ideal diode D1 (eqs. 23 and 34); without it, eqs. (23) and (26).

    Returns
    -------
    float or ndarray
        N times :func:`fsrlab.circuits.lm555.tau_ratio`; NaN where the circuit does not
        oscillate (N ≤ 4). [1]

    Notes
    -----
    Without the diode this equals eq. (32) as printed (:func:`tau_ratio_eq32_as_printed`), with it
    eq. (37) as printed: both printed ratios are the circuit's times N, as if τL had been divided by
    N (R_FSR replaced by R in the numerators of eqs. 26 and 34).
    """
    n = float_array("n_ratio", n_ratio)
    return n * tau_ratio(n, diode=diode)


@dataclass(frozen=True)
class RatioMinimum:
    """The minimum of eq. (32) as printed (N × the circuit's τH/τL) over N > 4.

    Parameters
    ----------
    n_ratio : float
        N where the minimum lies. [1]
    value : float
        The minimum of eq. (32) as printed. [1]
    """

    n_ratio: float
    value: float

    @property
    def duty_cycle(self) -> float:
        """The duty cycle this ratio would give, ``value/(1 + value)`` (the paper's 24.37/25.37). [1]"""
        return self.value / (1.0 + self.value)

    def to_dict(self) -> dict:
        """The report's JSON shape: ``expression``, ``minimum`` and ``at_N``."""
        return {"expression": "eq. (32) as printed (= N * tau_H/tau_L of eqs. 23, 26)", "minimum": self.value,
                "at_N": self.n_ratio}


def minimum_eq32_as_printed(bounds: tuple[float, float] = (4.2, 20.0), xatol: float = 1e-10) -> RatioMinimum:
    """Minimum of eq. (32) as printed for N > 4: the paper's "minimal value 24.37".

    Parameters
    ----------
    bounds : (float, float)
        Search interval for N; the default holds the single minimum (the printed eq. (32) grows
        without bound as N → 4 and as N → ∞). [1]
    xatol : float
        Absolute tolerance in N. [1]

    Returns
    -------
    RatioMinimum

    Raises
    ------
    ParameterError
        If the bounds are not 4 < low < high.

    Notes
    -----
    Bounded scalar minimisation of :func:`tau_ratio_eq32_as_printed`: 24.3796 at N = 6.0302
    (the printed 24.37 is this truncated; 24.3796/25.3796 = 0.9606). The circuit's ratio, eqs. (23)
    and (26), has no minimum for N > 4: it falls monotonically toward 2 (docs/errata.md, O1).
    """
    b = float_array("bounds", bounds)
    if b.shape != (2,) or not (4.0 < b[0] < b[1] < np.inf):
        raise ParameterError("must be a pair 4 < low < high < inf (the circuit oscillates for N > 4), "
                             f"got {plain(bounds)}", parameter="bounds")
    lo, hi = float(b[0]), float(b[1])
    check_positive("xatol", xatol, scalar=True)
    from scipy.optimize import minimize_scalar  # here: importing the module (the report's ngspice start) stays light

    res = minimize_scalar(lambda x: float(tau_ratio_eq32_as_printed(x)), bounds=(lo, hi), method="bounded",
                          options={"xatol": xatol})
    return RatioMinimum(n_ratio=float(res.x), value=float(res.fun))


def n_where_ratio_equals(value: float) -> float:
    """The N > 4 at which the circuit's τH/τL without the diode (eqs. 23 and 26) equals ``value``.

    Parameters
    ----------
    value : float
        A ratio τH/τL, > 2 (the infimum) and at most the ratio at N = 4 + 1e-9 (about 54). [1]

    Returns
    -------
    float
        N = R_FSR / R. [1]

    Raises
    ------
    ParameterError
        If ``value`` is outside that range.

    Notes
    -----
    The ratio (eq. 32 as printed divided by N) falls monotonically from +∞ at N = 4 to 2 as N → ∞,
    so the root is unique; it is bracketed between 4 + 1e-9 and an upper N doubled from 5 until the
    ratio falls below ``value``.
    """
    lo = 4.0 + 1e-9
    check_finite("value", value)
    if np.ndim(value) or not 2.0 < value <= float(tau_ratio(lo)):
        raise ParameterError(f"must be in (2, {float(tau_ratio(lo)):.4g}] (τH/τL for N > 4 + 1e-9), got {plain(value)}",
                             parameter="value")
    hi = 5.0
    while tau_ratio(hi) > value:
        hi = 4.0 + 2.0 * (hi - 4.0)
    from scipy.optimize import brentq

    return float(brentq(lambda x: tau_ratio(x) - value, lo, hi))


@dataclass(frozen=True)
class TauRatioTable:
    """τH/τL and duty cycle versus N, with and without D1, beside eqs. (32) and (37) as printed.

    Parameters
    ----------
    n_ratio : tuple of float
        N = R_FSR / R. [1]
    no_diode : ndarray
        τH/τL without the diode, from eqs. (23) and (26). [1]
    diode : ndarray
        τH/τL with the ideal diode, from eqs. (23) and (34). [1]
    eq37_as_printed : ndarray
        The paper's eq. (37) as printed (N times ``diode``). [1]
    eq32_as_printed : ndarray
        The paper's eq. (32) as printed (N times ``no_diode``). [1]
    """

    n_ratio: tuple
    no_diode: np.ndarray
    diode: np.ndarray
    eq37_as_printed: np.ndarray
    eq32_as_printed: np.ndarray

    @property
    def duty_cycle_no_diode(self) -> np.ndarray:
        """``τH/(τH + τL)`` without the diode, eq. (28). [1]"""
        return self.no_diode / (1 + self.no_diode)

    @property
    def duty_cycle_diode(self) -> np.ndarray:
        """``τH/(τH + τL)`` with the diode, eq. (36). [1]"""
        return self.diode / (1 + self.diode)

    def to_dict(self) -> dict:
        """The columns as lists of floats, keyed as in the report's ``paper.json`` (``oscillator``)."""
        return {
            "N": list(self.n_ratio),
            "tau_ratio_no_diode": [float(v) for v in self.no_diode],
            "tau_ratio_diode": [float(v) for v in self.diode],
            "paper_eq37_as_printed": [float(v) for v in self.eq37_as_printed],
            "paper_eq32_as_printed": [float(v) for v in self.eq32_as_printed],
            "duty_cycle_no_diode": [float(v) for v in self.duty_cycle_no_diode],
            "duty_cycle_diode": [float(v) for v in self.duty_cycle_diode],
        }


def tau_ratio_table(n_ratio: Sequence[float]) -> TauRatioTable:
    """τH/τL with and without D1 and eqs. (32), (37) as printed at each N (ideal parts, default thresholds).

    Parameters
    ----------
    n_ratio : sequence of float
        N = R_FSR / R, each > 4. [1]

    Returns
    -------
    TauRatioTable

    Raises
    ------
    ParameterError
        If an N is not > 4 (the circuit would not oscillate, eq. 30).
    """
    n = np.array(float_array("n_ratio", n_ratio))
    if n.ndim != 1 or not np.all(n > 4) or not np.all(np.isfinite(n)):
        raise ParameterError(f"must be a sequence of finite values > 4 (eq. 30), got {plain(n_ratio)}",
                             parameter="n_ratio")
    return TauRatioTable(n_ratio=tuple(n_ratio), no_diode=tau_ratio(n), diode=tau_ratio(n, diode=True),
                         eq37_as_printed=tau_ratio_eq37_as_printed(n), eq32_as_printed=tau_ratio_eq32_as_printed(n))


@dataclass(frozen=True)
class SimulatedRatios:
    """τH/τL and duty cycle versus N from ngspice transients.

    Parameters
    ----------
    n_ratio : tuple of float
        N = R_FSR / R. [1]
    tau_ratio : tuple of float
        ``DC/(1 − DC)`` from the simulated output edges. [1]
    duty_cycle : tuple of float
        Output high time over period. [1]
    """

    n_ratio: tuple
    tau_ratio: tuple
    duty_cycle: tuple

    def to_dict(self) -> dict:
        """The report's JSON shape: ``N``, ``tau_ratio`` and ``duty_cycle`` lists."""
        return {"N": list(self.n_ratio), "tau_ratio": list(self.tau_ratio), "duty_cycle": list(self.duty_cycle)}


def _simulated(n_ratio: Sequence[float], runs) -> SimulatedRatios:
    dc = [s.duty_cycle for s in runs]
    return SimulatedRatios(n_ratio=tuple(n_ratio), tau_ratio=tuple(d / (1 - d) for d in dc), duty_cycle=tuple(dc))


def simulate_tau_ratios(n_ratio: Sequence[float], diode: bool, r_ohm: float = 10e3, c_farad: float = 1e-9,
                        periods: int = 5) -> SimulatedRatios:
    """τH/τL and duty cycle at each N by an independent simulator (ngspice, fsrlab's behavioural 555).

    Parameters
    ----------
    n_ratio : sequence of float
        N = R_FSR / R, each > 4. [1]
    diode : bool
        With the ideal diode D1.
    r_ohm : float
        R_A = R_B = R; τH/τL and DC depend on N alone, so any R will do. [Ω]
    c_farad : float
        C_FSR (no C_off); any value will do, as for ``r_ohm``. [F]
    periods : int
        Periods measured after the start-up.

    Returns
    -------
    SimulatedRatios
        The ngspice runs go concurrently (:func:`fsrlab.circuits.spice.simulate_spice_many`).

    Raises
    ------
    FileNotFoundError, RuntimeError
        As :func:`fsrlab.circuits.spice.simulate_spice` when ngspice is missing or fails; check
        :func:`fsrlab.circuits.spice.ngspice_available` first.
    """
    runs = simulate_spice_many(({"r_ohm": r_ohm, "r_fsr_ohm": n * r_ohm, "c_fsr_farad": c_farad} for n in n_ratio),
                               diode=diode, periods=periods)
    return _simulated(n_ratio, runs)


class TauRatioRuns:
    """The ngspice runs of :func:`start_tau_ratios`, under way; :meth:`results` waits for them.

    Parameters
    ----------
    n_ratio : sequence of float
        N = R_FSR / R of each variant's runs. [1]
    diodes : sequence of bool
        The variants, in the order of the runs.
    batch : fsrlab.circuits.spice.SpiceBatch
        The runs: every N of the first variant, then of the next.
    """

    def __init__(self, n_ratio: Sequence[float], diodes: Sequence[bool], batch) -> None:
        self.n_ratio, self.diodes, self._batch = tuple(n_ratio), tuple(diodes), batch

    def results(self) -> list[SimulatedRatios]:
        """One :class:`SimulatedRatios` per variant, in the order of ``diodes``; the numbers
        :func:`simulate_tau_ratios` gives for each."""
        runs, n = self._batch.results(), len(self.n_ratio)
        return [_simulated(self.n_ratio, runs[k * n:(k + 1) * n]) for k in range(len(self.diodes))]


def start_tau_ratios(n_ratio: Sequence[float], diodes: Sequence[bool] = (False, True), r_ohm: float = 10e3,
                     c_farad: float = 1e-9, periods: int = 5) -> TauRatioRuns:
    """Start the ngspice runs of :func:`simulate_tau_ratios` for several variants at once; return at once.

    Parameters
    ----------
    n_ratio : sequence of float
        N = R_FSR / R, each > 4. [1]
    diodes : sequence of bool
        The variants: without (False) and with (True) the ideal diode D1.
    r_ohm, c_farad, periods
        As in :func:`simulate_tau_ratios`. [Ω, F, -]

    Returns
    -------
    TauRatioRuns
        Every variant's runs share one :func:`fsrlab.circuits.spice.start_spice_many` batch, so the
        longest of them all (with D1 at large N) starts first; ``.results()`` waits for them.

    Raises
    ------
    FileNotFoundError
        ngspice is not installed (:func:`fsrlab.circuits.spice.ngspice_available`).
    """
    cases = [{"r_ohm": r_ohm, "r_fsr_ohm": n * r_ohm, "c_fsr_farad": c_farad, "diode": bool(d)}
             for d in diodes for n in n_ratio]
    return TauRatioRuns(n_ratio, diodes, start_spice_many(cases, periods=periods))
