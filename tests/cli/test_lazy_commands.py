"""Lazy registration: ``fsrlab --help`` lists every command from the table in ``fsrlab/cli/__init__.py``
without importing the topic modules, and a command imports only its own.

References: the commands themselves (their names, modules and help as the topic modules declare them:
the table must say the same, so it cannot drift) and ``sys.modules`` of a fresh interpreter after the
command line ran (a property of what is imported, not a timing).
"""

from __future__ import annotations

import importlib
import json
import os
import subprocess
import sys

import pytest

from fsrlab.cli import COMMAND_GROUPS, COMMAND_MODULES, COMMANDS, _click_command, app

HEAVY = ("numpy", "scipy", "matplotlib", "pydantic", "serial", "bokeh")


def _registered() -> dict[str, str]:
    """Every command and group the topic modules add to ``app``: name -> the topic module adding it."""
    for module in COMMAND_MODULES:
        importlib.import_module(f"fsrlab.cli.{module}")
    out = {}
    for info in app.registered_commands:
        out[info.name or info.callback.__name__] = info.callback.__module__
    for info in app.registered_groups:
        (module,) = {i.callback.__module__ for i in info.typer_instance.registered_commands}
        out[info.name] = module
    return {name: module.removeprefix("fsrlab.cli.") for name, module in out.items()}


def test_the_table_names_every_command_and_the_module_that_adds_it():
    assert _registered() == {name: module for name, (module, _) in COMMANDS.items()}


@pytest.mark.parametrize("limit", [20, 45, 60, 74, 120, 400])
def test_the_table_summary_is_listed_as_the_command_itself_would_be(limit):
    # A group's help is cut to the line (click's default); a command's summary is whole (its first paragraph).
    _registered()
    group = _click_command()
    for name in COMMANDS:
        command = group.get_command(None, name)
        assert (name in COMMAND_GROUPS) == hasattr(command, "list_commands"), name
        assert group._stub(name).get_short_help_str(limit) == command.get_short_help_str(limit), name
        assert not command.hidden, name


def _fresh(code: str, columns: int = 80) -> dict:
    """Run ``code`` in a fresh interpreter (the way a user starts fsrlab) and read the JSON it prints last."""
    env = {**os.environ, "COLUMNS": str(columns)}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


_RUN = """
import contextlib, io, json, sys
from fsrlab.cli import COMMAND_MODULES, main

def run(args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main(args)
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()

def imported():
    topics = sorted(m for m in COMMAND_MODULES if f"fsrlab.cli.{m}" in sys.modules)
    return topics, sorted(m for m in """ + repr(HEAVY) + """ if m in sys.modules)
"""


@pytest.mark.parametrize("columns", [50, 80, 200])
def test_help_lists_every_command_without_importing_one(columns):
    # The same listing as from the commands themselves (every one built), at several terminal widths.
    result = _fresh(_RUN + """
code, lazy, _ = run(["--help"])
topics, heavy = imported()
from fsrlab.cli import COMMANDS, _click_command
group = _click_command()
for name in COMMANDS:
    group.commands[name]
_, built, _ = run(["--help"])
print(json.dumps({"code": code, "lazy": lazy, "built": built, "topics": topics, "heavy": heavy}))
""", columns)
    assert result["code"] == 0
    assert (result["topics"], result["heavy"]) == ([], [])
    assert result["lazy"] == result["built"]
    assert all(f"  {name} " in result["lazy"] for name in COMMANDS)


@pytest.mark.parametrize("args, topics", [
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--json"], ["oscillator"]),
    (["calibrate", "--help"], ["analysis"]),
    (["firmware", "hex", "--help"], ["firmware"]),
    (["--version"], []),
    (["oscilator"], []),
])
def test_a_command_imports_only_its_own_topic_module(args, topics):
    result = _fresh(_RUN + f"""
code, out, err = run({args!r})
print(json.dumps({{"code": code, "err": err, "topics": imported()[0]}}))
""")
    assert result["topics"] == topics
    assert result["code"] == (2 if args == ["oscilator"] else 0)


def test_a_mistyped_command_is_matched_against_every_command():
    # Reference: typer's suggestion of close names, which must see the commands not imported yet.
    result = _fresh(_RUN + """
print(json.dumps(run(["oscilator"])[2]))
""")
    assert result.strip() == "fsrlab: error: No such command 'oscilator'. Did you mean 'oscillator', 'doctor'?"
