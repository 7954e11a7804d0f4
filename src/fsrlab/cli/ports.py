"""``fsrlab ports``: the serial ports of this machine, and which one ``--port auto`` would pick."""

from __future__ import annotations

import typer

from fsrlab.cli import app
from fsrlab.cli.options import emit_json


@app.command("ports")
def ports(
    json_out: bool = typer.Option(False, "--json", help="Print the ports as JSON: device, usb_id, board, description, "
            "manufacturer, serial_number, and auto (the pick of --port auto or null)."),
) -> None:
    """List the serial ports with what is known about each, and what --port auto picks.

    A port whose USB id is an Arduino Uno's or a CH340 clone's is marked as an Uno; --port auto
    takes it when it is the only one.

    Examples:

    \b
      fsrlab ports
      fsrlab ports --json
    """
    from fsrlab.acquisition.ports import list_serial_ports, resolve_port
    from fsrlab.acquisition.serial_link import LinkError

    found = list_serial_ports()
    try:
        auto, why = resolve_port("auto", found), None
    except LinkError as exc:
        auto, why = None, exc.reason
    if json_out:
        emit_json({"ports": [p.to_dict() for p in found], "auto": auto, "auto_error": why})
        return
    if not found:
        typer.echo("no serial ports")
    for p in found:
        parts = [p.usb_id or "no USB id"]
        parts += [x for x in (p.board, p.description, p.manufacturer) if x]
        typer.echo(f"{p.device}  " + ", ".join(parts))
    typer.echo(f"--port auto: {auto}" if auto else f"--port {why}")
