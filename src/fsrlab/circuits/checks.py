"""The one check of the LM555's parameters, shared by the circuit values and every model function.

:class:`~fsrlab.circuits.circuit.LM555Circuit` validates itself with :func:`check_lm555`; the model
functions of :mod:`fsrlab.circuits.lm555`, :mod:`fsrlab.circuits.phases`, :mod:`fsrlab.circuits.decode`,
:mod:`fsrlab.circuits.transient` and :mod:`fsrlab.circuits.spice` take the same parts as keywords (a design
sweep passes an array of R) and call the same check.
"""

from __future__ import annotations

import math
import sys

from fsrlab.errors import ParameterError

__all__ = ["check_lm555", "check_fractions", "check_fraction", "check_supply", "check_vcc", "check_drop", "check_r_fsr",
           "broadcast", "check_single",
           "VCC_MAX_V"]

def check_fractions(lower_fraction: float, upper_fraction: float) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` unless ``0 < lower_fraction < upper_fraction < 1``.

    Parameters
    ----------
    lower_fraction, upper_fraction : float
        Comparator thresholds as fractions of Vcc. [1]

    Raises
    ------
    ParameterError
        Naming ``lower_fraction`` when it is not a number in (0, 1), else ``upper_fraction``.
    """
    check_fraction("lower_fraction", lower_fraction)
    check_fraction("upper_fraction", upper_fraction)
    if not lower_fraction < upper_fraction:
        raise ParameterError(f"must be above lower_fraction ({lower_fraction!r}), got {upper_fraction!r}",
                             parameter="upper_fraction")


#: Largest supply the models accept: far beyond any 555 (LM555: 4.5–16 V; CMOS parts 2–18 V), and small
#: enough that thresholds and currents stay finite in double precision. [V]
VCC_MAX_V = 1000.0


def _finite(x) -> bool:
    """A finite number (a Python or numpy scalar; a str is not one)."""
    if isinstance(x, (str, bytes)):
        return False
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def _is_bool(x) -> bool:
    """True or False, Python's or numpy's (a numpy bool can only come from a numpy already imported)."""
    if isinstance(x, bool):
        return True
    np = sys.modules.get("numpy")
    return np is not None and isinstance(x, np.bool_)


def _all(value, ok, finite: bool = True) -> bool:
    """Every element of ``value`` (a number or an array) a number, finite (when ``finite``) and ``ok(element)``.

    Plain numbers are checked without numpy, so building a circuit of numbers (the paper's, at import)
    does not import it.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return not math.isnan(value) and (math.isfinite(value) or not finite) and bool(ok(value))
    import numpy as np

    if isinstance(value, (str, bytes)) or value is None:
        return False
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return bool(not np.any(np.isnan(v)) and (np.all(np.isfinite(v)) or not finite) and np.all(ok(v)))


def check_vcc(vcc_v: float) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` unless ``0 < vcc_v <= VCC_MAX_V``.

    Parameters
    ----------
    vcc_v : float
        Supply. [V]
    """
    if not (_finite(vcc_v) and 0 < vcc_v <= VCC_MAX_V):
        raise ParameterError(f"must be a supply voltage > 0 V and ≤ {VCC_MAX_V:g} V, got {vcc_v!r}", parameter="vcc_v")


def check_drop(diode_drop_v: float) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` unless ``diode_drop_v`` is a finite number ≥ 0.

    Parameters
    ----------
    diode_drop_v : float
        Forward drop of D1. [V]
    """
    if not (_finite(diode_drop_v) and diode_drop_v >= 0):
        raise ParameterError(f"must be a finite forward drop >= 0 V, got {diode_drop_v!r}", parameter="diode_drop_v")


def check_fraction(name: str, value: float) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` naming ``name`` unless ``0 < value < 1``.

    Parameters
    ----------
    name : str
        The parameter (``lower_fraction``, ``upper_fraction``).
    value : float
        A comparator threshold as a fraction of Vcc. [1]
    """
    if not (_finite(value) and 0.0 < value < 1.0):
        raise ParameterError(f"must be a fraction of Vcc in (0, 1), got {value!r}", parameter=name)


def check_r_fsr(r_fsr_ohm) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` unless every R_FSR is > 0 (``inf`` allowed: an ideal capacitor).

    Parameters
    ----------
    r_fsr_ohm : float or array_like
        FSR resistance. [Ω]
    """
    if not _all(r_fsr_ohm, lambda v: v > 0, finite=False):
        raise ParameterError(f"must be > 0 Ω (inf allowed), got {r_fsr_ohm!r}", parameter="r_fsr_ohm")


def check_supply(diode: bool, diode_drop_v: float, vcc_v: float) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` for a bad supply or diode drop (a drop needs the diode).

    Parameters
    ----------
    diode : bool
        D1 present.
    diode_drop_v : float
        Forward drop of D1 (≥ 0). [V]
    vcc_v : float
        Supply, 0 < Vcc ≤ :data:`VCC_MAX_V`. [V]
    """
    check_vcc(vcc_v)
    check_drop(diode_drop_v)
    if not _is_bool(diode):
        raise TypeError(f"diode: must be True or False, got {type(diode).__name__}")
    if diode_drop_v > 0 and not diode:
        raise ParameterError("a forward drop needs diode=True (the drop belongs to D1 in series with R_B)",
                             parameter="diode_drop_v")


def check_lm555(r_ohm, c_off_farad, diode: bool, diode_drop_v: float, vcc_v: float,
                lower_fraction: float, upper_fraction: float, discharge_ohm=0.0) -> None:
    """The parameter checks shared by every model of the LM555 readout (scalars or arrays).

    Parameters
    ----------
    r_ohm : float or array_like
        R_A = R_B = R (> 0). [Ω]
    c_off_farad : float or array_like
        Offset capacitor (≥ 0). [F]
    diode : bool
        D1 in series with R_B.
    diode_drop_v : float
        Forward drop of D1 (≥ 0, needs ``diode``). [V]
    vcc_v : float
        Supply (> 0). [V]
    lower_fraction, upper_fraction : float
        Comparator thresholds as fractions of Vcc. [1]
    discharge_ohm : float or array_like
        Discharge-transistor on-resistance (≥ 0). [Ω]
    """
    check_fractions(lower_fraction, upper_fraction)
    check_supply(diode, diode_drop_v, vcc_v)
    for name, value, unit in (("discharge_ohm", discharge_ohm, "Ω"), ("c_off_farad", c_off_farad, "F")):
        if not _all(value, lambda v: v >= 0):
            raise ParameterError(f"must be finite and >= 0 {unit}, got {value!r}", parameter=name)
    if not _all(r_ohm, lambda v: v > 0):
        raise ParameterError(f"must be finite and > 0 Ω, got {r_ohm!r}", parameter="r_ohm")


def check_single(*named) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` naming the first of ``(name, value)`` that is an array.

    Parameters
    ----------
    *named : (str, object)
        Parameters of a model of one circuit (a transient, a netlist, a decoding), which take one value each.
    """
    for name, value in named:
        shape = getattr(value, "shape", ())
        if shape or isinstance(value, (list, tuple)):
            raise ParameterError(f"must be a single value (one circuit), got {type(value).__name__} of shape "
                                 f"{shape or (len(value),)}", parameter=name)


def broadcast(*named):
    """``np.broadcast_arrays`` of ``(name, array)`` pairs; an error naming the first that does not fit.

    Parameters
    ----------
    *named : (str, array_like)
        The parameters in the order their function takes them.

    Returns
    -------
    list of ndarray
        The arrays broadcast to one shape.

    Raises
    ------
    ParameterError
        Naming the first parameter whose shape does not broadcast with those before it.
    """
    import numpy as np

    arrays = [np.asarray(a) for _, a in named]
    try:
        return np.broadcast_arrays(*arrays)
    except ValueError:
        for k in range(1, len(arrays)):
            try:
                np.broadcast_shapes(*(a.shape for a in arrays[:k + 1]))
            except ValueError:
                before = ", ".join(f"{n} {a.shape}" for (n, _), a in zip(named[:k], arrays[:k], strict=True))
                raise ParameterError(f"shape {arrays[k].shape} does not broadcast with {before}",
                                     parameter=named[k][0]) from None
        raise
