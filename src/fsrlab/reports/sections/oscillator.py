"""Report section: the LM555 oscillator (paper §5): Figures 12 and 15 as they should be, errata O1–O5.

Every number is computed when the report is built: the printed and corrected τH/τL and its ngspice
check by :mod:`fsrlab.circuits.paper_ratio` (closed forms of :mod:`fsrlab.circuits.lm555`; ngspice
through :mod:`fsrlab.circuits.spice` when it is installed), the frequency decomposition by
:mod:`fsrlab.circuits.decomposition`, the paper's statements from :func:`fsrlab.reference.paper_values`.
This module draws and words them; the errata O1–O5 are worded in
:mod:`fsrlab.reports.sections._oscillator_errata`.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from pathlib import Path

import numpy as np

from fsrlab.circuits.decomposition import frequency_decomposition
from fsrlab.circuits.lm555 import astable, duty_cycle_limits, minimum_n_ratio, sensitivity, tau_ratio
from fsrlab.circuits.paper_ratio import (
    RatioMinimum,
    SimulatedRatios,
    TauRatioTable,
    minimum_eq32_as_printed,
    n_where_ratio_equals,
    start_tau_ratios,
    tau_ratio_eq32_as_printed,
    tau_ratio_eq37_as_printed,
    tau_ratio_table,
)
from fsrlab.circuits.spice import ngspice_available
from fsrlab.reference import paper_values
from fsrlab.reports.figures import new_figure, plain_log_labels, save
from fsrlab.reports.model import Figure, Section, Table
from fsrlab.reports.sections._oscillator_errata import oscillator_errata

#: N = R_FSR/R values shown in the table and simulated with ngspice.
N_TABLE = [4.5, 5.0, 6.0, 8.0, 10.0, 14.0, 20.0, 50.0, 100.0, 1000.0]

R_OHM, C_FARAD = 10e3, 1e-9  # fsrlab's choice; τH/τL and DC depend on N alone

def _claims() -> dict:
    """The §5 statements on τH/τL and the duty cycle, as printed (fractions for duty cycles)."""
    printed = paper_values()["section5_tau_ratio_claims"]
    return {k: v for k, v in printed.items() if k != "note"}


def _no_spice() -> tuple[None, None]:
    return None, None


def prefetch() -> Callable[[], tuple[SimulatedRatios | None, SimulatedRatios | None]]:
    """Start the section's ngspice runs now and return what waits for them (see :func:`build`).

    The runs are processes started at once (the longest first, no thread yet:
    :func:`fsrlab.circuits.paper_ratio.start_tau_ratios`), so they go on while the report imports and
    draws the other sections; :func:`fsrlab.reports.paper.build_sections` calls the returned function in
    a background thread and passes its future to :func:`build`.
    """
    if not ngspice_available():
        return _no_spice
    runs = start_tau_ratios(N_TABLE, (False, True), R_OHM, C_FARAD)
    return lambda: tuple(runs.results())


def _ratio_axes(ax, diode: bool, spice: SimulatedRatios | None, claims: dict, minimum: RatioMinimum) -> None:
    n = 4.0 + np.geomspace(1e-9, 16.0, 3000)
    ax.plot(n, tau_ratio(n, diode=diode), "C0-", lw=1.8,
            label=f"{'eq. (37) corrected' if diode else 'eq. (32) corrected'}: eqs. (23), ({34 if diode else 26})")
    if diode:
        ax.plot(n, tau_ratio_eq37_as_printed(n), "C3--", lw=1.4, label="eq. (37) as printed (extra factor N)")
        lim, lim_dc = claims["lim_tau_ratio_diode"], 100 * claims["min_duty_cycle_diode"]
        ax.axhline(lim, color="C3", ls=":", lw=1, label=f"printed eq. (37) → {lim:g} (paper: DC ≥ {lim_dc:g} %)")
        ax.axhline(0.0, color="C0", ls=":", lw=1, label="corrected → 0 as N → ∞")
    else:
        ax.plot(n, tau_ratio_eq32_as_printed(n), "C3--", lw=1.4,
                label=f"eq. (32) as printed (extra factor N; min {minimum.value:.2f} at N = {minimum.n_ratio:.2f})")
        ax.axhline(claims["min_tau_ratio_no_diode"], color="C3", ls=":", lw=1,
                   label=f"paper: “minimal value {claims['min_tau_ratio_no_diode']}”")
        ax.axhline(2.0, color="C0", ls=":", lw=1, label="infimum 2 (N → ∞), never reached")
    if spice:
        m = np.array(spice.n_ratio) <= 20
        ax.plot(np.array(spice.n_ratio)[m], np.array(spice.tau_ratio)[m], "ko", ms=5, mfc="none",
                label="ngspice transient")
    ax.axvline(4.0, color="0.5", lw=0.8)
    ax.set(xlim=(0, 20), ylim=(-4, 12) if diode else (-10, 60), xlabel="N = R_FSR / R", ylabel="τH / τL",
           title=("Figure 15" if diode else "Figure 12") + ": τH/τL vs N" + (" with D1" if diode else ""))
    ax.legend(fontsize=7.5)


def _duty_axes(ax, diode: bool, spice: SimulatedRatios | None, claims: dict) -> None:
    nn = np.geomspace(4.0005, 1e4, 2000)
    ax.semilogx(nn, 100 * astable(R_OHM, nn * R_OHM, C_FARAD, diode=diode).duty_cycle, "C0-", lw=1.8,
                label="fsrlab closed form")
    if diode:
        dc = 100 * claims["min_duty_cycle_diode"]
        ax.axhline(dc, color="C3", ls="--", lw=1.2, label=f"paper: smallest DC {dc:g} %")
    else:
        ax.axhline(100 * claims["min_duty_cycle_no_diode"], color="C3", ls="--", lw=1.2,
                   label=f"paper: DC ≥ {100 * claims['min_duty_cycle_no_diode']:g} %")
        ax.axhline(100 * duty_cycle_limits()[0], color="C0", ls=":", lw=1, label="infimum 66.7 %")
    if spice:
        ax.semilogx(spice.n_ratio, 100 * np.array(spice.duty_cycle), "ko", ms=5, mfc="none", label="ngspice")
    ax.set(xlabel="N = R_FSR / R", ylabel="duty cycle (%)", ylim=(0, 101),
           title="duty cycle vs N" + (" with D1" if diode else " without diode"))
    plain_log_labels(ax.xaxis)
    ax.legend(fontsize=7.5)


def _ratio_figure(outdir: Path, diode: bool, spice: SimulatedRatios | None, claims: dict, minimum: RatioMinimum,
                  t: TauRatioTable) -> Figure:
    """Figure 12 (no diode) or 15 (D1): τH/τL versus N on the left, the duty cycle on the right."""
    name = "fig15_tau_ratio_diode.png" if diode else "fig12_tau_ratio_no_diode.png"
    fig, (ax1, ax2) = new_figure(11.0, 4.2, ncols=2)
    _ratio_axes(ax1, diode, spice, claims, minimum)
    _duty_axes(ax2, diode, spice, claims)
    save(fig, outdir / name)
    if diode:
        return Figure(
            name, "Figure 15: τH/τL versus N with the diode D1 (eq. 37)",
            "Figure 15 plots eq. (37) (N 0–20, y −4 to 12); the text takes lim τH/τL = 2, so DC ≥ 66.6 %.",
            "Red dashed: eq. (37) as printed (→ 2). Blue: the ratio that follows from eqs. (23) and (34) (→ 0). "
            + ("ngspice points follow the blue curve." if spice else "ngspice not installed: no simulator points.")
            + " Right: the duty cycle reaches any value down to 0 (O2, O3).")
    return Figure(
        name, "Figure 12: τH/τL versus N without the diode (eq. 32)",
        "Figure 12 plots eq. (32) for N from 0 to 20 (y from −10 to 60); the text says its minimum for N > 4 "
        "is 24.37, so DC ≥ 96 %.",
        f"Red dashed: eq. (32) as printed, ln((2 − 2N)/(4 − N))·2N(N + 1)/(ln 2·(N + 2)); its minimum "
        f"({minimum.value:.2f} at N = {minimum.n_ratio:.2f}) is the paper's 24.37 and its values fit Figure 12's "
        f"axes ({t.eq32_as_printed[t.n_ratio.index(20.0)]:.1f} at N = 20): figure and number follow from the "
        "printed equation. Blue: the ratio of the paper's own τH and τL, eqs. (23) and (26), the printed one "
        f"divided by N; it decreases monotonically toward 2 with no minimum ({t.no_diode[t.n_ratio.index(20.0)]:.3f} "
        "at N = 20). "
        + ("ngspice points lie on the blue curve (within 0.01 %)." if spice else "ngspice not installed: no "
           "simulator points.") + " Right: the duty cycle stays above 66.7 %, not 96 % (O1).")


def _sensitivity_figure(outdir: Path, s20_nd: float, s20: float) -> Figure:
    """∂ln f/∂ln R_FSR versus N, with and without D1; ``s20_*`` are its values at N = 20."""
    fig, ax = new_figure()
    nn = np.geomspace(4.05, 1e3, 800)
    for diode, style in ((False, "C0"), (True, "C1")):
        s = sensitivity(R_OHM, nn * R_OHM, C_FARAD, diode=diode)
        name = "with D1" if diode else "without diode"
        ax.semilogx(nn, s.r_fsr, style + "-", label=f"∂ln f/∂ln R_FSR, {name}")
    ax.axhline(-1.0, color="0.4", ls=":", lw=1, label="∂ln f/∂ln C_FSR (C_off = 0)")
    ax.set(xlabel="N = R_FSR / R", ylabel="logarithmic sensitivity", ylim=(-1.5, 3.0),
           title="How resistive is the “capacitive” frequency? (extension)")
    plain_log_labels(ax.xaxis)
    ax.legend(fontsize=8)
    save(fig, outdir / "oscillator_sensitivity.png")
    return Figure(
        "oscillator_sensitivity.png", "Extension: sensitivity of f to R_FSR, per variant",
        "§5: even if R ≪ R_FSR, f still depends on R_FSR (eq. 35); Figure 19a shows f rising from about 3 to "
        "10 kHz with stress.",
        f"With D1, ∂ln f/∂ln R_FSR = {s20:.3f} at N = 20 and → −1 as N grows (f ≈ 1/(ln 2·R_FSR·C)): "
        "the “capacitive” frequency is then as much a resistance reading, and a falling R_FSR under load "
        "raises f as in Figure 19a. Without the diode it is "
        f"{s20_nd:+.3f} at N = 20 (f nearly independent of R_FSR, and it rises with R_FSR). "
        "∂ln f/∂ln C_FSR = −C_FSR/(C_FSR + C_off) in both variants.")


def _stress_text(fs: dict) -> Figure:
    d, nd = fs["diode"], fs["no_diode"]
    return Figure(
        "oscillator_frequency_vs_stress.png",
        "Extension: where the frequency change under load comes from (fsrlab's VirtualFSR, 0–10 kPa)",
        "Figure 19a: f rises from about 3 to 10 kHz as stress rises, read as a capacitive measurement.",
        f"On the VirtualFSR (R_FSR {fs['r_fsr_ohm'][0] / 1e6:.2f} → {fs['r_fsr_ohm'][1] / 1e6:.2f} MΩ, C_FSR "
        f"{fs['c_fsr_farad'][0] * 1e12:.0f} → {fs['c_fsr_farad'][1] * 1e12:.0f} pF) the paper's circuit with D1 "
        "(R = 10 kΩ, fsrlab's choice: the paper prints no value for R) "
        f"rises {d['frequency_hz'][0] / 1e3:.2f} → {d['frequency_hz'][1] / 1e3:.2f} kHz, "
        "like Figure 19a; with C_FSR alone it would fall "
        f"({d['c_only_hz'][0] / 1e3:.2f} → {d['c_only_hz'][1] / 1e3:.2f} kHz), with R_FSR "
        f"alone it would rise ({d['r_only_hz'][0] / 1e3:.2f} → {d['r_only_hz'][1] / 1e3:.2f} kHz): "
        "the rise is resistive. Without D1 f falls "
        f"{nd['frequency_hz'][0] / 1e3:.1f} → {nd['frequency_hz'][1] / 1e3:.1f} kHz, "
        "almost all of it from C_FSR. The sensor model is fsrlab's extension (fsrlab.physics.sensor), "
        "not the paper's; the decomposition holds for any sensor whose R_FSR falls under load.")


def _stress_figure(outdir: Path) -> tuple[Figure, dict]:
    """f versus stress on fsrlab's VirtualFSR for both variants, split into C-only and R-only parts."""
    from fsrlab.physics.sensor import VirtualFSR

    stress = np.linspace(0.0, 10e3, 101)  # the paper's Figure 17 range, 0–10 kPa
    resp = VirtualFSR().respond(stress)
    rf, cf = resp.r_fsr_ohm, resp.c_fsr_farad
    fig, axes = new_figure(11.0, 4.2, ncols=2)
    out = {"stress_pa": [float(stress[0]), float(stress[-1])], "r_fsr_ohm": [float(rf[0]), float(rf[-1])],
           "c_fsr_farad": [float(cf[0]), float(cf[-1])]}
    for ax, diode in zip(axes, (True, False), strict=True):
        parts = frequency_decomposition(R_OHM, rf, cf, diode=diode)
        ax.plot(stress / 1e3, parts.frequency_hz / 1e3, "k-", lw=2, label="f (R_FSR and C_FSR change)")
        ax.plot(stress / 1e3, parts.c_only_hz / 1e3, "C0--", label="only C_FSR changes")
        ax.plot(stress / 1e3, parts.r_only_hz / 1e3, "C1--", label="only R_FSR changes")
        ax.set(xlabel="stress σ (kPa)", ylabel="f (kHz)",
               title=("with D1 (the paper's Fig. 16 circuit)" if diode else "without D1")
               + "\nR = 10 kΩ (fsrlab's choice), C_off = 0")
        ax.legend(fontsize=8)
        out["diode" if diode else "no_diode"] = parts.to_dict()
    save(fig, outdir / "oscillator_frequency_vs_stress.png")
    return _stress_text(out), out


def _ratio_table(t: TauRatioTable, spice_nd: SimulatedRatios | None, spice_d: SimulatedRatios | None) -> Table:
    rows = []
    for i, ni in enumerate(t.n_ratio):
        rows.append([f"{ni:g}", float(t.no_diode[i]), spice_nd.tau_ratio[i] if spice_nd else "n/a",
                     float(t.eq32_as_printed[i]),
                     100 * float(t.duty_cycle_no_diode[i]), float(t.diode[i]),
                     spice_d.tau_ratio[i] if spice_d else "n/a",
                     float(t.eq37_as_printed[i]), 100 * float(t.duty_cycle_diode[i])])
    note = ("ngspice columns: transient simulation of fsrlab's behavioural-555 netlist, 5 periods after "
            "start-up, τH/τL = DC/(1 − DC) from the output edges." if spice_nd else
            "ngspice is not installed here, so the independent-simulator columns are empty "
            "(`make sysdeps` installs it).")
    return Table("τH/τL and duty cycle versus N (R = 10 kΩ, C = 1 nF; both depend on N only)",
                 ["N", "τH/τL eqs. (23), (26)", "ngspice", "eq. (32) as printed", "DC % no diode", "τH/τL with D1",
                  "ngspice (D1)",
                  "eq. (37) as printed", "DC % with D1"], rows, note=note, fmt="{:.4g}")


def _intro() -> str:
    with_rd = float(astable(R_OHM, 200e3, C_FARAD, discharge_ohm=50.0).frequency_hz)
    ideal = float(astable(R_OHM, 200e3, C_FARAD).frequency_hz)
    return (
        "The FSR (R_FSR ∥ C_FSR, plus C_off) is the timing element of an LM555 astable with R_A = R_B = R, with or "
        "without a diode D1 in series with R_B. τH/τL and the duty cycle depend on N = R_FSR/R only; the circuit "
        "oscillates only for N > 4 (eq. 30; with a diode drop V_D, N > 2uVcc/(Vcc − V_D − uVcc)).\n\n"
        "Closed forms: fsrlab.circuits.lm555; exact event-driven simulation: fsrlab.circuits.transient; "
        "independent check: ngspice with fsrlab's behavioural 555 (fsrlab.circuits.spice), which agrees with the "
        "closed forms to better than 1e-4 over N = 4.5–1000 with and without D1 and C_off "
        "(tests/circuits/test_spice.py).\n\n"
        "Beyond the paper's ideal parts, fsrlab models a diode forward drop (0.6 V raises the oscillation limit to "
        f"N > {minimum_n_ratio(0.6):.4g}), thresholds moved by the control pin, and the discharge transistor's "
        f"on-resistance (50 Ω changes f by {100 * (with_rd / ideal - 1):+.2f} % "
        "without D1 at R = 10 kΩ, R_FSR = 200 kΩ, and not at all with D1, which blocks R_B during the discharge). "
        "Neglected: comparator delay and offset, output edge times, input currents of pins 2 and 6, diode leakage "
        "and the current dependence of its drop."
    )


def build(outdir: Path, prefetched: Future | None = None) -> Section:
    """Build the oscillator section into ``outdir`` (PNGs) and return it.

    ``prefetched``: the future of :func:`prefetch`'s function when the ngspice runs were started earlier
    (without it they run now). The figures without simulator points are drawn before waiting for them.
    """
    outdir = Path(outdir)
    claims = _claims()
    table = tau_ratio_table(N_TABLE)
    minimum = minimum_eq32_as_printed()
    n_at_claim = n_where_ratio_equals(claims["min_tau_ratio_no_diode"])
    s20_nd = float(sensitivity(R_OHM, 20 * R_OHM, C_FARAD).r_fsr)
    s20 = float(sensitivity(R_OHM, 20 * R_OHM, C_FARAD, diode=True).r_fsr)
    stress_figure, fs = _stress_figure(outdir)
    sensitivity_figure = _sensitivity_figure(outdir, s20_nd, s20)
    spice_nd, spice_d = prefetched.result() if prefetched is not None else prefetch()()
    figures = [_ratio_figure(outdir, False, spice_nd, claims, minimum, table),
               _ratio_figure(outdir, True, spice_d, claims, minimum, table), sensitivity_figure, stress_figure]
    errata = oscillator_errata(table, minimum, n_at_claim, spice_nd, spice_d, R_OHM, C_FARAD)
    dc_inf_nd, dc_inf_d = duty_cycle_limits()[0], duty_cycle_limits(diode=True)[0]
    data = {"oscillator": {
        "paper_claims": claims,
        **table.to_dict(),
        "duty_cycle_infimum_no_diode": dc_inf_nd,
        "duty_cycle_infimum_diode": dc_inf_d,
        "tau_ratio_infimum_no_diode": dc_inf_nd / (1 - dc_inf_nd),
        "n_where_corrected_eq32_equals_24_37": n_at_claim,
        "paper_24_37_explained": minimum.to_dict(),
        "sensitivity_r_fsr_at_N20": {"no_diode": s20_nd, "diode": s20},
        "frequency_vs_stress_virtual_fsr": fs,
        "ngspice_available": spice_nd is not None,
        "ngspice_no_diode": spice_nd.to_dict() if spice_nd else None,
        "ngspice_diode": spice_d.to_dict() if spice_d else None,
    }}
    return Section(key="oscillator", title="LM555 oscillator (§5)", intro=_intro(), figures=figures,
                   tables=[_ratio_table(table, spice_nd, spice_d)], errata=errata, data=data)
