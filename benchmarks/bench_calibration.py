"""Calibration with degree selection on 10^6 readings: fsrlab vs scikit-learn, same data, same run.

Task: choose the polynomial degree 1..5 of stress(frequency) by 5-fold cross-validation that keeps
whole cycles together (grouped folds) -- the lowest degree within 1 % of the best RMSE, for both --
then fit the chosen degree on all readings.

- fsrlab: ``fsrlab.calibration.result.calibrate(x, y, degree="auto", groups=cycle)``
  (Chebyshev basis; per-fold sufficient statistics; one QR fit at the end).
- scikit-learn: for each degree, ``cross_val_score(make_pipeline(PolynomialFeatures(d),
  LinearRegression()), X, y, groups=cycle, cv=GroupKFold(5))``, then ``fit`` of the best degree.

Data: one synthetic cycle (VirtualFSR -> LM555 closed forms -> 62.5 ns timer, 0–50 kPa) repeated
20 times with fresh 0.2 % frequency noise per cycle (fsrlab.virtual.synthetic).
"""

from __future__ import annotations

import time

import numpy as np

TITLE = "Calibration with grouped cross-validation (10^6 readings)"
N_CYCLES = 20
POINTS_PER_RAMP = 25_000  # 50 001 readings per cycle → ≈ 1.0e6 readings


def make_data(seed: int = 0):
    from fsrlab.virtual.synthetic import synthetic_run

    base = synthetic_run(cycles=1, points_per_ramp=POINTS_PER_RAMP, frequency_noise=0.0, seed=seed).columns
    rng = np.random.default_rng(seed)
    f0, s0 = base["frequency_hz"], base["stress_pa"]
    f = np.concatenate([f0 * (1 + 0.002 * rng.standard_normal(f0.size)) for _ in range(N_CYCLES)])
    s = np.tile(s0, N_CYCLES)
    g = np.repeat(np.arange(N_CYCLES), f0.size)
    return f, s, g


def fsrlab_run(f, s, g):
    from fsrlab.calibration.result import calibrate

    cal = calibrate(f, s, degree="auto", groups=g, folds=5)
    return cal.degree, cal.cv.rmse


def sklearn_run(f, s, g, scaled=False):
    from sklearn.linear_model import LinearRegression
    from sklearn.model_selection import GroupKFold, cross_val_score
    from sklearn.pipeline import make_pipeline as sk_make_pipeline
    from sklearn.preprocessing import PolynomialFeatures, StandardScaler

    X = f[:, None]
    scores = []

    def make_pipeline(*steps):
        return sk_make_pipeline(StandardScaler(), *steps) if scaled else sk_make_pipeline(*steps)

    for d in range(1, 6):
        model = make_pipeline(PolynomialFeatures(d), LinearRegression())
        sc = cross_val_score(model, X, s, groups=g, cv=GroupKFold(5), scoring="neg_mean_squared_error")
        scores.append(float(np.sqrt(-sc.mean())))
    best = min(d for d, e in zip(range(1, 6), scores) if e <= 1.01 * min(scores))  # same rule as fsrlab
    make_pipeline(PolynomialFeatures(best), LinearRegression()).fit(X, s)
    return best, scores


def _best(fn, repeat):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


REPEAT = 3


def run() -> str:
    f, s, g = make_data()
    # Warm-up: every contender's imports and first-call costs are paid before any timing.
    small = slice(0, 5 * (POINTS_PER_RAMP * 2 + 1))
    fsrlab_run(f[small], s[small], g[small])
    sklearn_run(f[small], s[small], g[small], scaled=True)
    t_ours, (d_ours, rmse_ours) = _best(lambda: fsrlab_run(f, s, g), REPEAT)
    t_sk, (d_sk, rmse_sk) = _best(lambda: sklearn_run(f, s, g), REPEAT)
    t_sc, (d_sc, rmse_sc) = _best(lambda: sklearn_run(f, s, g, scaled=True), REPEAT)
    equal = "the same degree as fsrlab" if d_sc == d_ours else f"degree {d_sc}, fsrlab {d_ours}: NOT equal accuracy"
    rows = "\n".join(f"| {d} | {a:.2f} | {b:.2f} | {c:.2f} |"
                     for d, a, b, c in zip(range(1, 6), rmse_ours, rmse_sk, rmse_sc))
    return (
        f"{f.size:,} readings ({N_CYCLES} cycles of synthetic data), degrees 1–5, 5 grouped folds, final fit.\n\n"
        "The peer at equal accuracy is scikit-learn with StandardScaler first (it picks "
        f"{equal}); the unscaled pipeline is shown for its numerics, not as the peer.\n\n"
        "| implementation | time (s) | chosen degree | fsrlab is faster by |\n|---|---|---|---|\n"
        f"| scikit-learn StandardScaler + PolynomialFeatures + LinearRegression + cross_val_score(GroupKFold) "
        f"(the peer) | {t_sc:.2f} | {d_sc} | **{t_sc / t_ours:.0f}×** |\n"
        f"| same without StandardScaler (wrong degree) | {t_sk:.2f} | {d_sk} | {t_sk / t_ours:.0f}× |\n"
        f"| fsrlab `calibrate(degree=\"auto\")` | {t_ours:.3f} | {d_ours} | 1 |\n\n"
        "Cross-validated RMSE [Pa] per degree (fsrlab pools squared errors over folds; scikit-learn "
        "averages the folds' MSE — equal here because the folds hold equal numbers of whole cycles, and "
        "GroupKFold may pair the cycles differently):\n\n"
        "| degree | fsrlab | scikit-learn | scikit-learn, scaled |\n|---|---|---|---|\n" + rows + "\n\n"
        "Numerics, not only speed: on the raw frequency in Hz (x⁵ ≈ 10²⁰) the unscaled scikit-learn "
        "pipeline loses accuracy from degree 3 on, its cross-validated RMSE grows with the degree and it "
        "chooses a lower degree than the data support; with StandardScaler it agrees with fsrlab.\n\n"
        f"Every contender: best of {REPEAT} runs after a warm-up on 5 cycles (imports not timed). Why fsrlab is faster: the readout is mapped onto "
        "[-1, 1] and written in Chebyshev polynomials, so every fold's normal equations for every degree "
        "come from one pass of per-fold sums (T_0..T_10, T_k·y, y²) with `np.bincount`; no design matrix "
        "is built per fold and degree. The final model is one QR least-squares fit.\n"
    )


if __name__ == "__main__":
    print(run())
