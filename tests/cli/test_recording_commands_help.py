"""Help and parsers of the recording commands added for the reference force: ``loadcell``,
``weights``, ``measure`` (and ``acquire``'s new options).

References: the help conventions of docs/architecture.md (a [unit] for every numeric option, one or
two examples at the end, each parsing), and the spellings the parsers of cli/options.py document
(areas: m², cm², mm²; masses: g, kg, mg, a bare 0; mass lists strictly increasing).
"""

from __future__ import annotations

import re

import pytest
import typer

from clirun import run_cli
from fsrlab.cli import app
from fsrlab.cli.options import areas, mass_list, masses, out_path

COMMANDS = ("loadcell", "weights", "measure", "acquire", "bench", "report", "demo", "twin")


def _command(name):
    return typer.main.get_command(app).commands[name]


@pytest.mark.parametrize("name", COMMANDS)
def test_numeric_options_show_their_unit(name):
    code, out, err = run_cli([name, "--help"])
    assert code == 0 and err == ""
    for param in _command(name).params:
        info = param.type_descriptor.parameter_info
        numeric = param.type_descriptor.annotation in (float, int) or info.parser not in (None, out_path)
        if getattr(param, "is_flag", False) or not numeric or param.name == "seed":
            continue
        assert re.findall(r"\[[^\]\s]+\]", param.help or ""), f"fsrlab {name} {param.opts[0]}: no [unit]"


@pytest.mark.parametrize("name", COMMANDS)
def test_examples_end_the_help_and_parse(name):
    code, out, _ = run_cli([name, "--help"])
    last = out.split("\nOptions:")[0].split("\nArguments:")[0].rstrip().split("\n\n")[-1]
    examples = [line.split()[1:] for line in last.splitlines() if line.strip().startswith("fsrlab ")]
    assert 1 <= len(examples) <= 2
    command = typer.main.get_command(app)
    for args in examples:
        ctx = command.make_context("fsrlab", list(args))
        command.commands[args[0]].make_context(args[0], args[1:], parent=ctx)


def test_parsers():
    assert areas("71.3mm2") == pytest.approx(71.3e-6) and areas("0.713cm²") == pytest.approx(71.3e-6)
    assert areas("7.13e-5m2") == 7.13e-5
    assert masses("500g") == 0.5 and masses("250mg") == pytest.approx(2.5e-4) and masses("0") == 0.0
    assert mass_list("0,50g,100g,0.2kg") == pytest.approx([0.0, 0.05, 0.1, 0.2])
    for bad in ("500", "5N", "nan", "1e999kg", "5 lb"):
        with pytest.raises(typer.BadParameter):
            masses(bad)
    for bad, said in (("0,100g,100g", "'100g' is not larger"), ("0,,100g", "no empty item"), ("-5g,0", "'-5g'")):
        with pytest.raises(typer.BadParameter, match=said):
            mass_list(bad)
