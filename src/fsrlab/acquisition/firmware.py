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

import re
import shutil
import subprocess
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from fsrlab.acquisition.messages import Identity
from fsrlab.acquisition.serial_link import HandshakeError, LinkError, SerialLink, find_uno
from fsrlab.errors import FsrlabError

__all__ = ["SKETCH_NAME", "AVRDUDE_HINT", "FlashError", "ToolMissing", "FirmwareInfo", "FlashResult", "data_dir",
           "hex_path", "sketch_files", "twin_sources", "firmware_info", "write_sketch", "avrdude_command", "flash"]

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
    ValueError
        When ``meter.h`` does not define ``METER_FW_VERSION`` and ``METER_PROTOCOL_VERSION``.
    """
    header = (data_dir() / SKETCH_NAME / "meter.h").read_text(encoding="utf-8")
    version = re.search(r'^#define\s+METER_FW_VERSION\s+"([^"]+)"', header, re.M)
    protocol = re.search(r"^#define\s+METER_PROTOCOL_VERSION\s+(\d+)", header, re.M)
    if not version or not protocol:
        raise ValueError("the shipped meter.h defines no METER_FW_VERSION or METER_PROTOCOL_VERSION")
    return FirmwareInfo(version.group(1), int(protocol.group(1)), hex_path())


def write_sketch(directory: str | Path, overwrite: bool = False) -> Path:
    """Write the sketch for the Arduino IDE into ``directory/fsrlab_meter/``.

    Parameters
    ----------
    directory : str or Path
        Where the sketch folder goes (created when missing), e.g. the IDE's sketchbook.
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
    """
    target = Path(directory) / SKETCH_NAME
    files = sketch_files()
    if not overwrite:
        existing = [target / f.name for f in files if (target / f.name).exists()]
        if existing:
            raise FileExistsError(f"{existing[0]} exists ({len(existing)} of the sketch's {len(files)} files do); "
                                  "--overwrite replaces them")
    target.mkdir(parents=True, exist_ok=True)
    for f in files:
        shutil.copyfile(f, target / f.name)
    return target


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
    """
    if not check_timeout_s > 0:
        raise ValueError(f"check_timeout_s must be > 0 s, got {check_timeout_s!r}")
    exe = avrdude or shutil.which("avrdude")
    if exe is None:
        raise ToolMissing(f"avrdude is not installed: {AVRDUDE_HINT}")
    info = firmware_info()
    image = Path(hex_file) if hex_file is not None else info.hex_path
    if not image.is_file():
        raise FileNotFoundError(f"no firmware image at {image}")
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
