"""``fsrlab firmware``: the Uno image and sketch the package ships, and flashing an Uno with them."""

from __future__ import annotations

from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import emit_json, fail, seconds

firmware_app = typer.Typer(
    name="firmware",
    help="The meter's firmware shipped in the package: its image (hex), its sketch, flashing an Uno.",
    no_args_is_help=True,
    rich_markup_mode=None,
)
app.add_typer(firmware_app, name="firmware")


@firmware_app.command("hex")
def hex_(
    json_out: bool = typer.Option(False, "--json", help="Print the path, firmware version and protocol as JSON."),
) -> None:
    """Print the path of the Uno image (Intel hex) the package ships.

    It is the build of the sketch that `fsrlab firmware sketch` writes; flash it with
    `fsrlab firmware flash`, or with avrdude yourself:
    avrdude -c arduino -p atmega328p -b 115200 -P PORT -U flash:w:PATH:i

    Examples:

    \b
      fsrlab firmware hex
      fsrlab firmware hex --json
    """
    from fsrlab.acquisition.firmware import firmware_info

    info = firmware_info()
    if json_out:
        emit_json({"hex": info.hex_path, "firmware_version": info.version,
                   "protocol_version": info.protocol_version})
    else:
        typer.echo(str(info.hex_path))


@firmware_app.command("sketch")
def sketch(
    directory: str = typer.Argument(..., metavar="DIR", help="Folder that gets the sketch folder fsrlab_meter/ "
            "(created when missing, in an existing folder), e.g. your Arduino sketchbook."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace the sketch's files if they exist there "
            "(otherwise nothing is written)."),
) -> None:
    """Write the firmware's sketch for the Arduino IDE into DIR/fsrlab_meter/; prints the .ino's path.

    Open the printed fsrlab_meter.ino in the Arduino IDE, board "Arduino Uno", and upload. The IDE
    builds it with link-time optimisation, so its image differs from `fsrlab firmware hex` (same
    code and behaviour).

    Examples:

    \b
      fsrlab firmware sketch ~/Arduino
      fsrlab firmware sketch ~/Arduino --overwrite
    """
    from fsrlab.acquisition.firmware import SKETCH_NAME, write_sketch
    from fsrlab.io.outputs import OutputError

    try:
        folder = write_sketch(directory, overwrite=overwrite)
    except FileExistsError as exc:
        fail(str(exc), "DIR")
    except OutputError as exc:
        fail(exc.message, "DIR")
    typer.echo(str((folder / f"{SKETCH_NAME}.ino").resolve()))


@firmware_app.command("flash")
def flash(
    port: str = typer.Option(..., "--port", help="Serial port of the Uno (/dev/ttyACM0, COM3) or 'auto' (the one Uno "
            "by USB id)."),
    hex_file: Path = typer.Option(None, "--hex", metavar="FILE", help="Another Intel hex image to write (default: the "
            "shipped one)."),
    check_timeout: float = typer.Option("5s", "--check-timeout", parser=seconds, metavar="TIME", help="How long the "
            "board may take to answer ID after the upload [s]: 5, 5s, 500ms (> 0)."),
    json_out: bool = typer.Option(False, "--json", help="Print the port, image and the board's identity as JSON."),
) -> None:
    """Write the firmware to an Uno through its bootloader (avrdude), then check it answers ID.

    Runs avrdude -c arduino -p atmega328p -b 115200 -P PORT -U flash:w:HEX:i (avrdude from the
    system: `sudo apt-get install avrdude`), then opens the port and requires the board to answer
    ID with the shipped firmware's version and protocol. Close anything else that holds the port
    (a serial monitor, `fsrlab live`) first.

    Examples:

    \b
      fsrlab firmware flash --port auto
      fsrlab firmware flash --port /dev/ttyACM0 --json
    """
    from fsrlab.acquisition.firmware import flash as flash_board

    if not check_timeout > 0:
        fail(f"must be > 0 s, got {check_timeout:g} s", "--check-timeout")
    if hex_file is not None and not hex_file.is_file():
        fail(f"no such file: {hex_file}", "--hex")
    if hex_file is not None:
        from fsrlab.acquisition.firmware import check_intel_hex

        check_intel_hex(hex_file)  # refused before any port is looked at (its FileFormatError names --hex)
    result = flash_board(port, hex_file, check_timeout_s=check_timeout)
    ident = result.identity
    if json_out:
        emit_json({"port": result.port, "hex": result.hex_path, "firmware_version": ident.firmware_version,
                   "protocol_version": ident.protocol_version, "device": ident.name, "f_cpu_hz": ident.f_cpu_hz})
    else:
        typer.echo(f"{result.port}: flashed {result.hex_path.name}; the board answers {ident.name} "
                   f"firmware {ident.firmware_version}, protocol {ident.protocol_version}")
