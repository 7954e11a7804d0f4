"""``fsrlab physics``: hysteresis of R_A and C_A over one model cycle (the paper's Table 2)."""

from __future__ import annotations

import dataclasses

import typer
from rich.console import Console
from rich.table import Table
from scipy.constants import electron_volt

from fsrlab.cli import app
from fsrlab.cli._common import electronvolts, emit_json, fail, metres, number, option_names, pascals, volts
from fsrlab.physics.params import PAPER

_NAMES = {"u_v": "--u", "s0_m": "--s0", "modulus_pa": "--modulus", "sigma_f_pa": "--sigma-f", "k": "--k",
          "phi0_j": "--phi0", "eps_r": "--eps-r"}

_WHY = {11: "eq. (11) turns negative", 12: "eq. (12)'s bracket exp(−B) − r·exp(−B√r) is not positive"}


@app.command("physics")
def physics(
    u: list[float] = typer.Option([3.0, 2.0, 1.0], "--u", parser=volts, help="Voltage across the composite [V], e.g. 2 or 2V; repeat for several (default: Table 2's 3, 2, 1)."),
    s0: float = typer.Option(PAPER.s0_m, "--s0", parser=metres, help="Separation at zero stress s0 [m], e.g. 4.418n or 4.418nm."),
    modulus: float = typer.Option(PAPER.modulus_pa, "--modulus", parser=pascals, help="Material stiffness M [Pa], e.g. 4.73M or 4.73MPa."),
    sigma_f: float = typer.Option(PAPER.sigma_f_pa, "--sigma-f", parser=pascals, help="Final stress σf [Pa], e.g. 322k or 322kPa."),
    k: float = typer.Option(PAPER.k, "--k", parser=number, help="Unloading exponent k ≥ 1 (not printed by the paper; 2 reproduces Table 2's C_A)."),
    phi0: float = typer.Option(PAPER.phi0_j / electron_volt, "--phi0", parser=electronvolts, help="Barrier height φ0 [eV], e.g. 0.223 or 223meV."),
    eps_r: float = typer.Option(PAPER.eps_r, "--eps-r", parser=number, help="Relative permittivity ε_r."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Hysteresis error (eq. 13) of R_A and C_A over one cycle 0 → σf → 0; defaults are the paper's Table 1.

    R_A is shown only for voltages where the tunnelling equation gives a current density over the
    whole cycle; the range is computed for the parameters given and printed with the table.
    """
    from fsrlab.analysis.hysteresis import hysteresis_error_curves, model_cycle_errors
    from fsrlab.physics.electrical import capacitance_per_area
    from fsrlab.physics.separation import separation_loading, separation_unloading
    from fsrlab.physics.tunneling import tunneling_regime, voltage_limit

    if not phi0 > 0:
        fail(f"must be > 0 eV, got {phi0:g}", "--phi0")
    for v in u:
        if not v > 0:
            fail(f"must be > 0 V, got {v:g}", "--u")
    with option_names(_NAMES):
        p = dataclasses.replace(PAPER, s0_m=s0, modulus_pa=modulus, sigma_f_pa=sigma_f, k=k,
                                phi0_j=phi0 * electron_volt, eps_r=eps_r)
        # The film is thinnest at σf (eq. 3); thicker films keep J valid to higher voltages.
        s_min = separation_loading(p.sigma_f_pa, p.s0_m, p.modulus_pa)
        u_max = voltage_limit(s_min, p.phi0_j)
        rows, c_only = [], None
        for v in u:
            if v < u_max:
                r = model_cycle_errors(v, p)
                rows.append((v, r.regime, r.resistance, r.capacitance))
                continue
            if c_only is None:  # C_A does not depend on u: the same eq. (13) on eq. (15) alone
                c_only = hysteresis_error_curves(
                    lambda x: capacitance_per_area(separation_loading(x, p.s0_m, p.modulus_pa), p.eps_r),
                    lambda x: capacitance_per_area(separation_unloading(x, p.sigma_f_pa, p.s0_m, p.modulus_pa, p.k), p.eps_r),
                    p.sigma_f_pa)
            rows.append((v, tunneling_regime(v, p.phi0_j), None, c_only))
    out_of_range = [(v, regime) for v, regime, res, _ in rows if res is None]
    if json_out:
        emit_json({"parameters": p.as_dict(), "min_separation_m": s_min, "resistance_u_max_v": u_max, "rows": [
            {"u_v": v, "tunneling_equation": regime, "resistance_valid": res is not None,
             "resistance_per_area_percent": None if res is None else res.percent,
             "resistance_stress_at_max_pa": None if res is None else res.stress_at_max_pa,
             "capacitance_per_area_percent": cap.percent, "capacitance_stress_at_max_pa": cap.stress_at_max_pa}
            for v, regime, res, cap in rows]})
        return
    table = Table(title=f"Hysteresis error over 0 → {sigma_f / 1e3:g} kPa → 0 (eq. 13)")
    for col in ("u (V)", "HE R_A (%)", "σd R_A (kPa)", "HE C_A (%)", "σd C_A (kPa)", "J from"):
        table.add_column(col, justify="right")
    for v, regime, res, cap in rows:
        r_cols = ("—", "—") if res is None else (f"{res.percent:.2f}", f"{res.stress_at_max_pa / 1e3:.1f}")
        table.add_row(f"{v:g}", *r_cols, f"{cap.percent:.2f}", f"{cap.stress_at_max_pa / 1e3:.1f}",
                      f"eq. ({regime})")
    console = Console()
    console.print(table)
    console.print(f"R_A over this cycle needs 0 < u < {u_max:.4g} V (the film thins to {s_min * 1e9:.4g} nm at σf; "
                  "thinner films leave the tunnelling equations' range at lower voltages).")
    for regime in sorted({regime for _, regime in out_of_range}):
        volts_text = ", ".join(f"{v:g}" for v, r in out_of_range if r == regime)
        console.print(f"No R_A at u = {volts_text} V: {_WHY.get(regime, f'eq. ({regime}) gives no current density')} "
                      "there; C_A does not depend on u.")
