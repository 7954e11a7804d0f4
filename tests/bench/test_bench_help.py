"""Help of ``fsrlab bench``, ``report`` and ``demo``: a [unit] for every numeric option, one or two examples that parse.

Reference: the help conventions of docs/architecture.md (Extension points, CLI).
"""

from __future__ import annotations

import re

import pytest
import typer

from clirun import run_cli
from fsrlab.cli import app

COMMANDS = ("bench", "report", "demo")


def _command(name):
    return typer.main.get_command(app).commands[name]


@pytest.mark.parametrize("name", COMMANDS)
def test_numeric_options_show_their_unit(name):
    code, out, err = run_cli([name, "--help"])
    assert code == 0 and err == ""
    checked = 0
    for param in _command(name).params:
        info = param.type_descriptor.parameter_info
        numeric = param.type_descriptor.annotation in (float, int) or info.parser is not None
        if getattr(param, "is_flag", False) or not numeric or param.name == "seed":
            continue
        checked += 1
        assert re.findall(r"\[[^\]\s]+\]", param.help or ""), f"fsrlab {name} {param.opts[0]}: no [unit]"
    assert checked or name == "report"


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


def test_masses_option_states_its_unit():
    code, out, _ = run_cli(["bench", "--help"])
    assert "[kg]" in out and "[Pa]" in out and "[s]" in out


def test_report_examples_run(tmp_path, monkeypatch):
    # Reference: the files under examples/ (examples/README.md says where each came from).
    import shutil
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    code, out, _ = run_cli(["report", "--help"])
    last = out.split("\nOptions:")[0].split("\nArguments:")[0].rstrip().split("\n\n")[-1]
    examples = [line.split()[1:] for line in last.splitlines() if line.strip().startswith("fsrlab ")]
    shutil.copytree(root / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    for args in examples:
        code, out, err = run_cli(args)
        assert code == 0, f"{args}: {err}"
        assert "Traceback" not in err and "Warning" not in err
    assert (tmp_path / "report-run" / "index.html").is_file()
