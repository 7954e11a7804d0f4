"""The command line's contract: one-line errors with exit code 2, --version."""

import pytest

from clirun import run_cli


def test_unknown_command_is_one_line_exit_2(capsys):
    code, out, err = run_cli(["no-such-command"], capsys)
    assert code == 2
    assert err.count("\n") == 1 and "no-such-command" in err


def test_unknown_option_is_one_line_exit_2(capsys):
    code, _, err = run_cli(["paper", "--bogus"], capsys)
    assert code == 2 and err.strip().count("\n") == 0 and "--bogus" in err


def test_version(capsys):
    code, out, _ = run_cli(["--version"], capsys)
    assert code == 0 and out.startswith("fsrlab ")


@pytest.mark.parametrize("args, option", [
    (["--k", "0.5"], "--k"), (["--modulus", "100k"], "--modulus"), (["--s0", "abc"], "--s0"),
    (["--s0", "-1n"], "--s0"), (["--u", "-1"], "--u"), (["--phi0", "0"], "--phi0"), (["--eps-r", "nan"], "--eps-r"),
])
def test_physics_bad_values_one_line_naming_the_option(args, option, capsys):
    code, out, err = run_cli(["physics", *args], capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and option in err and "Traceback" not in err


def test_physics_json_reproduces_table2_capacitance(capsys):
    # Reference: Table 2 prints 1.73 % for C_A at every u (two decimals).
    import json

    code, out, _ = run_cli(["physics", "--u", "2", "--json"], capsys)
    row = json.loads(out)["rows"][0]
    assert code == 0 and row["tunneling_equation"] == 12
    assert row["capacitance_per_area_percent"] == pytest.approx(1.73, abs=0.005)
