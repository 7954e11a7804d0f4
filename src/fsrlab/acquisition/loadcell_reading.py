"""Reading the load cell through the meter for a while: the readings behind ``fsrlab loadcell tare`` and ``scale``.

:func:`read_reference` starts the meter, collects the load cell's window means (``ref_mean``,
``ref_n`` of each ``M`` frame) for a while and stops it.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass

import numpy as np

from fsrlab.acquisition.messages import Measurement
from fsrlab.acquisition.protocol import SEQ_MODULO
from fsrlab.errors import FsrlabError

__all__ = ["ReferenceReadings", "read_reference", "NoLoadCell"]


class NoLoadCell(FsrlabError, RuntimeError):
    """The meter has no load cell to read (protocol version 1, or ``ref_ok`` 0); the message says which.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


@dataclass(frozen=True)
class ReferenceReadings:
    """The load cell's readings over a while.

    Attributes
    ----------
    means : ndarray
        Window means of the windows with at least one conversion. [count]
    conversions : int
        HX711 conversions in those windows.
    windows : int
        Windows received (with or without a conversion).
    """

    means: np.ndarray
    conversions: int
    windows: int


def read_reference(link, duration_s: float, window_ms: int = 100, stop: threading.Event | None = None,
                   handshake_timeout_s: float = 3.0) -> ReferenceReadings:
    """Start the meter, collect the load cell's window means for ``duration_s`` and stop it.

    Parameters
    ----------
    link : SerialLink
        An open link.
    duration_s : float
        Reading time (> 0). [s]
    window_ms : int
        Measurement window. [ms]
    stop : threading.Event, optional
        Ends the reading early.
    handshake_timeout_s : float
        Longest wait for the device's identification. [s]

    Returns
    -------
    ReferenceReadings

    Raises
    ------
    NoLoadCell
        A protocol-1 device, or one reporting no HX711 (``ref_ok`` 0) in every window.
    LinkError
        The device does not answer.
    """
    ident = link.handshake(timeout_s=handshake_timeout_s)
    if ident.protocol_version < 2:
        raise NoLoadCell(f"the meter speaks protocol version {ident.protocol_version}, which has no load-cell "
                         "reference: update its firmware (docs/protocol.md, version 2)")
    link.stop()
    link.set_window(window_ms)
    first = (link.start().seq + 1) % SEQ_MODULO  # noqa: F841 - frames before START are discarded by start()
    means, conversions, windows, ok = [], 0, 0, 0
    end = time.monotonic() + duration_s
    try:
        while time.monotonic() < end and not (stop is not None and stop.is_set()):
            for frame in link.read_frames():
                if frame.kind != "M":
                    continue
                m = Measurement.from_frame(frame)
                windows += 1
                ok += int(bool(m.ref_ok))
                if m.ref_n > 0:
                    means.append(m.ref_mean)
                    conversions += m.ref_n
    finally:
        try:
            link.stop()
        except OSError:
            pass
    if windows and not ok:
        raise NoLoadCell("the meter reports no HX711 (ref_ok 0 in every window): check the load cell's board "
                         "(DOUT to D2, SCK to D3, VCC to 5 V, GND)")
    return ReferenceReadings(np.asarray(means, dtype=float), conversions, windows)
