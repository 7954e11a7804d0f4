"""The one check of the LM555's parameters, shared by the circuit values and every model function.

:class:`~fsrlab.circuits.circuit.LM555Circuit` validates itself with :func:`check_lm555`; the model
functions of :mod:`fsrlab.circuits.lm555`, :mod:`fsrlab.circuits.phases`, :mod:`fsrlab.circuits.decode`,
:mod:`fsrlab.circuits.transient` and :mod:`fsrlab.circuits.spice` take the same parts as keywords (a design
sweep passes an array of R) and call the same check.
"""

from __future__ import annotations

import math

__all__ = ["check_lm555", "check_fractions", "check_supply", "VCC_MAX_V"]

def check_fractions(lower_fraction: float, upper_fraction: float) -> None:
    """Raise ``ValueError`` unless ``0 < lower_fraction < upper_fraction < 1``.

    Parameters
    ----------
    lower_fraction, upper_fraction : float
        Comparator thresholds as fractions of Vcc. [1]
    """
    if not (0.0 < lower_fraction < upper_fraction < 1.0):
        raise ValueError(
            "lower_fraction and upper_fraction: need 0 < lower_fraction < upper_fraction < 1, got "
            f"{lower_fraction!r} and {upper_fraction!r}"
        )


#: Largest supply the models accept: far beyond any 555 (LM555: 4.5–16 V; CMOS parts 2–18 V), and small
#: enough that thresholds and currents stay finite in double precision. [V]
VCC_MAX_V = 1000.0


def _finite(x) -> bool:
    """A finite number (a Python or numpy scalar)."""
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def _all(value, ok) -> bool:
    """Every element of ``value`` (a number or an array) finite and ``ok(element)``.

    Plain numbers are checked without numpy, so building a circuit of numbers (the paper's, at import)
    does not import it.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return math.isfinite(value) and bool(ok(value))
    import numpy as np

    v = np.asarray(value, dtype=float)
    return bool(np.all(np.isfinite(v)) and np.all(ok(v)))


def check_supply(diode: bool, diode_drop_v: float, vcc_v: float) -> None:
    """Raise ``ValueError`` for a bad supply or diode drop (a drop needs the diode).

    Parameters
    ----------
    diode : bool
        D1 present.
    diode_drop_v : float
        Forward drop of D1 (≥ 0). [V]
    vcc_v : float
        Supply, 0 < Vcc ≤ :data:`VCC_MAX_V`. [V]
    """
    if not (_finite(vcc_v) and 0 < vcc_v <= VCC_MAX_V):
        raise ValueError(f"vcc_v: must be a supply voltage > 0 V and ≤ {VCC_MAX_V:g} V, got {vcc_v!r}")
    if not (_finite(diode_drop_v) and diode_drop_v >= 0):
        raise ValueError(f"diode_drop_v: must be a finite forward drop >= 0 V, got {diode_drop_v!r}")
    if diode_drop_v > 0 and not diode:
        raise ValueError("diode_drop_v: a forward drop needs diode=True (the drop belongs to D1 in series with R_B)")


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
            raise ValueError(f"{name}: must be finite and >= 0 {unit}, got {value!r}")
    if not _all(r_ohm, lambda v: v > 0):
        raise ValueError(f"r_ohm: must be finite and > 0 Ω, got {r_ohm!r}")
