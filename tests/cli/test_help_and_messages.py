"""Help text and error messages of `oscillator`, `decode`, `design`, `physics`, `paper` and `import`.

References: the options' own help strings and the commands' docstrings (cli/oscillator.py,
cli/physics.py, cli/report.py, cli/importer.py); the files shipped under examples/ (examples/README.md);
the contract of docs/architecture.md (bad input: one line on stderr naming the option, exit code 2,
plain numbers); the Python warnings format ("RuntimeWarning:").
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
import typer

from clirun import run_cli
from fsrlab.cli import app
from fsrlab.cli.options import out_path

ROOT = Path(__file__).resolve().parents[2]
COMMANDS = ("oscillator", "decode", "design", "physics", "paper", "import")


def _command(name):
    return typer.main.get_command(app).commands[name]


def _takes_a_number(param) -> bool:
    descriptor = param.type_descriptor
    annotation = descriptor.annotation
    numeric = annotation in (float, int) or str(annotation) in ("list[float]", "list[int]")
    parser = descriptor.parameter_info.parser
    return not getattr(param, "is_flag", False) and (numeric or parser not in (None, out_path))


def _help(name: str) -> str:
    code, out, err = run_cli([name, "--help"])
    assert (code, err) == (0, "")
    return out


@pytest.mark.parametrize("name", COMMANDS)
def test_every_numeric_option_shows_its_unit_in_help(name):
    out = " ".join(_help(name).split())
    for param in _command(name).params:
        if not _takes_a_number(param):
            continue
        units = re.findall(r"\[[^\]\s]+\]", param.help or "")
        assert units, f"fsrlab {name} {param.opts[0]}: no [unit] in its help"
        assert all(u in out for u in units), f"fsrlab {name} --help lost {units}"


def _examples(name: str) -> list[list[str]]:
    """The example command lines of the help's description (its last paragraph before Arguments or Options)."""
    description = _help(name).split("\nOptions:")[0].split("\nArguments:")[0].rstrip()
    last = description.split("\n\n")[-1]
    return [line.split()[1:] for line in last.splitlines() if line.strip().startswith("fsrlab ")]


@pytest.mark.parametrize("name", COMMANDS)
def test_help_ends_with_one_or_two_examples_of_the_command(name):
    examples = _examples(name)
    assert 1 <= len(examples) <= 2, f"fsrlab {name} --help: {examples}"
    assert all(e[0] == name for e in examples)


# paper's examples build the whole report (~13 s): tests/report covers that, test_examples_parse the lines.
EXAMPLES = [" ".join(args) for name in COMMANDS if name != "paper" for args in _examples(name)]


@pytest.mark.parametrize("example", EXAMPLES)
def test_examples_run(example, tmp_path, monkeypatch):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")  # the examples name files under examples/
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(example.split())
    assert (code, err) == (0, ""), err
    assert out


@pytest.mark.parametrize("name", COMMANDS)
def test_examples_parse(name):
    command = typer.main.get_command(app)
    for args in _examples(name):
        ctx = command.make_context("fsrlab", list(args), resilient_parsing=False)
        sub = command.commands[args[0]]
        sub.make_context(args[0], args[1:], parent=ctx)  # raises on an unknown option or a bad value


def _one_line_naming(err: str, option: str) -> None:
    assert err.count("\n") == 1 and "Traceback" not in err and "Warning" not in err
    assert option in err, err


@pytest.mark.parametrize("args, option", [
    # Were exit 0 with "inf Hz", "nan %" and numpy RuntimeWarnings on stderr.
    (["oscillator", "--r", "1e-300", "--rfsr", "200k", "--cfsr", "1n"], "--r/--rfsr/--cfsr/--coff"),
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1e308"], "--r/--rfsr/--cfsr/--coff"),
    (["decode", "--r", "1e308", "--frequency", "6478.5", "--duty", "0.10189", "--diode"],
     "--r/--frequency/--duty/--coff"),
    (["decode", "--r", "10k", "--frequency", "6478.5", "--duty", "1e-300", "--diode"], "--r/--frequency/--duty/--coff"),
    # Was "Invalid value: no oscillation: ..." without an option.
    (["decode", "--r", "10k", "--frequency", "6478.5", "--duty", "0.10189", "--diode-drop", "5"], "--diode-drop"),
    (["oscillator", "--r", "10k", "--rfsr", "35k", "--cfsr", "1n"], "--r/--rfsr"),
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--rdis", "1e308"], "--rdis"),
    # Blamed --modulus for a --sigma-f above it.
    (["physics", "--sigma-f", "1e9"], "--modulus/--sigma-f"),
    # Was an OverflowError traceback.
    (["design", "--rfsr-min", "100k", "--rfsr-max", "2M", "--cfsr-min", "0.5n", "--cfsr-max", "1.5n", "--fmin", "1k",
      "--fmax", "20k", "--vcc", "0"], "--vcc"),
    # Was "[Errno 17] File exists" without the option.
    (["paper", "--out", "a-file"], "--out"),
])
def test_bad_values_end_in_one_line_naming_the_option(args, option, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a-file").write_text("not a directory\n")
    code, out, err = run_cli(args)
    assert code == 2 and out == ""
    _one_line_naming(err, option)


def test_design_window_beyond_floating_point_is_not_a_traceback():
    # Was OverflowError: cannot convert float infinity to integer.
    code, out, err = run_cli(["design", "--rfsr-min", "100k", "--rfsr-max", "2M", "--cfsr-min", "0.5n",
                              "--cfsr-max", "1.5n", "--fmin", "1k", "--fmax", "20k", "--window", "1e308", "--json"])
    assert (code, err) == (0, "")
    assert json.loads(out)["resolution_window_hz"] == [0.0, 0.0]


@pytest.mark.parametrize("args", [["--phi0", "1e308"], ["--s0", "5"], ["--s0", "1e308"]])
def test_physics_extreme_parameters_still_give_c_a(args):
    # Were a RuntimeError traceback (brentq), "All-NaN slice encountered" and a solver's message.
    # C_A does not depend on the tunnelling equations: Table 2's 1.73 % stays (two decimals).
    code, out, err = run_cli(["physics", *args, "--json"])
    assert (code, err) == (0, "")
    rows = json.loads(out)["rows"]
    assert all(not r["resistance_valid"] for r in rows)
    assert all(r["capacitance_per_area_percent"] == pytest.approx(1.73, abs=0.01) for r in rows)


def test_physics_text_says_why_r_a_is_missing():
    code, out, err = run_cli(["physics", "--s0", "5"])
    assert (code, err) == (0, "")
    assert "No R_A at u = 3, 2, 1 V: the current density under- or overflows" in " ".join(out.split())
