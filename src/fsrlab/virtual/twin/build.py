"""The twin's harness for an installed package: built on first use into the user's cache folder.

A clone has ``firmware/build`` (``make firmware``); an installed package has instead the harness's C
sources and the firmware image as package data (:func:`fsrlab.acquisition.firmware.twin_sources`,
:func:`~fsrlab.acquisition.firmware.hex_path`). With a C compiler and simavr's headers and library
present, :func:`build_harness` compiles the harness into ``$XDG_CACHE_HOME/fsrlab/twin-<key>``
(``~/.cache/fsrlab/...`` by default), next to a copy of the image, once: the key is a hash of the
sources and the image, so a new version of the package builds its own.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

__all__ = ["INSTALL_HINT", "cache_root", "compiler", "simavr_include", "cached_build_dir", "cached_build",
           "build_harness"]

INSTALL_HINT = "sudo apt-get install gcc simavr libsimavr-dev (Debian, Ubuntu)"
"""What to install for the twin's harness to be built."""
_INCLUDE_DIRS = ("/usr/include/simavr", "/usr/local/include/simavr", "/opt/homebrew/include/simavr")
_SOURCES = ("fsrlab_twin.c", "hx711_model.c", "mcu.c")


def cache_root() -> Path:
    """``$XDG_CACHE_HOME/fsrlab``, or ``~/.cache/fsrlab`` when the variable is unset or empty."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "fsrlab"


def compiler() -> str | None:
    """The C compiler: ``$CC`` when set, else the first of ``cc``, ``gcc``, ``clang`` on the PATH."""
    for name in ([os.environ["CC"]] if os.environ.get("CC") else []) + ["cc", "gcc", "clang"]:
        path = shutil.which(name)
        if path:
            return path
    return None


def simavr_include() -> Path | None:
    """The folder of simavr's headers (the one holding ``sim_avr.h``), or None."""
    for d in _INCLUDE_DIRS:
        if (Path(d) / "sim_avr.h").exists():
            return Path(d)
    return None


def _key() -> str:
    from fsrlab.acquisition.firmware import hex_path, twin_sources

    h = hashlib.sha256()
    for f in sorted(twin_sources().iterdir()) + [hex_path()]:
        h.update(f.name.encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:12]


def cached_build_dir() -> Path:
    """Where this package's harness is (or would be) built: ``cache_root()/twin-<key>``."""
    return cache_root() / f"twin-{_key()}"


def cached_build() -> Path | None:
    """:func:`cached_build_dir` when the harness and the image are there, else None."""
    try:
        d = cached_build_dir()
    except OSError:  # no package data (a broken install): nothing cached either
        return None
    return d if (d / "fsrlab_twin").exists() and (d / "fsrlab_meter.hex").exists() else None


def build_harness() -> tuple[Path | None, str]:
    """Build the twin's harness into the cache folder unless it is there already.

    Returns
    -------
    (Path or None, str)
        ``(folder, "")`` with ``fsrlab_twin`` and ``fsrlab_meter.hex`` in it, or ``(None, reason)``:
        one line naming what is missing and how to install it, or the compiler's last line.
    """
    done = cached_build()
    if done is not None:
        return done, ""
    cc, include = compiler(), simavr_include()
    missing = [what for what, ok in (("a C compiler", cc), ("simavr's headers", include)) if not ok]
    if missing:
        return None, (f"the digital twin is built on first use and needs {' and '.join(missing)}: "
                      f"{INSTALL_HINT}; or point FSRLAB_FIRMWARE_BUILD to a built firmware/build")
    from fsrlab.acquisition.firmware import hex_path, twin_sources

    target = cached_build_dir()
    target.mkdir(parents=True, exist_ok=True)
    src = twin_sources()
    # Built under a temporary name and renamed: two first uses at once cannot see half a file.
    fd, tmp = tempfile.mkstemp(prefix=".fsrlab_twin.", dir=target)
    os.close(fd)
    cmd = [cc, "-O2", "-std=gnu99", f"-I{include}", f"-I{src}", *(str(src / s) for s in _SOURCES),
           "-o", tmp, "-lsimavr", "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, errors="replace")
        if proc.returncode != 0:
            last = [ln for ln in proc.stderr.splitlines() if ln.strip()][-1:] or [f"exit code {proc.returncode}"]
            return None, (f"the digital twin's harness did not build in {target} ({last[0].strip()}): "
                          f"{INSTALL_HINT}")
        shutil.copyfile(hex_path(), target / ".fsrlab_meter.hex.tmp")
        os.replace(target / ".fsrlab_meter.hex.tmp", target / "fsrlab_meter.hex")
        os.chmod(tmp, 0o755)
        os.replace(tmp, target / "fsrlab_twin")
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target, ""
