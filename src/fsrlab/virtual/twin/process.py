"""The twin's harness process: where it is, whether it can run, and the records it reads.

The harness (``firmware/build/fsrlab_twin``, source ``firmware/sim/fsrlab_twin.c``) runs the meter's
firmware (``firmware/build/fsrlab_meter.elf``) in simavr; both are built by ``make firmware``. Paths
are relative to the repository root (a clean clone after ``make firmware``; :func:`build_dir`), or
to the directory in the environment variable ``FSRLAB_FIRMWARE_BUILD``. An installed package, which
has no ``firmware/build``, builds the harness on first use into the user's cache folder and runs
the shipped ``fsrlab_meter.hex`` (:mod:`fsrlab.virtual.twin.build`).

Records on the harness's stdin: 16 bytes, little endian: type (1 byte), 3 bytes padding, int32
value, uint64 CPU cycle (the harness's documentation lists the types).
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path
from typing import NamedTuple

__all__ = ["F_CPU_HZ", "ROOT", "build_dir", "elf_path", "harness_path", "twin_available", "TwinAvailability",
           "pack_records", "RECORD_DTYPE"]

F_CPU_HZ = 16_000_000
"""CPU clock of the simulated ATmega328P (cycles per second). [Hz]"""
ROOT = Path(__file__).resolve().parents[4]
"""Repository root (``src/fsrlab/virtual/twin`` is four levels below)."""
SIMAVR_HEADER = Path("/usr/include/simavr/sim_avr.h")


def build_dir() -> Path:
    """Directory of the built firmware and harness.

    ``FSRLAB_FIRMWARE_BUILD`` when set; otherwise ``firmware/build`` of the repository this package
    lives in (an editable install of a clone), or else of the current directory (a clone next to an
    installed package), or else the harness built in the user's cache folder
    (:func:`fsrlab.virtual.twin.build.cached_build`).
    """
    env = os.environ.get("FSRLAB_FIRMWARE_BUILD")
    if env:
        return Path(env)
    here, cwd = ROOT / "firmware" / "build", Path.cwd() / "firmware" / "build"
    if not (here / "fsrlab_twin").exists() and (cwd / "fsrlab_twin").exists():
        return cwd
    if not (here / "fsrlab_twin").exists():
        from fsrlab.virtual.twin.build import cached_build

        return cached_build() or here
    return here


def elf_path() -> Path:
    """The firmware image, ``fsrlab_meter.elf`` (the cache's build: ``fsrlab_meter.hex``)."""
    d = build_dir()
    elf = d / "fsrlab_meter.elf"
    return d / "fsrlab_meter.hex" if not elf.exists() and (d / "fsrlab_meter.hex").exists() else elf


def harness_path() -> Path:
    """The twin's simavr harness, ``fsrlab_twin``."""
    return build_dir() / "fsrlab_twin"


class TwinAvailability(NamedTuple):
    """Whether the twin can run here: true or false in an ``if``, and ``ok, reason = ...`` unpacks it.

    A plain ``(False, reason)`` tuple would be true in an ``if`` (it is not empty); this one is as
    true as ``ok``.

    Parameters
    ----------
    ok : bool
        Whether the twin can run.
    reason : str
        Empty when it can; else one line saying what is missing and how to get it.
    """

    ok: bool
    reason: str

    def __bool__(self) -> bool:
        return bool(self.ok)


def twin_available() -> TwinAvailability:
    """Whether the twin can run here.

    Returns
    -------
    TwinAvailability
        ``(True, "")``, or ``(False, reason)``: one line saying what is missing and how to get it
        (``make sysdeps`` for simavr, ``make firmware`` for the firmware and its harness). It is
        false in an ``if`` when the twin cannot run, and unpacks as ``ok, reason``.
    """
    if not os.environ.get("FSRLAB_FIRMWARE_BUILD") and not harness_path().exists() \
            and not (ROOT / "firmware" / "Makefile").exists():
        from fsrlab.virtual.twin.build import build_harness  # an installed package: build on first use

        built, reason = build_harness()
        if built is None:
            return TwinAvailability(False, reason)
    harness, elf = harness_path(), elf_path()
    if not harness.exists() or not elf.exists():
        missing = harness if not harness.exists() else elf
        if not SIMAVR_HEADER.exists():
            return TwinAvailability(False, f"the digital twin needs simavr and the built firmware ({missing} is "
                                           "missing): run `make sysdeps`, then `make firmware`")
        return TwinAvailability(False, f"the digital twin needs the built firmware and its simavr harness "
                                       f"({missing} is missing): run `make firmware`")
    try:
        proc = subprocess.run([str(harness)], capture_output=True, timeout=10)
    except OSError as exc:
        return TwinAvailability(False, f"the digital twin's harness {harness} cannot run ({exc.strerror}): "
                                       "run `make firmware`")
    if proc.returncode != 2 or b"usage" not in proc.stderr:
        return TwinAvailability(False, f"the digital twin's harness {harness} cannot run (simavr library missing?): "
                                       "run `make sysdeps`, then `make firmware`")
    return TwinAvailability(True, "")


def _dtype():
    import numpy as np

    return np.dtype([("type", "u1"), ("pad", "V3"), ("value", "<i4"), ("cycle", "<u8")])


RECORD_DTYPE = None
"""numpy dtype of one record (set on first use; numpy is not imported at module load)."""


def pack_records(kind: str, values, cycles) -> bytes:
    """Records of one type as bytes for the harness's stdin.

    Parameters
    ----------
    kind : str
        One letter: ``P``, ``E``, ``L``, ``A`` or ``H``.
    values : array_like of int
        The records' values.
    cycles : array_like of int
        The records' CPU cycles (≥ 0). [cycle]
    """
    import numpy as np

    global RECORD_DTYPE
    if RECORD_DTYPE is None:
        RECORD_DTYPE = _dtype()
    v = np.atleast_1d(np.asarray(values, dtype=np.int64))
    c = np.atleast_1d(np.asarray(cycles, dtype=np.int64))
    rec = np.zeros(max(v.size, c.size), dtype=RECORD_DTYPE)
    rec["type"] = ord(kind)
    rec["value"] = v
    rec["cycle"] = np.maximum(c, 0)
    return rec.tobytes()
