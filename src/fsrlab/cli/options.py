"""Shared pieces of the command modules: option parsers, JSON output, one-line errors.

Option parsers, for ``typer.Option(..., parser=...)``; each turns a bad value into a usage error
that :func:`fsrlab.cli.main` prints as one line naming the option ("fsrlab: error: Invalid value
for --r: '1m' is ambiguous: ..."), exit code 2; none accepts ``nan`` or ``inf``:

========================  ==================================================================
``ohms``                  resistance: 10k, 10kΩ, 10kohm, 4k7, 1M, 1meg; ``1m`` refused
``farads``                capacitance: 4.7n, 4.7nF, 470p, 4n7; ``1m`` refused
``volts``                 voltage: 5, 5V, 600mV
``hertz``                 frequency: 6478.5, 6.4785k, 6.4785kHz
``pascals``               stress: 322k, 322kPa, 4.73MPa
``metres``                length: 4.418n, 4.418nm; ``5m`` refused (metres or milli?)
``electronvolts``         energy in eV: 0.223, 0.223eV, 223meV
``seconds``               duration: 90, 90s, 1.5min, 2h, 500ms, 250us; ``1m`` refused
``fraction``              0.1 or 10%; a value above 1 without ``%`` is refused
``number``                a plain number without unit or prefix
``areas``                 area: 71.3mm2, 71.3mm², 0.713cm2, 7.13e-5m2 (a bare number is m²)
``masses``                mass: 500g, 0.5kg, 250mg, 0 (a bare number other than 0 is refused)
``mass_list``             comma-separated masses: 0,50g,100g,0.2kg (strictly increasing)
``eng``                   any engineering notation, unit letters ignored (lenient, older)
========================  ==================================================================
"""

from __future__ import annotations

import json
import math
import re
from contextlib import contextmanager
from typing import Any, Callable, Iterator

import typer

from fsrlab.io.jsonable import to_jsonable
from fsrlab.units import parse_eng, parse_quantity

__all__ = ["eng", "ohms", "farads", "volts", "hertz", "pascals", "metres", "electronvolts", "seconds",
           "fraction", "number", "areas", "masses", "mass_list", "emit_json", "to_jsonable", "fail", "option_names", "plain_numbers"]


def eng(text: str | float) -> float:
    """Parse an option value in engineering notation (``10k``, ``4.7n``, ``1M``).

    Use as ``typer.Option(..., parser=eng)``; a bad value becomes a one-line usage error.
    """
    try:
        return parse_eng(text, name=None)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None


def _parser(name: str, quantity: str, doc: str) -> Callable[[str | float], float]:
    """An option parser for one quantity of :data:`fsrlab.units.QUANTITIES`."""

    def parse(text: str | float) -> float:
        try:
            return parse_quantity(text, quantity)
        except ValueError as exc:
            raise typer.BadParameter(str(exc)) from None

    parse.__name__ = parse.__qualname__ = name
    parse.__doc__ = doc
    return parse


ohms = _parser("ohms", "resistance", "Resistance [Ω]: 10k, 10kΩ, 10kohm, 4k7, 1M, 1meg; 1m is refused as ambiguous.")
farads = _parser("farads", "capacitance", "Capacitance [F]: 4.7n, 4.7nF, 470p, 4n7; 1m is refused as ambiguous.")
volts = _parser("volts", "voltage", "Voltage [V]: 5, 5V, 600mV; another quantity's unit is refused.")
hertz = _parser("hertz", "frequency", "Frequency [Hz]: 6478.5, 6.4785k, 6.4785kHz; another quantity's unit is refused.")
pascals = _parser("pascals", "stress", "Stress [Pa]: 322k, 322kPa, 4.73MPa; another quantity's unit is refused.")
metres = _parser("metres", "length", "Length [m]: 4.418n, 4.418nm; 5m is refused (5 m or 5 mm?).")
electronvolts = _parser("electronvolts", "energy", "Energy in electronvolts [eV]: 0.223, 0.223eV, 223meV.")
seconds = _parser("seconds", "duration", "Duration [s]: 90, 90s, 1.5min, 2h, 500ms, 250us; 1m is refused (minutes or milli?).")
fraction = _parser("fraction", "fraction", "Fraction: 0.1 or 10%; a value above 1 without % is refused, never read as percent.")
number = _parser("number", "number", "A plain finite number (2, 7.5, 1e3), without unit letters or prefixes.")

_MEASURE = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-zµ²0-9]*)$")
_AREA_UNITS = {"": 1.0, "m2": 1.0, "m²": 1.0, "cm2": 1e-4, "cm²": 1e-4, "mm2": 1e-6, "mm²": 1e-6}
_MASS_UNITS = {"kg": 1.0, "g": 1e-3, "mg": 1e-6}


def _measure(text: str | float, units: dict, what: str, examples: str) -> tuple[float, str]:
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        value, unit = float(text), ""
    else:
        m = _MEASURE.match(str(text).strip())
        if not m or m.group(2) not in units:
            raise typer.BadParameter(f"cannot read {text!r} as {what}; write e.g. {examples}")
        value, unit = float(m.group(1)) * units[m.group(2)], m.group(2)
    if not math.isfinite(value):
        raise typer.BadParameter(f"{text!r} is not a finite {what.split()[-1]}; write e.g. {examples}")
    return value, unit


def areas(text: str | float) -> float:
    """Area [m²]: 71.3mm2, 71.3mm², 0.713cm2, 7.13e-5m2; a bare number is in m²."""
    return _measure(text, _AREA_UNITS, "an area", "71.3mm2, 0.713cm2, 7.13e-5m2")[0]


def masses(text: str | float) -> float:
    """Mass [kg]: 500g, 0.5kg, 250mg; 0 without a unit; any other bare number is refused (g or kg?)."""
    value, unit = _measure(text, {**_MASS_UNITS, "": 1.0}, "a mass", "500g, 0.5kg, 250mg")
    if unit == "" and value != 0:
        raise typer.BadParameter(f"{text!r} has no unit: write {text}g or {text}kg (a mass in g, kg or mg)")
    return value


def mass_list(text: str) -> list[float]:
    """Comma-separated masses [kg], strictly increasing and ≥ 0: ``0,50g,100g,0.2kg``.

    A value in another unit, a negative mass, or a list that does not increase is refused, naming
    the value.
    """
    items = [t.strip() for t in str(text).split(",")]
    if not items or any(not t for t in items):
        raise typer.BadParameter(f"{text!r}: give comma-separated masses such as 0,50g,100g,200g (no empty item)")
    out: list[float] = []
    for t in items:
        try:
            v = masses(t)
        except typer.BadParameter as exc:
            raise typer.BadParameter(f"value {t!r}: {exc.message}") from None
        if v < 0:
            raise typer.BadParameter(f"value {t!r}: a mass must be >= 0")
        if out and not v > out[-1]:
            raise typer.BadParameter(f"value {t!r} is not larger than the mass before it ({out[-1] * 1e3:g} g): "
                                     "give the masses in increasing order")
        out.append(v)
    return out


def emit_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout."""
    typer.echo(json.dumps(to_jsonable(obj), indent=2))


def fail(message: str, field: str | None = None) -> None:
    """End the command with one line on stderr and exit code 2.

    Parameters
    ----------
    message : str
        What is wrong and what is allowed.
    field : str, optional
        The option or argument at fault, e.g. ``"--r"``.
    """
    raise typer.BadParameter(plain_numbers(message), param_hint=field)


# numpy >= 2 prints scalars as np.float64(37.8); arrays as array([1., 2.]).
_NUMPY_SCALAR = re.compile(r"\b(?:np|numpy)\.(?:float|int|uint|complex|bool|str)_?\d*\(([^()]*)\)")
_NUMPY_ARRAY = re.compile(r"\barray\((\[[^()]*\])(?:,\s*dtype=[\w.]+)?\)")


def plain_numbers(message: str) -> str:
    """``message`` with numpy reprs replaced by the plain values: ``np.float64(37.8)`` → ``37.8``.

    Parameters
    ----------
    message : str
        An error message, e.g. one a model wrote with ``{value!r}``.

    Returns
    -------
    str
        The message as a user should read it.
    """
    message = _NUMPY_SCALAR.sub(lambda m: m.group(1).strip("'\""), message)
    return _NUMPY_ARRAY.sub(lambda m: " ".join(m.group(1).split()), message)


@contextmanager
def option_names(mapping: dict[str, str]) -> Iterator[None]:
    """Re-raise a model's ``ValueError`` with its parameter names replaced by the CLI's option names.

    Numpy reprs in the message become plain numbers (:func:`plain_numbers`); a message that starts
    with an option is reported as that option's invalid value, any other as it is.

    Parameters
    ----------
    mapping : dict
        Model parameter name → option, e.g. ``{"modulus_pa": "--modulus"}``.
    """
    try:
        yield
    except ValueError as exc:
        message = plain_numbers(str(exc))
        # Longest names first, so that "sigma_f_pa" is replaced before a shorter name inside it.
        for name in sorted(mapping, key=len, reverse=True):
            message = re.sub(rf"(?<![\w-]){re.escape(name)}(?![\w-])", mapping[name], message)
        lead = re.match(r"^(--[\w-]+(?:/--[\w-]+)*)(?::\s*|\s+)(.+)$", message, re.DOTALL)
        if lead and lead.group(1) in mapping.values():
            raise typer.BadParameter(lead.group(2), param_hint=lead.group(1)) from None
        # No option leads the message: one line as it is ("fsrlab: error: ..."), not click's bare
        # "Invalid value: ...", which reads as if an option had been named.
        raise ValueError(message) from None
