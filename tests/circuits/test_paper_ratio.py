"""τH/τL as printed and as computed (fsrlab.circuits.paper_ratio), errata O1–O3.

References: the paper's §5 statements as printed (24.37, 0.96; fsrlab/data/paper.json), eqs. (32)
and (37) retyped here from the paper's extracted text, the ratio of eqs. (23) and (26) retyped here
from the paper's τH and τL, and ngspice as the independent simulator.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsrlab.circuits.lm555 import tau_ratio
from fsrlab.circuits.paper_ratio import (
    minimum_eq32_as_printed,
    n_where_ratio_equals,
    simulate_tau_ratios,
    tau_ratio_eq32_as_printed,
    tau_ratio_eq37_as_printed,
    tau_ratio_table,
    tau_ratio_times_n,
)
from toolcheck import require_tool


def eq32(n):
    """τH/τL from eqs. (23) and (26) with R_FSR = N·R (R = C = 1), retyped from the paper's τH and τL."""
    r, rf = 1.0, float(n)
    tau_h = math.log((2 * r - 2 * rf) / (4 * r - rf)) * 2 * r * rf / (2 * r + rf)  # eq. (23)
    tau_l = math.log(2) * r * rf / (r + rf)  # eq. (26)
    return tau_h / tau_l


def eq32_printed(n):
    """Eq. (32) as printed, retyped from "ln 2 − 2N / 4 −N 2N N + 1 / ln 2 N + 2" (read as eq. 37 is read)."""
    return math.log((2 - 2 * n) / (4 - n)) * 2 * n * (n + 1) / (math.log(2) * (n + 2))


def eq37_printed(n):
    """Eq. (37) as printed, retyped: ln((2 − 2N)/(4 − N))·2N/(ln 2·(N + 2))."""
    return math.log((2 - 2 * n) / (4 - n)) * 2 * n / (math.log(2) * (n + 2))


def test_eq37_as_printed_matches_the_retyped_equation_and_is_n_times_the_corrected_ratio():
    n = np.array([4.5, 10.0, 100.0])
    np.testing.assert_allclose(tau_ratio_eq37_as_printed(n), [eq37_printed(x) for x in n], rtol=1e-14)
    # Erratum O2: the ratio that follows from eqs. (23) and (34) is the printed one divided by N.
    np.testing.assert_allclose(tau_ratio_eq37_as_printed(n) / n, tau_ratio(n, diode=True), rtol=1e-12)
    # The paper's lim τH/τL = 2 holds for the printed form only (N = 1e6: within 1e-4 of 2).
    assert tau_ratio_eq37_as_printed(1e6) == pytest.approx(2.0, abs=1e-4)
    assert np.isnan(tau_ratio_eq37_as_printed(3.0))


def test_printed_eq32_is_n_times_the_ratio_of_eqs_23_and_26():
    # Erratum O1: the printed eq. (32) (retyped) is N × the ratio of the paper's own τH and τL
    # (retyped), the same extra factor N as the printed eq. (37) (O2).
    n = np.array([4.5, 6.0, 10.0, 20.0, 100.0])
    np.testing.assert_allclose(tau_ratio_eq32_as_printed(n), [eq32_printed(x) for x in n], rtol=1e-14)
    np.testing.assert_allclose(tau_ratio_eq32_as_printed(n) / n, [eq32(x) for x in n], rtol=1e-12)
    np.testing.assert_allclose(tau_ratio_eq32_as_printed(n) / n, tau_ratio(n), rtol=1e-12)
    # Figure 12's y-axis (−10 to 60 for N ≤ 20) holds the printed form (47.6 at N = 20), not the
    # corrected one (2.38 at N = 20).
    assert 40 < eq32_printed(20.0) < 60 and eq32(20.0) < 2.5
    assert np.isnan(tau_ratio_eq32_as_printed(3.0))


def test_the_papers_24_37_and_0_96_are_the_minimum_of_the_printed_eq32(paper):
    # Reference: §5 prints "the minimal value of the ratio τH/τL for N > 4 is 24.37" and
    # "24.37/25.37 = 0.96". The minimum of the printed eq. (32) (retyped) truncates to 24.37.
    claims = paper["section5_tau_ratio_claims"]
    m = minimum_eq32_as_printed()
    assert math.floor(100 * m.value) / 100 == claims["min_tau_ratio_no_diode"]
    assert round(m.duty_cycle, 2) == claims["min_duty_cycle_no_diode"]
    assert eq32_printed(m.n_ratio) == pytest.approx(m.value, rel=1e-12)
    # A minimum: the retyped printed equation is larger on both sides, and a dense grid finds
    # nothing lower (independent of the bounded minimiser).
    for dn in (-0.05, 0.05):
        assert eq32_printed(m.n_ratio + dn) > m.value
    grid = 4.0 + np.geomspace(1e-6, 1e4, 200_001)
    assert np.nanmin(tau_ratio_eq32_as_printed(grid)) >= m.value - 1e-9
    assert m.to_dict() == {"expression": "eq. (32) as printed (= N * tau_H/tau_L of eqs. 23, 26)",
                           "minimum": m.value, "at_N": m.n_ratio}


def test_the_corrected_ratio_reaches_24_37_only_next_to_the_oscillation_limit(paper):
    # Erratum O1: the ratio of eqs. (23) and (26) (retyped) equals 24.37 at N = 4.00024, right at N = 4.
    value = paper["section5_tau_ratio_claims"]["min_tau_ratio_no_diode"]
    n = n_where_ratio_equals(value)
    assert 4.0 < n < 4.001
    assert eq32(n) == pytest.approx(value, rel=1e-9)
    # Beyond the first bracket [4, 5]: the ratio is 2.1 near N = 69 (2 + 2(3/ln 2 − 1)/N ≈ 2.1).
    assert eq32(n_where_ratio_equals(2.1)) == pytest.approx(2.1, rel=1e-9)
    with pytest.raises(ValueError, match="value"):
        n_where_ratio_equals(2.0)  # the infimum is never reached


def test_times_n_is_n_times_the_closed_form():
    n = np.array([4.5, 6.0, 20.0])
    np.testing.assert_allclose(tau_ratio_times_n(n), [eq32_printed(x) for x in n], rtol=1e-12)
    np.testing.assert_allclose(tau_ratio_times_n(n, diode=True), [eq37_printed(x) for x in n], rtol=1e-12)


def test_table_columns_follow_the_retyped_equations():
    t = tau_ratio_table([4.5, 10.0, 1000.0])
    np.testing.assert_allclose(t.no_diode, [eq32(x) for x in (4.5, 10.0, 1000.0)], rtol=1e-12)
    np.testing.assert_allclose(t.eq37_as_printed, [eq37_printed(x) for x in (4.5, 10.0, 1000.0)], rtol=1e-12)
    np.testing.assert_allclose(t.eq32_as_printed, [eq32_printed(x) for x in (4.5, 10.0, 1000.0)], rtol=1e-12)
    # Eqs. (28) and (36): DC = τH/(τH + τL) = ratio/(1 + ratio); without D1 above 2/3, with D1 toward 0.
    np.testing.assert_allclose(t.duty_cycle_no_diode, t.no_diode / (1 + t.no_diode), rtol=1e-15)
    assert np.all(t.duty_cycle_no_diode > 2 / 3) and t.duty_cycle_diode[-1] < 0.01
    d = t.to_dict()
    assert d["N"] == [4.5, 10.0, 1000.0] and set(d) == {"N", "tau_ratio_no_diode", "tau_ratio_diode",
                                                         "paper_eq37_as_printed", "paper_eq32_as_printed",
                                                         "duty_cycle_no_diode",
                                                         "duty_cycle_diode"}
    with pytest.raises(ValueError, match="n_ratio"):
        tau_ratio_table([3.0, 10.0])


def test_ngspice_agrees_with_the_corrected_ratios():
    # Reference: ngspice transient of fsrlab's behavioural 555; 0.1 % as in test_spice.py.
    require_tool("ngspice")
    n = [5.0, 10.0]
    for diode in (False, True):
        sim = simulate_tau_ratios(n, diode)
        np.testing.assert_allclose(sim.tau_ratio, tau_ratio(np.array(n), diode=diode), rtol=1e-3)
        assert sim.to_dict()["N"] == n


def test_started_variants_give_the_numbers_of_one_variant_at_a_time():
    # start_tau_ratios (both variants in one batch of ngspice runs, the report's prefetch) against
    # simulate_tau_ratios for each variant alone: the same numbers, in the order of ``diodes``.
    from fsrlab.circuits.paper_ratio import start_tau_ratios

    require_tool("ngspice")
    n = [5.0, 50.0]
    together = start_tau_ratios(n, (True, False)).results()
    assert together == [simulate_tau_ratios(n, True), simulate_tau_ratios(n, False)]
