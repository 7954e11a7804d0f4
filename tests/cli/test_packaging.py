"""Packaging metadata that ``make venv`` builds from.

Reference: PEP 639 and the Python Packaging User Guide ("project.license" is an SPDX expression
string; the TOML-table form is deprecated and setuptools warns about it on every build). setuptools
reads the string form from version 77.0.0 on.
"""

import re
import tomllib
from pathlib import Path

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"


def _config():
    return tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))


def test_license_is_an_spdx_string():
    assert _config()["project"]["license"] == "MIT"


def test_build_requires_a_setuptools_that_reads_spdx_licenses():
    requires = _config()["build-system"]["requires"]
    setuptools = [r for r in requires if r.startswith("setuptools")]
    assert len(setuptools) == 1
    m = re.fullmatch(r"setuptools>=(\d+)(?:\.\d+)*", setuptools[0].replace(" ", ""))
    assert m and int(m.group(1)) >= 77


def test_console_script_is_the_cli_main():
    assert _config()["project"]["scripts"]["fsrlab"] == "fsrlab.cli:main"
