"""The serial link to an fsrlab meter: pyserial moves the bytes, :mod:`.protocol` frames them.

:class:`SerialLink` opens any port pyserial can (``/dev/ttyACM0``, ``COM3``, a pseudo-terminal of
the virtual device, ``loop://``) through ``serial.serial_for_url``, identifies the device (``ID`` →
protocol version check) and sends commands, waiting for their ``ACK``. :func:`find_uno` finds an
Arduino Uno by its USB identity for ``--port auto``.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass

import serial
from serial.tools import list_ports

from fsrlab.acquisition.messages import Ack, DeviceError, Identity
from fsrlab.acquisition.protocol import (
    DEFAULT_BAUD,
    DEVICE_NAME,
    SUPPORTED_PROTOCOLS,
    Frame,
    FrameParser,
    encode_command,
)
from fsrlab.errors import FsrlabError, ParameterError

__all__ = ["UNO_USB_IDS", "LinkError", "DeviceGone", "HandshakeError", "CommandRejected", "UsbPort",
           "find_uno", "SerialLink"]

UNO_USB_IDS: dict[tuple[int, int], str] = {
    (0x2341, 0x0043): "Arduino Uno R3",
    (0x2341, 0x0001): "Arduino Uno",
    (0x2A03, 0x0043): "Arduino Uno R3 (arduino.org)",
    (0x1A86, 0x7523): "CH340 USB-serial (Uno clone)",
}
"""USB vendor:product identities taken as an Uno for ``--port auto``."""


class LinkError(FsrlabError, OSError):
    """The serial link cannot be used (port missing, busy, no answer).

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


class DeviceGone(LinkError):
    """The device disappeared during use (unplugged, or the pseudo-terminal closed).

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


class HandshakeError(LinkError):
    """The device did not identify itself as an fsrlab meter speaking this protocol version.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


class CommandRejected(LinkError):
    """The device answered a command with ``$ERR``.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


@dataclass(frozen=True)
class UsbPort:
    """A serial port with its USB identity.

    Attributes
    ----------
    device : str
        Path or name of the port (``/dev/ttyACM0``, ``COM3``).
    vid, pid : int or None
        USB vendor and product id (None for a port that is not USB).
    description : str
        What the operating system calls it.
    """

    device: str
    vid: int | None
    pid: int | None
    description: str

    def __str__(self) -> str:
        ident = f"{self.vid:04X}:{self.pid:04X}" if self.vid is not None and self.pid is not None else "no USB id"
        described = self.description and self.description != "n/a"
        return f"{self.device} ({ident}, {self.description})" if described else f"{self.device} ({ident})"


def _ports() -> list[UsbPort]:
    return [UsbPort(p.device, p.vid, p.pid, p.description or "") for p in list_ports.comports()]


def find_uno(ports: list[UsbPort] | None = None) -> str:
    """The device path of the one Arduino Uno connected, found by USB vendor:product id.

    Parameters
    ----------
    ports : list of UsbPort, optional
        Ports to choose from; by default those ``serial.tools.list_ports.comports()`` reports.

    Returns
    -------
    str
        E.g. ``/dev/ttyACM0``.

    Raises
    ------
    LinkError
        When no port or more than one port has an Uno identity (:data:`UNO_USB_IDS`); the message
        lists what was found.
    """
    ports = _ports() if ports is None else list(ports)
    matches = [p for p in ports if (p.vid, p.pid) in UNO_USB_IDS]
    wanted = ", ".join(f"{v:04X}:{p:04X}" for v, p in UNO_USB_IDS)
    if not matches:
        seen = "; ".join(str(p) for p in ports) or "none"
        raise LinkError(f"auto found no Arduino Uno (USB ids {wanted}); serial ports present: {seen}", parameter="port")
    if len(matches) > 1:
        raise LinkError("auto found several Uno-like devices, choose one: " + "; ".join(str(p) for p in matches),
                        parameter="port")
    return matches[0].device


class SerialLink:
    """A connection to an fsrlab meter.

    Parameters
    ----------
    port : str
        A device path or pyserial URL (``/dev/ttyACM0``, ``/dev/pts/5``, ``loop://``), or ``auto``
        to use :func:`find_uno`.
    baud : int
        Line rate, 115200 by default (protocol v1). [bit/s]
    read_timeout_s : float
        Longest time one :meth:`read_frames` call waits for the first byte. [s]

    Raises
    ------
    LinkError
        When the port cannot be opened (the message names the port).

    Notes
    -----
    All frames pass through one :class:`~fsrlab.acquisition.protocol.FrameParser` (``self.parser``),
    whose counters describe the whole session. Frames that arrive while a command waits for its
    answer are kept and returned by the next :meth:`read_frames`, so no measurement is lost.
    """

    def __init__(self, port: str, baud: int = DEFAULT_BAUD, read_timeout_s: float = 0.05) -> None:
        if not baud > 0:
            raise ParameterError(f"must be > 0, got {baud!r}", parameter="baud")
        if not read_timeout_s >= 0:
            raise ParameterError(f"must be >= 0 s, got {read_timeout_s!r}", parameter="read_timeout_s")
        self.port = find_uno() if port == "auto" else str(port)
        self.baud = int(baud)
        try:
            self.serial = serial.serial_for_url(self.port, baudrate=self.baud, timeout=read_timeout_s,
                                                write_timeout=2.0)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise LinkError(f"cannot open {self.port}: {exc}", parameter="port") from None
        self.parser = FrameParser()
        self.identity: Identity | None = None
        self._backlog: deque[Frame] = deque()

    # -------------------------------------------------------------- bytes
    def _read_bytes(self) -> bytes:
        try:
            waiting = self.serial.in_waiting
            return self.serial.read(max(1, min(waiting, 65536)))
        except (serial.SerialException, OSError) as exc:
            raise DeviceGone(f"device on {self.port} disconnected ({exc})") from None

    def send(self, line: bytes) -> None:
        """Write one command line (see :func:`~fsrlab.acquisition.protocol.encode_command`)."""
        try:
            self.serial.write(line)
            self.serial.flush()
        except (serial.SerialException, OSError) as exc:
            raise DeviceGone(f"device on {self.port} disconnected ({exc})") from None

    # -------------------------------------------------------------- frames
    def read_frames(self) -> list[Frame]:
        """Frames kept while waiting for answers, then those that arrive within the read timeout.

        Raises
        ------
        DeviceGone
            When the port reports an error or end of file (device unplugged, pty closed).
        """
        if self._backlog:
            out = list(self._backlog)
            self._backlog.clear()
            return out
        return self.parser.feed(self._read_bytes())

    def _wait_for(self, match, timeout_s: float, discard_earlier: bool = False) -> Frame | None:
        """Read until ``match(frame)`` is true; keep every other frame in the backlog, in order.

        With ``discard_earlier`` the frames received before the match (and the backlog) are
        dropped instead; frames that arrived after the match in the same read are always kept.
        """
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            frames = self.parser.feed(self._read_bytes())
            for i, frame in enumerate(frames):
                if match(frame):
                    if discard_earlier:
                        self._backlog.clear()
                    self._backlog.extend(frames[i + 1:])
                    return frame
                if not discard_earlier:
                    self._backlog.append(frame)
        return None

    def handshake(self, timeout_s: float = 3.0, retry_s: float = 0.5) -> Identity:
        """Ask the device who it is and check the protocol version.

        Sends ``ID`` every ``retry_s`` seconds (an Uno restarts when its port opens and is deaf
        for up to ~2 s) until an ``ID`` frame arrives or ``timeout_s`` passes.

        Returns
        -------
        Identity

        Raises
        ------
        HandshakeError
            No answer (the message says whether anything arrived, which hints at the baud rate),
            another device, or another protocol version.
        """
        deadline = time.monotonic() + timeout_s
        frame = None
        while frame is None and time.monotonic() < deadline:
            self.send(encode_command("ID"))
            frame = self._wait_for(lambda f: f.kind == "ID", min(retry_s, max(deadline - time.monotonic(), 0)))
        if frame is None:
            st = self.parser.stats()
            if st.frames == 0 and (st.garbage_bytes or st.bad_frames):
                hint = (f"received {st.bytes_in} bytes but no valid frame ({st.bad_frames} bad lines): "
                        f"check the baud rate (protocol v1: {DEFAULT_BAUD})")
            elif st.frames:
                hint = f"received {st.frames} frames but no ID answer"
            else:
                hint = "received nothing: is the fsrlab firmware flashed and the port right?"
            raise HandshakeError(f"no identification from {self.port} within {timeout_s:g} s; {hint}")
        ident = Identity.from_frame(frame)
        if ident.name != DEVICE_NAME:
            raise HandshakeError(f"{self.port} is {ident.name!r}, not an {DEVICE_NAME}")
        if ident.protocol_version not in SUPPORTED_PROTOCOLS:
            raise HandshakeError(f"{self.port} speaks protocol version {ident.protocol_version}; "
                                 f"this fsrlab reads versions {', '.join(map(str, SUPPORTED_PROTOCOLS))}")
        self.identity = ident
        return ident

    def command(self, name: str, value: int | None = None, timeout_s: float = 1.0,
                discard_earlier: bool = False) -> Ack:
        """Send a command and wait for its ``ACK``.

        Parameters
        ----------
        name : str
            ``START``, ``STOP``, ``WINDOW`` or ``RANGE`` (``ID``: use :meth:`handshake`).
        value : int, optional
            Window [ms] or range.
        timeout_s : float
            Longest wait for the answer. [s]
        discard_earlier : bool
            Drop every frame received before the answer instead of keeping it for
            :meth:`read_frames` (used with ``START``: windows from before it are stale).

        Returns
        -------
        Ack

        Raises
        ------
        ValueError
            For a command or value protocol v1 does not allow (nothing is sent).
        CommandRejected
            The device answered ``$ERR``.
        LinkError
            No answer within ``timeout_s``.
        """
        line = encode_command(name, value)
        key = name.upper()
        self.send(line)
        frame = self._wait_for(lambda f: (f.kind == "ACK" and f.fields[0] == key) or f.kind == "ERR", timeout_s,
                               discard_earlier)
        if frame is None:
            raise LinkError(f"{self.port}: no answer to {line.decode().strip()!r} within {timeout_s:g} s")
        if frame.kind == "ERR":
            err = DeviceError.from_frame(frame)
            raise CommandRejected(f"{self.port} rejected {line.decode().strip()!r}: error {err.code} ({err.token})")
        return Ack.from_frame(frame)

    def start(self, discard_earlier: bool = True) -> Ack:
        """``START``: begin measuring windows.

        Parameters
        ----------
        discard_earlier : bool
            Drop frames received before the ``ACK`` (windows of an earlier run), by default.
        """
        return self.command("START", discard_earlier=discard_earlier)

    def stop(self) -> Ack:
        """``STOP``: stop measuring."""
        return self.command("STOP")

    def set_window(self, window_ms: int) -> Ack:
        """``WINDOW <ms>``: window length, 10..60000 ms."""
        return self.command("WINDOW", window_ms)

    def set_range(self, range_: int) -> Ack:
        """``RANGE <0|1>``: connect (1) or disconnect (0) C_off."""
        return self.command("RANGE", range_)

    def close(self) -> None:
        """Close the port (never raises)."""
        try:
            self.serial.close()
        except Exception:  # noqa: BLE001 - closing an unplugged port may fail; nothing to do
            pass

    def __enter__(self) -> SerialLink:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
