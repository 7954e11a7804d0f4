"""Report section 'measurements': Tables 4 and 5 recomputed from the printed readings.

Reference: the paper's printed values in tests/data/paper.json (the section keeps its own copy;
this test checks the copy against the fixture and every recomputed row against the printed
integers, ±0.5 from the rounding).
"""

from __future__ import annotations

import json

from fsrlab.report.sections import measurements


def test_section_copies_match_fixture(paper):
    assert measurements.PAPER_TABLE4 == {k: {kk: vv for kk, vv in v.items()}
                                         for k, v in paper["table4_repeatability_capacitive_kHz"].items() if k != "note"}
    assert measurements.PAPER_TABLE5 == {k: v for k, v in paper["table5_repeatability_traditional_V"].items() if k != "note"}
    t3 = paper["table3_hysteresis_error_percent"]
    assert measurements.PAPER_TABLE3 == {k: t3[k] for k in measurements.PAPER_TABLE3}
    assert measurements.PAPER_FIG17 == {"linear_r2": paper["figure17_fit_r2"]["linear"],
                                        "cubic_r2": paper["figure17_fit_r2"]["cubic"]}


def test_section_builds_with_all_rows_and_errata(tmp_path):
    s = measurements.build(tmp_path)
    assert {e.key for e in s.errata} == {"M1", "M2"}
    for key in ("table4", "table5"):
        rec = s.data[key]["recomputed"]
        assert len(rec["rows"]) == 8 and len(rec["means"]) == 2
        assert all(r["re1_match"] and r["re2_n_minus_1_match"] for r in rec["rows"] + rec["means"])
    f = s.data["repeatability_ddof_finding"]
    assert (f["rows"], f["re2_match_n_minus_1"], f["re2_match_n"], f["re1_match"]) == (20, 20, 15, 20)
    assert s.data["compensation_synthetic"]["he_before_percent"] >= 3 * s.data["compensation_synthetic"]["he_after_percent"]
    for fig in s.figures:
        assert (tmp_path / fig.filename).stat().st_size > 10_000
    json.dumps(s.data, allow_nan=False)
