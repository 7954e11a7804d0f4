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
                   "creep", "live", "twin", "bench", "report_run", "demo", "importer", "firmware", "ports", "doctor")
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


def _light_coercion() -> None:
    """Give plain options (bool, int, float, str, Path, or a ``parser=``) a coercion without pydantic.

    typer (≥ 0.29) checks every option's value once more after click has read it, through a pydantic
    ``TypeAdapter`` it builds the first time the option is used: importing pydantic and building the
    adapters is ~0.1 s of a short command's start (cProfile), the largest part of ``fsrlab oscillator``'s.
    For these options typer's adapter does something simple: with ``parser=`` it returns
    ``parser(value)``; for a value that already has the annotated type it returns it; a Path goes
    through ``coerce_cli_path``. This does the same directly, and hands anything else (another type
    or value, ranges, choices, files, a parser raising ValueError) to typer's own coercion.
    ``tests/cli/test_main.py`` compares both on every option of every command.
    """
    import os
    from dataclasses import dataclass
    from pathlib import Path

    from typer._coercion import RuntimeParam, build_runtime_param
    from typer._param_types import coerce_cli_path
    from typer.core import _TyperParameter

    if getattr(_TyperParameter, "_fsrlab_light", False):
        return

    @dataclass(frozen=True)
    class Plain(RuntimeParam):
        def _coerce_value(self, value, param, ctx):
            ann, parser = self.annotation, self.parameter_info.parser
            try:
                if parser is not None:
                    return parser(value)
                if type(value) is ann:
                    return value
                if ann is float and type(value) is int:
                    return float(value)
                if ann is Path and isinstance(value, (str, os.PathLike)):
                    return coerce_cli_path(value if isinstance(value, Path) else Path(value), self.parameter_info,
                                           path_type=Path, param=param, ctx=ctx)
            except ValueError:
                pass  # typer's coercion words it
            return build_runtime_param(param.type_descriptor)._coerce_value(value, param=param, ctx=ctx)

    def get_runtime_param(self):
        if self._runtime_param is None:
            desc = self.type_descriptor
            plain = (desc.parameter_info.parser is not None and not (desc.is_list or desc.is_tuple)) or (
                desc.annotation in (bool, int, float, str, Path) and not (desc.is_file or desc.is_choice or desc.is_ranged))
            self._runtime_param = (Plain(parameter_info=desc.parameter_info, annotation=desc.annotation) if plain
                                   else build_runtime_param(desc))
        return self._runtime_param

    _TyperParameter.get_runtime_param = get_runtime_param
    _TyperParameter._fsrlab_light = True


_light_coercion()


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
        if type(exc).__name__ == "NoArgsIsHelpError" and getattr(exc, "ctx", None) is not None:
            # a command group without its command (``fsrlab firmware``): its help, as bare ``fsrlab`` gives
            print(exc.ctx.get_help())
            code = 0
        else:
            message = exc.format_message()
            ctx = getattr(exc, "ctx", None)
            if message.strip() == "Missing command." and ctx is not None and hasattr(ctx.command, "list_commands"):
                message = (f"{ctx.command_path}: missing command (argument COMMAND): one of "
                           f"{', '.join(ctx.command.list_commands(ctx))}")
            print(f"fsrlab: error: {_one_line(message)}", file=sys.stderr)
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
