"""The paper's printed numbers, loaded from the package data (fsrlab.reference).

References: the paper's Tables 1–5 and Figure 17 as printed (spot checks of the transcription
against the paper's text) and the shape of the tables the report and tests rely on.
"""

from __future__ import annotations

from fsrlab.reference import paper_values


def test_spot_checks_against_the_printed_paper():
    p = paper_values()
    # Table 1: φ0 = 0.223 eV; Table 2: R_A at 3 V 2.21 %; Table 3 means 23.35 / 16.31; Figure 17 cubic R².
    assert p["table1_simulation_parameters"]["phi0_eV"] == 0.223
    assert p["table2_hysteresis_error_percent"]["resistance_per_area"][0] == 2.21
    t3 = p["table3_hysteresis_error_percent"]
    assert (t3["traditional_mean"], t3["proposed_mean"]) == (23.35, 16.31)
    assert p["figure17_fit_r2"]["cubic"] == 0.9974
    # §5: "The minimal value of the ratio τH/τL for N > 4 is 24.37."
    assert p["section5_tau_ratio_claims"]["min_tau_ratio_no_diode"] == 24.37


def test_repeatability_tables_have_five_readings_for_four_sensors():
    p = paper_values()
    for name in ("table4_repeatability_capacitive_kHz", "table5_repeatability_traditional_V"):
        for load in ("200g", "400g"):
            t = p[name][load]
            assert [len(r) for r in t["readings"]] == [5, 5, 5, 5]
            assert len(t["RE1_percent"]) == len(t["RE2_percent"]) == 4


def test_each_call_returns_an_independent_copy():
    a = paper_values()
    a["table2_hysteresis_error_percent"]["resistance_per_area"][0] = -1.0
    assert paper_values() != a
