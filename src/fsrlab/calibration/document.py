"""The calibration file: a :class:`~fsrlab.calibration.result.Calibration` as JSON, and back.

One JSON object (``"format": "fsrlab-calibration"``, ``"version": 1``) holding the polynomial in
its Chebyshev form (what is evaluated) and as plain power coefficients (for other tools), the fit
quality, the cross-validation, the data fingerprint, the circuit through which C_FSR was decoded
(:meth:`fsrlab.circuits.circuit.LM555Circuit.to_dict`) and, when fitted, the direction-aware
compensation; and, for the checks of ``fsrlab apply``, the calibrated readout range
(``"readout_range": [low, high]``, unit of x) and what the data were recorded with
(``"recorded_with"``: :meth:`fsrlab.calibration.provenance.RecordedWith.to_dict`, the run's LM555
circuit and op-amp readout, and the values of its ``range`` column, each null when unknown).

The file also holds the chosen model when it is not the polynomial
(``"model_family"``: :meth:`fsrlab.calibration.models.FamilyModel.to_dict`), the lag applied when
fitting (``"lag_s"``), the readout's floor (``"floor"``), the causal compensation (``"memory"``:
:meth:`fsrlab.calibration.play.MemoryModel.to_dict`, kept apart from the earlier ``"compensation"``
so that an earlier fsrlab still reads the file and applies the polynomial), the uncertainty table
(``"uncertainty"``, and ``"uncertainty_plain"`` for the estimate without the compensation), every candidate's cross-validated error (``"candidates"``), ``"cv_rmse"`` and
``"full_scale"``. Files without these keys load as before (no lag, no floor, no uncertainty).
When the compensation choice kept the branch polynomials, ``"compensation"`` holds them with
``"causal": true`` (applied with causal branch labels, :mod:`fsrlab.calibration.compensation`) and
there is no ``"memory"``; ``"compensation_candidates"`` and ``"compensation_choice"`` (kept in
``Calibration.extra``) record every candidate's cross-validated error and the choice. An earlier
fsrlab reading such a file applies the branches with its offline labels.

Earlier files are read too: those written before the circuit objects stored the decoding circuit
as ``"decode": {"r_ohm", "c_off_farad", "diode", "diode_drop_v"}`` (read as that circuit); those
without ``"recorded_with"`` load with ``Calibration.recorded_with = None`` (nothing to check a run
against), and their readout range is that of the polynomial's mapping (``x_center`` ±
``x_half_width``, the same numbers).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from fsrlab.calibration.compensation import DirectionAwareCalibration
from fsrlab.calibration.heldout_runs import METHOD as HELD_OUT
from fsrlab.calibration.heldout_runs import RunCalibration
from fsrlab.calibration.models import FamilyModel, Floor
from fsrlab.calibration.play import MemoryModel
from fsrlab.calibration.polynomial import CrossValidation, PolynomialModel
from fsrlab.calibration.provenance import RecordedWith
from fsrlab.calibration.result import Calibration
from fsrlab.calibration.uncertainty import Uncertainty
from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.io.calibration_file import CALIBRATION_FORMAT, read_calibration_document, write_calibration_document

__all__ = ["CALIBRATION_FORMAT", "calibration_to_dict", "calibration_from_dict", "save_calibration",
           "load_calibration"]

# Keys this module writes or reads; any other key of a file is kept in ``Calibration.extra``.
_KNOWN = {"format", "version", "model", "basis", "x", "y", "units", "degree", "chebyshev_coefficients", "x_center",
          "x_half_width", "coefficients", "coefficients_note", "metrics", "cross_validation", "data_fingerprint",
          "created", "circuit", "decode", "source", "compensation", "readout_range", "recorded_with",
          "model_family", "lag_s", "floor", "memory", "uncertainty", "candidates", "cv_rmse", "full_scale",
          "uncertainty_plain"}


def calibration_to_dict(cal: Calibration) -> dict[str, Any]:
    """The calibration file's content.

    Parameters
    ----------
    cal : Calibration

    Returns
    -------
    dict
        JSON-ready; ``circuit`` is :meth:`LM555Circuit.to_dict` or None; ``readout_range`` the
        calibrated readout range [unit of x]; ``recorded_with`` :meth:`RecordedWith.to_dict` or
        None; ``compensation`` (only
        when fitted) is :meth:`DirectionAwareCalibration.to_dict` with the hysteresis errors
        before and after; the entries of ``cal.extra`` follow.
    """
    return cal.to_dict()


def _model(m: dict) -> PolynomialModel:
    coef = np.asarray(m["chebyshev_coefficients"], dtype=float)
    center, half = float(m["x_center"]), float(m["x_half_width"])
    if coef.ndim != 1 or coef.size < 1 or not np.all(np.isfinite(coef)):
        raise ValueError("chebyshev_coefficients must be a list of finite numbers")
    if not (np.isfinite(center) and np.isfinite(half) and half > 0):
        raise ValueError("x_center must be finite and x_half_width finite and > 0")
    return PolynomialModel(coef, center, half)


def calibration_from_dict(d: dict) -> Calibration:
    """Inverse of :func:`calibration_to_dict`, for the current and the earlier layout.

    Parameters
    ----------
    d : dict
        A calibration file's content (format and version already checked).

    Returns
    -------
    Calibration

    Raises
    ------
    KeyError, TypeError, ValueError
        An entry missing or malformed.
    """
    met = d.get("metrics", {})
    cvd = d.get("cross_validation")
    cv = None if not cvd else CrossValidation(cvd["degrees"], cvd["rmse"], cvd["folds"], cvd["groups"],
                                              int(d["degree"]))
    # Earlier files: the decoding circuit's parts under "decode" (all of them LM555Circuit fields).
    parts = d.get("circuit") if "circuit" in d else d.get("decode")
    comp = d.get("compensation")
    he = None
    mem = d.get("memory")
    for holder in (comp, mem):
        if holder and "hysteresis_error_before_percent" in holder:
            he = (float(holder["hysteresis_error_before_percent"]), float(holder["hysteresis_error_after_percent"]))
    lag = d.get("lag_s", 0.0)
    if lag is not None and not np.isfinite(float(lag)):
        raise ValueError("lag_s must be a finite number of seconds or null")
    fam, fl, unc, unc0 = d.get("model_family"), d.get("floor"), d.get("uncertainty"), d.get("uncertainty_plain")
    return Calibration(
        model=_model(d), x_name=d["x"], y_name=d["y"], x_unit=d["units"]["x"], y_unit=d["units"]["y"],
        r2=met.get("r2", float("nan")), rmse=met.get("rmse", float("nan")),
        max_error_percent_fs=met.get("max_error_percent_fs", float("nan")), n=met.get("n", 0),
        data_fingerprint=d.get("data_fingerprint", ""), created=d.get("created", ""), cv=cv,
        circuit=None if not parts else LM555Circuit.from_dict(parts), source=d.get("source", ""),
        extra={k: v for k, v in d.items() if k not in _KNOWN},
        compensation=DirectionAwareCalibration.from_dict(comp) if comp else None, compensation_he_percent=he,
        recorded_with=RecordedWith.from_dict(d["recorded_with"]) if d.get("recorded_with") is not None else None,
        family=None if fam is None else FamilyModel.from_dict(fam), lag_s=None if lag is None else float(lag),
        floor=None if fl is None else Floor.from_dict(fl), memory=None if mem is None else MemoryModel.from_dict(mem),
        uncertainty=None if unc is None else Uncertainty.from_dict(unc),
        uncertainty_plain=None if unc0 is None else Uncertainty.from_dict(unc0),
        candidates=list(d.get("candidates") or []),
        cv_rmse=None if d.get("cv_rmse") is None else float(d["cv_rmse"]),
        full_scale=None if d.get("full_scale") is None else float(d["full_scale"]))


def save_calibration(cal: "Calibration | RunCalibration", path: str | os.PathLike) -> Path:
    """Write a calibration to a JSON file.

    Parameters
    ----------
    cal : Calibration or RunCalibration
    path : str or path-like

    Returns
    -------
    Path
    """
    return write_calibration_document(cal.to_dict(), path)


def load_calibration(path: str | os.PathLike) -> "Calibration | RunCalibration":
    """Read a calibration written by :func:`save_calibration` (or by an earlier fsrlab).

    A file with ``"method": "held-out"`` (``fsrlab calibrate``'s, :mod:`fsrlab.calibration.heldout_runs`)
    gives a :class:`~fsrlab.calibration.heldout_runs.RunCalibration`; the others a
    :class:`~fsrlab.calibration.result.Calibration`.

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
    ValueError
        One line naming the file and what is wrong.
    """
    p = Path(path)
    d = read_calibration_document(p)
    try:
        cal = RunCalibration.from_dict(d, p) if d.get("method") == HELD_OUT else calibration_from_dict(d)
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"{p}: calibration file incomplete or malformed ({type(exc).__name__}: {exc})") from None
    lo, hi = cal.x_range
    if isinstance(cal, RunCalibration):
        values = cal.model.curve_estimate(np.linspace(lo, hi, 65))
        if not np.all(np.isfinite(values)) or np.max(np.abs(values)) > _MAX_ESTIMATE:
            raise ValueError(f"{p}: the calibration's curve does not give finite values of {cal.y_name} over its own "
                             f"readout range {lo:.6g} … {hi:.6g} (values changed or damaged)")
        return cal
    with np.errstate(all="ignore"):
        values = cal(np.linspace(lo, hi, 65)) if np.isfinite(lo) and np.isfinite(hi) else np.array([np.nan])
    if not np.all(np.isfinite(values)) or np.max(np.abs(values)) > _MAX_ESTIMATE:
        raise ValueError(f"{p}: the calibration's model does not give finite values of {cal.y_name} over its own "
                         f"readout range {lo:.6g} … {hi:.6g} (coefficients changed or damaged)")
    cal.path = p
    return cal


#: Largest magnitude of a calibrated estimate (far beyond any force [N] or stress [Pa] an FSR sees;
#: larger values mean a damaged coefficient).
_MAX_ESTIMATE = 1e30
