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

from fsrlab.io.outputs import write_text_atomic
from fsrlab.io.runformat import read_json_document

__all__ = ["CALIBRATION_FORMAT", "CALIBRATION_VERSION", "CALIBRATION_VERSIONS_READ", "read_calibration_document", "write_calibration_document"]

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
    # Through a temporary file and a rename: an interrupted write leaves the old file or none.
    return write_text_atomic(path, json.dumps(doc, indent=2, allow_nan=False) + "\n")


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
    ValueError
        One line naming the file and what is wrong (a version other than those of
        :data:`CALIBRATION_VERSIONS_READ` too).
    """
    path = Path(path)
    try:
        return read_json_document(path, CALIBRATION_FORMAT, CALIBRATION_VERSION, "calibration")
    except ValueError as exc:
        if "version 1 not supported" not in str(exc):
            raise
    return read_json_document(path, CALIBRATION_FORMAT, 1, "calibration")
