"""``fsrlab --help`` lists its commands in panels: at least five, every command exactly once.

Reference: the commands the topic modules register on ``app`` (imported here, not read from the table the
listing is built from) and the text ``fsrlab --help`` prints, parsed as click's help format (a section title
ends with ":" at column 0, a command row starts with two spaces and the command's name).
"""

from __future__ import annotations

import importlib

from clirun import run_cli
from fsrlab.cli import COMMAND_MODULES, app


def _registered() -> set[str]:
    for module in COMMAND_MODULES:
        importlib.import_module(f"fsrlab.cli.{module}")
    names = {info.name or info.callback.__name__.replace("_", "-") for info in app.registered_commands}
    return names | {info.name for info in app.registered_groups}


def _panels(text: str) -> dict[str, list[str]]:
    """Section title -> the command names listed under it (the Options section left out)."""
    panels: dict[str, list[str]] = {}
    current = None
    for line in text.splitlines():
        if line and not line.startswith(" ") and line.endswith(":") and not line.startswith("Usage"):
            current = line[:-1]
            panels[current] = []
        elif current and current != "Options" and line.startswith("  ") and not line.startswith("   "):
            panels[current].append(line.split()[0])
    panels.pop("Options", None)
    return panels


def test_help_lists_every_command_once_in_at_least_five_panels():
    code, out, _ = run_cli(["--help"])
    assert code == 0
    panels = _panels(out)
    listed = [name for names in panels.values() for name in names]
    assert len(panels) >= 5, panels
    assert sorted(listed) == sorted(_registered()), panels  # each exactly once, none missing, none invented
    assert "Commands" not in panels  # every registered command has its panel


def test_a_panel_groups_what_it_names():
    _, out, _ = run_cli(["--help"])
    panels = _panels(out)
    assert set(panels["Measure"]) == {"acquire", "live", "measure", "weights", "loadcell"}
    assert set(panels["Setup"]) == {"doctor", "ports", "firmware"}
    assert {"calibrate", "apply", "import"} <= set(panels["Calibrate"])
