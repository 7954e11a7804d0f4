"""Throughput of the Table 2 pipeline: separation, R_A and C_A on both branches, and HE (eq. 13)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

TITLE = "Table 2 pipeline (sensor physics)"
N_POINTS = 1_000_000
N_LOOP = 100_000  # the plain loops are measured on fewer points; throughput is per point
N_SCALAR_CALLS = 5_000


def fsrlab_scalar_loop(u: float, n: int) -> tuple[float, float]:
    """The same computation with fsrlab's own functions called on one scalar stress at a time."""
    from fsrlab.physics.electrical import capacitance_per_area, resistance_per_area
    from fsrlab.physics.params import PAPER
    from fsrlab.physics.separation import separation_loading, separation_unloading

    best_r = best_c = 0.0
    r_f = c_f = 1.0
    for i in range(n + 1):
        x = PAPER.sigma_f_pa * i / n
        sl, su = separation_loading(x), separation_unloading(x)
        rl, ru = resistance_per_area(u, sl), resistance_per_area(u, su)
        cl, cu = capacitance_per_area(sl), capacitance_per_area(su)
        best_r, best_c = max(best_r, abs(ru - rl)), max(best_c, abs(cu - cl))
        r_f, c_f = rl, cl
    return 100 * best_r / r_f, 100 * best_c / c_f


def _best(fn, repeat):
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def run() -> str:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from reference_physics import table2_row

    from fsrlab.analysis.hysteresis import model_cycle_errors

    model_cycle_errors(2.0, n=1000)  # warm up imports
    t_vec = _best(lambda: model_cycle_errors(2.0, n=N_POINTS), 5)
    t_loop = _best(lambda: table2_row(2.0, N_LOOP), 2)
    t_calls = _best(lambda: fsrlab_scalar_loop(2.0, N_SCALAR_CALLS), 2)
    vec_rate = N_POINTS / t_vec
    loop_rate = (N_LOOP + 1) / t_loop
    calls_rate = (N_SCALAR_CALLS + 1) / t_calls
    return (
        f"The Table 2 computation at u = 2 V (eq. 1 and eq. 9 separation, eq. 12 R_A and eq. 15 C_A on both "
        f"branches, eq. 13 HE with σd refined) over {N_POINTS:,} stresses, as `fsrlab.analysis.hysteresis."
        f"model_cycle_errors`, against the same computation as a plain Python loop over scalars with the "
        f"`math` module (`tests/reference_physics.py::table2_row`, {N_LOOP:,} stresses), and against "
        f"fsrlab's own functions called in a Python loop on one scalar at a time ({N_SCALAR_CALLS:,} stresses). "
        f"Best of 5, 2 and 2 runs.\n\n"
        f"| implementation | time | stress points/s | fsrlab is |\n|---|---|---|---|\n"
        f"| fsrlab (numpy, vectorised) | {t_vec * 1e3:.1f} ms for {N_POINTS:,} | {vec_rate:.3g} | |\n"
        f"| loop calling fsrlab per scalar | {t_calls * 1e3:.0f} ms for {N_SCALAR_CALLS:,} | {calls_rate:.3g} | "
        f"{vec_rate / calls_rate:.0f}× faster |\n"
        f"| hand-written `math` loop | {t_loop * 1e3:.0f} ms for {N_LOOP:,} | {loop_rate:.3g} | "
        f"{vec_rate / loop_rate:.0f}× faster |\n\n"
        f"Target: ≥ 10⁷ points/s: {'met' if vec_rate >= 1e7 else 'NOT met'}; ≥ 100× the loop: "
        f"{'met' if vec_rate / calls_rate >= 100 else 'NOT met'} against the loop over fsrlab's functions, "
        f"{'met' if vec_rate / loop_rate >= 100 else 'not met'} against the hand-written `math` loop, which needs no "
        f"array bookkeeping: 100× of it would be ≈ {100 * loop_rate:.2g} points/s, about "
        f"{1e9 / (100 * loop_rate):.0f} ns per stress for four exponentials and ~40 other operations on one core.\n"
    )
