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


@pytest.mark.parametrize("directory, said", [("", "is empty"),
                                             ("/nonexistent/deep/dir", "/nonexistent/deep does not exist")])
def test_sketch_refuses_an_empty_or_unrooted_folder(directory, said):
    """The output policy: "" is not "here", and a mistyped path is not made from / (issue 40)."""
    code, out, err = run_cli(["firmware", "sketch", directory])
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("fsrlab: error: Invalid value for DIR: ") and said in err
    assert not __import__("os").path.exists("/nonexistent")


def test_sketch_makes_one_folder_in_an_existing_one(tmp_path):
    code, out, err = run_cli(["firmware", "sketch", tmp_path / "new"])
    assert code == 0 and (tmp_path / "new" / "fsrlab_meter" / "fsrlab_meter.ino").is_file()
    assert [p.name for p in (tmp_path / "new" / "fsrlab_meter").iterdir() if p.name.startswith(".")] == []


def test_shipped_image_is_intel_hex():
    """Reference: the Intel hex format (Intel, "Hexadecimal Object File Format Specification", rev. A, 1988):
    the shipped image passes, and the same image with one checksum changed, cut before its end record, or
    moved past 32 KiB does not."""
    assert 1000 < firmware.check_intel_hex(firmware.hex_path()) <= firmware.FLASH_BYTES


@pytest.mark.parametrize("change, said", [
    (lambda t: t.replace(t.splitlines()[0],
                         t.splitlines()[0][:-2] + ("00" if t.splitlines()[0][-2:] != "00" else "01")), "checksum"),
    (lambda t: "\n".join(t.splitlines()[:-1]) + "\n", "no end-of-file record"),
    (lambda t: ":020000040001F9\n" + t, "beyond an ATmega328P"),
    (lambda t: "time_s,frequency_hz\n0,1\n", "is not an Intel hex record"),
])
def test_flash_refuses_a_file_that_is_not_an_uno_image_before_avrdude_runs(tmp_path, monkeypatch, change, said):
    bad = tmp_path / "bad.hex"
    bad.write_text(change(firmware.hex_path().read_text()))
    ran = []
    monkeypatch.setattr(firmware.subprocess, "run", lambda *a, **k: ran.append(a))
    with pytest.raises(ValueError, match=said) as info:
        firmware.flash("/dev/null", bad, avrdude="avrdude")
    assert info.value.parameter == "hex_file" and ran == []
    code, out, err = run_cli(["firmware", "flash", "--port", "/dev/null", "--hex", bad])
    assert code == 2 and ran == [] and err.startswith("fsrlab: error: Invalid value for --hex: ") and said in err
