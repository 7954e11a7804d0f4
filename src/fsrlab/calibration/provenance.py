"""What a calibration was recorded with, and whether another run was recorded the same way.

A calibration maps one readout to stress for one readout circuit: the frequency of an LM555 with
R = 10 kΩ says nothing about the stress under R = 4.7 kΩ, and range 1 (C_off switched in) lowers
every frequency. A calibration therefore records the circuits of the run it was fitted on and the
ranges its readings were taken on (:class:`fsrlab.io.recorded.RecordedWith`), and :func:`mismatches` tells what
differs in a run it is applied to. Which differences matter depends on the readout:

=================================  ===========================================================
``frequency_hz``, ``duty_cycle``   the LM555 circuit on each range the run uses (``c_off_farad``
                                   counts only where ``range`` is 1); where a circuit is unknown,
                                   the ranges themselves
``c_fsr_farad`` (decoded)          the LM555 circuit only (the recorded one, else the one decoded
                                   through): each reading is decoded on its own range, and C_FSR
                                   does not depend on the circuit
``voltage_v``                      the op-amp readout (R_F and its drive voltage)
any other column                   nothing
=================================  ===========================================================

A part that one side does not know (a run without a sidecar, a calibration file written before
fsrlab recorded this) is not compared.
"""

from __future__ import annotations

import numpy as np

from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.io.recorded import RecordedWith
from fsrlab.io.runformat import C_FSR

__all__ = ["mismatches", "describe_range"]

# How the parts are named and shown in messages (the sidecar's names are for files).
_PARTS = {"r_ohm": ("R", "Ω"), "c_off_farad": ("C_off", "F"), "diode": ("D1", None),
          "diode_drop_v": ("D1's drop", "V"), "vcc_v": ("Vcc", "V"), "lower_fraction": ("lower threshold", "·Vcc"),
          "upper_fraction": ("upper threshold", "·Vcc"), "discharge_ohm": ("discharge resistance", "Ω"),
          "r_f_ohm": ("R_F", "Ω")}
_OPAMP_PARTS = {"vcc_v": ("the op-amp's drive", "V")}


def same_unit(a: str, b: str) -> bool:
    """Whether two readout units name the same unit, or either is unknown (empty): ``count`` and ``counts``,
    ``V`` and ``v`` are one.

    Parameters
    ----------
    a, b : str
        The units, as run files and calibrations write them.
    """
    def norm(u: str) -> str:
        u = str(u or "").strip().lower()
        return {"counts": "count", "ohms": "ohm", "ω": "ohm", "Ω": "ohm"}.get(u, u)

    return not norm(a) or not norm(b) or norm(a) == norm(b)


def describe_range(ranges: tuple[int, ...]) -> str:
    """``"range 1 (C_off in)"``, ``"ranges 0 and 1"``: the ranges as a user reads them.

    Parameters
    ----------
    ranges : tuple of int
        Values of a ``range`` column.

    Returns
    -------
    str
    """
    if isinstance(ranges, (str, bytes)) or not hasattr(ranges, "__len__") or \
            not all(isinstance(r, (int, np.integer)) and not isinstance(r, bool) for r in ranges):
        raise TypeError(f"ranges: must be a tuple of range values (0, 1), got {ranges!r}")
    if not ranges:
        return "no range"
    if len(ranges) == 1:
        return f"range {ranges[0]} ({'C_off in' if ranges[0] else 'C_off out'})"
    return "ranges " + " and ".join(str(r) for r in ranges)


def _part(key: str, value, names: dict) -> str:
    from fsrlab.units import format_eng

    label, unit = names.get(key, _PARTS.get(key, (key, "")))
    if unit is None:
        return f"{label} {'yes' if value else 'no'}"
    if unit.startswith("·"):
        return f"{label} = {value:.6g}{unit}"
    return f"{label} = {format_eng(value, unit, digits=6)}"


def _difference(a, b, names: dict | None = None) -> tuple[str, str]:
    """The parts in which two circuits differ, as ``("R = 4.7 kΩ", "R = 10 kΩ")``."""
    from dataclasses import asdict

    da, db = asdict(a), asdict(b)
    keys = [k for k in da if da[k] != db[k]]
    return (", ".join(_part(k, da[k], names or {}) for k in keys),
            ", ".join(_part(k, db[k], names or {}) for k in keys))


def mismatches(x: str, calibration: RecordedWith, run: RecordedWith,
               decode_circuit: LM555Circuit | None = None) -> list[tuple[str, str]]:
    """How a run's readout differs from the one a calibration was recorded with.

    Parameters
    ----------
    x : str
        The calibration's readout (``frequency_hz``, ``duty_cycle``, ``c_fsr_farad``, ``voltage_v``, ...).
    calibration : RecordedWith
        What the calibration's data were recorded with.
    run : RecordedWith
        The run's (:meth:`fsrlab.io.runformat.Run.recorded_with`).
    decode_circuit : LM555Circuit, optional
        For ``x = "c_fsr_farad"``: the circuit C_FSR is decoded through, compared with the run's
        when the calibration does not know the circuit its run was recorded with.

    Returns
    -------
    list of (str, str)
        One ``(the run's, the calibration's)`` pair of descriptions per difference that changes
        the readout's meaning (see the module's table); empty when nothing that is known differs.
    """
    out: list[tuple[str, str]] = []
    if x == C_FSR:
        # Against the circuit the calibration run was recorded with: a part the user corrected
        # at calibration (--r) is corrected alike in a run recorded on the same bench.
        cal = calibration.circuit if calibration.circuit is not None else decode_circuit
        if cal is not None and run.circuit is not None and cal != run.circuit:
            out.append(_difference(run.circuit, cal))
    elif x in ("frequency_hz", "duty_cycle"):
        if run.circuit is not None and calibration.circuit is not None:
            # The circuit as the meter runs it on each range (C_off only where range is 1).
            on_cal = ([calibration.circuit.on_range(r) for r in calibration.ranges] if calibration.ranges
                      else [calibration.circuit])
            for r in run.ranges or (None,):
                circuit = run.circuit if r is None else run.circuit.on_range(r)
                if circuit not in on_cal:
                    a, b = _difference(circuit, on_cal[0])
                    out.append((("" if r is None else f"{describe_range((r,))}: ") + a,
                                (f"{describe_range(calibration.ranges)}: " if calibration.ranges else "") + b))
                    break
        elif (run.ranges is not None and calibration.ranges is not None
              and not set(run.ranges) <= set(calibration.ranges)):
            out.append((describe_range(run.ranges), describe_range(calibration.ranges)))
    elif x == "voltage_v":
        if run.opamp is not None and calibration.opamp is not None and run.opamp != calibration.opamp:
            out.append(_difference(run.opamp, calibration.opamp, _OPAMP_PARTS))
        elif (run.opamp is None) != (calibration.opamp is None):  # an op-amp's voltage is not a divider's
            out.append(tuple("the op-amp readout" if o is not None else "voltage_v without the op-amp readout"
                             for o in (run.opamp, calibration.opamp)))
    return out
