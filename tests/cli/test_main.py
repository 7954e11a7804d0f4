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


def test_no_arguments_prints_the_help_and_exits_0(capsys):
    # Reference: the usual command-line convention (git, pip): a bare program name shows its help.
    code, out, err = run_cli([], capsys)
    assert code == 0 and err == ""
    assert "Usage: fsrlab" in out and "physics" in out


def test_physics_help_shows_the_units_of_its_options(capsys):
    # Reference: the options' own help strings in cli/physics.py; rich markup used to drop "[m]", "[eV]".
    code, out, _ = run_cli(["physics", "--help"], capsys)
    assert code == 0
    for unit in ("[V]", "[m]", "[Pa]", "[eV]"):
        assert unit in out
    assert "<bool>" not in out


def _bracketed(text):
    import re

    return re.findall(r"\[[^\]\s]+\]", text or "")


def test_every_command_help_keeps_the_bracketed_text_of_its_options(capsys):
    # Reference: each option's help string, as written in the command modules.
    import typer

    from fsrlab.cli import app

    group = typer.main.get_command(app)
    for name, command in group.commands.items():
        code, out, _ = run_cli([name, "--help"], capsys)
        assert code == 0, name
        for param in command.params:
            for token in _bracketed(getattr(param, "help", None)):
                assert token in out, f"fsrlab {name} --help lost {token}"


def test_command_list_shows_whole_first_sentences(capsys):
    # Reference: the commands' docstrings; "(eq. 13)" must not end the summary at "eq.".
    code, out, _ = run_cli(["--help"], capsys)
    assert code == 0 and "Hysteresis error (eq. 13) of R_A and C_A" in " ".join(out.split())


def test_the_click_command_is_built_once_per_set_of_commands():
    # Building it takes ~20 ms (typer.main.get_command); the fuzzer runs 10^4 command lines.
    from fsrlab.cli import _click_command, app

    first = _click_command()
    assert _click_command() is first

    @app.command("probe-cache")
    def probe() -> None:
        """A command added for this test."""

    try:
        assert "probe-cache" in _click_command().commands
    finally:
        app.registered_commands[:] = [i for i in app.registered_commands if i.name != "probe-cache"]
    assert "probe-cache" not in _click_command().commands


def test_light_coercion_gives_what_typers_pydantic_coercion_gives():
    # Reference: typer's own coercion (typer._coercion.build_runtime_param, pydantic TypeAdapters) on the
    # same values: every option's default and a few typed values, for every command.
    from pathlib import Path

    import typer
    from typer._click.exceptions import BadParameter
    from typer._coercion import build_runtime_param

    from fsrlab.cli import app

    group = typer.main.get_command(app)
    samples = {bool: [True, False], int: [0, 7], float: [0.0, 2.5, 3], str: ["abc"], Path: [Path("x.csv"), "y.csv"]}
    checked = 0
    for name, command in group.commands.items():
        ctx = command.make_context(name, ["--help"], resilient_parsing=True)
        for param in command.params:
            desc = getattr(param, "type_descriptor", None)
            if desc is None:
                continue
            values = [v for v in [param.default] if v is not None and not callable(v)]
            values += samples.get(desc.annotation, []) if desc.parameter_info.parser is None else []
            for value in values:
                # Bound as defaults: each closure is called at once, in its own iteration (ruff B023).
                def outcome(runtime, value=value, param=param, ctx=ctx):
                    try:
                        out = runtime.coerce(value, param=param, ctx=ctx)
                        return type(out), out
                    except BadParameter as exc:
                        return "error", exc.format_message()
                light = outcome(param.get_runtime_param())
                full = outcome(build_runtime_param(desc))
                assert light == full, (name, param.name, value)
                checked += 1
    assert checked > 200
