"""The peer of benchmarks/bench_realdata.py that a user can fit: a plain polynomial whose degree is chosen
on the training runs alone (README and docs/calibration.md quote the calibration's ratio to it).

References: closed forms (a noise-free quadratic is fitted exactly by every degree from 2; a straight
line with noise extrapolates worst at high degrees), and the oracle's definition (its degree is the
best on the test run, so the peer can never beat it).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import bench_realdata as B  # noqa: E402


def _run(path: Path, x, y) -> Path:
    return B._write(path, np.arange(x.size) * 0.1, x, y)


def test_a_noise_free_quadratic_is_fitted_exactly(tmp_path):
    x = np.linspace(0.0, 1.0, 400)
    train = _run(tmp_path / "train.csv", x, 2.0 + 3.0 * x ** 2)
    xt = np.linspace(0.0, 1.2, 300)  # the test run reaches beyond the training range
    test = _run(tmp_path / "test.csv", xt, 2.0 + 3.0 * xt ** 2)
    rmse, degree = B._fair_polynomial([train], [test])
    assert degree >= 2 and rmse < 1e-6


@pytest.mark.parametrize("runs", [1, 2])
def test_a_noisy_line_keeps_a_low_degree_and_never_beats_the_oracle(tmp_path, runs):
    rng = np.random.default_rng(7)
    train = []
    for k in range(runs):  # one run: its first 70 % fitted, the rest scored; two: each left out in turn
        x = np.linspace(0.0, 1.0, 300) if runs == 1 else np.linspace(0.5 * k, 0.5 * k + 0.5, 150)
        train.append(_run(tmp_path / f"train{k}.csv", x, 1.0 + 4.0 * x + rng.normal(0, 0.05, x.size)))
    xt = np.linspace(0.0, 1.5, 300)
    test = _run(tmp_path / "test.csv", xt, 1.0 + 4.0 * xt + rng.normal(0, 0.05, xt.size))
    rmse, degree = B._fair_polynomial(train, [test])
    oracle, _ = B._best_polynomial(train, [test])
    assert degree <= 2
    assert rmse >= oracle - 1e-12
    # the noise alone, in % of the test's span (about 6.1 N): the peer stays within twice it
    assert rmse < 2 * 100 * 0.05 / (4.0 * 1.5)
