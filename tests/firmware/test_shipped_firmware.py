"""The firmware the package ships (``fsrlab/firmware_data``) is the firmware of ``firmware/``.

References: the sources in ``firmware/fsrlab_meter`` and ``firmware/sim`` (the copies must be equal,
byte for byte), and a fresh avr-gcc build of the shipped sketch with ``firmware/Makefile`` in a
temporary folder (the shipped ``.hex`` must be byte-identical to it). When one fails, run
``make -C firmware package-data`` and commit the copies.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from fsrlab.acquisition import firmware
from toolcheck import require_file, require_tool

ROOT = Path(__file__).resolve().parents[2]
SKETCH_SRC = ROOT / "firmware" / "fsrlab_meter"
SIM_SRC = ROOT / "firmware" / "sim"
FIX = "run `make -C firmware package-data` and commit the copies"


def test_shipped_sketch_is_the_sketch_of_firmware_folder():
    shipped = {p.name: p.read_bytes() for p in firmware.sketch_files()}
    sources = {p.name: p.read_bytes() for p in SKETCH_SRC.iterdir() if p.suffix in (".ino", ".S", ".c", ".cpp", ".h")}
    assert sorted(shipped) == sorted(sources), FIX
    stale = [name for name in sources if shipped[name] != sources[name]]
    assert not stale, f"shipped sketch files differ from firmware/fsrlab_meter: {stale}; {FIX}"


def test_shipped_twin_sources_are_those_of_firmware_sim():
    shipped = {p.name: p.read_bytes() for p in firmware.twin_sources().iterdir()}
    # what firmware/Makefile compiles into fsrlab_twin, and the headers they include
    names = ["fsrlab_twin.c", "hx711_model.c", "hx711_model.h", "mcu.c", "mcu.h"]
    assert sorted(shipped) == sorted(names), FIX
    stale = [n for n in names if shipped[n] != (SIM_SRC / n).read_bytes()]
    assert not stale, f"shipped twin sources differ from firmware/sim: {stale}; {FIX}"


def test_firmware_info_is_what_meter_h_defines():
    info = firmware.firmware_info()
    header = (SKETCH_SRC / "meter.h").read_text()
    assert f'#define METER_FW_VERSION "{info.version}"' in header
    assert re.search(rf"^#define METER_PROTOCOL_VERSION {info.protocol_version}$", header, re.M)
    assert info.hex_path == firmware.hex_path() and info.hex_path.is_file()


def test_shipped_hex_is_byte_identical_to_a_fresh_build(tmp_path):
    require_tool("avr-gcc")
    require_tool("make")
    require_file("/usr/share/arduino/hardware/arduino/avr/cores/arduino/Arduino.h", "arduino-core-avr")
    sketch = firmware.data_dir() / firmware.SKETCH_NAME
    build = tmp_path / "build"
    # Only the image's target: never package-data, which would copy this build over the file under test.
    proc = subprocess.run(["make", "-s", "-C", str(ROOT / "firmware"), f"BUILD={build}", f"SKETCH_DIR={sketch}",
                           str(build / "fsrlab_meter.hex")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    fresh = (build / "fsrlab_meter.hex").read_bytes()
    assert firmware.hex_path().read_bytes() == fresh, f"the shipped fsrlab_meter.hex is stale; {FIX}"


def test_write_sketch_refuses_to_overwrite_then_overwrites(tmp_path):
    folder = firmware.write_sketch(tmp_path)
    assert folder == tmp_path / "fsrlab_meter"
    assert sorted(p.name for p in folder.iterdir()) == sorted(p.name for p in firmware.sketch_files())
    (folder / "meter.h").write_text("edited")
    with pytest.raises(FileExistsError, match="--overwrite"):
        firmware.write_sketch(tmp_path)
    assert (folder / "meter.h").read_text() == "edited"
    firmware.write_sketch(tmp_path, overwrite=True)
    assert (folder / "meter.h").read_bytes() == (SKETCH_SRC / "meter.h").read_bytes()


def test_avrdude_command_is_the_uno_bootloader_upload():
    # Reference: the Arduino IDE's upload line for the Uno (boards.txt: protocol arduino, 115200 baud).
    cmd = firmware.avrdude_command("/dev/ttyACM0", "/x/fsrlab_meter.hex")
    assert cmd == ["avrdude", "-c", "arduino", "-p", "atmega328p", "-b", "115200", "-P", "/dev/ttyACM0",
                   "-U", "flash:w:/x/fsrlab_meter.hex:i"]
