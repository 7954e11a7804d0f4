"""The analog multiplexer on the 555's timing node: eight FSRs on one meter (a CD74HC4051).

One LM555 and its C_off switch as in the paper's Fig. 16; a CD74HC4051 (8:1) connects one FSR at a
time between the timing node and its return. The switch adds its on-resistance in series with the
FSR and the capacitance of its common node (and of the selected input) in parallel with it. The
meter's firmware selects the channel (S0..S2 on D5..D7) and discards the edges that follow a switch
(docs/multiplexing.md, docs/protocol.md ``SCAN``/``DWELL``/``SETTLE``).

The timing network with the switch is lumped into the single-capacitor astable of
:mod:`fsrlab.circuits.lm555`: the capacitor is ``C_FSR + C_node`` and both resistances it charges and
discharges through gain ``R_on`` (:func:`mux_parts`, :meth:`Multiplexer.timing_circuit`). That places
C_node behind R_on too, an error of order ``R_on/R · C_node/C`` (≈ 1e-3 with the datasheet's values);
a per-channel calibration absorbs the rest.

After a switch the FSR just connected brings its own voltage: while it was disconnected its
capacitance discharged through its own resistance (:func:`disconnected_voltage`), and on reconnection
it shares its charge with the node (:func:`shared_voltage`).

References
----------
.. [1] Texas Instruments, CD74HC4051 datasheet (SCHS122): R_on 70–180 Ω at 4.5 V, ΔR_on 9 Ω between
   channels, C_I 5 pF per input, C_COM 25–130 pF (switch off/on), charge injection of a few pC.
.. [2] Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5 ("high-speed multiplexing").
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_at_least, check_finite, float_array

__all__ = ["Multiplexer", "CD74HC4051", "mux_parts", "disconnected_voltage", "shared_voltage"]


@dataclass(frozen=True)
class Multiplexer:
    """An analog multiplexer between the 555's timing node and the FSRs.

    Parameters
    ----------
    r_on_ohm : float
        On-resistance of the closed switch (≥ 0). [Ω]
    c_node_farad : float
        Capacitance the timing node gains: the common node's plus the selected input's (≥ 0). [F]
    channels : int
        Inputs of the switch (1..8).
    """

    r_on_ohm: float = 125.0
    c_node_farad: float = 55e-12
    channels: int = 8

    def __post_init__(self) -> None:
        for name in ("r_on_ohm", "c_node_farad"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ParameterError(f"must be a finite number >= 0, got {v!r}", parameter=name)
        if isinstance(self.channels, bool) or not isinstance(self.channels, int) or not 1 <= self.channels <= 8:
            raise ParameterError(f"must be an integer 1..8, got {self.channels!r}", parameter="channels")

    def timing_circuit(self, circuit):
        """The 555 circuit whose charging resistance includes the switch: ``R + R_on``.

        Parameters
        ----------
        circuit : LM555Circuit
            The circuit the switch feeds.

        Returns
        -------
        LM555Circuit
        """
        from fsrlab.circuits.circuit import LM555Circuit

        if not isinstance(circuit, LM555Circuit):
            raise TypeError(f"circuit: must be an LM555Circuit, got {type(circuit).__name__}")
        return circuit.replace(r_ohm=circuit.r_ohm + self.r_on_ohm)

    def to_dict(self) -> dict:
        """``{"r_on_ohm", "c_node_farad", "channels"}`` (SI), as a run's sidecar keeps it."""
        return asdict(self)


CD74HC4051 = Multiplexer()
"""The CD74HC4051 at 5 V: R_on 125 Ω (the middle of the datasheet's 70–180 Ω), 50 pF on the common node
(25–130 pF) plus the selected input's 5 pF."""


def mux_parts(r_fsr_ohm, c_fsr_farad, mux: Multiplexer = CD74HC4051):
    """The FSR as the timing node sees it through the closed switch.

    Parameters
    ----------
    r_fsr_ohm : float or array_like
        FSR resistance. [Ω]
    c_fsr_farad : float or array_like
        FSR capacitance. [F]
    mux : Multiplexer
        The switch.

    Returns
    -------
    (r_ohm, c_farad) : ndarrays
        ``R_FSR + R_on`` [Ω] and ``C_FSR + C_node`` [F] (lumped, see the module's notes).
    """
    if not isinstance(mux, Multiplexer):
        raise TypeError(f"mux: must be a Multiplexer, got {type(mux).__name__}")
    r = float_array("r_fsr_ohm", r_fsr_ohm) + mux.r_on_ohm
    c = float_array("c_fsr_farad", c_fsr_farad) + mux.c_node_farad
    return r, c


def disconnected_voltage(v0_v, off_s, r_fsr_ohm, c_fsr_farad):
    """Voltage of an FSR's capacitance after ``off_s`` disconnected: its own R_FSR·C_FSR decay.

    Parameters
    ----------
    v0_v : float or array_like
        Voltage when the switch opened. [V]
    off_s : float or array_like
        Time since (≥ 0). [s]
    r_fsr_ohm, c_fsr_farad : float or array_like
        The FSR's resistance [Ω] and capacitance [F] meanwhile (held constant).

    Returns
    -------
    ndarray
        ``v0 · exp(−t / (R_FSR·C_FSR))``. [V]
    """
    off = float_array("off_s", off_s)
    if np.any(np.isnan(off) | (off < 0)):
        raise ParameterError(f"must be >= 0 s, got {off_s!r}", parameter="off_s")
    tau = float_array("r_fsr_ohm", r_fsr_ohm) * float_array("c_fsr_farad", c_fsr_farad)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(tau > 0, off / tau, np.inf)
    return float_array("v0_v", v0_v) * np.exp(-x)


def shared_voltage(v_node_v, c_node_farad, v_fsr_v, c_fsr_farad):
    """Node voltage right after an FSR is connected to it: charge conservation.

    Parameters
    ----------
    v_node_v : float
        Voltage of the node (and what stays connected to it, C_off) just before. [V]
    c_node_farad : float
        Capacitance that stays on the node. [F]
    v_fsr_v : float
        Voltage of the FSR being connected. [V]
    c_fsr_farad : float
        Its capacitance. [F]

    Returns
    -------
    float
        ``(C_node·V_node + C_FSR·V_FSR) / (C_node + C_FSR)``. [V]
    """
    check_finite("v_node_v", v_node_v, scalar=True)
    check_at_least("c_node_farad", c_node_farad, 0.0, "F", scalar=True)
    check_finite("v_fsr_v", v_fsr_v, scalar=True)
    check_at_least("c_fsr_farad", c_fsr_farad, 0.0, "F", scalar=True)
    total = c_node_farad + c_fsr_farad
    if not np.all(total > 0):
        raise ParameterError("c_node_farad + c_fsr_farad must be > 0 F", parameter="c_fsr_farad")
    return float((c_node_farad * v_node_v + c_fsr_farad * v_fsr_v) / total)
