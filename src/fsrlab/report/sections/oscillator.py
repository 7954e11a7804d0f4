"""Report section: the LM555 oscillator (paper §5): Figures 12 and 15 as they should be, errata O1–O5.

Every number is computed when the report is built: closed forms from
:mod:`fsrlab.circuits.lm555`, and, when ngspice is installed, an independent transient simulation
of the circuit (:mod:`fsrlab.circuits.spice`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fsrlab.circuits.lm555 import astable, duty_cycle_limits, minimum_n_ratio, sensitivity, tau_ratio
from fsrlab.circuits.spice import ngspice_available, simulate_spice
from fsrlab.report.figures import new_figure, save
from fsrlab.report.model import Erratum, Figure, Section, Table

#: What the paper states (§5), quoted for the comparison.
PAPER_CLAIMS = {
    "min_tau_ratio_no_diode": 24.37,
    "min_duty_cycle_no_diode": 0.96,
    "lim_tau_ratio_diode": 2.0,
    "min_duty_cycle_diode": 0.666,
}

#: N = R_FSR/R values shown in the table and simulated with ngspice.
N_TABLE = [4.5, 5.0, 6.0, 8.0, 10.0, 14.0, 20.0, 50.0, 100.0, 1000.0]

R_OHM, C_FARAD = 10e3, 1e-9  # any R, C: τH/τL and DC depend on N alone


def paper_eq37_as_printed(n):
    """The paper's eq. (37) exactly as printed: ``ln((2 − 2N)/(4 − N))·2N/(ln 2·(N + 2))``."""
    n = np.asarray(n, dtype=float)
    return np.log((2 - 2 * n) / (4 - n)) * 2 * n / (math.log(2) * (n + 2))


def paper_ratio_as_computed(n, diode: bool = False):
    """τH/τL as the paper's numbers and Figures 12/15 behave: N × the ratio of eqs. (23) and (26)/(34).

    Both the quoted minimum 24.37 (no diode) and the printed eq. (37) (diode) are N times the ratio
    that follows from the paper's own τH and τL, as if τL had been divided by N (R_FSR replaced by R
    in the numerators of eqs. 26 and 34).
    """
    n = np.asarray(n, dtype=float)
    return n * tau_ratio(n, diode=diode)


def paper_min_24_37() -> tuple[float, float]:
    """(N, value) of the minimum of N × eq. (32) for N > 4: where the paper's 24.37 comes from."""
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(lambda x: float(paper_ratio_as_computed(x)), bounds=(4.2, 20.0), method="bounded",
                          options={"xatol": 1e-10})
    return float(res.x), float(res.fun)


def _spice_points(diode: bool) -> dict | None:
    if not ngspice_available():
        return None
    ratio, dc = [], []
    for n in N_TABLE:
        s = simulate_spice(R_OHM, n * R_OHM, C_FARAD, diode=diode, periods=5)
        ratio.append(s.duty_cycle / (1 - s.duty_cycle))
        dc.append(s.duty_cycle)
    return {"N": N_TABLE, "tau_ratio": ratio, "duty_cycle": dc}


def _figure(outdir: Path, name: str, diode: bool, spice: dict | None) -> None:
    fig, _ = new_figure(11.0, 4.2)
    fig.clf()
    ax1, ax2 = fig.subplots(1, 2)
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
    n = 4.0 + np.geomspace(1e-9, 16.0, 3000)
    g = tau_ratio(n, diode=diode)
    label = "eq. (37) corrected" if diode else "eq. (32)"
    ax1.plot(n, g, "C0-", lw=1.8, label=f"{label}, fsrlab")
    if diode:
        ax1.plot(n, paper_eq37_as_printed(n), "C3--", lw=1.4, label="eq. (37) as printed (extra factor N)")
        ax1.axhline(2.0, color="C3", ls=":", lw=1, label="printed eq. (37) → 2 (paper: DC ≥ 66.6 %)")
        ax1.axhline(0.0, color="C0", ls=":", lw=1, label="corrected → 0 as N → ∞")
    else:
        n_p, v_p = paper_min_24_37()
        ax1.plot(n, paper_ratio_as_computed(n), "C3--", lw=1.4,
                 label=f"N × eq. (32): the paper's numbers (min {v_p:.2f} at N = {n_p:.2f})")
        ax1.axhline(PAPER_CLAIMS["min_tau_ratio_no_diode"], color="C3", ls=":", lw=1,
                    label="paper: “minimal value 24.37”")
        ax1.axhline(2.0, color="C0", ls=":", lw=1, label="infimum 2 (N → ∞), never reached")
    if spice:
        m = np.array(spice["N"]) <= 20
        ax1.plot(np.array(spice["N"])[m], np.array(spice["tau_ratio"])[m], "ko", ms=5, mfc="none",
                 label="ngspice transient")
    ax1.axvline(4.0, color="0.5", lw=0.8)
    ax1.set(xlim=(0, 20), ylim=(-4, 12) if diode else (-10, 60), xlabel="N = R_FSR / R", ylabel="τH / τL",
            title=("Figure 15" if diode else "Figure 12") + ": τH/τL vs N" + (" with D1" if diode else ""))
    ax1.legend(fontsize=7.5)
    nn = np.geomspace(4.0005, 1e4, 2000)
    res = astable(R_OHM, nn * R_OHM, C_FARAD, diode=diode)
    ax2.semilogx(nn, 100 * res.duty_cycle, "C0-", lw=1.8, label="fsrlab closed form")
    if diode:
        ax2.axhline(100 * PAPER_CLAIMS["min_duty_cycle_diode"], color="C3", ls="--", lw=1.2,
                    label="paper: smallest DC 66.6 %")
    else:
        ax2.axhline(100 * PAPER_CLAIMS["min_duty_cycle_no_diode"], color="C3", ls="--", lw=1.2,
                    label="paper: DC ≥ 96 %")
        ax2.axhline(100 * 2 / 3, color="C0", ls=":", lw=1, label="infimum 66.7 %")
    if spice:
        ax2.semilogx(spice["N"], 100 * np.array(spice["duty_cycle"]), "ko", ms=5, mfc="none", label="ngspice")
    ax2.set(xlabel="N = R_FSR / R", ylabel="duty cycle (%)", ylim=(0, 101),
            title="duty cycle vs N" + (" with D1" if diode else " without diode"))
    ax2.legend(fontsize=7.5)
    save(fig, outdir / name)


def _sensitivity_figure(outdir: Path) -> None:
    fig, ax = new_figure()
    nn = np.geomspace(4.05, 1e3, 800)
    for diode, style in ((False, "C0"), (True, "C1")):
        s = sensitivity(R_OHM, nn * R_OHM, C_FARAD, diode=diode)
        name = "with D1" if diode else "without diode"
        ax.semilogx(nn, s.r_fsr, style + "-", label=f"∂ln f/∂ln R_FSR, {name}")
    ax.axhline(-1.0, color="0.4", ls=":", lw=1, label="∂ln f/∂ln C_FSR (C_off = 0)")
    ax.set(xlabel="N = R_FSR / R", ylabel="logarithmic sensitivity", ylim=(-1.5, 3.0),
           title="How resistive is the “capacitive” frequency? (extension)")
    ax.legend(fontsize=8)
    save(fig, outdir / "oscillator_sensitivity.png")


def _stress_figure(outdir: Path) -> dict:
    """f versus stress on the lead's VirtualFSR for both variants, split into C-only and R-only parts."""
    from fsrlab.physics.sensor import VirtualFSR

    stress = np.linspace(0.0, 10e3, 101)  # the paper's Figure 17 range, 0–10 kPa
    resp = VirtualFSR().respond(stress)
    rf, cf = resp.r_fsr_ohm, resp.c_fsr_farad
    fig, _ = new_figure(11.0, 4.2)
    fig.clf()
    axes = fig.subplots(1, 2)
    out = {"stress_pa": [float(stress[0]), float(stress[-1])], "r_fsr_ohm": [float(rf[0]), float(rf[-1])],
           "c_fsr_farad": [float(cf[0]), float(cf[-1])]}
    for ax, diode in zip(axes, (True, False)):
        both = astable(R_OHM, rf, cf, diode=diode).frequency_hz
        c_only = astable(R_OHM, rf[0], cf, diode=diode).frequency_hz
        r_only = astable(R_OHM, rf, cf[0], diode=diode).frequency_hz
        ax.grid(True, alpha=0.3)
        ax.plot(stress / 1e3, both / 1e3, "k-", lw=2, label="f (R_FSR and C_FSR change)")
        ax.plot(stress / 1e3, c_only / 1e3, "C0--", label="only C_FSR changes")
        ax.plot(stress / 1e3, r_only / 1e3, "C1--", label="only R_FSR changes")
        ax.set(xlabel="stress σ (kPa)", ylabel="f (kHz)",
               title=("with D1 (paper's Fig. 16)" if diode else "without D1") + ", R = 10 kΩ, C_off = 0")
        ax.legend(fontsize=8)
        out["diode" if diode else "no_diode"] = {
            "frequency_hz": [float(both[0]), float(both[-1])], "c_only_hz": [float(c_only[0]), float(c_only[-1])],
            "r_only_hz": [float(r_only[0]), float(r_only[-1])]}
    save(fig, outdir / "oscillator_frequency_vs_stress.png")
    return out


def build(outdir: Path) -> Section:
    """Build the oscillator section into ``outdir`` (PNGs) and return it."""
    outdir = Path(outdir)
    spice_nd = _spice_points(False)
    spice_d = _spice_points(True)
    have_spice = spice_nd is not None
    _figure(outdir, "fig12_tau_ratio_no_diode.png", False, spice_nd)
    _figure(outdir, "fig15_tau_ratio_diode.png", True, spice_d)
    _sensitivity_figure(outdir)
    fs = _stress_figure(outdir)

    n = np.array(N_TABLE)
    g_nd, g_d, g_37 = tau_ratio(n), tau_ratio(n, diode=True), paper_eq37_as_printed(n)
    dc_nd, dc_d = g_nd / (1 + g_nd), g_d / (1 + g_d)
    dc_inf_nd, _ = duty_cycle_limits()
    from scipy.optimize import brentq

    n_at_2437 = brentq(lambda x: tau_ratio(x) - PAPER_CLAIMS["min_tau_ratio_no_diode"], 4 + 1e-9, 5)
    n_min_paper, min_paper = paper_min_24_37()
    s20 = sensitivity(R_OHM, 20 * R_OHM, C_FARAD, diode=True)
    s20_nd = sensitivity(R_OHM, 20 * R_OHM, C_FARAD)

    def sp(d, key, i):
        return d[key][i] if d else None

    rows = []
    for i, ni in enumerate(N_TABLE):
        rows.append([f"{ni:g}", float(g_nd[i]), sp(spice_nd, "tau_ratio", i) if have_spice else "n/a",
                     100 * float(dc_nd[i]), float(g_d[i]), sp(spice_d, "tau_ratio", i) if have_spice else "n/a",
                     float(g_37[i]), 100 * float(dc_d[i])])
    spice_note = ("ngspice columns: transient simulation of fsrlab's behavioural-555 netlist, 5 periods after "
                  "start-up, τH/τL = DC/(1 − DC) from the output edges." if have_spice else
                  "ngspice is not installed here, so the independent-simulator columns are empty "
                  "(`make sysdeps` installs it).")
    table = Table(
        "τH/τL and duty cycle versus N (R = 10 kΩ, C = 1 nF; both depend on N only)",
        ["N", "τH/τL eq. (32)", "ngspice", "DC % no diode", "τH/τL with D1", "ngspice (D1)",
         "eq. (37) as printed", "DC % with D1"],
        rows, note=spice_note, fmt="{:.4g}")

    def at(d, key, value):
        if not d:
            return None
        return d[key][N_TABLE.index(value)]

    ev_spice = ""
    if have_spice:
        ev_spice = (f" ngspice (independent transient simulation) gives τH/τL = {at(spice_nd, 'tau_ratio', 10.0):.4f} at "
                    f"N = 10 and DC = {100 * at(spice_nd, 'duty_cycle', 1000.0):.3f} % at N = 1000, "
                    f"against {g_nd[N_TABLE.index(10.0)]:.4f} and {100 * dc_nd[-1]:.3f} % from the closed form.")
    else:
        ev_spice = " (ngspice not installed when this report was built: no simulator numbers.)"
    ev_spice_d = ""
    if have_spice:
        ev_spice_d = (f" ngspice: τH/τL = {at(spice_d, 'tau_ratio', 10.0):.4f} at N = 10, "
                      f"{at(spice_d, 'tau_ratio', 100.0):.5f} at N = 100, DC = "
                      f"{100 * at(spice_d, 'duty_cycle', 1000.0):.3f} % at N = 1000.")
    else:
        ev_spice_d = " (ngspice not installed when this report was built: no simulator numbers.)"
    i10, i100, i1000 = N_TABLE.index(10.0), N_TABLE.index(100.0), N_TABLE.index(1000.0)

    errata = [
        Erratum(
            "O1", "Without the diode τH/τL has no minimum 24.37 and the duty cycle is not limited to ≥ 96 %",
            "“The minimal value of the ratio τH/τL for N > 4 is 24.37. This means that the duty cycle of the "
            "output signal cannot be smaller than 24.37/25.37 = 0.96.”",
            "Eq. (32), τH/τL = ln((2N − 2)/(N − 4))·2(N + 1)/((N + 2)·ln 2), falls monotonically for N > 4 from "
            f"+∞ to its infimum 2 (N → ∞), which it never reaches: there is no minimum. τH/τL = {g_nd[i10]:.3f} "
            f"at N = 10 (DC {100 * dc_nd[i10]:.1f} %), {g_nd[i100]:.3f} at N = 100 (DC {100 * dc_nd[i100]:.2f} %). "
            f"Every duty cycle in ({100 * dc_inf_nd:.2f} %, 100 %) is reachable. The quoted 24.37 is the minimum of "
            f"N × eq. (32): {min_paper:.4f} at N = {n_min_paper:.3f} (24.37 truncated; DC {100 * min_paper / (1 + min_paper):.2f} %), "
            "the same extra factor N as in the printed eq. (37) (O2), as if τL had been divided by N (R_FSR "
            "replaced by R in the numerators of eqs. 26 and 34). Figure 12's axes (up to 60 at N ≤ 20, where eq. (32) "
            f"stays below 6.5 for N ≥ 4.5) fit N × eq. (32) too ({20 * g_nd[N_TABLE.index(20.0)]:.1f} at N = 20). Eq. (32) itself reaches 24.37 only at N = {n_at_2437:.5f}. "
            "The paper's point that DC stays high without the diode holds (always above 2/3).",
            "Derivation from eqs. (23), (26): as N → ∞, τH → 2RC·ln 2 and τL → RC·ln 2, ratio 2 (the classic "
            "555); the 1/N term of the expansion, 2(3/ln 2 − 1)/N, is positive, and a dense evaluation over "
            "N ∈ (4, 10⁷) is strictly decreasing (tests/circuits/test_lm555.py). The minimum of N × eq. (32) is "
            "found numerically (bounded minimisation)." + ev_spice,
        ),
        Erratum(
            "O2", "Eq. (37) as printed carries an extra factor N",
            "Eq. (37): τH/τL = ln((2 − 2N)/(4 − N))·2N/(ln 2·(N + 2)), with lim τH/τL = 2 as N → ∞.",
            "With eq. (34), τL = ln 2·R_FSR·C = ln 2·N·R·C, and eq. (23), τH = ln((2N − 2)/(N − 4))·2NR/(N + 2)·C, "
            "the ratio is τH/τL = 2·ln((2N − 2)/(N − 4))/(ln 2·(N + 2)) — the printed one divided by N. It tends to "
            f"0, not 2: {g_d[i10]:.4f} at N = 10 (printed: {g_37[i10]:.4f}), {g_d[i100]:.5f} at N = 100 "
            f"(printed: {g_37[i100]:.4f}).",
            "Substitution of eq. (31) into eqs. (23) and (34); the paper's own eqs. (35) and (36) agree with the "
            "corrected ratio, not with eq. (37)." + ev_spice_d,
        ),
        Erratum(
            "O3", "With the diode the duty cycle can go far below 66.6 %",
            "“Due to the fact that lim τH/τL = 2 … the smallest duty cycle possible is 66.6 % and any value "
            "above this can be achieved by selecting the proper value of R.”",
            f"With D1 the duty cycle falls toward 0 as N grows: {100 * dc_d[i10]:.2f} % at N = 10, "
            f"{100 * dc_d[i100]:.3f} % at N = 100, {100 * dc_d[i1000]:.4f} % at N = 1000; every DC in (0, 100 %) "
            "is reachable. 66.7 % is the infimum of the circuit without the diode (O1). The conclusion that the "
            "diode widens the duty-cycle range stands, and more strongly than stated.",
            "Follows from O2's corrected ratio; the issue-3 example R = 10 kΩ, R_FSR = 200 kΩ, C = 1 nF with D1 "
            f"gives DC = {100 * float(astable(R_OHM, 200e3, C_FARAD, diode=True).duty_cycle):.3f} %." + ev_spice_d,
        ),
        Erratum(
            "O4", "Eq. (19) for the classic astable (as extracted)",
            "The extracted text of eq. (19) reads “f = 1 442RC1”, i.e. f = 1.44/(2R·C1) (or 1.442/(R·C1)), for "
            "Figure 9(a), where R_A = R_B = R.",
            "Neither reading is the classic astable's f = 1.44/((R_A + 2R_B)·C) = 1.44/(3RC) for R_A = R_B = R; fsrlab's closed "
            f"form tends to it as R_FSR → ∞ ({float(astable(R_OHM, math.inf, C_FARAD).frequency_hz):.1f} Hz for "
            f"10 kΩ, 1 nF vs 1.44/(3RC) = {1.44 / (3 * R_OHM * C_FARAD):.1f} Hz).",
            "LM555 datasheet astable formula; limit test in tests/circuits/test_lm555.py. Only the text extraction "
            "was available: check the printed PDF before citing this one.",
        ),
        Erratum(
            "O5", "Figure 10's caption refers to Figure 8(b)",
            "Figure 10: “… LM555 in astable configuration modified according to Figure 8(b) …”.",
            "The modified astable is Figure 9(b) (Figure 8 shows R_A and C_A versus stress); Figure 11's caption "
            "says 9(b).",
            "The captions of Figures 8–11.",
        ),
    ]

    figures = [
        Figure("fig12_tau_ratio_no_diode.png", "Figure 12: τH/τL versus N without the diode (eq. 32)",
               "Figure 12 plots eq. (32) for N from 0 to 20 (y from −10 to 60); the text says its minimum for N > 4 "
               "is 24.37, so DC ≥ 96 %.",
               f"Eq. (32) decreases monotonically toward 2; no minimum. At N = 20 τH/τL = {g_nd[N_TABLE.index(20.0)]:.3f}. "
               f"Red dashed: N × eq. (32), which has the paper's minimum ({min_paper:.2f} at N = {n_min_paper:.2f}) and "
               "fits Figure 12's axes: the printed figure and number appear to carry the extra N of eq. (37). "
               + ("ngspice points lie on the curve (within 0.01 %)." if have_spice else "ngspice not installed: "
                  "no simulator points.") + " Right: the duty cycle stays above 66.7 %, not 96 % (O1)."),
        Figure("fig15_tau_ratio_diode.png", "Figure 15: τH/τL versus N with the diode D1 (eq. 37)",
               "Figure 15 plots eq. (37) (N 0–20, y −4 to 12); the text takes lim τH/τL = 2, so DC ≥ 66.6 %.",
               "Red dashed: eq. (37) as printed (→ 2). Blue: the ratio that follows from eqs. (23) and (34) (→ 0). "
               + ("ngspice points follow the blue curve." if have_spice else "ngspice not installed: no simulator "
                  "points.") + " Right: the duty cycle reaches any value down to 0 (O2, O3)."),
        Figure("oscillator_sensitivity.png", "Extension: sensitivity of f to R_FSR, per variant",
               "§5: even if R ≪ R_FSR, f still depends on R_FSR (eq. 35); Figure 19a shows f rising from about 3 to "
               "10 kHz with stress.",
               f"With D1, ∂ln f/∂ln R_FSR = {float(s20.r_fsr):.3f} at N = 20 and → −1 as N grows (f ≈ 1/(ln 2·R_FSR·C)): "
               "the “capacitive” frequency is then as much a resistance reading, and a falling R_FSR under load "
               "raises f as in Figure 19a. Without the diode it is "
               f"{float(s20_nd.r_fsr):+.3f} at N = 20 (f nearly independent of R_FSR, and it rises with R_FSR). "
               "∂ln f/∂ln C_FSR = −C_FSR/(C_FSR + C_off) in both variants."),
        Figure("oscillator_frequency_vs_stress.png",
               "Extension: where the frequency change under load comes from (lead's VirtualFSR, 0–10 kPa)",
               "Figure 19a: f rises from about 3 to 10 kHz as stress rises, read as a capacitive measurement.",
               f"On the VirtualFSR (R_FSR {fs['r_fsr_ohm'][0] / 1e6:.2f} → {fs['r_fsr_ohm'][1] / 1e6:.2f} MΩ, C_FSR "
               f"{fs['c_fsr_farad'][0] * 1e12:.0f} → {fs['c_fsr_farad'][1] * 1e12:.0f} pF) the paper's circuit with D1 "
               f"rises {fs['diode']['frequency_hz'][0] / 1e3:.2f} → {fs['diode']['frequency_hz'][1] / 1e3:.2f} kHz, "
               "like Figure 19a; with C_FSR alone it would fall "
               f"({fs['diode']['c_only_hz'][0] / 1e3:.2f} → {fs['diode']['c_only_hz'][1] / 1e3:.2f} kHz), with R_FSR "
               f"alone it would rise ({fs['diode']['r_only_hz'][0] / 1e3:.2f} → {fs['diode']['r_only_hz'][1] / 1e3:.2f} kHz): "
               "the rise is resistive. Without D1 f falls "
               f"{fs['no_diode']['frequency_hz'][0] / 1e3:.1f} → {fs['no_diode']['frequency_hz'][1] / 1e3:.1f} kHz, "
               "almost all of it from C_FSR. The sensor model is the lead's extension (fsrlab.physics.sensor), "
               "not the paper's; the decomposition holds for any sensor whose R_FSR falls under load."),
    ]

    data = {
        "oscillator": {
            "paper_claims": PAPER_CLAIMS,
            "N": N_TABLE,
            "tau_ratio_no_diode": [float(v) for v in g_nd],
            "tau_ratio_diode": [float(v) for v in g_d],
            "paper_eq37_as_printed": [float(v) for v in g_37],
            "duty_cycle_no_diode": [float(v) for v in dc_nd],
            "duty_cycle_diode": [float(v) for v in dc_d],
            "duty_cycle_infimum_no_diode": dc_inf_nd,
            "duty_cycle_infimum_diode": 0.0,
            "tau_ratio_infimum_no_diode": 2.0,
            "n_where_eq32_equals_24_37": n_at_2437,
            "paper_24_37_explained": {"expression": "N * eq. (32)", "minimum": min_paper, "at_N": n_min_paper},
            "sensitivity_r_fsr_at_N20": {"no_diode": float(s20_nd.r_fsr), "diode": float(s20.r_fsr)},
            "frequency_vs_stress_virtual_fsr": fs,
            "ngspice_available": have_spice,
            "ngspice_no_diode": spice_nd,
            "ngspice_diode": spice_d,
        }
    }
    intro = (
        "The FSR (R_FSR ∥ C_FSR, plus C_off) is the timing element of an LM555 astable with R_A = R_B = R, with or "
        "without a diode D1 in series with R_B. τH/τL and the duty cycle depend on N = R_FSR/R only; the circuit "
        "oscillates only for N > 4 (eq. 30; with a diode drop V_D, N > 2uVcc/(Vcc − V_D − uVcc)).\n\n"
        "Closed forms: fsrlab.circuits.lm555; exact event-driven simulation: fsrlab.circuits.transient; "
        "independent check: ngspice with fsrlab's behavioural 555 (fsrlab.circuits.spice), which agrees with the "
        "closed forms to better than 1e-4 over N = 4.5–1000 with and without D1 and C_off (tests/circuits/test_spice.py).\n\n"
        "Beyond the paper's ideal parts, fsrlab models a diode forward drop (0.6 V raises the oscillation limit to "
        f"N > {minimum_n_ratio(0.6):.4g}), thresholds moved by the control pin, and the discharge transistor's "
        "on-resistance (50 Ω changes f by "
        f"{100 * (float(astable(R_OHM, 200e3, C_FARAD, discharge_ohm=50.0).frequency_hz) / float(astable(R_OHM, 200e3, C_FARAD).frequency_hz) - 1):+.2f} % "
        "without D1 at R = 10 kΩ, R_FSR = 200 kΩ, and not at all with D1, which blocks R_B during the discharge). "
        "Neglected: comparator delay and offset, output edge times, input currents of pins 2 and 6, diode leakage "
        "and the current dependence of its drop."
    )
    return Section(key="oscillator", title="LM555 oscillator (§5)", intro=intro, figures=figures, tables=[table],
                   errata=errata, data=data)
