"""The serial ports of this machine and what is known about each (``fsrlab ports``).

pyserial lists the ports (``serial.tools.list_ports.comports``); a port whose USB vendor:product id
is in :data:`~fsrlab.acquisition.serial_link.UNO_USB_IDS` (Arduino's Unos, CH340 clones) is taken
for an Uno, which is what ``--port auto`` picks (:func:`~fsrlab.acquisition.serial_link.find_uno`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from fsrlab.acquisition.serial_link import UNO_USB_IDS, UsbPort, find_uno

__all__ = ["PortInfo", "list_serial_ports", "resolve_port"]


@dataclass(frozen=True)
class PortInfo:
    """One serial port.

    Attributes
    ----------
    device : str
        Its path or name (``/dev/ttyACM0``, ``COM3``).
    vid, pid : int or None
        USB vendor and product id (None for a port that is not USB).
    description, manufacturer, serial_number : str or None
        What the operating system reports.
    board : str or None
        The board its USB id stands for (``Arduino Uno R3``, ``CH340 USB-serial (Uno clone)``), or
        None: not a board ``--port auto`` would pick.
    """

    device: str
    vid: int | None
    pid: int | None
    description: str | None
    manufacturer: str | None
    serial_number: str | None
    board: str | None

    @property
    def usb_id(self) -> str | None:
        """``VVVV:PPPP`` in hexadecimal, or None."""
        return f"{self.vid:04X}:{self.pid:04X}" if self.vid is not None and self.pid is not None else None

    def to_dict(self) -> dict:
        """The fields and ``usb_id``, for JSON."""
        return {**asdict(self), "usb_id": self.usb_id}


def list_serial_ports(ports=None) -> list[PortInfo]:
    """The serial ports pyserial sees, sorted by device name.

    Parameters
    ----------
    ports : iterable, optional
        Objects with pyserial's ``ListPortInfo`` attributes (``device``, ``vid``, ``pid``,
        ``description``, ``manufacturer``, ``serial_number``); by default ``comports()``.
    """
    if ports is None:
        from serial.tools import list_ports

        ports = list_ports.comports()
    out = []
    for p in ports:
        desc = getattr(p, "description", None)
        out.append(PortInfo(
            device=p.device, vid=p.vid, pid=p.pid,
            description=None if desc in (None, "", "n/a") else desc,
            manufacturer=getattr(p, "manufacturer", None),
            serial_number=getattr(p, "serial_number", None),
            board=UNO_USB_IDS.get((p.vid, p.pid)),
        ))
    return sorted(out, key=lambda p: p.device)


def resolve_port(port: str, ports: list[PortInfo] | None = None) -> str:
    """``port`` itself, or for ``auto`` the device of the one Uno connected.

    Parameters
    ----------
    port : str
        A device path, a pyserial URL, or ``auto``.
    ports : list of PortInfo, optional
        Ports to choose from (by default those connected).

    Raises
    ------
    LinkError
        ``auto`` and no Uno, or several (the message lists the candidates).
    """
    if port != "auto":
        return port
    usb = None if ports is None else [UsbPort(p.device, p.vid, p.pid, p.description or "") for p in ports]
    return find_uno(usb)
