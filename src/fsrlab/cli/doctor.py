"""``fsrlab doctor``: what this machine has for fsrlab, what each thing enables, how to get the rest."""

from __future__ import annotations

import typer

from fsrlab.cli import app
from fsrlab.cli.options import emit_json


@app.command("doctor")
def doctor(
    port: list[str] = typer.Option(None, "--port", help="Ask the device on this port ID (repeatable; default: every "
            "port with an Uno's USB id). Opening an Uno's port restarts it."),
    no_probe: bool = typer.Option(False, "--no-probe", help="Open no serial port (boards are not asked)."),
    json_out: bool = typer.Option(False, "--json", help="Print the checks and boards as JSON: "
            "{checks: [{name, found, detail, enables, install}], boards: [...]}."),
) -> None:
    """Say what this machine has for fsrlab and what each thing enables, with install commands.

    Checks ngspice (--spice, the report's circuit checks), a C compiler and simavr's headers (the
    digital twin, built on first use), avrdude (fsrlab firmware flash), the AVR toolchain (building
    the firmware from source), Chromium and chromedriver (the live page's browser tests), and asks
    the boards on serial ports for their firmware and protocol version. Exit code 0 whatever is
    missing: it is a report.

    Examples:

    \b
      fsrlab doctor
      fsrlab doctor --json --no-probe
    """
    from fsrlab.bench.doctor import diagnose

    result = diagnose(ports=port or None, probe=not no_probe)
    if json_out:
        emit_json(result.to_dict())
        return
    for c in result.checks:
        mark = "ok  " if c.found else "MISSING"
        typer.echo(f"{mark:7} {c.name}: {c.detail}")
        typer.echo(f"        enables {c.enables}")
        if c.install:
            typer.echo(f"        install: {c.install}")
    if no_probe:
        typer.echo("boards: not asked (--no-probe)")
    elif not result.boards:
        typer.echo("boards: no port with an Uno's USB id (fsrlab ports lists the ports; --port PORT asks one)")
    for b in result.boards:
        typer.echo(f"{'ok' if b.ok and b.matches_package else 'CHECK':7} board on {b.port}: {b.detail}")
