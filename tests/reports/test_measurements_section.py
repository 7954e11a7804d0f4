"""Report section 'measurements': Tables 4 and 5 recomputed from the printed readings.

Reference: the paper's printed values in fsrlab/data/paper.json (the section quotes them from that
one file; this test checks what it quotes and every recomputed row against the printed integers,
±0.5 from the rounding). The computations it renders are tested in test_repeatability.py.
"""

from __future__ import annotations

import json

import pytest

from fsrlab.reports.sections import measurements


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("measurements")
    return measurements.build(out), out


def test_section_quotes_the_transcription(built, paper):
    s, _ = built
    for key, name in (("table4", "table4_repeatability_capacitive_kHz"),
                      ("table5", "table5_repeatability_traditional_V")):
        assert s.data[key]["printed"] == {k: v for k, v in paper[name].items() if k != "note"}
    assert s.data["table3"]["printed"] == paper["table3_hysteresis_error_percent"]
    assert s.data["figure17_synthetic"]["paper"] == {"linear_r2": paper["figure17_fit_r2"]["linear"],
                                                     "cubic_r2": paper["figure17_fit_r2"]["cubic"]}


def test_section_builds_with_all_rows_and_errata(built):
    s, out = built
    assert {e.key for e in s.errata} == {"M1", "M2"}
    for key in ("table4", "table5"):
        rec = s.data[key]["recomputed"]
        assert len(rec["rows"]) == 8 and len(rec["means"]) == 2
        assert all(r["re1_match"] and r["re2_n_minus_1_match"] for r in rec["rows"] + rec["means"])
    f = s.data["repeatability_ddof_finding"]
    assert (f["rows"], f["re2_match_n_minus_1"], f["re2_match_n"], f["re1_match"]) == (20, 20, 15, 20)
    synthetic = s.data["compensation_synthetic"]
    assert synthetic["he_before_percent"] >= 3 * synthetic["he_after_percent"]
    for fig in s.figures:
        assert (out / fig.filename).stat().st_size > 10_000
    json.dumps(s.data, allow_nan=False)
