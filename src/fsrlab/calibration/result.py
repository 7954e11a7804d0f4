"""A fitted calibration (:class:`Calibration`) and the array-level fit :func:`calibrate`.

:func:`calibrate` fits y(x) as a polynomial whose degree is chosen by grouped cross-validation
(:mod:`fsrlab.calibration.polynomial`); calibrating a recorded run (its cycles, its circuit, the lag,
the model family, the compensation) is :mod:`fsrlab.calibration.fit`, and the calibration file is
:mod:`fsrlab.calibration.document`.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5, Figure 17.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fsrlab.calibration.polynomial import (
    MAX_DEGREE, CrossValidation, PolynomialModel, _prepare, _scaling, cross_validate_degrees, default_groups, fingerprint, fit_metrics,
    fit_polynomial,
)
from fsrlab.io.calibration_file import CALIBRATION_FORMAT

if TYPE_CHECKING:
    from fsrlab.calibration.provenance import RecordedWith
    from fsrlab.circuits.circuit import LM555Circuit

__all__ = ["Calibration", "calibrate"]


@dataclass
class Calibration:
    """A fitted calibration, ready to save and apply.

    Parameters
    ----------
    model : PolynomialModel
        y(x).
    x_name, y_name : str
        Columns (``frequency_hz`` -> ``stress_pa``; ``c_fsr_farad`` for the physics-informed option).
    x_unit, y_unit : str
        Units of x and y.
    r2, rmse, max_error_percent_fs : float
        In-sample fit quality on all readings (RMSE in the unit of y).
    n : int
        Readings used.
    data_fingerprint : str
        See :func:`fingerprint`.
    created : str
        UTC time, ISO 8601.
    cv : CrossValidation or None
        The degree selection, when ``degree="auto"``.
    circuit : LM555Circuit or None
        Circuit through which C_FSR was decoded (physics-informed option).
    source : str
        Where the data came from.
    extra : dict
        Further entries kept in the calibration file.
    compensation : DirectionAwareCalibration or None
        Direction-aware hysteresis compensation fitted on the same data (an extension, see
        :mod:`fsrlab.calibration.compensation`).
    compensation_he_percent : (float, float) or None
        Hysteresis error (eq. 13) of the calibrated stress on the calibration data, plain
        polynomial and compensated. [%]
    recorded_with : RecordedWith or None
        The readout the data were recorded with (circuits, ranges), checked when the calibration
        is applied to another run (:mod:`fsrlab.calibration.provenance`); None when unknown (a
        calibration file written before fsrlab recorded it).
    path : Path or None
        The file the calibration was read from (not stored in the file).
    family : FamilyModel or None
        The chosen model when it is not ``model`` itself (a conductance or power-law family,
        :mod:`fsrlab.calibration.models`); None: the polynomial ``model`` is the calibration.
    lag_s : float or None
        Lag applied when fitting: the readout at t went with the reference at ``t − lag_s``
        (:mod:`fsrlab.calibration.alignment`); None when the run had no time column. [s]
    floor : Floor or None
        The readout's floor (dead zone): readings at it are "below activation".
    memory : MemoryModel or None
        The causal hysteresis compensation (:mod:`fsrlab.calibration.play`).
    uncertainty : Uncertainty or None
        Standard uncertainty per estimate by level and direction (:mod:`fsrlab.calibration.play`),
        of the estimate as applied by default (with the compensation when there is one).
    uncertainty_plain : Uncertainty or None
        The same for the estimate without the compensation (only when there is one).
    candidates : list of dict
        Every candidate model's cross-validated RMSE (``model``, ``cv_rmse``, ``parameters``).
    cv_rmse : float or None
        Cross-validated RMSE of the estimate as applied (with the compensation when fitted). [unit of y]
    full_scale : float or None
        Full scale of the reference (its range over the calibration data). [unit of y]
    """

    model: PolynomialModel
    x_name: str
    y_name: str
    x_unit: str
    y_unit: str
    r2: float
    rmse: float
    max_error_percent_fs: float
    n: int
    data_fingerprint: str
    created: str
    cv: CrossValidation | None = None
    circuit: "LM555Circuit | None" = None
    source: str = ""
    extra: dict = field(default_factory=dict)
    compensation: Any = None  # a DirectionAwareCalibration (fsrlab.calibration.compensation) or None
    compensation_he_percent: tuple[float, float] | None = None
    recorded_with: "RecordedWith | None" = None
    path: Path | None = None
    family: Any = None
    lag_s: float | None = 0.0
    floor: Any = None
    memory: Any = None
    uncertainty: Any = None
    uncertainty_plain: Any = None
    candidates: list = field(default_factory=list)
    cv_rmse: float | None = None
    full_scale: float | None = None

    @property
    def model_name(self) -> str:
        """The chosen model: ``polynomial-3``, ``conductance-power``, ..."""
        return self.family.name if self.family is not None else f"polynomial-{self.degree}"

    @property
    def degree(self) -> int:
        """Polynomial degree."""
        return self.model.degree

    @property
    def x_range(self) -> tuple[float, float]:
        """Calibrated readout range (lowest, highest). [unit of x]"""
        return (self.model.center - self.model.half_width, self.model.center + self.model.half_width)

    def __call__(self, x) -> np.ndarray:
        """y estimated from readout ``x`` by the chosen model (without compensation)."""
        return self.model(x) if self.family is None else self.family(x)

    def inverse(self, y, points: int = 8193) -> np.ndarray:
        """Readout x that the calibration maps to ``y`` (e.g. the frequency expected at a stress).

        Parameters
        ----------
        y : array_like
            Values of the calibrated quantity (stress [Pa]).
        points : int
            Grid points over the calibrated readout range used for the inversion.

        Returns
        -------
        ndarray
            Readout [unit of x]; NaN where ``y`` lies outside the calibrated range.

        Raises
        ------
        ValueError
            If the polynomial is not monotonic over the calibrated range (no unique inverse).

        Notes
        -----
        The polynomial is evaluated on a fine grid of the calibrated readout range and inverted by
        linear interpolation; with 8193 points the interpolation error is below 1e-7 of the range
        for a degree-5 polynomial.
        """
        xs = np.linspace(*self.x_range, points)
        ys = self.model(xs)
        d = np.diff(ys)
        if not (np.all(d > 0) or np.all(d < 0)):
            raise ValueError(f"the degree-{self.degree} calibration is not monotonic over its readout range; "
                             "it has no unique inverse")
        if d[0] < 0:
            xs, ys = xs[::-1], ys[::-1]
        yv = np.asarray(y, dtype=float)
        return np.interp(yv, ys, xs, left=np.nan, right=np.nan)

    def to_dict(self) -> dict[str, Any]:
        """The calibration file's content (``docs/calibration.md``; read back by
        :func:`fsrlab.calibration.document.calibration_from_dict`).

        Returns
        -------
        dict
            JSON-ready; ``circuit`` is :meth:`LM555Circuit.to_dict` or None; ``readout_range`` the
            calibrated readout range [unit of x]; ``recorded_with`` :meth:`RecordedWith.to_dict` or
            None; ``compensation`` (only when fitted) is :meth:`DirectionAwareCalibration.to_dict` with
            the hysteresis errors before and after; the entries of ``extra`` follow.
        """
        d = {
            "format": CALIBRATION_FORMAT,
            "version": 1,
            "model": self.model_name if self.family is not None else "polynomial",
            "basis": "chebyshev",
            "x": self.x_name, "y": self.y_name,
            "units": {"x": self.x_unit, "y": self.y_unit},
            "degree": self.degree,
            "chebyshev_coefficients": self.model.coefficients.tolist(),
            "x_center": self.model.center,
            "x_half_width": self.model.half_width,
            "coefficients": self.model.power_coefficients().tolist(),
            "coefficients_note": "y = sum(coefficients[k] * x**k); evaluation uses the Chebyshev form (better conditioned)",
            "metrics": {"r2": self.r2, "rmse": self.rmse, "max_error_percent_fs": self.max_error_percent_fs, "n": self.n},
            "cross_validation": None if self.cv is None else {
                "degrees": self.cv.degrees, "rmse": self.cv.rmse, "folds": self.cv.folds, "groups": self.cv.groups},
            "data_fingerprint": self.data_fingerprint,
            "created": self.created,
            "circuit": None if self.circuit is None else self.circuit.to_dict(),
            "source": self.source,
            "readout_range": list(self.x_range),
            "recorded_with": None if self.recorded_with is None else self.recorded_with.to_dict(),
        }
        d.update({
            "model_family": None if self.family is None else self.family.to_dict(),
            "lag_s": self.lag_s,
            "floor": None if self.floor is None else self.floor.to_dict(),
            "memory": None if self.memory is None else self.memory.to_dict(),
            "uncertainty": None if self.uncertainty is None else self.uncertainty.to_dict(),
            "uncertainty_plain": None if self.uncertainty_plain is None else self.uncertainty_plain.to_dict(),
            "candidates": self.candidates,
            "cv_rmse": self.cv_rmse,
            "full_scale": self.full_scale,
        })
        if self.memory is not None and self.compensation_he_percent is not None:
            d["memory"]["hysteresis_error_before_percent"], d["memory"]["hysteresis_error_after_percent"] = \
                self.compensation_he_percent
        if self.compensation is not None:
            d["compensation"] = self.compensation.to_dict()
            if self.compensation_he_percent is not None:
                before, after = self.compensation_he_percent
                d["compensation"]["hysteresis_error_before_percent"] = before
                d["compensation"]["hysteresis_error_after_percent"] = after
        d.update(self.extra)
        return d

    def plot(self, ax=None, x=None, y=None, points: int = 200):
        """Draw the calibration curve over its calibrated readout range, with the data if given.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).
        x, y : array_like, optional
            Readings to show as points: readout [unit of x] and reference [unit of y].
        points : int
            Points of the drawn curve.

        Returns
        -------
        matplotlib.axes.Axes
            The data (when given) first, then the polynomial, then the compensation's loading and
            unloading curves (when the calibration holds one).
        """
        if (x is None) != (y is None):
            raise ValueError("x and y: give both (the data) or neither")
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots()
        grid = np.linspace(*self.x_range, points)
        if x is not None:
            ax.plot(np.asarray(x, dtype=float), np.asarray(y, dtype=float), ".", ms=3, alpha=0.5, label="data")
        ax.plot(grid, self(grid), "-", color="k", label=f"degree {self.degree}, R² = {self.r2:.4f}")
        if self.compensation is not None:
            ax.plot(grid, self.compensation.load_model(grid), "--", label="compensation: loading")
            ax.plot(grid, self.compensation.unload_model(grid), "--", label="compensation: unloading")
        ax.set_xlabel(f"{self.x_name} [{self.x_unit}]")
        ax.set_ylabel(f"{self.y_name} [{self.y_unit}]")
        ax.legend()
        return ax


def _finite_pairs(x, y):
    x, y = _prepare(x, y)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3:
        raise ValueError("x, y: fewer than 3 readings with both values present")
    return ok


def calibrate(x, y, degree: int | str = "auto", groups=None, folds: int = 5, x_name: str = "frequency_hz",
              y_name: str = "stress_pa", x_unit: str = "Hz", y_unit: str = "Pa", source: str = "",
              circuit: "LM555Circuit | None" = None) -> Calibration:
    """Fit y(x) as a polynomial, choosing the degree by grouped cross-validation.

    Parameters
    ----------
    x : array_like
        Readout (or the reference for an inverse model). Rows where x or y is NaN are skipped.
    y : array_like
        Reference stress [Pa] (or the readout for an inverse model).
    degree : int or "auto"
        1..5, or ``"auto"``: the lowest degree whose out-of-fold RMSE is within 1 % of the
        smallest (grouped cross-validation, see :func:`cross_validate_degrees`).
    groups : array_like, optional
        Group (cycle) of each reading for the folds (see :func:`default_groups`); default:
        contiguous blocks in time order.
    folds : int
        Folds of the cross-validation (≥ 2).
    x_name, y_name, x_unit, y_unit : str
        Names and units recorded in the calibration.
    source : str
        Provenance recorded in the calibration.
    circuit : LM555Circuit, optional
        Circuit through which x was decoded (physics-informed option), recorded with the calibration.

    Returns
    -------
    Calibration
    """
    x, y = _prepare(x, y)
    ok = _finite_pairs(x, y)
    xs, ys = x[ok], y[ok]
    g = default_groups(x.size, None, folds) if groups is None else np.asarray(groups)
    if g.shape != x.shape:
        raise ValueError("groups must have one label per reading")
    g = g[ok]
    center, half = _scaling(xs)
    cv = None
    if isinstance(degree, str):
        if degree != "auto":
            raise ValueError(f"degree must be an integer from 1 to {MAX_DEGREE} or 'auto', got {degree!r}")
        cv = cross_validate_degrees(xs, ys, g, folds=folds, center=center, half_width=half)
        degree = cv.best_degree
        # Final fit from the same sums (the Chebyshev Gram matrix on [-1, 1] is well conditioned).
        model = PolynomialModel(coefficients=cv.full_fit(degree), center=center, half_width=half)
    else:
        model = fit_polynomial(xs, ys, degree, center, half)
    met = fit_metrics(ys, model(xs))
    return Calibration(model=model, x_name=x_name, y_name=y_name, x_unit=x_unit, y_unit=y_unit, r2=met["r2"],
                       rmse=met["rmse"], max_error_percent_fs=met["max_error_percent_fs"], n=int(xs.size),
                       data_fingerprint=fingerprint(xs, ys),
                       created=datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z"),
                       cv=cv, circuit=circuit, source=source)
