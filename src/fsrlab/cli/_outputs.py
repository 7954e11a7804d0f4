"""The output policy (:mod:`fsrlab.outputs`) as the commands use it: one line naming the option, exit 2.

``typer.Option(..., parser=out_path)`` refuses an empty value before it becomes ``Path(".")``;
:func:`checked` runs :func:`fsrlab.outputs.check_output` and turns a refusal into :func:`fail`.
"""

from __future__ import annotations

from pathlib import Path

import typer

from fsrlab.cli._common import fail
from fsrlab.outputs import OutputError, check_output, output_path

__all__ = ["out_path", "checked", "OVERWRITE_HELP", "OVERWRITE_DIR_HELP"]

OVERWRITE_HELP = "Replace an existing output file; without it an existing one stops the command. An input is never replaced."
OVERWRITE_DIR_HELP = ("Write into a directory that is not empty, replacing the files this command writes there; "
                      "without it a non-empty directory stops the command. An input is never replaced.")


def out_path(text) -> Path:
    """An output path option's value; an empty or blank one is refused (it would mean "here")."""
    try:
        return output_path(text, "")
    except OutputError as exc:
        raise typer.BadParameter(exc.message) from None


def checked(path, option: str, **kwargs) -> Path:
    """:func:`fsrlab.outputs.check_output`, a refusal ending the command with one line naming ``option``.

    Parameters
    ----------
    path : path-like
        The output.
    option : str
        Its option, e.g. ``"--output"``.
    **kwargs
        ``overwrite``, ``inputs``, ``kind``, ``names`` of :func:`fsrlab.outputs.check_output`.

    Returns
    -------
    Path
    """
    try:
        return check_output(path, option, **kwargs)
    except OutputError as exc:
        fail(exc.message, exc.option)
        raise AssertionError from None  # fail() raises
