"""The paper's printed sensor parameters, in SI units: the one place they live.

The paper's circuits (Figs. 16 and 18) are values of the circuits layer:
:data:`fsrlab.circuits.circuit.PAPER_CIRCUIT` and :data:`fsrlab.circuits.circuit.PAPER_OPAMP`.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, Table 1.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from fsrlab.errors import ParameterError

__all__ = ["PaperParameters", "PAPER", "check_positive", "check_finite", "check_at_least", "check_between", "check_int",
           "float_array", "paired_series", "plain"]

#: The electronvolt in joules: CODATA 2018, exact since the 2019 SI (e = 1.602176634e-19 C); equal to
#: ``scipy.constants.electron_volt``, written out so that importing the parameters does not import scipy.
electron_volt = 1.602176634e-19


def _numbers(name: str, value):
    """``value`` as a float or a float array; a TypeError naming ``name`` when it holds no numbers."""
    if isinstance(value, (int, float)):  # a number (bool included): no numpy needed
        return float(value)
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name}: must be a number or an array of numbers, got {type(value).__name__}")
    import numpy as np

    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: must be a number or an array of numbers, got {type(value).__name__}") from None


def float_array(name: str, value):
    """``value`` as a float ndarray; a TypeError naming ``name`` when it is not numbers.

    Parameters
    ----------
    name : str
        Parameter name for the message.
    value : float or array_like
        Numbers (a str, bytes, None or a mapping is refused rather than converted).

    Returns
    -------
    ndarray of float
    """
    import numpy as np

    return np.asarray(_numbers(name, value), dtype=float)


def paired_series(x_name: str, x, y_name: str, y):
    """Two float arrays of one 1-D shape (times and readings, stress and charge, ...): ``x`` 1-D, ``y`` of its
    shape; a ParameterError naming the one that is not (a TypeError when not numbers, :func:`float_array`).

    Parameters
    ----------
    x_name, y_name : str
        Parameter names for the messages.
    x, y : array_like
        The two series.

    Returns
    -------
    (ndarray, ndarray)
    """
    from fsrlab.errors import ParameterError

    xa, ya = float_array(x_name, x), float_array(y_name, y)
    if xa.ndim != 1:
        raise ParameterError(f"must be a 1-D array, got shape {xa.shape}", parameter=x_name)
    if ya.shape != xa.shape:
        raise ParameterError(f"must have the shape of {x_name} {xa.shape}, got {ya.shape}", parameter=y_name)
    return xa, ya


def plain(value) -> str:
    """A value as a message shows it.

    Parameters
    ----------
    value : object
        A number is written as a user writes it (``322000``, not ``np.float64(322000.0)``), anything else by
        its ``repr``, cut at 80 characters.

    Returns
    -------
    str
    """
    from numbers import Real

    if isinstance(value, Real) and not isinstance(value, bool):
        return f"{float(value):g}"
    return f"{value!r}"[:80]


def check_finite(name: str, value, scalar: bool = False) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` naming ``name`` unless every element of ``value`` is finite.

    Parameters
    ----------
    name : str
        Parameter name for the message and the error's ``parameter``.
    value : float or array_like
        The value to check.
    scalar : bool
        Require a single number (an array, even of one element, is refused).

    Raises
    ------
    TypeError
        If ``value`` is not a number or an array of numbers (the message names ``name``).
    ParameterError
        If an element is nan or ±inf, or ``scalar`` and ``value`` is an array.
    """
    x = _numbers(name, value)
    if scalar and not isinstance(x, float) and x.ndim:
        raise ParameterError(f"must be a single number, got an array of shape {x.shape}", parameter=name)
    if isinstance(x, float):
        finite = math.isfinite(x)
    else:
        import numpy as np

        finite = bool(np.all(np.isfinite(x)))
    if not finite:
        raise ParameterError(f"must be finite, got {plain(value)}", parameter=name)


def check_positive(name: str, value, unit: str = "", scalar: bool = False) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` naming ``name`` unless ``value`` is finite and > 0 (every element).

    Parameters
    ----------
    name : str
        Parameter name for the message and the error's ``parameter``.
    value : float or array_like
        The value to check.
    unit : str
        Unit shown in the message.
    scalar : bool
        Require a single number.

    Raises
    ------
    TypeError
        If ``value`` is not a number or an array of numbers (the message names ``name``).
    ParameterError
        If an element is not finite or not > 0, or ``scalar`` and ``value`` is an array.
    """
    check_at_least(name, value, 0.0, unit, strict=True, scalar=scalar)


def check_at_least(name: str, value, lower: float, unit: str = "", strict: bool = False, scalar: bool = False) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` naming ``name`` unless ``value`` is finite and ≥ ``lower``.

    Parameters
    ----------
    name : str
        Parameter name for the message and the error's ``parameter``.
    value : float or array_like
        The value to check (every element).
    lower : float
        The smallest value allowed.
    unit : str
        Unit shown in the message.
    strict : bool
        Require ``value > lower`` instead.
    scalar : bool
        Require a single number.

    Raises
    ------
    TypeError
        If ``value`` is not a number or an array of numbers (the message names ``name``).
    ParameterError
        If an element is not finite or below the bound, or ``scalar`` and ``value`` is an array.
    """
    check_finite(name, value, scalar)
    x = _numbers(name, value)
    if isinstance(x, float):
        ok = x > lower if strict else x >= lower
    else:
        import numpy as np

        ok = bool(np.all(x > lower if strict else x >= lower))
    if not ok:
        bound = f"{'>' if strict else '>='} {lower:g}{(' ' + unit) if unit else ''}"
        raise ParameterError(f"must be {bound}, got {plain(value)}", parameter=name)


def check_between(name: str, value, lower: float, upper: float, unit: str = "", *, lower_open: bool = False,
                  upper_open: bool = False, scalar: bool = False) -> None:
    """Raise :class:`~fsrlab.errors.ParameterError` naming ``name`` unless ``value`` is finite and within bounds.

    Parameters
    ----------
    name : str
        Parameter name for the message and the error's ``parameter``.
    value : float or array_like
        The value to check (every element).
    lower, upper : float
        The bounds, included unless ``lower_open`` / ``upper_open``.
    unit : str
        Unit shown in the message.
    lower_open, upper_open : bool
        Exclude the bound.
    scalar : bool
        Require a single number.

    Raises
    ------
    TypeError
        If ``value`` is not a number or an array of numbers (the message names ``name``).
    ParameterError
        If an element is not finite or outside the bounds, or ``scalar`` and ``value`` is an array.
    """
    check_finite(name, value, scalar)
    import numpy as np

    x = np.asarray(_numbers(name, value))
    ok = (x > lower if lower_open else x >= lower) & (x < upper if upper_open else x <= upper)
    if not bool(np.all(ok)):
        interval = f"{'(' if lower_open else '['}{lower:g}, {upper:g}{')' if upper_open else ']'}"
        raise ParameterError(f"must be in {interval}{(' ' + unit) if unit else ''}, got {plain(value)}",
                             parameter=name)


def check_int(name: str, value, lower: int | None = None) -> int:
    """``value`` as an int, or an error naming ``name``.

    Parameters
    ----------
    name : str
        Parameter name for the message and the error's ``parameter``.
    value : int
        An integer (a bool or a float is refused).
    lower : int, optional
        The smallest value allowed.

    Returns
    -------
    int

    Raises
    ------
    TypeError
        If ``value`` is not an integer (the message names ``name``).
    ParameterError
        If it is below ``lower``.
    """
    from numbers import Integral

    if not isinstance(value, Integral) or isinstance(value, bool):
        raise TypeError(f"{name}: must be an int, got {type(value).__name__}")
    if lower is not None and value < lower:
        raise ParameterError(f"must be >= {lower}, got {value}", parameter=name)
    return int(value)


@dataclass(frozen=True)
class PaperParameters:
    """Simulation parameters of the paper's Table 1 (Figures 4 and 8, Table 2).

    Parameters
    ----------
    modulus_pa : float
        Material stiffness M. [Pa]
    sigma_f_pa : float
        Final (largest) stress σf of the loading–unloading cycle. [Pa]
    u_v : float
        Voltage U across the composite. [V]
    s0_m : float
        Interparticle separation at zero stress s0. [m]
    phi0_j : float
        Barrier height φ0 (Table 1 prints 0.223 eV). [J]
    eps_r : float
        Relative permittivity of the polymer matrix. [-]
    k : float
        Unloading exponent. Not printed; k = 2 reproduces Table 2's capacitance column. [-]
    """

    modulus_pa: float = 4.73e6
    sigma_f_pa: float = 322e3
    u_v: float = 2.0
    s0_m: float = 4.418e-9
    phi0_j: float = 0.223 * electron_volt
    eps_r: float = 7.0
    k: float = 2.0

    def __post_init__(self) -> None:
        check_positive("s0_m", self.s0_m, "m", scalar=True)
        check_positive("sigma_f_pa", self.sigma_f_pa, "Pa", scalar=True)
        check_positive("modulus_pa", self.modulus_pa, "Pa", scalar=True)
        check_positive("u_v", self.u_v, "V", scalar=True)
        check_positive("phi0_j", self.phi0_j, "J", scalar=True)
        check_positive("eps_r", self.eps_r, scalar=True)
        check_at_least("k", self.k, 1.0, scalar=True)
        if not self.modulus_pa > self.sigma_f_pa:
            raise ParameterError(f"must be > sigma_f_pa ({self.sigma_f_pa:g} Pa), got {self.modulus_pa:g}",
                                 parameter="modulus_pa")

    def as_dict(self) -> dict:
        """Values keyed by name, plus the barrier height in eV for display."""
        d = asdict(self)
        d["phi0_ev"] = self.phi0_j / electron_volt
        return d


#: Table 1 of the paper, with k = 2.
PAPER = PaperParameters()
