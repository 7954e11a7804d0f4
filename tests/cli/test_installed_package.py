"""The package as a user installs it: sdist and wheel built, the wheel installed into a fresh venv,
the commands run from a folder outside the repository.

References: ``pyproject.toml`` (name, version, licence, dependencies, console script: the wheel's
metadata must say the same), the package data of the source tree (every file of
``src/fsrlab/firmware_data`` in both archives), ``firmware/Makefile``'s build of the image (what
``fsrlab firmware hex`` of the installed package must point to, byte for byte), and the shipped
firmware's identity (``meter.h``).
"""

from __future__ import annotations

import email
import json
import os
import subprocess
import sys
import tarfile
import tomllib
import zipfile
from pathlib import Path

import pytest

from toolcheck import require_file, require_tool

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "src" / "fsrlab" / "firmware_data"


def _run(cmd, **kw):
    proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    assert proc.returncode == 0, f"{cmd}: {proc.stderr[-3000:]}"
    return proc.stdout


@pytest.fixture(scope="module")
def dist(tmp_path_factory):
    pytest.importorskip("build", reason="the build package (pip install -e '.[dev]')")
    out = tmp_path_factory.mktemp("dist")
    _run([sys.executable, "-m", "build", "--outdir", out, ROOT])
    (wheel,), (sdist,) = out.glob("*.whl"), out.glob("*.tar.gz")
    return wheel, sdist


def test_archives_hold_the_firmware_and_the_metadata_of_pyproject(dist):
    wheel, sdist = dist
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    data = sorted(str(p.relative_to(DATA.parent.parent)) for p in DATA.rglob("*") if p.is_file())
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        info = f"fsrlab-{project['version']}.dist-info"
        meta = email.message_from_string(z.read(f"{info}/METADATA").decode())
        entry_points = z.read(f"{info}/entry_points.txt").decode()
    assert not [d for d in data if d not in names], "package data missing from the wheel"
    assert (meta["Name"], meta["Version"]) == (project["name"], project["version"])
    assert meta["License-Expression"] == project["license"]
    assert meta["Requires-Python"] == project["requires-python"]
    from packaging.requirements import Requirement

    def reqs(lines):
        return sorted((r.name, r.specifier) for r in map(Requirement, lines) if r.marker is None)

    assert reqs(meta.get_all("Requires-Dist")) == reqs(project["dependencies"])
    assert "fsrlab = fsrlab.cli:main" in entry_points
    with tarfile.open(sdist) as t:
        members = {m.split("/", 1)[1] for m in t.getnames() if "/" in m}
    assert not [d for d in data if f"src/{d}" not in members], "package data missing from the sdist"


@pytest.mark.slow
def test_installed_wheel_runs_outside_the_repository(dist, tmp_path):
    require_tool("avr-gcc")
    require_tool("make")
    require_tool("gcc")
    require_file("/usr/include/simavr/sim_avr.h", "libsimavr-dev (simavr headers)")
    _run(["make", "-s", "-C", ROOT / "firmware", "build/fsrlab_meter.hex"])
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", venv])
    _run([venv / "bin" / "python", "-m", "pip", "install", "-q", dist[0]])
    run = tmp_path / "run"
    run.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("FSRLAB_FIRMWARE_BUILD", "PYTHONPATH", "VIRTUAL_ENV")}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    fsrlab = venv / "bin" / "fsrlab"

    def cli(*args):
        return _run([fsrlab, *args], cwd=run, env=env)

    hex_path = Path(cli("firmware", "hex").strip())
    assert hex_path.is_relative_to(venv) and not hex_path.is_relative_to(ROOT)
    assert hex_path.read_bytes() == (ROOT / "firmware" / "build" / "fsrlab_meter.hex").read_bytes()

    checks = {c["name"]: c for c in json.loads(cli("doctor", "--json", "--no-probe"))["checks"]}
    assert checks["digital twin"]["found"], checks["digital twin"]
    assert str(tmp_path / "cache" / "fsrlab") in checks["digital twin"]["detail"]  # built on first use

    port = cli("twin", "--profile", "triangle", "--duration", "3s", "--speed", "max").strip()
    assert port.startswith("/dev/")

    demo = json.loads(cli("demo", "--out", "d", "--no-paper", "--cycles", "1", "--period", "2s", "--repeat", "2",
                          "--json"))
    assert demo["device"] == "twin" and (run / demo["index"]).is_file()

    sketch = Path(cli("firmware", "sketch", "ide").strip())
    assert sketch == run / "ide" / "fsrlab_meter" / "fsrlab_meter.ino"
    assert sketch.read_bytes() == (ROOT / "firmware" / "fsrlab_meter" / "fsrlab_meter.ino").read_bytes()
