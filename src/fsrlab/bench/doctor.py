"""What this machine has for fsrlab, and what each thing enables (``fsrlab doctor``).

Every check is a :class:`Check`: what was looked for, whether it was found (and where, which
version), which commands need it, and the command that installs it. The install commands are
Debian's (``apt-get``), which ``make sysdeps`` runs in a clone. A board on a serial port is asked
``ID`` (:func:`probe_board`); opening an Uno's port restarts it, so only the ports asked for, or
those with an Uno's USB id, are opened.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import asdict, dataclass
from pathlib import Path

__all__ = ["Check", "BoardCheck", "Diagnosis", "check_tools", "probe_board", "diagnose"]


@dataclass(frozen=True)
class Check:
    """One thing fsrlab can use.

    Attributes
    ----------
    name : str
        What was looked for (``ngspice``, ``avrdude``, ``simavr``, ...).
    found : bool
        Whether it is usable here.
    detail : str
        Where it was found and its version, or what is missing.
    enables : str
        The commands or checks that need it.
    install : str or None
        The command that installs it (None when found).
    """

    name: str
    found: bool
    detail: str
    enables: str
    install: str | None


@dataclass(frozen=True)
class BoardCheck:
    """A serial port asked ``ID``.

    Attributes
    ----------
    port : str
        The port.
    ok : bool
        It answered as an fsrlab meter in a protocol this fsrlab reads.
    firmware_version, protocol_version : str or None, int or None
        What it answered.
    matches_package : bool
        Its firmware and protocol are those the package ships (``fsrlab firmware flash`` writes).
    detail : str
        The answer in words, or why there was none.
    """

    port: str
    ok: bool
    firmware_version: str | None
    protocol_version: int | None
    matches_package: bool
    detail: str


@dataclass(frozen=True)
class Diagnosis:
    """The machine's tools and the boards asked.

    Attributes
    ----------
    checks : list of Check
    boards : list of BoardCheck
    """

    checks: list[Check]
    boards: list[BoardCheck]

    def to_dict(self) -> dict:
        """Plain types for JSON."""
        return {"checks": [asdict(c) for c in self.checks], "boards": [asdict(b) for b in self.boards]}


def _version(cmd: list[str], key: str) -> str:
    """The first output line of ``cmd`` (a version flag) that contains ``key``, or ``""``."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, errors="replace", timeout=20,
                              stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return ""
    for line in (proc.stdout + "\n" + proc.stderr).splitlines():
        line = line.strip(" *")
        if key in line.lower():
            return line.split(", URL")[0].split(" : ")[0]
    return ""


def _which(*names: str) -> str | None:
    for name in names:
        path = shutil.which(name)
        if path:
            return path
    return None


def _tool(name: str, names: tuple[str, ...], version_args: list[str], enables: str, install: str,
          key: str | None = None) -> Check:
    path = _which(*names)
    if path is None:
        return Check(name, False, f"not on the PATH (looked for {', '.join(names)})", enables, install)
    version = _version([path, *version_args], key or name) if version_args else ""
    return Check(name, True, f"{path}" + (f" ({version})" if version else ""), enables, None)


def check_tools() -> list[Check]:
    """The external programs and libraries fsrlab uses, each checked.

    Returns
    -------
    list of Check
        ngspice, the twin (C compiler, simavr's headers and library, the harness), avrdude, the AVR
        toolchain with the Arduino core (building the firmware), Chromium and its WebDriver.
    """
    from fsrlab.virtual.twin import build

    checks = [_tool("ngspice", ("ngspice",), ["--version"], "--spice (the circuit commands' independent check) and the "
                    "reproduction report's ngspice comparisons", "sudo apt-get install ngspice")]

    cc, include = build.compiler(), build.simavr_include()
    checks.append(Check("C compiler", cc is not None, cc or "none of $CC, cc, gcc, clang on the PATH",
                        "building the digital twin's harness on first use (fsrlab twin, bench --twin)",
                        None if cc else "sudo apt-get install gcc"))
    checks.append(Check("simavr headers", include is not None,
                        str(include) if include else "sim_avr.h not found (/usr/include/simavr, "
                                "/usr/local/include/simavr)",
                        "the digital twin (fsrlab twin, bench --twin, demo with the real firmware)",
                        None if include else "sudo apt-get install simavr libsimavr-dev"))
    from fsrlab.virtual.twin import twin_available
    from fsrlab.virtual.twin.process import build_dir

    ok, reason = twin_available()
    checks.append(Check("digital twin", ok, f"harness in {build_dir()}" if ok else reason,
                        "fsrlab twin, bench --twin; the demo runs the real firmware instead of the Python device",
                        None if ok else f"{build.INSTALL_HINT}; in a clone: make sysdeps && make firmware"))

    checks.append(_tool("avrdude", ("avrdude",), ["-?"],
                        "fsrlab firmware flash (writing the meter's firmware to an Uno)",
                        "sudo apt-get install avrdude", key="version"))
    avr_gcc = _which("avr-gcc")

    core = Path("/usr/share/arduino/hardware/arduino/avr/cores/arduino/Arduino.h").exists()
    checks.append(Check("AVR toolchain", bool(avr_gcc and core),
                        f"{avr_gcc}, Arduino core "
                        f"{'found' if core else 'missing'}" if avr_gcc else "avr-gcc not on the PATH",
                        "building the firmware from source (make firmware; the package ships the built image)",
                        None if avr_gcc and core else "sudo apt-get install gcc-avr avr-libc arduino-core-avr"))
    browser = _which("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
    driver = _which("chromedriver")
    checks.append(Check("Chromium and chromedriver", bool(browser and driver),
                        ", ".join(x for x in (browser, driver) if x) or "neither on the PATH",
                        "the live page's browser tests and its screenshot (make live-screenshot); "
                        "fsrlab live itself works with any browser",
                        None if browser and driver else "sudo apt-get install chromium chromium-driver"))
    return checks


def probe_board(port: str, timeout_s: float = 3.0) -> BoardCheck:
    """Ask the device on ``port`` who it is.

    Parameters
    ----------
    port : str
        A device path or pyserial URL.
    timeout_s : float
        How long to wait for the answer (an Uno restarts when its port opens, ~2 s). [s]

    Returns
    -------
    BoardCheck
        Never raises for a device that does not answer: ``ok`` is False and ``detail`` says why.
    """
    from fsrlab.acquisition.firmware import firmware_info
    from fsrlab.acquisition.serial_link import LinkError, SerialLink

    info = firmware_info()
    try:
        with SerialLink(port) as link:
            ident = link.handshake(timeout_s=timeout_s)
    except (LinkError, OSError, ValueError) as exc:
        # The reason without the parameter's name: the detail is read next to the port already.
        return BoardCheck(port, False, None, None, False, getattr(exc, "reason", str(exc)))
    same = (ident.firmware_version, ident.protocol_version) == (info.version, info.protocol_version)
    detail = (f"{ident.name} firmware {ident.firmware_version}, protocol {ident.protocol_version}"
              + ("" if same else f"; the package ships {info.version} (protocol {info.protocol_version}): "
                 f"fsrlab firmware flash --port {port}"))
    return BoardCheck(port, True, ident.firmware_version, ident.protocol_version, same, detail)


def diagnose(ports: list[str] | None = None, probe: bool = True) -> Diagnosis:
    """All the checks, and the boards asked ``ID``.

    Parameters
    ----------
    ports : list of str, optional
        Ports to ask; by default those with an Uno's USB id (:func:`fsrlab.acquisition.ports.list_serial_ports`).
    probe : bool
        Ask boards at all (False: no port is opened).
    """
    boards: list[BoardCheck] = []
    if probe:
        if ports is None:
            from fsrlab.acquisition.ports import list_serial_ports

            ports = [p.device for p in list_serial_ports() if p.board]
        boards = [probe_board(p) for p in ports]
    return Diagnosis(check_tools(), boards)
