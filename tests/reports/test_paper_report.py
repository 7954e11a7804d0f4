"""`fsrlab paper --out DIR`: files, paper.json keys, Table 2 beside the paper's values."""

import json

import pytest

from fsrlab.cli import main


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    with pytest.raises(SystemExit) as exc:
        main(["paper", "--out", str(out)])
    assert exc.value.code == 0
    return out


def test_files_written(report):
    for name in ["index.html", "paper.json", "fig2a_separation_sigma_f.png", "fig2b_separation_k.png",
                 "fig4a_current_density.png", "fig4b_resistance_per_area.png", "fig8a_resistance_per_area.png",
                 "fig8b_capacitance_per_area.png"]:
        path = report / name
        assert path.exists() and path.stat().st_size > 1000, name
    assert (report / "fig2a_separation_sigma_f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_paper_json_contract(report, paper):
    # The report's contract, with the paper's printed Table 1 and Table 2 as reference.
    d = json.loads((report / "paper.json").read_text())
    p = d["parameters"]
    t1 = paper["table1_simulation_parameters"]
    assert p["k"] == 2
    assert p["M_Pa"] == t1["M_Pa"] and p["sigma_f_Pa"] == t1["sigma_f_Pa"]
    assert p["phi0_eV"] == pytest.approx(t1["phi0_eV"])
    t2 = d["table2"]
    assert t2["u_V"] == [3, 2, 1]
    assert len(t2["resistance_per_area_percent"]) == 3
    printed = paper["table2_hysteresis_error_percent"]
    assert t2["capacitance_per_area_percent"] == pytest.approx(printed["capacitance_per_area"], abs=0.005)
    assert t2["paper"] == {"resistance_per_area_percent": printed["resistance_per_area"],
                           "capacitance_per_area_percent": printed["capacitance_per_area"]}
    assert {e["key"] for e in d["errata"]} >= {"P1", "P2", "P3"}


def test_index_is_self_contained_and_shows_both_values(report, paper):
    html = (report / "index.html").read_text()
    assert "data:image/png;base64," in html and "<img" in html
    # The paper's Table 2 value beside ours (docs/errata.md P1: 1.47 % at 3 V).
    assert f"{paper['table2_hysteresis_error_percent']['resistance_per_area'][0]:.2f}" in html and "1.47" in html
    assert "Errata" in html and "P1" in html


def test_report_in_a_process_of_its_own_writes_the_same_report(report, tmp_path):
    # Reference: the report written in this process (the fixture). start_report builds it in another
    # interpreter (the demo draws it while its last recording runs) and hands back the same result.
    from fsrlab.reports.paper import start_report

    result = start_report(tmp_path / "other", nice=3).result()  # at a lower priority, as the demo starts it
    assert result.json.read_bytes() == (report / "paper.json").read_bytes()
    assert [s.key for s in result.sections] == ["physics", "oscillator", "measurements", "experiment"]
    assert result.index == tmp_path / "other" / "index.html" and all(p.exists() for p in result.figures)
    with pytest.raises(ValueError, match="nice"):
        start_report(tmp_path / "never", nice=-1)
