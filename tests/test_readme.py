"""README.md's examples run: its Python blocks, its command-line quick start, and every option it names.

References: the README itself (its blocks are run as a reader would run them, in order, in an empty directory
with ``examples/`` beside them) and each command's own ``--help`` (an option the README names for hardware,
which cannot run here, must be one the command lists). Also the README's shape the manual promises: at most
150 lines, ``make demo`` and ``make test`` in its first 20.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from clirun import run_cli

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _blocks(language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", README, flags=re.S | re.M)


def _commands(block: str) -> list[list[str]]:
    """The ``fsrlab`` lines of a shell block, as argument lists (comments dropped)."""
    return [shlex.split(line, comments=True)[1:] for line in block.splitlines() if line.startswith("fsrlab ")]


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_readme_is_short_and_starts_with_the_two_commands():
    lines = README.splitlines()
    assert len(lines) <= 150, len(lines)
    head = "\n".join(lines[:20])
    assert "make demo" in head and "make test" in head


def test_readme_has_the_examples_this_test_runs():
    assert len(_blocks("python")) >= 1
    assert sum(len(_commands(b)) for b in _blocks("sh")) >= 10


@pytest.mark.parametrize("index", range(len(_blocks("python"))))
def test_readme_python_block_runs(index, workdir):
    # In a fresh interpreter, as a reader pastes it: a block must not lean on this test process's imports.
    proc = subprocess.run([sys.executable, "-c",
                           "import matplotlib; matplotlib.use('Agg')\n" + _blocks("python")[index]],
                          cwd=workdir, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]


@pytest.mark.parametrize("index", range(len(_blocks("sh"))))
def test_readme_shell_block_runs(index, workdir):
    for args in _commands(_blocks("sh")[index]):
        code, out, err = run_cli(args)
        assert code == 0, (args, err[-2000:])


def _inline_commands() -> list[list[str]]:
    """Every ``fsrlab ...`` in inline code (the steps with a real Uno, the multiplexer), as argument lists."""
    return [shlex.split(text)[1:] for text in re.findall(r"`(fsrlab [^`]+)`", README)]


@pytest.mark.parametrize("args", _inline_commands(), ids=" ".join)
def test_every_option_the_readme_names_is_the_commands(args):
    words = [a for a in args if not a.startswith("-")]
    command = args[: 2 if words[:1] in (["firmware"], ["loadcell"]) else 1]
    code, out, _ = run_cli([*command, "--help"])
    assert code == 0, command
    listed = set(re.findall(r"(?<![\w-])(--[a-z][\w-]*)", out))
    named = {a for a in args if a.startswith("--")}
    assert named <= listed, (command, named - listed)
