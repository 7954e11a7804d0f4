"""Engineering notation as circuit people write it: ``10k``, ``4.7n``, ``470p``, ``1M``, ``4k7``.

:func:`parse_eng` is lenient: ``M`` is mega (as on schematics and part labels), ``m`` is milli,
SPICE's ``meg`` is accepted too, and a trailing unit symbol (``Ω``, ``ohm``, ``F``, ``V``, ``Hz``,
``s``, ``Pa``, ``N``, ``%``) is ignored after the prefix, so ``4.7nF`` and ``10kohm`` work.

:func:`parse_quantity` reads a value of one known quantity (a resistance, a duration, a fraction,
...) and refuses what could be misread: a unit of another quantity (``10kF`` for a resistance), a
lower-case ``m`` where mega or milli are both plausible (``1m`` for a resistor), ``m`` on a duration
(minutes or milliseconds), a fraction above 1 written without ``%``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from decimal import Decimal
from numbers import Integral, Real

from fsrlab.errors import ParameterError

__all__ = ["PREFIXES", "QUANTITIES", "STANDARD_GRAVITY", "Quantity", "parse_eng", "parse_quantity", "format_eng"]

#: Standard acceleration of gravity g0 (exact, CGPM 1901): a mass of m kg weighs m·g0 N; grams-force = N·1000/g0. [m/s²]
STANDARD_GRAVITY = 9.80665

#: Multiplier of each SI prefix letter.
PREFIXES = {
    "f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "µ": 1e-6, "μ": 1e-6, "m": 1e-3,
    "": 1.0, "k": 1e3, "K": 1e3, "M": 1e6, "meg": 1e6, "MEG": 1e6, "Meg": 1e6, "G": 1e9, "T": 1e12,
}

_UNITS = r"(?:ohms?|Ohms?|Ω|F|V|A|Hz|hz|s|Pa|N|W|%)?"
_PREFIX = r"(meg|MEG|Meg|[fpnuµμmkKMGT])?"
_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_PLAIN = re.compile(rf"^\s*({_NUMBER})\s*{_PREFIX}\s*{_UNITS}\s*$")
# RKM code (IEC 60062): the prefix letter stands for the decimal point, "4k7" = 4.7e3.
_RKM = re.compile(rf"^\s*(\d+)(meg|MEG|Meg|[fpnuµμmkKMGTR])(\d+)\s*{_UNITS}\s*$")


def parse_eng(text: str | float | int, name: str | None = "value") -> float:
    """Parse a number written in engineering notation.

    Parameters
    ----------
    text : str or float
        ``"10k"``, ``"4.7n"``, ``"470pF"``, ``"1M"``, ``"4k7"``, ``"2.5e-3"`` or a number.
    name : str or None
        Name of the field, used in the error message (``None``: the caller adds it).

    Returns
    -------
    float
        The value in SI base units.

    Raises
    ------
    ParameterError
        If the text is not a finite number in engineering notation; its ``parameter`` is ``name``.
    TypeError
        If ``text`` is neither a number nor a str.

    Examples
    --------
    >>> parse_eng("4k7"), parse_eng("10k"), parse_eng("1M")
    (4700.0, 10000.0, 1000000.0)
    """
    if isinstance(text, Real) and not isinstance(text, bool):
        value = float(text)
    else:
        match = _PLAIN.match(_text(text, name))
        if match:
            value = float(match.group(1)) * PREFIXES[match.group(2) or ""]
        else:
            rkm = _RKM.match(text)
            if not rkm:
                raise ParameterError(f"cannot read {text!r}; write a number with an optional SI prefix "
                                     "such as 10k, 4.7n, 470p, 1M, 4k7", parameter=name)
            scale = 1.0 if rkm.group(2) == "R" else PREFIXES[rkm.group(2)]
            value = float(f"{rkm.group(1)}.{rkm.group(3)}") * scale
    if not math.isfinite(value):
        raise ParameterError(f"must be a finite number, got {text!r}", parameter=name)
    return value


def _text(text, name: str | None) -> str:
    """``text`` when it is a str; a TypeError naming the field otherwise."""
    if not isinstance(text, str):
        raise TypeError(f"{name or 'text'}: must be a number or a str such as '10k', got {type(text).__name__}")
    return text


@dataclass(frozen=True)
class Quantity:
    """How values of one physical quantity are written.

    Parameters
    ----------
    what : str
        The quantity with its article, for messages (``"a resistance"``).
    symbol : str
        The SI unit symbol shown in messages (``"Ω"``).
    units : dict
        Accepted unit spellings (``""`` for none) and their factor to the SI unit.
    prefixed : bool
        Whether an SI prefix may stand before a unit (``4.7n``, ``4.7nF``).
    milli : bool
        Whether a lower-case ``m`` prefix is read as milli; when False it is refused as ambiguous.
    rkm : bool
        Whether the RKM code is read (IEC 60062: ``4k7`` = 4.7k, ``2R2`` = 2.2).
    examples : str
        Spellings shown when a value cannot be read.
    """

    what: str
    symbol: str
    units: dict
    prefixed: bool = True
    milli: bool = True
    rkm: bool = False
    examples: str = ""


_SECONDS = {"": 1.0, "s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6, "ns": 1e-9, "min": 60.0, "h": 3600.0}

#: The quantities :func:`parse_quantity` reads, by name.
QUANTITIES = {
    "resistance": Quantity("a resistance", "Ω", {"": 1.0, "Ω": 1.0, "\u2126": 1.0, "ohm": 1.0, "ohms": 1.0, "Ohm": 1.0,
                                                 "Ohms": 1.0}, milli=False, rkm=True,
                                                 examples="10k, 10kΩ, 10kohm, 4k7, 1M, 1meg"),
    "capacitance": Quantity("a capacitance", "F", {"": 1.0, "F": 1.0}, milli=False, rkm=True,
                            examples="4.7n, 4.7nF, 470p, 4n7, 1u"),
    "voltage": Quantity("a voltage", "V", {"": 1.0, "V": 1.0, "v": 1.0}, examples="5, 5V, 600mV"),
    "frequency": Quantity("a frequency", "Hz", {"": 1.0, "Hz": 1.0, "hz": 1.0}, examples="6478.5, 6.4785k, 6.4785kHz"),
    "stress": Quantity("a stress", "Pa", {"": 1.0, "Pa": 1.0, "pa": 1.0}, examples="322k, 322kPa, 4.73MPa"),
    "energy": Quantity("an energy in electronvolts", "eV", {"": 1.0, "eV": 1.0, "ev": 1.0},
                       examples="0.223, 0.223eV, 223meV"),
    "length": Quantity("a length", "m", {"": 1.0, "m": 1.0}, examples="4.418n, 4.418nm"),
    "duration": Quantity("a duration", "s", _SECONDS, prefixed=False, examples="90, 90s, 1.5min, 2h, 500ms, 250us"),
    "fraction": Quantity("a fraction", "", {"": 1.0, "%": 0.01}, prefixed=False, examples="0.1, 10%"),
    "number": Quantity("a plain number", "", {"": 1.0}, prefixed=False, examples="2, 7.5, 1e3"),
}

_NUMBER_AND_SUFFIX = re.compile(rf"^({_NUMBER})(.*)$")
_RKM_ANY = re.compile(r"^(\d+)(meg|MEG|Meg|[fpnuµμmkKMGTR])(\d+)(.*)$")
_NOT_FINITE = re.compile(r"^[+-]?(nan|inf|infinity)$", re.IGNORECASE)


def _readings(suffix: str, q: Quantity) -> list[tuple[str, str, float]]:
    """Every way to read ``suffix`` as prefix + unit of ``q``: (prefix, unit, factor)."""
    out = []
    for unit, factor in q.units.items():
        if not suffix.endswith(unit):
            continue
        head = suffix[: len(suffix) - len(unit)]
        if head == "":
            out.append(("", unit, factor))
        elif q.prefixed and head in PREFIXES:
            out.append((head, unit, factor * PREFIXES[head]))
    return out


def _milli_message(number: str, value: float, q: Quantity, text: str) -> str:
    milli = f"{number}e-3" if re.fullmatch(r"[+-]?[\d.]+", number) else f"{value * 1e-3:g}"
    if q.symbol == "F":  # nobody means megafarads: say how to write the small prefixes instead
        return (f"{text!r} is ambiguous: write {milli} for {number} mF, or a small prefix such as "
                f"{number}u ({number} µF), {number}n or {number}p")
    return (f"{text!r} is ambiguous: write {number}M or {number}meg for {number} M{q.symbol}, "
            f"or {milli} for {number} m{q.symbol}")


def parse_quantity(text: str | float | int, quantity: str, name: str | None = None) -> float:
    """Read a value of one quantity, refusing spellings that could be misread.

    Parameters
    ----------
    text : str or float
        What the user wrote, e.g. ``"10k"`` (resistance), ``"1.5min"`` (duration), ``"10%"``
        (fraction); a number is taken as already in SI units.
    quantity : str
        A key of :data:`QUANTITIES`: resistance, capacitance, voltage, frequency, stress, energy
        (in eV), length, duration, fraction or number.
    name : str or None
        Name of the field, put before the message (``None``: the caller adds it).

    Returns
    -------
    float
        The value in SI units (seconds for a duration, a ratio for a fraction, eV for an energy).

    Raises
    ------
    ParameterError
        If the value is not finite, cannot be read, carries the unit of another quantity, uses a
        lower-case ``m`` on a resistance or capacitance, ``m`` on a duration, or is a fraction
        above 1 without ``%``; the message says how to write it, and ``parameter`` is ``name``
        (``quantity`` for an unknown quantity).
    TypeError
        If ``text`` is neither a number nor a str.

    Notes
    -----
    Resistance and capacitance take ``M`` or ``meg`` for mega and refuse ``m``: on a part label
    ``1M`` is a megohm, and a lower-case ``1m`` is as likely a slip for it as a milliohm. Durations
    take ``s``, ``ms``, ``us``, ``ns``, ``min`` and ``h``; ``1m`` is refused (minutes or milli?).
    """
    q = QUANTITIES.get(quantity) if isinstance(quantity, str) else None
    if q is None:
        raise ParameterError(f"must be one of {', '.join(QUANTITIES)}, got {quantity!r}", parameter="quantity")
    if isinstance(text, Real) and not isinstance(text, bool):
        value, unit = float(text), ""
        if not math.isfinite(value):
            raise ParameterError(f"must be a finite number, got {value:g}", parameter=name)
    else:
        value, unit = _read(_text(text, name), q, name)
    if quantity == "fraction" and unit == "" and abs(value) > 1:
        raise ParameterError(f"{text!r} is not a fraction (0..1): write {text}% for {value / 100:g}, "
                             f"or a number from 0 to 1", parameter=name)
    return value


def _read(text: str, q: Quantity, name: str | None) -> tuple[float, str]:
    compact = "".join(text.split())
    if _NOT_FINITE.match(compact):
        raise ParameterError(f"must be a finite number, got {text!r}", parameter=name)
    rkm = _RKM_ANY.match(compact) if q.rkm else None
    if rkm:
        digits, letter, decimals, unit = rkm.groups()
        if unit in q.units and (letter != "R" or q.symbol == "Ω"):
            number = f"{digits}.{decimals}"
            if letter == "m":
                raise ParameterError(_milli_message(number, float(number), q, text), parameter=name)
            value = _scaled(number, 1.0 if letter == "R" else PREFIXES[letter])
            return _finite(value, text, name), unit
    match = _NUMBER_AND_SUFFIX.match(compact)
    if not match:
        raise ParameterError(f"cannot read {text!r} as {q.what}; write e.g. {q.examples}", parameter=name)
    number, suffix = match.groups()
    readings = _readings(suffix, q)
    if not q.milli and any(prefix == "m" for prefix, _, _ in readings):
        raise ParameterError(_milli_message(number, float(number), q, text), parameter=name)
    if len({factor for _, _, factor in readings}) > 1:  # e.g. "5m" for a length: 5 m or 5 mm
        spelled = ", or ".join(
            f"{number}{prefix}{q.symbol} for {_scaled(number, factor):g} {q.symbol}" if unit == "" else
            f"{_scaled(number, factor):g} for {_scaled(number, factor):g} {q.symbol}"
            for prefix, unit, factor in readings)
        raise ParameterError(f"{text!r} is ambiguous: write {spelled}", parameter=name)
    if not readings:
        if q is QUANTITIES["duration"] and suffix == "m":
            raise ParameterError(f"{text!r} is ambiguous (minutes or milliseconds?): write {number}min for "
                                 f"{float(number) * 60:g} s or {number}ms for {float(number) * 1e-3:g} s",
                                 parameter=name)
        other = next((o for o in QUANTITIES.values()
                      if o is not q and any(u for _, u, _ in _readings(suffix, o))), None)
        if other is not None:
            unit_text = f"in {q.symbol}" if q.symbol else "without a unit"
            raise ParameterError(f"{text!r} is {other.what}, not {q.what}: write it {unit_text}, e.g. {q.examples}",
                                 parameter=name)
        raise ParameterError(f"cannot read {text!r} as {q.what}; write e.g. {q.examples}", parameter=name)
    _, unit, factor = readings[0]
    return _finite(_scaled(number, factor), text, name), unit


def _scaled(number: str, factor: float) -> float:
    """``number`` times ``factor``, exact for powers of ten (``4.7n`` is 4.7e-9, not 4.700000000000001e-09)."""
    exponent = round(math.log10(factor))
    if factor == 10.0**exponent:
        return float(Decimal(number).scaleb(exponent))
    return float(number) * factor


def _finite(value: float, text: str, name: str | None) -> float:
    if not math.isfinite(value):
        raise ParameterError(f"must be a finite number, got {text!r}", parameter=name)
    return value


def format_eng(value: float, unit: str = "", digits: int = 4) -> str:
    """Format ``value`` with an SI prefix, e.g. ``format_eng(4.7e-9, "F") == "4.7 nF"``.

    Parameters
    ----------
    value : float
        Value in SI base units.
    unit : str
        Unit symbol appended after the prefix.
    digits : int
        Significant digits, ≥ 1.

    Returns
    -------
    str
        The formatted value.

    Raises
    ------
    TypeError
        If ``value`` is not a real number or ``digits`` not an int.
    ParameterError
        If ``digits`` is below 1.
    """
    if not isinstance(value, Real) or isinstance(value, bool):
        raise TypeError(f"value: must be a real number, got {type(value).__name__}")
    if not isinstance(digits, Integral) or isinstance(digits, bool):
        raise TypeError(f"digits: must be an int, got {type(digits).__name__}")
    if digits < 1:
        raise ParameterError(f"must be at least 1, got {digits}", parameter="digits")
    unit = str(unit)
    if value == 0 or not math.isfinite(value):
        return f"{value:g} {unit}".strip()
    exponent = int(math.floor(math.log10(abs(value)) / 3) * 3)
    exponent = max(-15, min(12, exponent))
    prefix = {-15: "f", -12: "p", -9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G", 12: "T"}[exponent]
    return f"{value / 10**exponent:.{digits}g} {prefix}{unit}".strip()
