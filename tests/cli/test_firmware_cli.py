"""``fsrlab firmware hex|sketch|flash``, ``ports`` and ``doctor``: help, output and bad input.

References: the contract of docs/architecture.md (help ends with examples of the command; bad
input: one line on stderr naming the option, exit code 2), the shipped firmware's files and
identity (``fsrlab.acquisition.firmware``, read from ``meter.h``).
"""

from __future__ import annotations

import json

import pytest
from clirun import run_cli

from fsrlab.acquisition import firmware

COMMANDS = [["firmware", "hex"], ["firmware", "sketch"], ["firmware", "flash"], ["ports"], ["doctor"]]


@pytest.mark.parametrize("command", COMMANDS, ids=" ".join)
def test_help_ends_with_examples_of_the_command(command):
    code, out, err = run_cli([*command, "--help"])
    assert (code, err) == (0, "")
    last = out.split("\nOptions:")[0].split("\nArguments:")[0].rstrip().split("\n\n")[-1]
    examples = [line.split()[1:] for line in last.splitlines() if line.strip().startswith("fsrlab ")]
    assert 1 <= len(examples) <= 2 and all(e[:len(command)] == command for e in examples), examples


def test_flash_help_shows_the_timeout_unit():
    code, out, _ = run_cli(["firmware", "flash", "--help"])
    assert code == 0 and "[s]" in out


def test_hex_prints_the_shipped_image():
    code, out, err = run_cli(["firmware", "hex"])
    assert (code, err) == (0, "") and out.strip() == str(firmware.hex_path())
    code, out, err = run_cli(["firmware", "hex", "--json"])
    info = firmware.firmware_info()
    assert json.loads(out) == {"hex": str(info.hex_path), "firmware_version": info.version,
                               "protocol_version": info.protocol_version}


def test_sketch_writes_then_refuses_naming_the_option(tmp_path):
    code, out, err = run_cli(["firmware", "sketch", tmp_path])
    assert (code, err) == (0, "") and out.strip() == str(tmp_path / "fsrlab_meter" / "fsrlab_meter.ino")
    code, out, err = run_cli(["firmware", "sketch", tmp_path])
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "DIR" in err and "--overwrite" in err
    assert run_cli(["firmware", "sketch", tmp_path, "--overwrite"])[0] == 0


@pytest.mark.parametrize("args, option", [
    (["--port", "/dev/null", "--check-timeout", "0"], "--check-timeout"),
    (["--port", "/dev/null", "--hex", "/nonexistent.hex"], "--hex"),
])
def test_flash_bad_input_is_one_line_naming_the_option(args, option, monkeypatch):
    code, out, err = run_cli(["firmware", "flash", *args])
    assert code == 2 and out == "" and err.count("\n") == 1 and option in err
