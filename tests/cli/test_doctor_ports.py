"""``fsrlab doctor`` and ``fsrlab ports``.

References: the PATH itself (``shutil.which``: a tool is reported found exactly when it is there),
the shipped firmware's identity (``meter.h``), and the virtual device, which answers ``ID`` as
firmware ``fsrlab.virtual.device.FIRMWARE_VERSION`` (not the shipped one, so the doctor
must say the board needs flashing). Port listings are built from pyserial-like records, as
``serial.tools.list_ports`` returns them.
"""

from __future__ import annotations

import json
import shutil
from types import SimpleNamespace

import pytest

from clirun import run_cli
from fsrlab.acquisition import firmware
from fsrlab.acquisition.ports import list_serial_ports, resolve_port
from fsrlab.acquisition.serial_link import LinkError

TOOLS = {"ngspice": ("ngspice",), "avrdude": ("avrdude",)}


def _checks(args):
    code, out, err = run_cli(["doctor", "--json", *args])
    assert (code, err) == (0, ""), err
    doc = json.loads(out)
    return {c["name"]: c for c in doc["checks"]}, doc["boards"]


def test_doctor_reports_what_the_path_has():
    checks, boards = _checks(["--no-probe"])
    assert boards == []
    for name, exes in TOOLS.items():
        found = any(shutil.which(e) for e in exes)
        assert checks[name]["found"] is found
        assert (checks[name]["install"] is None) is found
    assert {"C compiler", "simavr headers", "digital twin", "AVR toolchain", "Chromium and chromedriver"} <= set(checks)
    assert all(c["enables"] for c in checks.values())


def test_doctor_without_tools_gives_each_install_command(monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    checks, _ = _checks(["--no-probe"])
    expected = {"ngspice": "apt-get install ngspice", "avrdude": "apt-get install avrdude",
                "C compiler": "apt-get install gcc",
                "AVR toolchain": "apt-get install gcc-avr avr-libc arduino-core-avr",
                "Chromium and chromedriver": "apt-get install chromium chromium-driver"}
    for name, install in expected.items():
        assert checks[name]["found"] is False and install in checks[name]["install"], checks[name]


def test_doctor_asks_a_board_its_firmware_version():
    from fsrlab.virtual.device import FIRMWARE_VERSION, VirtualDevice

    with VirtualDevice(seed=0) as dev:
        _, boards = _checks(["--port", dev.port])
    (board,) = boards
    assert board["ok"] is True and board["port"] == dev.port
    assert board["firmware_version"] == FIRMWARE_VERSION != firmware.firmware_info().version
    assert board["matches_package"] is False and "fsrlab firmware flash" in board["detail"]


def test_doctor_text_says_why_a_port_did_not_answer(tmp_path):
    code, out, err = run_cli(["doctor", "--port", str(tmp_path / "nothing")])
    assert (code, err) == (0, "")
    assert f"CHECK   board on {tmp_path / 'nothing'}: cannot open" in out


def _port(device, vid=None, pid=None, description="n/a"):
    return SimpleNamespace(device=device, vid=vid, pid=pid, description=description, manufacturer=None,
                           serial_number=None)


def test_ports_mark_unos_and_auto_picks_the_only_one():
    found = list_serial_ports([_port("/dev/ttyS0"), _port("/dev/ttyACM0", 0x2341, 0x0043, "Arduino Uno"),
                               _port("/dev/ttyUSB0", 0x0403, 0x6001, "FT232R")])
    assert [p.device for p in found] == ["/dev/ttyACM0", "/dev/ttyS0", "/dev/ttyUSB0"]
    assert [p.board for p in found] == ["Arduino Uno R3", None, None]
    assert found[0].usb_id == "2341:0043" and found[1].usb_id is None and found[1].description is None
    assert resolve_port("auto", found) == "/dev/ttyACM0"
    assert resolve_port("/dev/ttyUSB0", found) == "/dev/ttyUSB0"


@pytest.mark.parametrize("records, words", [
    ([_port("/dev/ttyS0")], "found no Arduino Uno"),
    ([_port("/dev/ttyACM0", 0x2341, 0x0043), _port("/dev/ttyUSB0", 0x1A86, 0x7523)], "several"),
])
def test_auto_refuses_none_or_several_naming_the_candidates(records, words):
    with pytest.raises(LinkError, match=words) as info:
        resolve_port("auto", list_serial_ports(records))
    assert all(r.device in str(info.value) for r in records)


def test_ports_command_json_lists_and_says_what_auto_does():
    code, out, err = run_cli(["ports", "--json"])
    assert (code, err) == (0, "")
    doc = json.loads(out)
    assert set(doc) == {"ports", "auto", "auto_error"}
    assert (doc["auto"] is None) != (doc["auto_error"] is None)
