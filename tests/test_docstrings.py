"""Every public function and class of fsrlab documents each of its parameters (numpydoc).

Reference: a property of the source (the project's style: a test fails when a public parameter is
undocumented, as in python-control). Public means listed in a module's ``__all__``; the CLI modules are Typer commands
whose options carry their own help text, and are left out.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re

import pytest

import fsrlab

MODULES = sorted(
    m.name for m in pkgutil.walk_packages(fsrlab.__path__, "fsrlab.")
    if not m.ispkg and not m.name.startswith("fsrlab.cli")
)


def _public(mod):
    for name in getattr(mod, "__all__", []):
        obj = getattr(mod, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            yield name, obj


def _documented(doc: str) -> set[str]:
    names = set()
    for line in doc.splitlines():
        m = re.match(r"^\s*([A-Za-z_*][\w*]*(?:\s*,\s*[A-Za-z_*][\w*]*)*)\s*(?::|$)", line)
        if m:
            names.update(n.strip().lstrip("*") for n in m.group(1).split(","))
    return names


def test_every_module_is_covered():
    # The walk finds the topic modules; a typo in the package layout would silently shrink the test.
    for name in ("fsrlab.physics.separation", "fsrlab.circuits.lm555", "fsrlab.calibration.result",
                 "fsrlab.acquisition.protocol", "fsrlab.io.runformat", "fsrlab.units"):
        assert name in MODULES


@pytest.mark.parametrize("modname", MODULES)
def test_parameters_documented(modname):
    mod = importlib.import_module(modname)
    missing = []
    for name, obj in _public(mod):
        doc = inspect.getdoc(obj) or ""
        assert doc, f"{modname}.{name} has no docstring"
        target = obj.__init__ if inspect.isclass(obj) and "__init__" in obj.__dict__ else obj
        try:
            sig = inspect.signature(target)
        except (TypeError, ValueError):
            continue
        documented = _documented(doc)
        for p in sig.parameters.values():
            if p.name in ("self", "cls") or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                continue
            if p.name not in documented:
                missing.append(f"{name}({p.name})")
    assert not missing, f"{modname}: undocumented parameters {missing}"
