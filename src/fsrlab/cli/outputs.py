"""The output policy as the commands use it: ``parser=out_path``, :func:`checked`, :func:`check_out` and the
``--overwrite`` help texts (the policy itself is :mod:`fsrlab.io.outputs`). Re-exported by
:mod:`fsrlab.cli.options`, where the command modules take them from."""

from __future__ import annotations

from pathlib import Path

import typer

OVERWRITE_HELP = ("Replace an existing output file; without it an existing one stops the command. An input is "
                  "never replaced.")
OVERWRITE_DIR_HELP = ("Write into a directory that is not empty, replacing the files this command writes there; "
                      "without it a non-empty directory stops the command. An input is never replaced.")


def out_path(text) -> Path:
    """An output path option's value (``parser=out_path``); an empty or blank one is refused (it would mean "here")."""
    from fsrlab.io.outputs import OutputError, output_path

    try:
        return output_path(text, "")
    except OutputError as exc:
        raise typer.BadParameter(exc.message) from None


def checked(path, option: str, **kwargs) -> Path:
    """:func:`fsrlab.io.outputs.check_output` (``overwrite``, ``inputs``, ``kind``, ``names``), a refusal
    ending the command with one line naming ``option``."""
    from fsrlab.io.outputs import OutputError, check_output

    try:
        return check_output(path, option, **kwargs)
    except OutputError as exc:
        raise typer.BadParameter(exc.message, param_hint=exc.option) from None


def check_out(out: Path, overwrite: bool, inputs=(), option: str = "--out") -> None:
    """Refuse a run output that exists (unless ``overwrite``), is an input or an input's sidecar, or cannot be
    written, before any device is touched (the output policy, :mod:`fsrlab.io.outputs`)."""
    checked(out, option, overwrite=overwrite, inputs=inputs, kind="run")
