"""The calibration file: a :class:`~fsrlab.calibration.result.Calibration` as JSON, and back.

One JSON object (``"format": "fsrlab-calibration"``, ``"version": 2``): ``method`` (``held-out``),
``model`` (its name), ``x`` and ``y`` (readout and reference columns) with their ``units``, the
calibrated ``readout_range``, ``lag_s``, ``n``, ``r2``, ``created``, ``sources``, ``recorded_with``
(the circuit and range the runs were recorded with, checked when applied:
:meth:`fsrlab.io.recorded.RecordedWith.to_dict`), ``circuit`` (the LM555 C_FSR was decoded
through, or null), ``selection`` (what was tried and why) and ``calibration`` (the curve, the memory,
the uncertainty: :meth:`fsrlab.calibration.model.HeldoutCalibration.to_dict`). docs/calibration.md
describes each entry.

Files of version 1 load too, read-only: those of the held-out engine (``"method": "held-out"``, the same
layout without ``circuit``) and those of the earlier cross-validated engine (a Chebyshev polynomial or a
model family, floor, play-operator memory, uncertainty table: :mod:`fsrlab.calibration.legacy`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from fsrlab.calibration.result import Calibration, require_calibration
from fsrlab.errors import FileFormatError, ParameterError
from fsrlab.io.calibration_file import CALIBRATION_FORMAT, read_calibration_document, write_calibration_document

__all__ = ["CALIBRATION_FORMAT", "save_calibration", "load_calibration"]

#: Largest magnitude of a calibrated estimate (far beyond any force [N] or stress [Pa] an FSR sees;
#: larger values mean a damaged coefficient).
_MAX_ESTIMATE = 1e30


def save_calibration(cal: Calibration, path: str | os.PathLike, overwrite: bool = False, inputs=()) -> Path:
    """Write a calibration to a JSON file, through the output policy (:mod:`fsrlab.io.outputs`).

    Written atomically (an interrupted write leaves the old file or none). An existing file is replaced
    only with ``overwrite=True``; the runs it was calibrated on (``cal.sources``), ``inputs`` and their
    sidecars never are, and an empty path is refused.

    Parameters
    ----------
    cal : Calibration
        From :func:`fsrlab.calibrate` or :func:`load_calibration`.
    path : str or path-like
        The JSON file.
    overwrite : bool
        Replace an existing file.
    inputs : iterable of path-like
        Further files never to replace (with their sidecars), e.g. the runs a command read.

    Returns
    -------
    Path

    Raises
    ------
    ParameterError
        ``cal`` not a :class:`Calibration`, ``overwrite`` not a bool.
    OutputError
        The output refused (a :class:`~fsrlab.errors.ParameterError` naming ``path``).
    """
    from fsrlab.io.outputs import check_output

    require_calibration(cal)
    if not isinstance(overwrite, bool):
        raise ParameterError(f"must be True or False, got {overwrite!r}", parameter="overwrite")
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    try:
        inputs = list(inputs)
    except TypeError:
        raise TypeError("inputs: must be paths (an iterable of str or path-like), got "
                f"{type(inputs).__name__}") from None
    if not all(isinstance(i, (str, os.PathLike)) for i in inputs):
        raise TypeError(f"inputs: must be paths (str or path-like), got {inputs!r}")
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bool):
        raise TypeError(f"path: must be a file's path (str or path-like), got {type(path).__name__}")
    target = check_output(path, "path", overwrite=overwrite, inputs=[*inputs, *cal.sources])
    return write_calibration_document(cal.to_dict(), target)


def load_calibration(path: str | os.PathLike) -> Calibration:
    """Read a calibration written by :func:`save_calibration` (or by an earlier fsrlab).

    Parameters
    ----------
    path : str or path-like
        The JSON file.

    Returns
    -------
    Calibration
        With ``path`` set to the file.

    Raises
    ------
    fsrlab.errors.FileFormatError
        One line naming the file and what is wrong (its parameter ``path``), also when its curve does not
        give finite values over its own readout range (a damaged file); a ParameterError or TypeError for
        a path that is no file.
    """
    d = read_calibration_document(path)
    p = Path(path)
    try:
        cal = Calibration.from_dict(d, p)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:  # a value of another type too
        raise FileFormatError(f"{p}: calibration file incomplete or malformed ({type(exc).__name__}: {exc})",
                              parameter="path") from None
    lo, hi = cal.x_range
    with np.errstate(all="ignore"):
        values = cal.model.curve_estimate(np.linspace(lo, hi, 65)) if np.isfinite(lo) and np.isfinite(hi) \
            else np.array([np.nan])
    if not np.all(np.isfinite(values)) or np.max(np.abs(values)) > _MAX_ESTIMATE:
        raise FileFormatError(f"{p}: the calibration's curve does not give finite values of {cal.y_name} over its "
                              f"own readout range {lo:.6g} … {hi:.6g} (values changed or damaged)", parameter="path")
    return cal
