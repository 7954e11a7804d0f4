"""``fsrlab physics``: hysteresis of R_A and C_A over one model cycle (the paper's Table 2)."""

from __future__ import annotations

import dataclasses
import math
import warnings

import typer

from fsrlab.cli import app
from fsrlab.cli.options import electronvolts, emit_json, fail, metres, number, option_names, pascals, volts
from fsrlab.physics.params import PAPER, electron_volt
from fsrlab.units import format_eng

_NAMES = {"u_v": "--u", "s0_m": "--s0", "modulus_pa": "--modulus", "sigma_f_pa": "--sigma-f", "k": "--k",
          "phi0_j": "--phi0", "eps_r": "--eps-r"}

_WHY = {11: "eq. (11) turns negative", 12: "eq. (12)'s bracket exp(−B) − r·exp(−B√r) is not positive"}
# R_A of a voltage below the limit that still has no finite value (J under- or overflows on such films).
_NOT_FINITE = "the current density under- or overflows over the cycle with these parameters"


def _voltage_limit(s_min: float, phi0_j: float) -> float:
    """u_max of the tunnelling equations, or NaN where the root finder cannot place it (extreme films)."""
    from fsrlab.physics.tunneling import voltage_limit

    try:
        return voltage_limit(s_min, phi0_j)
    except (ValueError, RuntimeError, OverflowError):  # scipy's brentq: no sign change, NaN, no convergence
        return math.nan


def _finite_percent(result) -> bool:
    return math.isfinite(result.percent) and math.isfinite(result.stress_at_max_pa)


@app.command("physics")
def physics(
    u: list[float] = typer.Option([3.0, 2.0, 1.0], "--u", parser=volts, help="Voltage across the composite [V], e.g. 2 "
            "or 2V; repeat for several (default: Table 2's 3, 2, 1)."),
    s0: float = typer.Option(PAPER.s0_m, "--s0", parser=metres, help="Separation at zero stress s0 [m], e.g. 4.418n or "
            "4.418nm."),
    modulus: float = typer.Option(PAPER.modulus_pa, "--modulus", parser=pascals, help="Material stiffness M [Pa], e.g. "
            "4.73M or 4.73MPa."),
    sigma_f: float = typer.Option(PAPER.sigma_f_pa, "--sigma-f", parser=pascals, help="Final stress σf [Pa], e.g. 322k "
            "or 322kPa."),
    k: float = typer.Option(PAPER.k, "--k", parser=number, help="Unloading exponent k ≥ 1 [1] (not printed by the "
            "paper; 2 reproduces Table 2's C_A)."),
    phi0: float = typer.Option(PAPER.phi0_j / electron_volt, "--phi0", parser=electronvolts, help="Barrier height φ0 "
            "[eV], e.g. 0.223 or 223meV."),
    eps_r: float = typer.Option(PAPER.eps_r, "--eps-r", parser=number, help="Relative permittivity ε_r [1], e.g. 7."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON."),
) -> None:
    """Hysteresis error (eq. 13) of R_A and C_A over one cycle 0 → σf → 0; defaults are the paper's Table 1.

    R_A is shown only for voltages where the tunnelling equation gives a current density over the
    whole cycle; the range is computed for the parameters given and printed with the table.

    Examples (Table 2; the Uno's 5 V beside 2 V with a lower final stress, as JSON):

    \b
      fsrlab physics
      fsrlab physics --u 2V --u 5V --sigma-f 200kPa --json
    """
    from fsrlab.physics.separation import separation_loading

    if not phi0 > 0:
        fail(f"must be > 0 eV, got {phi0:g}", "--phi0")
    for v in u:
        if not v > 0:
            fail(f"must be > 0 V, got {v:g}", "--u")
    if sigma_f > 0 and modulus > 0 and not modulus > sigma_f:  # eq. (1) needs M > σf; either may be the slip
        fail(f"--modulus ({modulus:g} Pa) must be greater than --sigma-f ({sigma_f:g} Pa)", "--modulus/--sigma-f")
    with option_names(_NAMES):
        p = dataclasses.replace(PAPER, s0_m=s0, modulus_pa=modulus, sigma_f_pa=sigma_f, k=k,
                                phi0_j=phi0 * electron_volt, eps_r=eps_r)
    # Extreme parameters (films of metres, barriers of 1e300 eV) overflow or underflow on the way:
    # such a row shows no R_A, and the reason; numpy's warnings about them would only repeat it.
    import numpy as np

    with option_names(_NAMES), np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        # The film is thinnest at σf (eq. 3); thicker films keep J valid to higher voltages.
        s_min = separation_loading(p.sigma_f_pa, p.s0_m, p.modulus_pa)
        u_max = _voltage_limit(s_min, p.phi0_j)
        rows = _rows(u, p, s_min, u_max)
    if json_out:
        emit_json({"parameters": p.as_dict(), "min_separation_m": s_min, "resistance_u_max_v": u_max, "rows": [
            {"u_v": v, "tunneling_equation": regime, "resistance_valid": res is not None,
             "resistance_per_area_percent": None if res is None else res.percent,
             "resistance_stress_at_max_pa": None if res is None else res.stress_at_max_pa,
             "capacitance_per_area_percent": cap.percent, "capacitance_stress_at_max_pa": cap.stress_at_max_pa}
            for v, regime, res, cap, _ in rows]})
        return
    _print_table(rows, sigma_f, u_max, s_min)


def _rows(u: list[float], p, s_min: float, u_max: float) -> list[tuple]:
    """Per voltage: (u, the tunnelling equation, R_A's hysteresis error or None, C_A's, why there is no R_A).
    R_A is tried below the voltage limit (or where the limit is unknown) and kept only where finite."""
    from fsrlab.metrics.hysteresis import hysteresis_error_curves, model_cycle_errors
    from fsrlab.physics.electrical import capacitance_per_area
    from fsrlab.physics.separation import separation_loading, separation_unloading
    from fsrlab.physics.tunneling import tunneling_regime

    rows, c_only = [], None
    for v in u:
        if not v >= u_max:  # below the limit, or the limit unknown: try, and keep only finite values
            try:
                r = model_cycle_errors(v, p)
            except (ValueError, RuntimeError, OverflowError):  # "All-NaN slice": no J anywhere
                r = None
            if r is not None and _finite_percent(r.resistance) and _finite_percent(r.capacitance):
                rows.append((v, r.regime, r.resistance, r.capacitance, None))
                continue
        if c_only is None:  # C_A does not depend on u: the same eq. (13) on eq. (15) alone
            c_only = hysteresis_error_curves(
                lambda x: capacitance_per_area(separation_loading(x, p.s0_m, p.modulus_pa), p.eps_r),
                lambda x: capacitance_per_area(separation_unloading(x, p.sigma_f_pa, p.s0_m, p.modulus_pa, p.k),
                                               p.eps_r),
                p.sigma_f_pa)
            if not _finite_percent(c_only):
                fail(f"C_A has no finite hysteresis error for these parameters (film {p.s0_m:g} m at zero "
                     f"stress, {s_min:g} m at σf)", "--s0/--modulus/--sigma-f/--eps-r")
        regime = tunneling_regime(v, p.phi0_j)
        why = _WHY.get(regime, f"eq. ({regime}) gives no current density") if v >= u_max else _NOT_FINITE
        rows.append((v, regime, None, c_only, why))
    return rows


def _print_table(rows: list[tuple], sigma_f: float, u_max: float, s_min: float) -> None:
    """The rows as a table, the voltage range of R_A and why a voltage has no R_A."""
    out_of_range = [(v, why) for v, _, res, _, why in rows if res is None]
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"Hysteresis error over 0 → {sigma_f / 1e3:g} kPa → 0 (eq. 13)")
    for col in ("u (V)", "HE R_A (%)", "σd R_A (kPa)", "HE C_A (%)", "σd C_A (kPa)", "J from"):
        table.add_column(col, justify="right")
    for v, regime, res, cap, _ in rows:
        r_cols = ("—", "—") if res is None else (f"{res.percent:.2f}", f"{res.stress_at_max_pa / 1e3:.1f}")
        table.add_row(f"{v:g}", *r_cols, f"{cap.percent:.2f}", f"{cap.stress_at_max_pa / 1e3:.1f}",
                      f"eq. ({regime})")
    console = Console()
    console.print(table)
    if math.isfinite(u_max):
        console.print(f"R_A over this cycle needs 0 < u < {u_max:.4g} V (the film thins to {s_min * 1e9:.4g} nm at σf; "
                      "thinner films leave the tunnelling equations' range at lower voltages).")
    else:
        console.print(f"The voltage range of R_A could not be placed for a film of {format_eng(s_min, 'm')} at σf.")
    for why in dict.fromkeys(why for _, why in out_of_range):
        volts_text = ", ".join(f"{v:g}" for v, w in out_of_range if w == why)
        console.print(f"No R_A at u = {volts_text} V: {why}; C_A does not depend on u.")
