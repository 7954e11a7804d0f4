"""Run the ``fsrlab`` command line in-process and capture what it prints."""

from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout

from fsrlab.cli import main


def run_cli(argv, capsys=None) -> tuple[int, str, str]:
    """Return ``(exit code, stdout, stderr)`` of ``fsrlab ARGV``; ``capsys`` is accepted and unused."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            main([str(a) for a in argv])
            code = 0
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()
