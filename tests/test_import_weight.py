"""Structural check: the closed-form modules and the command line import no heavy package at start.

Reference: ``sys.modules`` in a fresh interpreter after the import (a property, not a timing; the
start-up cost they would add: scipy.constants alone 0.10–0.13 s, measured with ``python -X importtime``).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("scipy", "matplotlib", "serial", "rich")


@pytest.mark.parametrize("module", ["fsrlab.physics.params", "fsrlab.circuits.lm555", "fsrlab.circuits.circuit",
                                    "fsrlab.cli"])
def test_module_does_not_import_heavy_packages(module):
    # fsrlab.cli imports no command's module (tests/cli/test_lazy_commands.py); a command imports what it
    # needs when it runs.
    code = (f"import json, sys, {module}; "
            f"print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r})))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert json.loads(out) == []


def test_electron_volt_literal_is_codata():
    # CODATA 2018 / SI 2019: e = 1.602176634e-19 C exactly; scipy.constants agrees.
    from scipy.constants import electron_volt as scipy_ev

    from fsrlab.physics.params import electron_volt

    assert electron_volt == scipy_ev == 1.602176634e-19


@pytest.mark.parametrize("module", ["fsrlab.cli", "fsrlab.physics.params", "fsrlab.circuits.circuit"])
def test_command_line_start_does_not_import_numpy(module):
    # `fsrlab --help` and the paper's parameters and circuit (plain numbers, checked with math) need no
    # numpy: ~0.05-0.07 s of every start (python -X importtime). Commands import it when they run.
    code = f"import sys, {module}; print('numpy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


@pytest.mark.parametrize("args, absent", [
    (["--help"], ("numpy", "pydantic", "scipy", "matplotlib")),
    (["oscillator", "--help"], ("numpy", "pydantic")),
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--json"], ("pydantic", "scipy", "matplotlib")),
])
def test_command_line_runs_without_heavy_packages(args, absent):
    # The whole command as a user starts it (a subprocess), then sys.modules: `fsrlab --help` needs no
    # numpy, and no command's option parsing needs pydantic (fsrlab.cli's light coercion; typer would
    # import it, ~0.1 s). The oscillator's closed form needs numpy, not scipy or matplotlib.
    code = ("import atexit, json, sys\n"
            f"atexit.register(lambda: print(json.dumps(sorted(m for m in {absent!r} if m in sys.modules)), "
            "file=sys.stderr))\n"
            "from fsrlab.cli import main\n"
            f"main({args!r})\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stderr.strip().splitlines()[-1]) == []
