"""fsrlab's exception classes: one base, :class:`FsrlabError`, whose instances carry the parameter at fault.

Every class keeps the built-in base that code caught before it existed (``ValueError`` for a bad value
or file, ``OSError`` for a serial link), so ``except ValueError`` still works; the base adds
:attr:`FsrlabError.parameter`, the name of the parameter at fault (``None`` when no single one is), and
:attr:`FsrlabError.reason`, the message without that name. The command line maps ``parameter`` to its
option (``port`` → ``--port``) without reading the message.
"""

from __future__ import annotations

__all__ = ["FsrlabError", "ParameterError", "FileFormatError", "ProvenanceError"]


class FsrlabError(Exception):
    """Base of fsrlab's errors.

    Parameters
    ----------
    reason : str
        What is wrong and what is allowed, without the parameter's name.
    parameter : str, optional
        The parameter at fault (a Python name: ``port``, ``r_ohm``); the message then reads
        ``"<parameter>: <reason>"``. Default: the class's own :attr:`parameter`.
    """

    parameter: str | None = None
    """Name of the parameter at fault, or None."""

    def __init__(self, reason: str = "", parameter: str | None = None):
        if parameter is not None:
            self.parameter = parameter
        self.reason = str(reason)
        super().__init__(f"{self.parameter}: {self.reason}" if self.parameter else self.reason)


class ParameterError(FsrlabError, ValueError):
    """A parameter's value outside what is allowed (the message says what is).

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


class FileFormatError(FsrlabError, ValueError):
    """A file that is not what it should be: one line naming the file, the row and the column.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


class ProvenanceError(FsrlabError, ValueError):
    """A calibration recorded with another circuit, range or readout than the run it is applied to.

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """
