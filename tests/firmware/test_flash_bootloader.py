"""``fsrlab firmware flash`` against the Uno's own bootloader, without hardware.

The board: ``firmware/build/fsrlab_boot`` runs optiboot (built by ``firmware/Makefile`` from the
source in Debian's arduino-core-avr) in simavr as an ATmega328P whose USART0 is a pseudo-terminal.
The system's avrdude uploads the shipped image through it (STK500 v1, as to an Uno), the bootloader
resets into what it wrote, and the command checks that firmware answers ``ID``. References: the
shipped Intel hex, parsed here independently of avrdude and simavr (the simulated flash must hold
exactly its bytes, and nothing else outside the boot section); the ATmega328P datasheet's MCUSR
bits (EXTRF = 2 for the reset that keeps optiboot, WDRF = 8 for the one that starts the firmware).
"""

from __future__ import annotations

import json
import os
import subprocess
import tty
from pathlib import Path

import pytest

from clirun import run_cli
from fsrlab.acquisition import firmware
from toolcheck import require_tool

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "firmware" / "build"
BOOT_START = 0x7E00
FLASH_SIZE = 32768


def _ihex(path: Path) -> dict[int, int]:
    """Address → byte of an Intel hex file (records 00, 01, 02, 04; start addresses ignored)."""
    mem: dict[int, int] = {}
    base = 0
    for line in path.read_text().split():
        rec = bytes.fromhex(line[1:])
        assert line[0] == ":" and sum(rec) % 256 == 0 and len(rec) == rec[0] + 5, line
        addr, kind, data = (rec[1] << 8) | rec[2], rec[3], rec[4:-1]
        if kind == 0:
            mem.update((base + addr + i, b) for i, b in enumerate(data))
        elif kind == 1:
            break
        elif kind in (2, 4):
            base = int.from_bytes(data, "big") << (4 if kind == 2 else 16)
    return mem


@pytest.mark.slow
def test_flash_through_the_simulated_uno_bootloader(fw, tmp_path):
    require_tool("avrdude")
    harness, bootloader = BUILD / "fsrlab_boot", BUILD / "optiboot_atmega328.hex"
    assert harness.exists() and bootloader.exists()
    master, slave = os.openpty()
    tty.setraw(slave)
    port = os.ttyname(slave)
    dump, log = tmp_path / "flash.bin", tmp_path / "boot.log"
    with open(log, "w") as err:
        proc = subprocess.Popen([str(harness), str(bootloader), "--uart-fd", str(master), "--flash-out", str(dump)],
                                stdin=subprocess.PIPE, stderr=err, pass_fds=(master,))
    os.close(master)
    try:
        code, out, errors = run_cli(["firmware", "flash", "--port", port, "--json"])
    finally:
        proc.stdin.close()  # end of stdin: the harness writes the flash and ends
        proc.wait()
        os.close(slave)
    assert (code, errors) == (0, ""), errors + log.read_text()
    answer = json.loads(out)
    info = firmware.firmware_info()
    assert (answer["firmware_version"], answer["protocol_version"]) == (info.version, info.protocol_version)
    assert answer["device"] == "fsrlab-meter" and answer["port"] == port

    flash = dump.read_bytes()
    assert len(flash) == FLASH_SIZE
    image, boot = _ihex(firmware.hex_path()), _ihex(bootloader)
    assert min(boot) == BOOT_START and max(boot) < FLASH_SIZE
    wrong = [a for a, b in image.items() if flash[a] != b]
    assert not wrong, f"{len(wrong)} bytes of the image differ in flash, first at 0x{wrong[0]:04X}"
    assert all(flash[a] == b for a, b in boot.items()), "the bootloader was overwritten"
    stray = [a for a in range(BOOT_START) if a not in image and flash[a] != 0xFF]
    assert not stray, f"bytes written outside the image, first at 0x{stray[0]:04X}"
    resets = [line.split() for line in log.read_text().splitlines() if line.startswith("#RESET")]
    assert [r[2] for r in resets] == ["2", "8"], resets  # external (avrdude's), then the watchdog's


def test_flash_without_avrdude_says_how_to_install_it(monkeypatch):
    monkeypatch.setenv("PATH", "")
    code, out, err = run_cli(["firmware", "flash", "--port", "/dev/ttyACM0"])
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "avrdude is not installed" in err and "apt-get install avrdude" in err
