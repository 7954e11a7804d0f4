"""Errata O1–O5 of the oscillator section, worded from the numbers :mod:`fsrlab.circuits.paper_ratio`
computes (the same entries as docs/errata.md). A helper of :mod:`fsrlab.reports.sections.oscillator`,
not a section builder.
"""

from __future__ import annotations

import math

from fsrlab.circuits.lm555 import astable, duty_cycle_limits
from fsrlab.circuits.paper_ratio import RatioMinimum, SimulatedRatios, TauRatioTable
from fsrlab.reports.model import Erratum

__all__ = ["oscillator_errata"]

_NO_SPICE = " (ngspice not installed when this report was built: no simulator numbers.)"


def _at(spice: SimulatedRatios, key: str, n: float) -> float:
    return getattr(spice, key)[spice.n_ratio.index(n)]


def _spice_evidence(t: TauRatioTable, spice_nd: SimulatedRatios | None, spice_d: SimulatedRatios | None) -> tuple[str,
        str]:
    """Sentences quoting ngspice beside the closed forms, without and with D1."""
    if not spice_nd:
        return _NO_SPICE, _NO_SPICE
    ev = (f" ngspice (independent transient simulation) gives τH/τL = {_at(spice_nd, 'tau_ratio', 10.0):.4f} at "
          f"N = 10 and DC = {100 * _at(spice_nd, 'duty_cycle', 1000.0):.3f} % at N = 1000, "
          f"against {t.no_diode[t.n_ratio.index(10.0)]:.4f} and "
          f"{100 * t.duty_cycle_no_diode[t.n_ratio.index(1000.0)]:.3f} % from the "
          "closed form.")
    ev_d = (f" ngspice: τH/τL = {_at(spice_d, 'tau_ratio', 10.0):.4f} at N = 10, "
            f"{_at(spice_d, 'tau_ratio', 100.0):.5f} at N = 100, DC = "
            f"{100 * _at(spice_d, 'duty_cycle', 1000.0):.3f} % at N = 1000.")
    return ev, ev_d


def _erratum_o1(t: TauRatioTable, minimum: RatioMinimum, n_at_claim: float, evidence: str) -> Erratum:
    i10, i100, i20 = (t.n_ratio.index(n) for n in (10.0, 100.0, 20.0))
    g, dc = t.no_diode, t.duty_cycle_no_diode
    return Erratum(
        "O1", "Eq. (32) as printed carries an extra factor N: without the diode τH/τL has no minimum 24.37 "
        "and the duty cycle is not limited to ≥ 96 %",
        "Eq. (32): τH/τL = ln((2 − 2N)/(4 − N))·2N(N + 1)/(ln 2·(N + 2)) (extracted text “ln 2 − 2N / 4 −N 2N N + 1 "
        "/ ln 2 N + 2”, read as eq. (37) is read); “The minimal value of the ratio τH/τL for N > 4 is 24.37. This "
        "means that the duty cycle of the output signal cannot be smaller than 24.37/25.37 = 0.96.”",
        "The printed eq. (32) is N times the ratio of the paper's own τH (eq. 23) and τL (eq. 26), "
        "τH/τL = ln((2N − 2)/(N − 4))·2(N + 1)/((N + 2)·ln 2): the same extra factor N as eq. (37) (O2), as if τL "
        "had been divided by N (R_FSR replaced by R in the numerator of eq. 26). The quoted numbers follow from the "
        f"printed equation: its minimum is {minimum.value:.4f} at N = {minimum.n_ratio:.3f} (24.37 truncated; "
        f"{minimum.value:.4f}/{1 + minimum.value:.4f} = {minimum.duty_cycle:.4f}, the printed 0.96), and Figure 12's "
        f"axes (up to 60 for N ≤ 20) fit it ({t.eq32_as_printed[i20]:.1f} at N = 20), not the corrected ratio "
        f"({g[i20]:.3f} at N = 20). So the derivation's last step is wrong, and with it the number, the 0.96 and "
        "Figure 12. The circuit's ratio falls monotonically for N > 4 from +∞ to its infimum 2 (N → ∞), which it "
        f"never reaches: there is no minimum. τH/τL = {g[i10]:.3f} at N = 10 (DC {100 * dc[i10]:.1f} %), "
        f"{g[i100]:.3f} at N = 100 (DC {100 * dc[i100]:.2f} %); every duty cycle in "
        f"({100 * duty_cycle_limits()[0]:.2f} %, 100 %) is reachable, and τH/τL = 24.37 only at "
        f"N = {n_at_claim:.5f}, at the oscillation limit. The paper's point that DC stays high without the diode "
        "holds (always above 2/3), not the 96 % bound.",
        "Substitution of eq. (31) into eqs. (23) and (26): τH = ln((2N − 2)/(N − 4))·2NR·C/(N + 2), "
        "τL = ln 2·NR·C/(N + 1). As N → ∞, τH → 2RC·ln 2 and τL → RC·ln 2, ratio 2 (the classic 555); the 1/N "
        "term of the expansion, 2(3/ln 2 − 1)/N, is positive, and a dense evaluation over N ∈ (4, 10⁷) is strictly "
        "decreasing (tests/circuits/test_lm555.py). The minimum of the printed eq. (32) is found by bounded "
        "minimisation and checked against a retyped printed equation (tests/circuits/test_paper_ratio.py). Only the "
        "text extraction was available: the reading of eq. (32) should be checked on the printed PDF." + evidence,
    )


def _erratum_o2(t: TauRatioTable, evidence_d: str) -> Erratum:
    i10, i100 = t.n_ratio.index(10.0), t.n_ratio.index(100.0)
    return Erratum(
        "O2", "Eq. (37) as printed carries an extra factor N",
        "Eq. (37): τH/τL = ln((2 − 2N)/(4 − N))·2N/(ln 2·(N + 2)), with lim τH/τL = 2 as N → ∞.",
        "With eq. (34), τL = ln 2·R_FSR·C = ln 2·N·R·C, and eq. (23), τH = ln((2N − 2)/(N − 4))·2NR/(N + 2)·C, "
        "the ratio is τH/τL = 2·ln((2N − 2)/(N − 4))/(ln 2·(N + 2)) — the printed one divided by N. It tends to "
        f"0, not 2: {t.diode[i10]:.4f} at N = 10 (printed: {t.eq37_as_printed[i10]:.4f}), {t.diode[i100]:.5f} at "
        f"N = 100 (printed: {t.eq37_as_printed[i100]:.4f}).",
        "Substitution of eq. (31) into eqs. (23) and (34); the paper's own eqs. (35) and (36) agree with the "
        "corrected ratio, not with eq. (37). Eq. (32) as printed has the same extra factor N (O1)." + evidence_d,
    )


def _erratum_o3(t: TauRatioTable, evidence_d: str, r_ohm: float, c_farad: float) -> Erratum:
    dc = t.duty_cycle_diode
    i10, i100, i1000 = (t.n_ratio.index(n) for n in (10.0, 100.0, 1000.0))
    example = float(astable(r_ohm, 200e3, c_farad, diode=True).duty_cycle)
    return Erratum(
        "O3", "With the diode the duty cycle can go far below 66.6 %",
        "“Due to the fact that lim τH/τL = 2 … the smallest duty cycle possible is 66.6 % and any value "
        "above this can be achieved by selecting the proper value of R.”",
        f"With D1 the duty cycle falls toward 0 as N grows: {100 * dc[i10]:.2f} % at N = 10, "
        f"{100 * dc[i100]:.3f} % at N = 100, {100 * dc[i1000]:.4f} % at N = 1000; every DC in (0, 100 %) "
        "is reachable. 66.7 % is the infimum of the circuit without the diode (O1). The conclusion that the "
        "diode widens the duty-cycle range stands, and more strongly than stated.",
        f"Follows from O2's corrected ratio; for example, R = {r_ohm / 1e3:g} kΩ, R_FSR = 200 kΩ, "
        f"C = {c_farad * 1e9:g} nF with D1 gives DC = {100 * example:.3f} %." + evidence_d,
    )


def _erratum_o4(r_ohm: float, c_farad: float) -> Erratum:
    classic = float(astable(r_ohm, math.inf, c_farad).frequency_hz)
    return Erratum(
        "O4", "Eq. (19) for the classic astable (as extracted)",
        "The extracted text of eq. (19) reads “f = 1 442RC1”, i.e. f = 1.44/(2R·C1) (or 1.442/(R·C1)), for "
        "Figure 9(a), where R_A = R_B = R.",
        "Neither reading is the classic astable's f = 1.44/((R_A + 2R_B)·C) = 1.44/(3RC) for R_A = R_B = R; fsrlab's "
        f"closed form tends to it as R_FSR → ∞ ({classic:.1f} Hz for {r_ohm / 1e3:g} kΩ, {c_farad * 1e9:g} nF vs "
        f"1.44/(3RC) = {1.44 / (3 * r_ohm * c_farad):.1f} Hz).",
        "LM555 datasheet astable formula; limit test in tests/circuits/test_lm555.py. Only the text extraction "
        "was available: check the printed PDF before citing this one.",
    )


_ERRATUM_O5 = Erratum(
    "O5", "Figure 10's caption refers to Figure 8(b)",
    "Figure 10: “… LM555 in astable configuration modified according to Figure 8(b) …”.",
    "The modified astable is Figure 9(b) (Figure 8 shows R_A and C_A versus stress); Figure 11's caption "
    "says 9(b).",
    "The captions of Figures 8–11.",
)


def oscillator_errata(table: TauRatioTable, minimum: RatioMinimum, n_at_claim: float,
                      spice_nd: SimulatedRatios | None, spice_d: SimulatedRatios | None,
                      r_ohm: float, c_farad: float) -> list[Erratum]:
    """Errata O1–O5 with the section's numbers.

    Parameters
    ----------
    table : TauRatioTable
        τH/τL over N; must include N = 10, 20, 100 and 1000 (quoted).
    minimum : RatioMinimum
        The minimum of eq. (32) as printed.
    n_at_claim : float
        N where the corrected τH/τL (eqs. 23 and 26) equals the printed 24.37. [1]
    spice_nd, spice_d : SimulatedRatios or None
        ngspice without and with D1 over the same N; None when ngspice is not installed.
    r_ohm : float
        R of the example circuits. [Ω]
    c_farad : float
        C of the example circuits. [F]

    Returns
    -------
    list of Erratum
    """
    ev, ev_d = _spice_evidence(table, spice_nd, spice_d)
    return [_erratum_o1(table, minimum, n_at_claim, ev), _erratum_o2(table, ev_d),
            _erratum_o3(table, ev_d, r_ohm, c_farad), _erratum_o4(r_ohm, c_farad), _ERRATUM_O5]
