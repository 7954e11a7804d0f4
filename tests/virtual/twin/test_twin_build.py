"""The twin's harness built on first use from the package's sources (an installed package's path).

References: the shipped firmware's identity (``meter.h``: version and protocol, which the harness's
firmware must answer on ``ID``), and the harness built by ``firmware/Makefile`` from the same
sources (``firmware/sim``), which the other twin tests check against the LM555 transient.
"""

from __future__ import annotations

from pathlib import Path

from fsrlab.acquisition import firmware
from fsrlab.virtual.twin import build
from toolcheck import require_file, require_tool


def test_harness_built_into_the_cache_runs_the_shipped_image(tmp_path, monkeypatch):
    require_tool("gcc")
    require_file("/usr/include/simavr/sim_avr.h", "libsimavr-dev (simavr headers)")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert build.cached_build() is None
    folder, reason = build.build_harness()
    assert reason == "" and folder is not None
    assert folder.parent == tmp_path / "fsrlab" and folder.name.startswith("twin-")
    assert (folder / "fsrlab_meter.hex").read_bytes() == firmware.hex_path().read_bytes()
    stamp = (folder / "fsrlab_twin").stat().st_mtime_ns
    assert build.build_harness() == (folder, "") and (folder / "fsrlab_twin").stat().st_mtime_ns == stamp

    monkeypatch.setenv("FSRLAB_FIRMWARE_BUILD", str(folder))
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.virtual.twin import Twin, twin_available
    from fsrlab.virtual.twin.process import elf_path

    assert twin_available() == (True, "") and elf_path() == folder / "fsrlab_meter.hex"
    with Twin(speed="max") as twin, SerialLink(twin.port) as link:
        ident = link.handshake()
    info = firmware.firmware_info()
    assert (ident.name, ident.firmware_version, ident.protocol_version) == ("fsrlab-meter", info.version,
                                                                             info.protocol_version)


def test_without_a_compiler_one_line_names_what_to_install(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    folder, reason = build.build_harness()
    assert folder is None and "\n" not in reason
    assert "a C compiler" in reason and "apt-get install gcc simavr libsimavr-dev" in reason
    assert "FSRLAB_FIRMWARE_BUILD" in reason


def test_cache_root_follows_xdg_cache_home(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert build.cache_root() == tmp_path / "fsrlab"
    monkeypatch.setenv("XDG_CACHE_HOME", "")
    assert build.cache_root() == Path.home() / ".cache" / "fsrlab"


def test_twin_available_is_false_in_an_if_when_the_twin_cannot_run(tmp_path, monkeypatch):
    # Reference: twin_available's contract (False with a one-line reason when the harness is missing; True
    # when it answers its usage with exit code 2). A plain (False, reason) tuple is true in an if.
    from fsrlab.virtual.twin import twin_available

    monkeypatch.setenv("FSRLAB_FIRMWARE_BUILD", str(tmp_path))
    answer = twin_available()
    assert not answer and bool(answer) is False
    ok, reason = answer
    assert ok is False and "fsrlab_twin is missing" in reason and "\n" not in reason
    # A harness that answers as the real one does (usage on stderr, exit 2) beside a firmware image.
    harness = tmp_path / "fsrlab_twin"
    harness.write_text("#!/bin/sh\necho 'usage: fsrlab_twin FIRMWARE' >&2\nexit 2\n")
    harness.chmod(0o755)
    (tmp_path / "fsrlab_meter.elf").write_bytes(b"\x7fELF")
    answer = twin_available()
    assert answer and answer == (True, "")
