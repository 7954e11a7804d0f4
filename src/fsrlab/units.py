"""Engineering notation as circuit people write it: ``10k``, ``4.7n``, ``470p``, ``1M``, ``4k7``.

``M`` is mega (as on schematics and part labels); ``m`` is milli; SPICE's ``meg`` is accepted too.
A trailing unit symbol (``Ω``, ``ohm``, ``F``, ``V``, ``Hz``, ``s``, ``Pa``, ``N``, ``%``) is ignored
after the prefix, so ``4.7nF`` and ``10kohm`` work.
"""

from __future__ import annotations

import math
import re

__all__ = ["PREFIXES", "parse_eng", "format_eng"]

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
    ValueError
        If the text is not a finite number in engineering notation; the message names ``name``.
    """
    if isinstance(text, (int, float)):
        value = float(text)
    else:
        match = _PLAIN.match(text)
        if match:
            value = float(match.group(1)) * PREFIXES[match.group(2) or ""]
        else:
            rkm = _RKM.match(text)
            if not rkm:
                raise ValueError(
                    f"{_lead(name)}cannot read {text!r}; write a number with an optional SI prefix "
                    "such as 10k, 4.7n, 470p, 1M, 4k7"
                )
            scale = 1.0 if rkm.group(2) == "R" else PREFIXES[rkm.group(2)]
            value = float(f"{rkm.group(1)}.{rkm.group(3)}") * scale
    if not math.isfinite(value):
        raise ValueError(f"{_lead(name)}must be a finite number, got {text!r}")
    return value


def _lead(name: str | None) -> str:
    return f"{name}: " if name else ""


def format_eng(value: float, unit: str = "", digits: int = 4) -> str:
    """Format ``value`` with an SI prefix, e.g. ``format_eng(4.7e-9, "F") == "4.7 nF"``.

    Parameters
    ----------
    value : float
        Value in SI base units.
    unit : str
        Unit symbol appended after the prefix.
    digits : int
        Significant digits.

    Returns
    -------
    str
        The formatted value.
    """
    if value == 0 or not math.isfinite(value):
        return f"{value:g} {unit}".strip()
    exponent = int(math.floor(math.log10(abs(value)) / 3) * 3)
    exponent = max(-15, min(12, exponent))
    prefix = {-15: "f", -12: "p", -9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G", 12: "T"}[exponent]
    return f"{value / 10**exponent:.{digits}g} {prefix}{unit}".strip()
