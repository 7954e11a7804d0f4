"""The calibration file on disk: one JSON document (``"format": "fsrlab-calibration"``, ``"version": 2``).

Reading checks the format, the version and that every number is finite, with one line naming the file
(:func:`fsrlab.io.runformat.read_json_document`); writing replaces the file. What the document holds and
how it becomes a :class:`~fsrlab.calibration.result.Calibration` is :mod:`fsrlab.calibration.document`
(``docs/calibration.md``). Files of version 1 (both earlier layouts) are read too.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.io.outputs import write_text_atomic
from fsrlab.io.runformat import input_file, read_json_document

__all__ = ["CALIBRATION_FORMAT", "CALIBRATION_VERSION", "CALIBRATION_VERSIONS_READ", "read_calibration_document",
           "write_calibration_document"]

#: Value of the calibration file's ``"format"`` key.
CALIBRATION_FORMAT = "fsrlab-calibration"
#: Version of the calibration file's layout that fsrlab writes.
CALIBRATION_VERSION = 2
#: Versions it reads (1: the earlier layouts, read-only).
CALIBRATION_VERSIONS_READ = (1, 2)


def write_calibration_document(doc: dict, path: str | os.PathLike) -> Path:
    """Write a calibration document as indented JSON (non-finite numbers refused), atomically.

    Parameters
    ----------
    doc : dict
        JSON-ready content (:meth:`fsrlab.calibration.result.Calibration.to_dict`).
    path : str or path-like

    Returns
    -------
    Path
    """
    if not isinstance(doc, dict):
        raise TypeError(f"doc: must be a calibration document (a dict), got {type(doc).__name__}")
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bool) or not str(path):
        raise TypeError(f"path: must be a file's path (str or path-like), got {path!r}")
    if Path(path).is_dir():
        raise ParameterError(f"{path} is a directory, not a file", parameter="path")
    try:
        text = json.dumps(doc, indent=2, allow_nan=False) + "\n"
    except (TypeError, ValueError) as exc:  # a value JSON cannot hold
        raise ParameterError(f"not a JSON document ({exc})", parameter="doc") from None
    # Through a temporary file and a rename: an interrupted write leaves the old file or none.
    return write_text_atomic(path, text)


def read_calibration_document(path: str | os.PathLike) -> dict:
    """Read a calibration document, checking its format, version and numbers.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    dict

    Raises
    ------
    fsrlab.errors.FileFormatError
        One line naming the file and what is wrong (a version other than those of
        :data:`CALIBRATION_VERSIONS_READ` too), its parameter ``path``; a ParameterError or TypeError for a
        path that is no file.
    """
    path = input_file(path, "path")

    def refused(message: str) -> FileFormatError:
        return FileFormatError(message, parameter="path")

    try:
        return read_json_document(path, CALIBRATION_FORMAT, CALIBRATION_VERSION, "calibration", refused)
    except FileFormatError as exc:
        if "version 1 not supported" not in str(exc):
            raise
    return read_json_document(path, CALIBRATION_FORMAT, 1, "calibration", refused)
