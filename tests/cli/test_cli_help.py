"""The analysis commands' help: a unit for every option with a value, and examples that run.

Reference: the commands' own option declarations (cli/analysis.py) and the files shipped under
examples/ (see examples/README.md for their provenance). Each command's help ends with examples
("fsrlab ..." lines after "Examples"); each is run here, in a copy of examples/, and must succeed.
"""

from __future__ import annotations

import re
import shlex
import shutil
from pathlib import Path

import pytest

from clirun import run_cli

ROOT = Path(__file__).resolve().parents[2]
COMMANDS = ("hysteresis", "repeatability", "calibrate", "apply", "iso376")


def _examples(help_text: str) -> list[str]:
    tail = help_text.split("Examples", 1)[1].split("\nArguments:")[0].split("\nOptions:")[0]
    return [ln.strip() for ln in tail.splitlines() if ln.strip().startswith("fsrlab ")]


def _options(help_text: str) -> dict[str, str]:
    """Option (with its value placeholder) -> its help text, from the rendered help."""
    section = help_text.split("\nOptions:\n", 1)[1]
    entries: dict[str, str] = {}
    key = None
    for line in section.splitlines():
        m = (re.match(r"^  (-\S+(?:, -\S+)*(?: <\w+>)?)\s{2,}(.*)$", line)
             or re.match(r"^  (-\S+(?:, -\S+)*(?: <\w+>)?)$", line))
        if m:
            key = m.group(1)
            entries[key] = m.group(2) if m.lastindex == 2 else ""
        elif key:
            entries[key] += " " + line.strip()
    return entries


@pytest.mark.parametrize("name", COMMANDS)
def test_every_option_with_a_value_shows_its_unit(name):
    code, out, _ = run_cli([name, "--help"])
    options = _options(out)
    valued = {k: v for k, v in options.items() if "<" in k and not k.endswith(("<path>", "<Path>"))}
    assert valued, out
    for option, text in valued.items():
        units = [u for u in re.findall(r"\[([^\]]+)\]", text) if not u.startswith(("default", "required"))]
        assert units, f"fsrlab {name} {option}: no unit in its help ({text})"


@pytest.mark.parametrize("name", COMMANDS)
def test_help_ends_with_examples_that_run(name, tmp_path, monkeypatch):
    code, out, _ = run_cli([name, "--help"])
    assert code == 0
    description = out.split("\nArguments:")[0].split("\nOptions:")[0].rstrip()
    examples = _examples(out)
    assert 1 <= len(examples) <= 2 and description.splitlines()[-1].strip() == examples[-1]
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    for line in examples:
        code, out, err = run_cli(shlex.split(line)[1:])
        assert code == 0, f"{line}: {err}"
        assert "Traceback" not in err and "Warning" not in err
