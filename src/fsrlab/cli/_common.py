"""Shared pieces of the command modules: engineering-notation values and JSON output."""

from __future__ import annotations

import json
import math
import re
from contextlib import contextmanager
from typing import Any, Iterator

import numpy as np
import typer

from fsrlab.units import parse_eng

__all__ = ["eng", "emit_json", "to_jsonable", "fail", "option_names"]


def eng(text: str | float) -> float:
    """Parse an option value in engineering notation (``10k``, ``4.7n``, ``1M``).

    Use as ``typer.Option(..., parser=eng)``; a bad value becomes a one-line usage error.
    """
    try:
        return parse_eng(text, name=None)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars and arrays, paths and nested containers to JSON types.

    Parameters
    ----------
    obj : object
        Nested dicts, lists, numpy values.

    Returns
    -------
    object
        The same structure made of JSON types; non-finite floats become ``None``.
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if hasattr(obj, "__fspath__"):
        return str(obj)
    return obj


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
    raise typer.BadParameter(message, param_hint=field)


@contextmanager
def option_names(mapping: dict[str, str]) -> Iterator[None]:
    """Re-raise a model's ``ValueError`` with its parameter names replaced by the CLI's option names.

    Parameters
    ----------
    mapping : dict
        Model parameter name → option, e.g. ``{"modulus_pa": "--modulus"}``.
    """
    try:
        yield
    except ValueError as exc:
        message = str(exc)
        for name, option in mapping.items():
            message = re.sub(rf"\b{re.escape(name)}\b", option, message)
        raise typer.BadParameter(message) from None
