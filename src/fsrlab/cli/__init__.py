"""The ``fsrlab`` command line: thin Typer commands, one module per topic, no computation here.

Every command that prints numbers takes ``--json``. Bad input ends with one line on stderr that
names the field and what is allowed, and exit code 2 (see :func:`main`).
"""

from __future__ import annotations

import importlib
import inspect
import os
import re
import sys

import typer

from fsrlab import __version__
from fsrlab.errors import FsrlabError

#: The option of each library parameter an error can name (:attr:`fsrlab.errors.FsrlabError.parameter`).
PARAMETER_OPTIONS = {"port": "--port"}

app = typer.Typer(
    name="fsrlab",
    help="Force sensing with FSRs: physics, LM555 readout, firmware, acquisition, calibration, reports.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # Plain help: rich markup would read the units in option help ("[m]", "[eV]", "[s]") as style
    # tags and drop them, and it shows a "<bool>" value placeholder after every flag.
    rich_markup_mode=None,
)

# Topic modules that add commands to ``app``; a topic not written yet is simply absent.
COMMAND_MODULES = ("report", "physics", "oscillator", "analysis", "acquisition", "loadcell", "weights", "measure",
                   "creep", "live", "twin", "bench", "report_run", "demo")
for _name in COMMAND_MODULES:
    try:
        importlib.import_module(f"{__name__}.{_name}")
    except ModuleNotFoundError as _err:
        if _err.name != f"{__name__}.{_name}":
            raise

# The command list shows each command's first paragraph whole: click's default cuts it at the
# first ". ", which in "Hysteresis error (eq. 13) of ..." is inside the equation number.
for _info in app.registered_commands:
    if _info.short_help is None:
        _doc = _info.help or inspect.getdoc(_info.callback) or ""
        _info.short_help = " ".join(_doc.split("\n\n")[0].split()) or None


def _version(value: bool) -> None:
    if value:
        typer.echo(f"fsrlab {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version and exit."),
) -> None:
    """Force sensing with FSRs read through their piezocapacitance (Matute et al. 2018)."""


_CLICK: dict = {}


def _click_command():
    """``app`` as a click command, built once per set of registered commands (building takes ~20 ms)."""
    key = tuple((id(info), info.name) for info in app.registered_commands)
    if key not in _CLICK:
        _CLICK.clear()
        _CLICK[key] = typer.main.get_command(app)
    return _CLICK[key]


def main(argv: list[str] | None = None) -> int:
    """Run the command line; usage errors and invalid values end with one line and exit code 2.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; ``sys.argv[1:]`` when omitted.

    Returns
    -------
    int
        The exit code (also raised as ``SystemExit``).
    """
    args = sys.argv[1:] if argv is None else list(argv)
    if not args:  # bare ``fsrlab``: the help, as a successful command
        args = ["--help"]
    command = _click_command()
    try:
        # In non-standalone mode typer returns an explicit Exit's code, or the command's value.
        result = command.main(args=args, prog_name="fsrlab", standalone_mode=False)
        code = result if isinstance(result, int) else 0
    except typer.Abort:
        print("fsrlab: aborted", file=sys.stderr)
        code = 130
    except typer.TyperException as exc:  # click's usage errors (bad option, bad value): exit 2
        print(f"fsrlab: error: {_one_line(exc.format_message())}", file=sys.stderr)
        code = getattr(exc, "exit_code", 2)
    except (ValueError, OSError) as exc:
        # Our models raise ValueError naming the parameter; files raise OSError. An FsrlabError carries the
        # parameter at fault: the message names its option instead.
        if os.environ.get("FSRLAB_DEBUG"):
            raise
        message = str(exc)
        if isinstance(exc, FsrlabError) and exc.parameter in PARAMETER_OPTIONS:
            message = f"{PARAMETER_OPTIONS[exc.parameter]}: {exc.reason}"
        print(f"fsrlab: error: {_one_line(message)}", file=sys.stderr)
        code = 2
    raise SystemExit(code)


def _one_line(message: str) -> str:
    from fsrlab.cli.options import plain_numbers

    # click quotes the option it found ("'--r'"), fail() and option_names do not: one spelling.
    message = re.sub(r"^Invalid value for '(-[^']*)'(?: / '-[^']*')*", r"Invalid value for \1", message.strip())
    return " ".join(plain_numbers(message).split())
