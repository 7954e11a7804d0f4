"""The meter's firmware as the package ships it: the Uno image, the sketch, and flashing an Uno.

The package holds the build of ``firmware/`` (``make -C firmware`` copies it into
``fsrlab/firmware_data``): ``fsrlab_meter.hex`` (the Intel hex image avrdude writes),
``fsrlab_meter/`` (the sketch, for the Arduino IDE) and ``twin/`` (the C sources of the digital
twin's simavr harness). The test ``tests/firmware/test_shipped_firmware.py`` rebuilds the image from
the shipped sketch and requires it byte-identical.

Flashing goes through the Uno's bootloader (optiboot, STK500 v1 at 115200 baud) with avrdude:
``avrdude -c arduino -p atmega328p -b 115200 -P PORT -U flash:w:HEX:i``; then the board must answer
``ID`` with this firmware's version and protocol (:func:`flash`).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from fsrlab.acquisition.messages import Identity
from fsrlab.acquisition.serial_link import HandshakeError, LinkError, SerialLink, find_uno
from fsrlab.errors import FsrlabError, ParameterError

__all__ = ["SKETCH_NAME", "AVRDUDE_HINT", "FlashError", "ToolMissing", "FirmwareInfo", "FlashResult", "data_dir",
           "hex_path", "sketch_files", "twin_sources", "firmware_info", "write_sketch", "check_intel_hex",
           "FLASH_BYTES",
           "avrdude_command", "flash"]

SKETCH_NAME = "fsrlab_meter"
"""Name of the sketch: its folder and its ``.ino`` (the Arduino IDE wants them equal)."""
AVRDUDE_HINT = ("install avrdude: `sudo apt-get install avrdude` (Debian, Ubuntu), `brew install avrdude` (macOS), "
                "or the Arduino IDE's copy on the PATH")
"""How to get avrdude, for the messages that need it."""
_SKETCH_SUFFIXES = (".ino", ".S", ".c", ".cpp", ".h")


class ToolMissing(FsrlabError, OSError):
    """A program fsrlab runs (avrdude, a C compiler) is not installed; the message says how to get it.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


class FlashError(LinkError):
    """avrdude could not write the firmware (the message gives avrdude's own last lines).

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


@dataclass(frozen=True)
class FirmwareInfo:
    """What the shipped firmware says about itself (from its ``meter.h``).

    Attributes
    ----------
    version : str
        Firmware version, as the ``ID`` frame sends it (``2.0.0``).
    protocol_version : int
        Protocol version it speaks.
    hex_path : Path
        The Intel hex image.
    """

    version: str
    protocol_version: int
    hex_path: Path


@dataclass(frozen=True)
class FlashResult:
    """A finished upload, checked.

    Attributes
    ----------
    port : str
        The port written through (``auto`` resolved).
    hex_path : Path
        The image written.
    identity : Identity
        The board's answer to ``ID`` after the upload.
    command : list of str
        The avrdude command line that ran.
    """

    port: str
    hex_path: Path
    identity: Identity
    command: list[str]


def data_dir() -> Path:
    """The package's firmware folder (``fsrlab/firmware_data``) as a directory on disk."""
    root = resources.files("fsrlab").joinpath("firmware_data")
    path = Path(str(root))
    if not path.is_dir():
        raise FileNotFoundError(f"the package has no firmware folder ({path}): reinstall fsrlab, "
                                "or run `make -C firmware` in a clone")
    return path


def hex_path() -> Path:
    """The Uno image, ``fsrlab_meter.hex`` (Intel hex, what avrdude writes)."""
    return data_dir() / f"{SKETCH_NAME}.hex"


def sketch_files() -> list[Path]:
    """The sketch's files (``fsrlab_meter.ino`` and its ``.S``, ``.cpp``, ``.h``), sorted by name."""
    folder = data_dir() / SKETCH_NAME
    return sorted(p for p in folder.iterdir() if p.suffix in _SKETCH_SUFFIXES)


def twin_sources() -> Path:
    """Folder of the C sources of the digital twin's harness (``fsrlab_twin.c`` and what it includes)."""
    return data_dir() / "twin"


def firmware_info() -> FirmwareInfo:
    """Version and protocol of the shipped firmware, read from the sketch's ``meter.h``.

    Raises
    ------
    FileFormatError
        When ``meter.h`` does not define ``METER_FW_VERSION`` and ``METER_PROTOCOL_VERSION``.
    """
    header = (data_dir() / SKETCH_NAME / "meter.h").read_text(encoding="utf-8")
    version = re.search(r'^#define\s+METER_FW_VERSION\s+"([^"]+)"', header, re.M)
    protocol = re.search(r"^#define\s+METER_PROTOCOL_VERSION\s+(\d+)", header, re.M)
    if not version or not protocol:
        from fsrlab.errors import FileFormatError

        raise FileFormatError("the shipped meter.h defines no METER_FW_VERSION or METER_PROTOCOL_VERSION")
    return FirmwareInfo(version.group(1), int(protocol.group(1)), hex_path())


def write_sketch(directory: str | Path, overwrite: bool = False) -> Path:
    """Write the sketch for the Arduino IDE into ``directory/fsrlab_meter/``.

    The output policy (:mod:`fsrlab.io.outputs`): an empty ``directory`` is refused (it would mean "here");
    ``directory`` is created when missing only where its parent exists (a mistyped path is not made from
    ``/``); each file is written under a temporary name and renamed into place.

    Parameters
    ----------
    directory : str or Path
        Where the sketch folder goes (created when missing, in an existing folder), e.g. the IDE's sketchbook.
    overwrite : bool
        Replace files of the sketch that already exist there (otherwise nothing is written).

    Returns
    -------
    Path
        The sketch folder; open its ``fsrlab_meter.ino`` in the IDE.

    Raises
    ------
    FileExistsError
        When a file of the sketch exists and ``overwrite`` is false (the message names it).
    OutputError
        ``directory`` is empty, a file, or in a folder that does not exist (``.option`` is ``"directory"``).
    """
    from fsrlab.errors import ParameterError
    from fsrlab.io.outputs import OutputError, output_path, write_bytes_atomic

    if not isinstance(overwrite, bool):
        raise ParameterError(f"must be True or False, got {overwrite!r}", parameter="overwrite")
    base = output_path(directory, "directory")
    if base.exists() and not base.is_dir():
        raise OutputError("directory", f"{base} is a file, not a folder")
    if not base.exists() and not base.parent.is_dir():
        raise OutputError("directory", f"{base.parent} does not exist; give an existing folder (or one to make in "
                                       "an existing folder)")
    target = base / SKETCH_NAME
    if target.exists() and not target.is_dir():
        raise OutputError("directory", f"{target} is a file, not the sketch's folder")
    files = sketch_files()
    if not overwrite:
        existing = [target / f.name for f in files if os.path.lexists(target / f.name)]
        if existing:
            raise FileExistsError(f"{existing[0]} exists ({len(existing)} of the sketch's {len(files)} files do); "
                                  "--overwrite replaces them")
    target.mkdir(parents=True, exist_ok=True)
    for f in files:
        write_bytes_atomic(target / f.name, f.read_bytes())
    return target


#: Bytes of an ATmega328P's flash: an image must fit below it. [bytes]
FLASH_BYTES = 32 * 1024
_HEX_LINE = re.compile(r":[0-9A-Fa-f]{10,}")


def check_intel_hex(path: str | Path) -> int:
    """Check that ``path`` is an Intel hex image for an Uno: every record well formed, its checksum right,
    its data inside the ATmega328P's 32 KiB of flash, and an end-of-file record last.

    Parameters
    ----------
    path : str or Path
        The image.

    Returns
    -------
    int
        Bytes of data it holds. [bytes]

    Raises
    ------
    FileFormatError
        One line naming the file, the line and what is wrong (``.parameter`` is ``"hex_file"``).
    OSError
        The file cannot be read.
    """
    from fsrlab.errors import FileFormatError
    from fsrlab.io.runformat import input_file
    from fsrlab.io.shown import shown

    p = input_file(path, "hex_file")
    if p.stat().st_size > 8 * FLASH_BYTES:  # 32 KiB of data is at most ~90 KB of hex text
        raise FileFormatError(f"{p}: {p.stat().st_size} bytes, more than an Intel hex image of an Uno's "
                              f"{FLASH_BYTES // 1024} KiB of flash", parameter="hex_file")
    lines = p.read_bytes().decode("ascii", errors="replace").splitlines()
    total, base, ended = 0, 0, False
    for k, line in enumerate(lines, start=1):
        line = line.strip()
        if not line:
            continue
        where = f"{p}: line {k}"
        if ended:
            raise FileFormatError(f"{where}: a record after the end-of-file record", parameter="hex_file")
        if not _HEX_LINE.fullmatch(line) or len(line) % 2 == 0:
            raise FileFormatError(f"{where}: {shown(line[:40])} is not an Intel hex record (':' then pairs of hex "
                                  "digits); is this a firmware image?", parameter="hex_file")
        record = bytes.fromhex(line[1:])
        count, address, kind = record[0], int.from_bytes(record[1:3], "big"), record[3]
        if len(record) != count + 5 or sum(record) & 0xFF:
            raise FileFormatError(f"{where}: the record's length or checksum is wrong", parameter="hex_file")
        if kind == 0:
            if base + address + count > FLASH_BYTES:
                raise FileFormatError(f"{where}: data at 0x{base + address:X}, beyond an ATmega328P's "
                                      f"{FLASH_BYTES // 1024} KiB of flash", parameter="hex_file")
            total += count
        elif kind == 1:
            ended = True
        elif kind in (2, 4):
            base = int.from_bytes(record[4:6], "big") << (4 if kind == 2 else 16)
        elif kind not in (3, 5):
            raise FileFormatError(f"{where}: record type {kind:02X} is not an Intel hex type", parameter="hex_file")
    if not ended:
        raise FileFormatError(f"{p}: no end-of-file record (:00000001FF); the image is cut short or not Intel hex",
                              parameter="hex_file")
    return total


def avrdude_command(port: str, hex_file: str | Path | None = None, avrdude: str = "avrdude") -> list[str]:
    """The avrdude command line that writes the image through an Uno's bootloader.

    Parameters
    ----------
    port : str
        The board's serial port (``/dev/ttyACM0``, ``COM3``).
    hex_file : str or Path, optional
        The image; the shipped one by default.
    avrdude : str
        The avrdude executable.
    """
    if hex_file is not None and not isinstance(hex_file, (str, os.PathLike)):
        raise TypeError(f"hex_file: must be a path (str or path-like), got {type(hex_file).__name__}")
    image = Path(hex_file) if hex_file is not None else hex_path()
    return [avrdude, "-c", "arduino", "-p", "atmega328p", "-b", "115200", "-P", str(port),
            "-U", f"flash:w:{image}:i"]


def flash(port: str, hex_file: str | Path | None = None, *, avrdude: str | None = None,
          check_timeout_s: float = 5.0) -> FlashResult:
    """Write the firmware to an Uno with avrdude, then check the board answers ``ID`` as this firmware.

    Parameters
    ----------
    port : str
        The board's serial port, or ``auto`` (the one Uno by USB id:
        :func:`~fsrlab.acquisition.serial_link.find_uno`).
    hex_file : str or Path, optional
        The image; the shipped one (:func:`hex_path`) by default. With another image the check
        expects the shipped firmware's version all the same.
    avrdude : str, optional
        The avrdude executable; found on the PATH by default.
    check_timeout_s : float
        How long the board may take to answer ``ID`` after the upload (the bootloader hands over
        within about a second). [s]

    Returns
    -------
    FlashResult

    Raises
    ------
    ToolMissing
        avrdude is not installed (the message says how to get it).
    FlashError
        avrdude failed (its last lines are in the message).
    HandshakeError
        The board answered as another firmware version or protocol, or not at all.
    LinkError
        ``auto`` found no Uno or several.
    FileFormatError
        ``hex_file`` is not an Intel hex image for an Uno (:func:`check_intel_hex`), refused before avrdude runs.
    """
    if not check_timeout_s > 0:
        raise ParameterError(f"must be > 0 s, got {check_timeout_s!r}", parameter="check_timeout_s")
    info = firmware_info()
    image = Path(hex_file) if hex_file is not None else info.hex_path
    if not image.is_file():
        raise ParameterError(f"no firmware image at {image}", parameter="hex_file")
    check_intel_hex(image)  # before avrdude runs: avrdude takes a minute to give up on a file that is not one
    exe = avrdude or shutil.which("avrdude")
    if exe is None:
        raise ToolMissing(f"avrdude is not installed: {AVRDUDE_HINT}")
    device = find_uno() if port == "auto" else str(port)
    command = avrdude_command(device, image, exe)
    try:
        proc = subprocess.run(command, capture_output=True, text=True, errors="replace")
    except OSError as exc:
        raise ToolMissing(f"avrdude cannot run ({exc.strerror}): {AVRDUDE_HINT}") from None
    if proc.returncode != 0:
        lines = [ln.strip() for ln in proc.stderr.splitlines() if ln.strip() and "Thank you" not in ln]
        raise FlashError(f"avrdude could not write {device} (exit code {proc.returncode}): "
                         + " | ".join(lines[-3:]))
    with SerialLink(device) as link:
        ident = link.handshake(timeout_s=check_timeout_s)
    if ident.firmware_version != info.version or ident.protocol_version != info.protocol_version:
        raise HandshakeError(f"{device} answers firmware {ident.firmware_version} protocol {ident.protocol_version} "
                             f"after the upload, expected {info.version} protocol {info.protocol_version}")
    return FlashResult(device, image, ident, command)
