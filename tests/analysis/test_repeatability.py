"""RE1/RE2 (eq. 39) against the paper's printed Tables 4 and 5 (real readings, tests/data/paper.json).

Tolerance: the tables print integers, so a recomputed value matches when it rounds to the printed
one, i.e. |computed - printed| <= 0.5.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, strategies as st
from hypothesis.extra.numpy import arrays

from fsrlab.analysis.repeatability import grouped_repeatability, repeatability
from fsrlab.tables import load_grouped_csv

TABLES = ["table4_repeatability_capacitive_kHz", "table5_repeatability_traditional_V"]
LOADS = ["200g", "400g"]


@pytest.mark.parametrize("table", TABLES)
@pytest.mark.parametrize("load", LOADS)
def test_default_reproduces_every_printed_row_and_mean(paper, table, load):
    t = paper[table][load]
    r = repeatability(t["readings"])  # default ddof=1
    np.testing.assert_allclose(r.re1_percent, t["RE1_percent"], atol=0.5)
    np.testing.assert_allclose(r.re2_percent, t["RE2_percent"], atol=0.5)
    assert abs(np.mean(r.re1_percent) - t["mean_RE1"]) <= 0.5
    assert abs(np.mean(r.re2_percent) - t["mean_RE2"]) <= 0.5


def test_population_std_misses_five_printed_re2_values(paper):
    """Eq. (39) as printed (divisor n) misses Table 5's RE2 at 200 g sensors 1, 4 and mean, 400 g sensors 1, 2."""
    misses = []
    for table in TABLES:
        for load in LOADS:
            t = paper[table][load]
            r = repeatability(t["readings"], ddof=0)
            for i, (c, p) in enumerate(zip(r.re2_percent, t["RE2_percent"])):
                if abs(c - p) > 0.5:
                    misses.append((table[:6], load, i + 1))
            if abs(np.mean(r.re2_percent) - t["mean_RE2"]) > 0.5:
                misses.append((table[:6], load, "mean"))
    assert misses == [("table5", "200g", 1), ("table5", "200g", 4), ("table5", "200g", "mean"),
                      ("table5", "400g", 1), ("table5", "400g", 2)]


def test_closed_form_small_example():
    # Independent closed form: readings 1, 2, 3 -> mean 2, range 2, sample std 1, population std sqrt(2/3).
    r1 = repeatability([1.0, 2.0, 3.0])
    assert r1.re1_percent == pytest.approx(100.0)
    assert r1.re2_percent == pytest.approx(50.0)
    assert repeatability([1.0, 2.0, 3.0], ddof=0).re2_percent == pytest.approx(100 * np.sqrt(2 / 3) / 2)


def test_grouped_matches_tables_and_csv_roundtrip(paper, tmp_path):
    lines = ["load,sensor,reading"]
    for load in LOADS:
        for s, row in enumerate(paper[TABLES[1]][load]["readings"], start=1):
            lines += [f"{load},{s},{v}" for v in row]
    path = tmp_path / "t5.csv"
    path.write_text("\n".join(lines) + "\n")
    res = grouped_repeatability(*load_grouped_csv(path))
    assert [g.load for g in res.groups] == ["200g"] * 4 + ["400g"] * 4
    assert [m.load for m in res.means] == LOADS
    printed = paper[TABLES[1]]
    for m in res.means:
        assert abs(m.re1_percent - printed[m.load]["mean_RE1"]) <= 0.5
        assert abs(m.re2_percent - printed[m.load]["mean_RE2"]) <= 0.5
    d = res.to_dict()
    assert set(d) == {"groups", "means"}
    assert set(d["groups"][0]) == {"load", "sensor", "re1_percent", "re2_percent"}


def test_errors():
    with pytest.raises(ValueError, match="ddof"):
        repeatability([1, 2], ddof=2)
    with pytest.raises(ValueError, match="at least 2"):
        repeatability([1.0])
    with pytest.raises(ValueError, match="zero mean"):
        repeatability([1.0, -1.0])
    with pytest.raises(ValueError, match="group load='a' sensor=1"):
        grouped_repeatability(["a", "b", "b"], [1, 1, 1], [1.0, 2.0, 3.0])


def test_bad_csv_one_line(tmp_path):
    p = tmp_path / "b.csv"
    p.write_text("load,sensor,reading\n200g,1,0.2\n200g,1,abc\n")
    with pytest.raises(ValueError, match=r"row 2 \(line 3\), column 'reading': non-numeric"):
        load_grouped_csv(p)
    p.write_text("load,reading\n1,2\n")
    with pytest.raises(ValueError, match="column 'sensor' missing"):
        load_grouped_csv(p)


@given(arrays(float, st.integers(2, 20), elements=st.floats(0.1, 1e3)), st.floats(0.01, 100))
def test_scale_invariance_and_sample_ge_population(x, k):
    # Properties: RE1, RE2 are relative (invariant to scaling); divisor n-1 gives the larger RE2.
    a, b = repeatability(x), repeatability(k * x)
    assert a.re1_percent == pytest.approx(b.re1_percent, rel=1e-9, abs=1e-9)
    assert a.re2_percent == pytest.approx(b.re2_percent, rel=1e-9, abs=1e-9)
    assert a.re2_percent >= repeatability(x, ddof=0).re2_percent - 1e-12
