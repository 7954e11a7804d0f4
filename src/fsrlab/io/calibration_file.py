"""The calibration file on disk: one JSON document (``"format": "fsrlab-calibration"``, ``"version": 1``).

Reading checks the format, the version and that every number is finite, with one line naming the file
(:func:`fsrlab.io.runformat.read_json_document`); writing replaces the file. What the document holds and
how it becomes a :class:`~fsrlab.calibration.result.Calibration` is :mod:`fsrlab.calibration.document`
(``docs/calibration.md``).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from fsrlab.io.outputs import write_text_atomic
from fsrlab.io.runformat import read_json_document

__all__ = ["CALIBRATION_FORMAT", "CALIBRATION_VERSION", "read_calibration_document", "write_calibration_document"]

#: Value of the calibration file's ``"format"`` key.
CALIBRATION_FORMAT = "fsrlab-calibration"
#: Version of the calibration file's layout.
CALIBRATION_VERSION = 1


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
        One line naming the file and what is wrong.
    """
    return read_json_document(Path(path), CALIBRATION_FORMAT, CALIBRATION_VERSION, "calibration")
