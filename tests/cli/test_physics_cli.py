"""``fsrlab physics`` where the tunnelling equation has no value: the Uno's 5 V and above.

Reference: Table 2 of the paper (C_A's hysteresis error 1.73 % at every u) and the independent
scalar eq. (12) of tests/reference_physics.py, whose bracket turns negative above the computed limit.
"""

import json
import warnings

import pytest

from clirun import run_cli
from fsrlab.metrics.hysteresis import model_cycle_errors
from fsrlab.physics.params import PAPER
from fsrlab.physics.separation import separation_loading
from fsrlab.physics.tunneling import voltage_limit
from reference_physics import REL, TABLE1, j12

S_F = TABLE1["s0"] * (1 - TABLE1["sigma_f"] / TABLE1["modulus"])


def _run(*args):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy warning may reach the user
        return run_cli(["physics", *args])


@pytest.mark.parametrize("u", ["5", "6", "8", "10"])
def test_voltages_beyond_eq12_say_so_and_keep_c_a(u):
    code, out, err = _run("--u", u)
    assert (code, err) == (0, "")
    text = " ".join(out.split())
    assert f"No R_A at u = {u} V" in text and "C_A does not depend on u" in text
    assert "R_A over this cycle needs 0 < u < 4.325 V" in text
    assert "1.73" in text  # Table 2: HE of C_A


def test_json_marks_the_missing_resistance_and_gives_the_range():
    code, out, err = _run("--u", "5", "--u", "2", "--json")
    assert (code, err) == (0, "")
    data = json.loads(out)
    high, two = data["rows"]
    assert high["resistance_valid"] is False and high["resistance_per_area_percent"] is None
    assert high["resistance_stress_at_max_pa"] is None
    assert high["capacitance_per_area_percent"] == pytest.approx(1.73, abs=0.005)  # Table 2, two decimals
    # C_A does not depend on u: the same number as at a voltage where R_A exists.
    assert high["capacitance_per_area_percent"] == two["capacitance_per_area_percent"]
    assert high["capacitance_stress_at_max_pa"] == two["capacitance_stress_at_max_pa"]
    u_max = data["resistance_u_max_v"]
    assert u_max == voltage_limit(separation_loading(PAPER.sigma_f_pa), PAPER.phi0_j)
    assert data["min_separation_m"] == pytest.approx(S_F, rel=1e-12)
    # Independent check of the range: the scalar eq. (12) at the thinnest film changes sign there.
    assert j12(u_max * (1 - REL), S_F) > 0 > j12(u_max * (1 + REL), S_F)


def test_voltages_in_range_are_unchanged():
    # The rows the model can compute are model_cycle_errors' numbers, bit for bit.
    code, out, _ = _run("--u", "3", "--u", "2", "--u", "1", "--json")
    assert code == 0
    for row in json.loads(out)["rows"]:
        ref = model_cycle_errors(row["u_v"], PAPER)
        assert row["resistance_valid"] is True
        assert row["resistance_per_area_percent"] == ref.resistance.percent
        assert row["capacitance_per_area_percent"] == ref.capacitance.percent
        assert row["tunneling_equation"] == ref.regime


def test_range_follows_the_parameters():
    # A thicker film at σf keeps eq. (12) valid to a higher voltage; the printed range is computed.
    code, out, _ = _run("--u", "5", "--s0", "6n", "--json")
    data = json.loads(out)
    assert code == 0 and data["rows"][0]["resistance_valid"] is True
    assert data["resistance_u_max_v"] > 5
