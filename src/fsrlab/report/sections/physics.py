"""Report section: sensor physics (paper §2–4): Figures 2, 4, 8, Table 2 and their errata."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from scipy.constants import electron_volt, epsilon_0
from scipy.optimize import minimize_scalar

from fsrlab.analysis.hysteresis import model_cycle_errors
from fsrlab.physics.electrical import capacitance_per_area, resistance_per_area
from fsrlab.physics.params import PAPER, PaperParameters
from fsrlab.physics.separation import separation_history, separation_loading, separation_unloading
from fsrlab.physics.tunneling import current_density
from fsrlab.report.figures import new_figure, save
from fsrlab.report.model import Erratum, Figure, Section, Table

#: The paper's Table 2 (reference values, not targets).
PAPER_TABLE2 = {"u_V": [3, 2, 1], "resistance_per_area_percent": [2.21, 5.95, 10.58],
                "capacitance_per_area_percent": [1.73, 1.73, 1.73]}
#: Ranges read off the axes of the paper's Figures 4a and 4b (J in A/µm², R_A in Ω·µm²).
PAPER_FIG4_AXES = {"current_A_per_um2": (0.52, 0.64), "resistance_ohm_um2": (3.1, 3.8)}

_UM2 = 1e-12  # m² per µm²


def _params(phi0_ev: float) -> PaperParameters:
    return dataclasses.replace(PAPER, phi0_j=phi0_ev * electron_volt)


def table2(params: PaperParameters = PAPER) -> dict:
    """HE of R_A and C_A at u = 3, 2, 1 V for ``params``, as in the paper's Table 2."""
    rows = [model_cycle_errors(u, params) for u in PAPER_TABLE2["u_V"]]
    return {
        "u_V": PAPER_TABLE2["u_V"],
        "resistance_per_area_percent": [r.resistance.percent for r in rows],
        "capacitance_per_area_percent": [r.capacitance.percent for r in rows],
        "resistance_stress_at_max_Pa": [r.resistance.stress_at_max_pa for r in rows],
        "capacitance_stress_at_max_Pa": [r.capacitance.stress_at_max_pa for r in rows],
        "tunneling_equation": [r.regime for r in rows],
    }


def best_phi0_ev() -> float:
    """Barrier height that brings Table 2's R_A column closest to the printed one (least squares)."""
    target = np.array(PAPER_TABLE2["resistance_per_area_percent"])

    def cost(phi0_ev: float) -> float:
        return float(np.sum((np.array(table2(_params(phi0_ev))["resistance_per_area_percent"]) - target) ** 2))

    return float(minimize_scalar(cost, bounds=(0.225, 0.235), method="bounded", options={"xatol": 1e-6}).x)


def _branches(params: PaperParameters, n: int = 400):
    x = np.linspace(0, params.sigma_f_pa, n)
    s_l = separation_loading(x, params.s0_m, params.modulus_pa)
    s_u = separation_unloading(x, params.sigma_f_pa, params.s0_m, params.modulus_pa, params.k)
    return x, s_l, s_u


def _fig2(outdir: Path) -> list[Figure]:
    p = PAPER
    fig, ax = new_figure()
    x = np.linspace(0, p.sigma_f_pa, 400)
    ax.plot(x / 1e3, separation_loading(x) * 1e9, "k-", lw=1.5, label="loading, eq. (1)")
    for i, sf in enumerate([80e3, 160e3, 240e3, 322e3], 1):
        xs = np.linspace(0, sf, 300)
        ax.plot(xs / 1e3, separation_unloading(xs, sf, k=4) * 1e9, label=f"unloading, σf{i} = {sf / 1e3:.0f} kPa")
    ax.set(xlabel="stress σ (kPa)", ylabel="separation s (nm)", title="Figure 2a: s(σ) for several σf, k = 4")
    ax.legend(fontsize=8)
    save(fig, outdir / "fig2a_separation_sigma_f.png")
    fig, ax = new_figure()
    ax.plot(x / 1e3, separation_loading(x) * 1e9, "k-", lw=1.5, label="loading, eq. (1)")
    for k in (2, 4, 6, 8):
        ax.plot(x / 1e3, separation_unloading(x, p.sigma_f_pa, k=k) * 1e9, label=f"unloading, k = {k}")
    ax.set(xlabel="stress σ (kPa)", ylabel="separation s (nm)", title="Figure 2b: s(σ) for k = 2, 4, 6, 8 (σf = 322 kPa)")
    ax.legend(fontsize=8)
    save(fig, outdir / "fig2b_separation_k.png")
    return [
        Figure("fig2a_separation_sigma_f.png", "Figure 2a: separation for several final stresses (k = 4)",
               "Loading is one straight line from s0; each unloading branch leaves it at its own σf and returns "
               "to s0 along a curve. The paper does not print its σf values.",
               "Reproduced with Table 1's s0 and M and σf = 80, 160, 240, 322 kPa, using eq. (9) in its exact "
               "simplified form s_u = s_f + (s0 − s_f)(1 − σ/σf)^k. Same shape as the paper's."),
        Figure("fig2b_separation_k.png", "Figure 2b: separation for k = 2, 4, 6, 8",
               "A larger k keeps s near s_f longer during unloading: more hysteresis.",
               "Reproduced; the simplified eq. (9) is real for any k ≥ 1, so k need not be even as eq. (8) requires."),
    ]


def _fig4_8(outdir: Path, phi0_fit_ev: float) -> list[Figure]:
    p = PAPER
    alt = _params(phi0_fit_ev)
    x, s_l, s_u = _branches(p)
    figs = []
    kpa = x / 1e3
    for key, title, fn, unit, scale, fname, num in [
        ("J", "Figure 4a: current density at u = 2 V (eq. 12)", current_density, "A/µm²", _UM2, "fig4a_current_density.png", "4a"),
        ("R", "Figure 4b: resistance per unit area at u = 2 V (eq. 18)", resistance_per_area, "Ω·µm²", 1 / _UM2, "fig4b_resistance_per_area.png", "4b"),
        ("R", "Figure 8a: resistance per unit area at u = 2 V", resistance_per_area, "Ω·µm²", 1 / _UM2, "fig8a_resistance_per_area.png", "8a"),
    ]:
        fig, ax = new_figure()
        for params, style, tag in [(p, "-", "Table 1 (φ0 = 0.223 eV)"), (alt, "--", f"φ0 = {phi0_fit_ev:.4f} eV")]:
            ax.plot(kpa, fn(p.u_v, s_l, params.phi0_j) * scale, "b" + style, label=f"loading, {tag}")
            ax.plot(kpa, fn(p.u_v, s_u, params.phi0_j) * scale, "g" + style, label=f"unloading, {tag}")
        ax.set(xlabel="stress σ (kPa)", ylabel=f"{'J' if key == 'J' else 'R_A'} ({unit})", title=title)
        ax.legend(fontsize=7)
        save(fig, outdir / fname)
        lo, hi = (fn(p.u_v, s_l, p.phi0_j) * scale)[[0, -1]]
        lo2, hi2 = (fn(p.u_v, s_l, alt.phi0_j) * scale)[[0, -1]]
        axes = PAPER_FIG4_AXES["current_A_per_um2" if key == "J" else "resistance_ohm_um2"]
        figs.append(Figure(
            fname, title,
            f"Loading and unloading branches with Table 1's parameters; the paper's axis spans about "
            f"{axes[0]}–{axes[1]} {unit}.",
            f"With the printed parameters the loading branch runs from {lo:.3f} to {hi:.3f} {unit} (solid); "
            f"with φ0 = {phi0_fit_ev:.4f} eV, the barrier height that reproduces Table 2, from {lo2:.3f} to "
            f"{hi2:.3f} {unit} (dashed), which is where the paper's curves lie (erratum P2)."))
    fig, ax = new_figure()
    ax.plot(kpa, capacitance_per_area(s_l) * 1e3, "b-", label="loading")
    ax.plot(kpa, capacitance_per_area(s_u) * 1e3, "g-", label="unloading")
    ax.set(xlabel="stress σ (kPa)", ylabel="C_A (mF/m²)", title="Figure 8b: capacitance per unit area (eq. 15)")
    ax.legend(fontsize=8)
    save(fig, outdir / "fig8b_capacitance_per_area.png")
    c0, cf = capacitance_per_area(s_l)[[0, -1]] * 1e3
    figs.append(Figure(
        "fig8b_capacitance_per_area.png", "Figure 8b: capacitance per unit area",
        "C_A rises from about 14 to 15 mF/m² and its branches show less hysteresis than R_A's.",
        f"Reproduced: C_A runs from {c0:.2f} to {cf:.2f} mF/m² (CODATA ε0 = {epsilon_0:.4e} F/m; Table 1 "
        "prints 8.85e-12, which changes C_A by 0.05 % and no hysteresis error)."))
    return figs


def _fig_memory(outdir: Path) -> Figure:
    sf = PAPER.sigma_f_pa
    path = np.concatenate([np.linspace(0, sf, 200), np.linspace(sf, 120e3, 120)[1:], np.linspace(120e3, 240e3, 80)[1:],
                           np.linspace(240e3, 160e3, 60)[1:], np.linspace(160e3, sf, 120)[1:],
                           np.linspace(sf, 0, 200)[1:]])
    hist = separation_history(path)
    fig, ax = new_figure()
    ax.plot(path / 1e3, hist.separation_m * 1e9, "m-", lw=1.2, label="history with minor loops")
    ax.plot(path[:200] / 1e3, separation_loading(path[:200]) * 1e9, "k:", label="eq. (1)")
    xs = np.linspace(0, sf, 300)
    ax.plot(xs / 1e3, separation_unloading(xs, sf) * 1e9, "k--", lw=0.8, label="eq. (9), σf = 322 kPa")
    for i, sp, ss in hist.turning_points:
        ax.plot(sp / 1e3, ss * 1e9, "ko", ms=3)
    ax.set(xlabel="stress σ (kPa)", ylabel="separation s (nm)", title="Extension: separation with memory (k = 2)")
    ax.legend(fontsize=8)
    save(fig, outdir / "ext_separation_memory.png")
    return Figure("ext_separation_memory.png", "Extension: separation under a stress history with minor loops",
                  "The paper models one cycle only and notes that real composites have memory and minor loops.",
                  "fsrlab's turning-point rule (fsrlab.physics.separation.separation_history): reloading heads "
                  "back to the last reversal along the shape of eq. (1), unloading heads for the previous one "
                  "along the shape of eq. (9), and a closed minor loop is wiped out. Dots mark reversals. A single "
                  "full cycle gives eqs. (1) and (9) exactly (tested).")


def build(outdir: Path) -> Section:
    """Build the sensor-physics section into ``outdir``."""
    ours = table2(PAPER)
    phi0_fit = best_phi0_ev()
    fitted = table2(_params(phi0_fit))
    paper_r = PAPER_TABLE2["resistance_per_area_percent"]
    figures = _fig2(outdir) + _fig4_8(outdir, phi0_fit) + [_fig_memory(outdir)]
    rows = []
    for i, u in enumerate(ours["u_V"]):
        rows.append([f"{u} V", paper_r[i], ours["resistance_per_area_percent"][i],
                     fitted["resistance_per_area_percent"][i], PAPER_TABLE2["capacitance_per_area_percent"][i],
                     ours["capacitance_per_area_percent"][i],
                     f"{ours['resistance_stress_at_max_Pa'][i] / 1e3:.1f} / {ours['capacitance_stress_at_max_Pa'][i] / 1e3:.1f}",
                     f"eq. ({ours['tunneling_equation'][i]})"])
    t2 = Table(
        "Table 2: hysteresis error (eq. 13) of R_A and C_A over one cycle 0 → 322 kPa → 0",
        ["u", "R_A paper (%)", "R_A fsrlab (%)", f"R_A, φ0 = {phi0_fit:.4f} eV (%)", "C_A paper (%)",
         "C_A fsrlab (%)", "σd R_A / C_A (kPa)", "J from"],
        rows,
        note="fsrlab: Table 1's parameters with k = 2 (the only integer exponent that gives the printed 1.73 % for "
             "C_A; k = 4 gives 3.27 %), eq. (1) loading, eq. (9) unloading, eqs. (15)–(18), eq. (13) on 4001 "
             "stresses with σd refined. Printed values carry two decimals (±0.005). The column with the fitted "
             "φ0 shows which single parameter change reproduces the paper (erratum P1).",
    )
    p = PAPER
    params_json = {"M_Pa": p.modulus_pa, "sigma_f_Pa": p.sigma_f_pa, "U_V": p.u_v, "s0_m": p.s0_m,
                   "phi0_eV": p.phi0_j / electron_volt, "eps_r": p.eps_r, "eps0_F_per_m": epsilon_0, "k": int(p.k) if float(p.k).is_integer() else p.k}
    errata = [
        Erratum(
            "P1", "Table 2's R_A column does not follow from Table 1's parameters",
            "HE of R_A is 2.21 %, 5.95 %, 10.58 % at u = 3, 2, 1 V (C_A: 1.73 %).",
            "With the printed parameters (k = 2, the exponent that reproduces C_A's 1.73 %) HE of R_A is "
            + ", ".join(f"{v:.2f} %" for v in ours["resistance_per_area_percent"])
            + "; C_A gives " + ", ".join(f"{v:.2f} %" for v in ours["capacitance_per_area_percent"]) + " as printed. "
            f"A barrier height of φ0 = {phi0_fit:.4f} eV instead of 0.223 eV gives "
            + ", ".join(f"{v:.2f} %" for v in fitted["resistance_per_area_percent"])
            + ", the printed values to their last digit; no choice of k does (k moves C_A's 1.73 %).",
            "Two independent implementations agree (fsrlab's vectorised model with a refined σd, and the "
            "plain-scalar brute force in tests/physics/test_table2.py); the issue's own independent check gave "
            "1.47 / 5.62 / 10.23 %. The fitted φ0 also moves Figure 4's curves onto the paper's axes (P2), so the "
            "paper's simulations most likely used φ0 ≈ 0.23 eV, not the printed 0.223 eV.",
        ),
        Erratum(
            "P2", "Figures 4 and 8a: magnitudes of J and R_A",
            "At u = 2 V, J spans about 0.52–0.64 A/µm² and R_A about 3.1–3.8 Ω·µm² (axes of Figure 4).",
            "With Table 1's φ0 = 0.223 eV, J spans "
            f"{current_density(2.0, separation_loading(np.array([0, p.sigma_f_pa]))).min() * _UM2:.3f}–"
            f"{current_density(2.0, separation_loading(np.array([0, p.sigma_f_pa]))).max() * _UM2:.3f} A/µm² and R_A "
            f"{resistance_per_area(2.0, separation_loading(p.sigma_f_pa)) / _UM2:.2f}–"
            f"{resistance_per_area(2.0, p.s0_m) / _UM2:.2f} Ω·µm²; with φ0 = {phi0_fit:.4f} eV, "
            f"{current_density(2.0, p.s0_m, phi0_fit * electron_volt) * _UM2:.3f}–"
            f"{current_density(2.0, separation_loading(p.sigma_f_pa), phi0_fit * electron_volt) * _UM2:.3f} A/µm² and "
            f"{resistance_per_area(2.0, separation_loading(p.sigma_f_pa), phi0_fit * electron_volt) / _UM2:.2f}–"
            f"{resistance_per_area(2.0, p.s0_m, phi0_fit * electron_volt) / _UM2:.2f} Ω·µm².",
            "Figures 4a, 4b and 8a of this report plot both; the shapes agree, only the scale differs, as a "
            "slightly higher barrier predicts.",
        ),
        Erratum(
            "P3", "Table 2 is said to come from Figures 9(a) and 9(b)",
            "“Table 2 presents the values of HE for the simulations performed in Figures 9(a) and 9(b).”",
            "Figures 9(a) and 9(b) are the LM555 circuit diagrams; the simulations are those of Figure 8, as "
            "Table 2's own caption says.",
            "The paper's text, §4, and the captions of Figures 8 and 9.",
        ),
    ]
    intro = (
        "Interparticle separation on loading, eq. (1), and unloading, eq. (9); Simmons tunnelling, eqs. (10)–(12); "
        "resistance and capacitance per unit area, eqs. (14)–(18); hysteresis error, eq. (13). Parameters: "
        "Table 1 (M = 4.73 MPa, σf = 322 kPa, U = 2 V, s0 = 4.418 nm, φ0 = 0.223 eV, ε_r = 7) with k = 2, "
        "which the paper does not print.\n\n"
        "The tunnelling regimes do not join: near u = 0 eq. (10) is 3/2 of eq. (11), and at u = φ0/e eq. (11) is "
        "about half of eq. (12). fsrlab reports the equation it used; at u = 1, 2, 3 V it is eq. (12).\n\n"
        "Eq. (9) as printed needs an even k (eq. 8); it simplifies exactly to s_u = s_f + (s0 − s_f)(1 − σ/σf)^k, "
        "which is real for any k ≥ 1 and is what fsrlab computes."
    )
    data = {
        "parameters": params_json,
        "table2": {**{k: ours[k] for k in ("u_V", "resistance_per_area_percent", "capacitance_per_area_percent",
                                              "resistance_stress_at_max_Pa", "capacitance_stress_at_max_Pa",
                                              "tunneling_equation")},
                   "paper": {k: PAPER_TABLE2[k] for k in ("resistance_per_area_percent", "capacitance_per_area_percent")},
                   "phi0_reproducing_paper_eV": phi0_fit,
                   "resistance_per_area_percent_at_that_phi0": fitted["resistance_per_area_percent"]},
    }
    return Section("physics", "Sensor physics (§2–4)", intro, figures, [t2], errata, data)
