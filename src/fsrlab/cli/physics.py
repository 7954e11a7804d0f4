"""``fsrlab physics``: hysteresis of R_A and C_A over one model cycle (the paper's Table 2)."""

from __future__ import annotations

import dataclasses

import typer
from rich.console import Console
from rich.table import Table
from scipy.constants import electron_volt

from fsrlab.cli import app
from fsrlab.cli._common import emit_json, eng, fail, option_names
from fsrlab.physics.params import PAPER


@app.command("physics")
def physics(
    u: list[str] = typer.Option(["3", "2", "1"], "--u", help="Voltage across the composite [V]; repeat for several (default: Table 2's 3, 2, 1)."),
    s0: float = typer.Option(PAPER.s0_m, "--s0", parser=eng, help="Separation at zero stress s0 [m], e.g. 4.418n."),
    modulus: float = typer.Option(PAPER.modulus_pa, "--modulus", parser=eng, help="Material stiffness M [Pa], e.g. 4.73M."),
    sigma_f: float = typer.Option(PAPER.sigma_f_pa, "--sigma-f", parser=eng, help="Final stress σf [Pa], e.g. 322k."),
    k: float = typer.Option(PAPER.k, "--k", parser=eng, help="Unloading exponent k ≥ 1 (not printed by the paper; 2 reproduces Table 2's C_A)."),
    phi0: float = typer.Option(PAPER.phi0_j / electron_volt, "--phi0", parser=eng, help="Barrier height φ0 [eV]."),
    eps_r: float = typer.Option(PAPER.eps_r, "--eps-r", parser=eng, help="Relative permittivity ε_r."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Hysteresis error (eq. 13) of R_A and C_A over one cycle 0 → σf → 0; defaults are the paper's Table 1."""
    from fsrlab.analysis.hysteresis import model_cycle_errors
    from fsrlab.units import parse_eng

    if not phi0 > 0:
        fail(f"must be > 0 eV, got {phi0:g}", "--phi0")
    with option_names({"u_v": "--u", "s0_m": "--s0", "modulus_pa": "--modulus", "sigma_f_pa": "--sigma-f",
                       "k": "--k", "eps_r": "--eps-r"}):
        voltages = [parse_eng(v, "--u") for v in u]
        params = dataclasses.replace(PAPER, s0_m=s0, modulus_pa=modulus, sigma_f_pa=sigma_f, k=k,
                                     phi0_j=phi0 * electron_volt, eps_r=eps_r)
        rows = [model_cycle_errors(v, params) for v in voltages]
    if json_out:
        emit_json({"parameters": params.as_dict(), "rows": [
            {"u_v": r.u_v, "tunneling_equation": r.regime,
             "resistance_per_area_percent": r.resistance.percent, "resistance_stress_at_max_pa": r.resistance.stress_at_max_pa,
             "capacitance_per_area_percent": r.capacitance.percent, "capacitance_stress_at_max_pa": r.capacitance.stress_at_max_pa}
            for r in rows]})
        return
    table = Table(title=f"Hysteresis error over 0 → {sigma_f / 1e3:g} kPa → 0 (eq. 13)")
    for col in ("u (V)", "HE R_A (%)", "σd R_A (kPa)", "HE C_A (%)", "σd C_A (kPa)", "J from"):
        table.add_column(col, justify="right")
    for r in rows:
        table.add_row(f"{r.u_v:g}", f"{r.resistance.percent:.2f}", f"{r.resistance.stress_at_max_pa / 1e3:.1f}",
                      f"{r.capacitance.percent:.2f}", f"{r.capacitance.stress_at_max_pa / 1e3:.1f}", f"eq. ({r.regime})")
    Console().print(table)
