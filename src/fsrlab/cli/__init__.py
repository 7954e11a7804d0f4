"""The ``fsrlab`` command line: thin Typer commands, one module per topic, no computation here.

Every command that prints numbers takes ``--json``. Bad input ends with one line on stderr that
names the field and what is allowed, and exit code 2 (see :func:`main`).
"""

from __future__ import annotations

import importlib
import inspect
import os
import sys
from collections.abc import MutableMapping

import typer

from fsrlab import __version__
from fsrlab.errors import FsrlabError

#: The option of each library parameter an error can name (:attr:`fsrlab.errors.FsrlabError.parameter`).
PARAMETER_OPTIONS = {"port": "--port", "masses_kg": "--masses"}

# Every command ``fsrlab --help`` lists, in its order: the topic module that adds it to ``app`` and its
# summary (the first paragraph of its help). The listing is built from this table, so ``fsrlab --help``
# imports no topic module and ``fsrlab CMD`` imports only CMD's; tests/cli/test_lazy_commands.py checks
# the table against the commands themselves. A topic module adds its commands with ``@app.command()``.
COMMANDS = {
    "paper": ("report", "Reproduce every figure and table of the paper, with the paper's values beside ours and the "
                        "errata."),
    "physics": ("physics", "Hysteresis error (eq. 13) of R_A and C_A over one cycle 0 → σf → 0; defaults are the "
                           "paper's Table 1."),
    "oscillator": ("oscillator", "Frequency, duty cycle and sensitivities of the LM555 astable with the FSR as timing "
                                 "element."),
    "decode": ("oscillator", "Recover R_FSR and C_FSR from a measured frequency and duty cycle (uncertainty: 62.5 ns "
                             "timer ticks)."),
    "design": ("oscillator", "Propose R, C_off and the variant for a sensor's R_FSR/C_FSR ranges and a wanted "
                             "frequency band."),
    "hysteresis": ("analysis", "Hysteresis error (eq. 13) of a run, per loading-unloading cycle and overall."),
    "repeatability": ("analysis", "Repeatability errors RE1 and RE2 (eq. 39) per load and sensor, and their means per "
                                  "load."),
    "calibrate": ("analysis", "Calibrate readout → force or stress, every choice scored where it will be used."),
    "apply": ("analysis", "Apply a calibration to a run: adds <reference>_estimate, <reference>_uncertainty and "
                          "in_range."),
    "iso376": ("analysis", "ISO 376:2011 quantities (b, b', fc, f0, v, c) and the class they reach (beyond the "
                           "paper)."),
    "acquire": ("acquisition", "Record measurement windows (frequency, duty cycle, A0 voltage) from an fsrlab meter "
                               "into a run file."),
    "virtual-device": ("acquisition", "Emulate an fsrlab meter on a pseudo-terminal; prints its path (open it with "
                                      "--port PATH or any serial tool)."),
    "loadcell": ("loadcell", "Calibrate the load cell: tare (offset, nothing on the cell), then scale (counts per "
                             "newton from a known mass)."),
    "weights": ("weights", "Guided known-weight calibration: place each mass, wait until the reading is stable, "
                           "record it."),
    "measure": ("measure", "Show the force live from a calibration (N and g; the load cell's reading beside it) and "
                           "record it."),
    "creep": ("creep", "Creep of a readout under held loads: drift per decade of time and time constant, per hold."),
    "live": ("live", "Serve the meter's front panel: frequency, duty cycle, op-amp voltage and the reference live, "
                     "the loading/unloading loop, the link's health, and controls (recording, range, window)."),
    "twin": ("twin", "Run the digital twin: the meter's real firmware in simavr on a pty; prints its path first."),
    "bench": ("bench", "Run a bench protocol (spring cycles, dead-weight re-placements, a creep hold) into a run "
                       "file."),
    "report": ("report_run", "Measurement report of a recorded run: HE of f and V0 side by side, RE1/RE2, ISO 376, "
                             "calibration."),
    "demo": ("demo", "The measurement chain on a virtual bench: record, calibrate, compensate, report; then the paper "
                     "report."),
    "import": ("importer", "Import a foreign CSV (your own sketch, a data logger, a spreadsheet) as a run."),
    "calibrate-channels": ("channels", "Calibrate every channel of a multi-channel run from one command; one file "
                                       "keyed by sensor id."),
    "crosstalk": ("channels", "Cross-talk check: load one channel at a time, read all of them; prints the channels × "
                              "channels matrix."),
    "ports": ("ports", "List the serial ports with what is known about each, and what --port auto picks."),
    "doctor": ("doctor", "Say what this machine has for fsrlab and what each thing enables, with install commands."),
    "firmware": ("firmware", "The meter's firmware shipped in the package: its image (hex), its sketch, flashing an "
                             "Uno."),
}
# The panels ``fsrlab --help`` lists the commands in, in their order (typer's ``rich_help_panel``): every command of
# the table is in exactly one (tests/cli/test_help_panels.py). A command registered outside the table is listed
# last, under "Commands".
PANELS = {
    "Measure": ("acquire", "live", "measure", "weights", "loadcell"),
    "Analyse": ("hysteresis", "repeatability", "iso376", "creep", "report", "crosstalk"),
    "Calibrate": ("calibrate", "calibrate-channels", "apply", "import"),
    "Bench and twin": ("bench", "twin", "virtual-device", "demo"),
    "The paper": ("paper", "physics", "oscillator", "decode", "design"),
    "Setup": ("doctor", "ports", "firmware"),
}
PANEL_OF = {name: panel for panel, names in PANELS.items() for name in names}
# Command groups (``fsrlab firmware hex``): the list shows their summary cut to the line, as click does for a
# command without a short help.
COMMAND_GROUPS = frozenset({"firmware"})
COMMAND_MODULES = tuple(dict.fromkeys(module for module, _ in COMMANDS.values()))


def _summarise(info) -> None:
    """Give a registered command its whole first paragraph as short help.

    click's default cuts the summary at the first ". ", which in "Hysteresis error (eq. 13) of ..." is
    inside the equation number.
    """
    if info.short_help is None:
        doc = info.help or inspect.getdoc(info.callback) or ""
        info.short_help = " ".join(doc.split("\n\n")[0].split()) or None


def _name(info) -> str:
    return info.name or typer.main.get_command_name(info.callback.__name__)


def _registration(name: str):
    """The command's or group's registration on ``app`` (``CommandInfo``, ``TyperInfo``), or None."""
    for info in app.registered_commands:
        if _name(info) == name:
            return info
    return next((info for info in app.registered_groups if info.name == name), None)


def _build(name: str):
    """The click command ``name`` from ``app``'s registrations, its topic module imported first if need be."""
    info = _registration(name)
    if info is None and name in COMMANDS:
        importlib.import_module(f"{__name__}.{COMMANDS[name][0]}")
        info = _registration(name)
    if info is None:
        return None
    if getattr(info, "rich_help_panel", None) is None:
        info.rich_help_panel = PANEL_OF.get(name)
    if isinstance(info, typer.models.TyperInfo):
        return typer.main.get_group_from_info(info, pretty_exceptions_short=app.pretty_exceptions_short,
                                              suggest_commands=app.suggest_commands,
                                              rich_markup_mode=app.rich_markup_mode)
    _summarise(info)
    return typer.main.get_command_from_info(info, pretty_exceptions_short=app.pretty_exceptions_short,
                                            rich_markup_mode=app.rich_markup_mode)


class _Commands(MutableMapping):
    """A group's commands by name, each built (its topic module imported) when it is first looked up.

    Its names are the table's and then any other command registered on ``app`` (tests add some): listing
    them imports nothing; looking one up (``[name]``, ``get``, ``in``) builds that one; ``items()`` builds all.
    """

    def __init__(self, built: dict):
        self._built = dict(built)

    def __getitem__(self, name):
        if name not in self._built:
            command = _build(name)
            if command is None:
                raise KeyError(name)
            self._built[name] = command
        return self._built[name]

    def __setitem__(self, name, command):
        self._built[name] = command

    def __delitem__(self, name):
        del self._built[name]

    def __iter__(self):
        registered = [_name(i) for i in app.registered_commands] + [i.name for i in app.registered_groups]
        return iter(dict.fromkeys([*COMMANDS, *self._built, *registered]))

    def __len__(self):
        return sum(1 for _ in self)

    def built(self, name: str) -> bool:
        """Whether ``name`` is built already (looking it up would import nothing)."""
        return name in self._built


class _LazyGroup(typer.core.TyperGroup):
    """The ``fsrlab`` group: commands built on first use; the command list and typo hints from the table."""

    def __init__(self, *, commands=None, **attrs):
        super().__init__(commands=_Commands(commands or {}), **attrs)
        self._summaries_only = False
        self._stubs: dict = {}

    def list_commands(self, ctx) -> list[str]:
        return list(self.commands)

    def get_command(self, ctx, cmd_name: str):
        if self._summaries_only and cmd_name in COMMANDS and not self.commands.built(cmd_name):
            return self._stub(cmd_name)
        return self.commands.get(cmd_name)

    def _stub(self, name: str):
        """A stand-in that lists ``name`` with the table's summary, as the command itself would be listed."""
        if name not in self._stubs:
            summary = COMMANDS[name][1]
            self._stubs[name] = (typer.core.TyperCommand(name, help=summary, rich_markup_mode=self.rich_markup_mode)
                                 if name in COMMAND_GROUPS else
                                 typer.core.TyperCommand(name, short_help=summary,
                                                         rich_markup_mode=self.rich_markup_mode))
            self._stubs[name].rich_help_panel = PANEL_OF.get(name)
        return self._stubs[name]

    def format_commands(self, ctx, formatter) -> None:
        """List the commands in their panels (:data:`PANELS`), each a section as click writes "Commands"."""
        self._summaries_only = True  # the list shows every command: from the table, importing no topic module
        try:
            commands = [(name, self.get_command(ctx, name)) for name in self.list_commands(ctx)]
            commands = [(name, cmd) for name, cmd in commands if cmd is not None and not cmd.hidden]
        finally:
            self._summaries_only = False
        if not commands:
            return
        limit = formatter.width - 6 - max(len(name) for name, _ in commands)
        rank = {name: i for i, name in enumerate(name for names in PANELS.values() for name in names)}
        sections: dict[str, list] = {panel: [] for panel in PANELS}
        for name, cmd in sorted(commands, key=lambda item: rank.get(item[0], len(rank))):
            panel = getattr(cmd, "rich_help_panel", None) or PANEL_OF.get(name) or "Commands"
            sections.setdefault(panel, []).append((name, cmd.get_short_help_str(limit)))
        for panel, rows in sections.items():
            if rows:
                with formatter.section(panel):
                    formatter.write_dl(rows)


app = typer.Typer(
    name="fsrlab",
    help="Force sensing with FSRs: physics, LM555 readout, firmware, acquisition, calibration, reports.",
    cls=_LazyGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # Plain help: rich markup would read the units in option help ("[m]", "[eV]", "[s]") as style
    # tags and drop them, and it shows a "<bool>" value placeholder after every flag.
    rich_markup_mode=None,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"fsrlab {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version and "
            "exit."),
) -> None:
    """Force sensing with FSRs read through their piezocapacitance (Matute et al. 2018)."""


_CLICK: dict = {}


def _click_command():
    """``app`` as a click command, built once per set of registered commands (building takes ~20 ms)."""
    key = tuple((id(info), info.name) for info in app.registered_commands)
    if key not in _CLICK:
        _CLICK.clear()
        for info in app.registered_commands:
            _summarise(info)
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
                desc.annotation in (bool, int, float, str,
                                    Path) and not (desc.is_file or desc.is_choice or desc.is_ranged))
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
    from fsrlab.cli.console import escaped_output

    with escaped_output():  # the one rendering boundary: nothing printed acts on the terminal
        code = _run(command, args)
    raise SystemExit(code)


def _run(command, args: list[str]) -> int:
    """Run the click ``command`` on ``args``; the exit code, every error said in one line on stderr."""
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
            message = _click_message(exc)
            ctx = getattr(exc, "ctx", None)
            if message.strip() == "Missing command." and ctx is not None and hasattr(ctx.command, "list_commands"):
                message = (f"{ctx.command_path}: missing command (argument COMMAND): one of "
                           f"{', '.join(ctx.command.list_commands(ctx))}")
            opt = getattr(exc, "option_name", None)
            if type(exc).__name__ == "NoSuchOption" and opt and opt not in args:
                # a cluster of short options (``-00``) is reported by its first letter: name the word given
                word = next((a for a in args if a.startswith(opt) and not a.startswith("--")), None)
                message += f" (from {word!r}, read as one-letter options)" if word else ""
            print(f"fsrlab: error: {_one_line(message)}", file=sys.stderr)
            code = getattr(exc, "exit_code", 2)
    except (ValueError, OSError) as exc:
        # Our models raise ValueError naming the parameter; files raise OSError. An FsrlabError carries the
        # parameter at fault: the message names its option instead.
        if os.environ.get("FSRLAB_DEBUG"):
            raise
        message = str(exc)
        option = _option_of(exc.parameter, args) if isinstance(exc, FsrlabError) and exc.parameter else None
        if option is not None:
            message = f"Invalid value for {option}: {exc.reason}"
        elif isinstance(exc, FsrlabError) and exc.parameter:  # no option of this command: the Python name is noise
            message = exc.reason
        print(f"fsrlab: error: {_one_line(message)}", file=sys.stderr)
        code = 2
    return code


def _option_of(parameter: str, args: list[str]) -> str | None:
    """The option of the command ``args`` run whose parameter is ``parameter`` (a library parameter's name, which
    the command's own parameter shares: ``between_runs`` → ``--between-runs``), else
    :data:`PARAMETER_OPTIONS`'s; None when neither has it. No message is read."""
    command = _click_command()
    for word in args:
        if word.startswith("-") or not hasattr(command, "get_command"):
            break
        sub = command.get_command(None, word)
        if sub is None:
            break
        command = sub
    for param in getattr(command, "params", ()):
        if param.name == parameter and getattr(param, "opts", None):
            long = [o for o in param.opts if o.startswith("--")]
            if param.param_type_name == "option":
                return (long or param.opts)[0]
            return getattr(param, "metavar", None) or param.name.upper()  # an argument: its metavar (RUN.csv)
    return PARAMETER_OPTIONS.get(parameter)


def _click_message(exc) -> str:
    """click's message for a usage error; an option's invalid value names the option as fail() and option_names
    do (``Invalid value for --r: ...``), where click would quote each of its spellings (``'--output' / '-o'``)."""
    param = getattr(exc, "param", None)
    if (type(exc).__name__ == "BadParameter" and exc.param_hint is None and param is not None
            and param.param_type_name == "option" and param.opts):
        return f"Invalid value for {param.opts[0]}: {exc.message}"
    return exc.format_message()


def _one_line(message: str) -> str:
    from fsrlab.cli.options import plain_numbers

    return " ".join(plain_numbers(message.strip()).split())
