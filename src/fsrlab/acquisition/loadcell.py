"""The load cell and its HX711 as a pure model, and the load-cell calibration (tare and scale).

The reference force of a bench comes from a strain-gauge load cell under the FSR, read by an HX711
24-bit ADC (gain 128, channel A) on the same Arduino (docs/protocol.md, version 2). Two pieces:

- :class:`LoadCellModel` says what the HX711 reports for a force: ``raw = offset + drift·t +
  scale·F + noise``, rounded and clipped to the 24-bit two's-complement range; one conversion every
  ``1/rate`` seconds (10 or 80 samples/s), each the mean of the force over the conversion period
  that ends with it. :func:`window_reference` gives what one ``M`` frame carries for a window
  (``ref_ok``, ``ref_n``, ``ref_mean`` rounded as the firmware does): 0..n conversions per window,
  and a lag of half a conversion period behind the force (50 ms at 10 samples/s) — the FSR's
  window, by contrast, is centred on its own middle.
- :class:`LoadCellCalibration` is the calibration of one load cell, like the HX711 libraries'
  ``tare()`` and ``set_scale()``: ``force = (raw − offset) / scale``, stored as a small JSON file
  with its date, the mass and g used, and the noise of the readings (:func:`load_loadcell`,
  :meth:`LoadCellCalibration.save`). :func:`tare_from_readings` refuses an unstable reading
  (:data:`TARE_STABILITY`).

The default model is a 5 kg, 2 mV/V bar load cell excited at 5 V into the HX711 at gain 128
(input range ±0.5·AVDD/128 = ±19.5 mV): 10 mV at 49 N is 10/19.53 · 2²³ ≈ 4.3·10⁶ counts, i.e.
about 87 600 counts/N.

References
----------
.. [1] Avia Semiconductor, HX711 24-bit ADC for weigh scales, datasheet (output data rate 10 or
       80 samples/s; gain 128 on channel A: full-scale differential input ±20 mV at AVDD = 5 V;
       output 24-bit two's complement, 800000h..7FFFFFh).
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fsrlab.acquisition.protocol import HX711_MAX, HX711_MIN
from fsrlab.errors import FsrlabError, ParameterError
from fsrlab.physics.params import check_at_least, check_between, check_finite, check_int, check_positive, float_array
from fsrlab.units import STANDARD_GRAVITY

__all__ = ["HX711_RATES", "STANDARD_GRAVITY", "TARE_STABILITY", "LoadCellModel", "WindowReference",
           "window_reference", "LoadCellCalibration", "load_loadcell", "tare_from_readings",
           "scale_from_readings", "LoadCellError", "raw_to_force"]

HX711_RATES = (10, 80)
"""Output data rates of the HX711 (pin RATE low: 10, high: 80). [samples/s]"""


TARE_STABILITY = {"min_samples": 5, "max_drift_sigmas": 4.0, "max_relative_spread": 1e-3}
"""When a tare (or a scale reading) is accepted: at least ``min_samples`` readings (window means of
the HX711's conversions), and the drift between the first and the second half of them (the
difference of their means) within ``max_drift_sigmas`` standard errors of that difference (white
noise alone exceeds 4 standard errors once in 16 000 readings) *or* within ``max_relative_spread``
of the cell's span (capacity × scale, when both are known); anything else is an unstable reading
(something still moving or settling on the cell) and is refused."""


class LoadCellError(FsrlabError, ValueError):
    """A load-cell calibration cannot be made or read; the message says why (one line).

    Parameters
    ----------
    reason, parameter
        As for :class:`~fsrlab.errors.FsrlabError`: the message and the parameter at fault.
    """


@dataclass(frozen=True)
class LoadCellModel:
    """A load cell read by an HX711: what the 24-bit ADC reports for a force.

    Parameters
    ----------
    offset_counts : float
        Reading with no force (bridge imbalance and ADC offset). [count]
    scale_counts_per_n : float
        Counts per newton (> 0; a cell mounted the other way round gives a negative one, not modelled). [count/N]
    noise_counts : float
        Standard deviation of one conversion (≥ 0). [count]
    rate_sps : int
        Output data rate, 10 or 80. [samples/s]
    drift_counts_per_s : float
        Offset drift (creep of the cell, warm-up of the bridge). [count/s]
    capacity_n : float
        Rated capacity (> 0): informative (the span a calibration is judged against). [N]
    phase_s : float
        Time of the first conversion after START, 0 ≤ phase < 1/rate (the HX711 runs on its own clock). [s]
    """

    offset_counts: float = 8192.0
    scale_counts_per_n: float = 87600.0
    noise_counts: float = 40.0
    rate_sps: int = 80
    drift_counts_per_s: float = 0.0
    capacity_n: float = 5.0 * STANDARD_GRAVITY
    phase_s: float = 0.0037

    def __post_init__(self) -> None:
        rate = self.rate_sps
        if isinstance(rate, bool) or not isinstance(rate, (int, float, np.integer, np.floating)) \
                or rate not in HX711_RATES:
            raise ParameterError(f"must be 10 or 80 samples/s, got {rate!r}", parameter="rate_sps")
        check_positive("scale_counts_per_n", self.scale_counts_per_n, "count/N", scalar=True)
        check_at_least("noise_counts", self.noise_counts, 0.0, "count", scalar=True)
        check_positive("capacity_n", self.capacity_n, "N", scalar=True)
        check_finite("offset_counts", self.offset_counts, scalar=True)
        check_finite("drift_counts_per_s", self.drift_counts_per_s, scalar=True)
        check_between("phase_s", self.phase_s, 0.0, 1.0 / rate, "s", upper_open=True, scalar=True)

    @property
    def period_s(self) -> float:
        """Time between conversions, 1/rate. [s]"""
        return 1.0 / self.rate_sps

    @property
    def lag_s(self) -> float:
        """Mean delay of a conversion behind the force: half a conversion period. [s]"""
        return 0.5 / self.rate_sps

    def calibration(self) -> LoadCellCalibration:
        """The exact calibration of this cell (its own offset and scale): what a perfect tare and
        scale would find; the virtual bench's default."""
        return LoadCellCalibration(self.offset_counts, self.scale_counts_per_n, self.capacity_n, _now(),
                                   {"source": "the virtual load cell's model parameters (fsrlab.acquisition.loadcell."
                                              "LoadCellModel)", "noise_counts": self.noise_counts})

    def conversion_times(self, t0_s: float, t1_s: float) -> np.ndarray:
        """Times of the conversions that complete in ``[t0_s, t1_s)`` (time since START). [s]"""
        p = self.period_s
        k0 = math.ceil((t0_s - self.phase_s) / p - 1e-9)
        k1 = math.ceil((t1_s - self.phase_s) / p - 1e-9)
        k = np.arange(max(k0, 0), max(k1, 0))
        return self.phase_s + k * p

    def raw(self, force_n, t_s=0.0, rng: np.random.Generator | None = None) -> np.ndarray:
        """Raw counts for a force: ``offset + drift·t + scale·F + noise``, rounded, clipped to 24 bits.

        Parameters
        ----------
        force_n : float or array_like
            Force on the cell (the mean over the conversion). [N]
        t_s : float or array_like
            Time since START (for the drift). [s]
        rng : numpy.random.Generator, optional
            Noise source; without one the reading is noiseless.

        Returns
        -------
        ndarray
            Counts, integers in HX711_MIN..HX711_MAX (the HX711 saturates there). [count]
        """
        f = np.asarray(force_n, dtype=float)
        value = self.offset_counts + self.drift_counts_per_s * np.asarray(t_s,
                                                                          dtype=float) + self.scale_counts_per_n * f
        if rng is not None and self.noise_counts > 0:
            value = value + rng.normal(0.0, self.noise_counts, np.shape(value))
        return np.clip(np.round(value), HX711_MIN, HX711_MAX)


@dataclass(frozen=True)
class WindowReference:
    """What an ``M`` frame carries about the load cell for one window (protocol version 2).

    Attributes
    ----------
    ref_ok : int
        1: a conversion completed in the last second; 0: no HX711 (or it stopped answering).
    ref_n : int
        Conversions completed in the window.
    ref_mean : int
        Their mean as the firmware rounds it, ``floor(sum/n + 1/2)``; 0 when ``ref_n`` is 0 (on the
        wire; the host reads NaN). [count]
    """

    ref_ok: int
    ref_n: int
    ref_mean: int


def window_reference(model: LoadCellModel | None, force_at: Callable[[np.ndarray], np.ndarray], t0_s: float,
                     t1_s: float, rng: np.random.Generator | None = None, substeps: int = 8) -> WindowReference:
    """The load cell's part of the ``M`` frame for the window ``[t0_s, t1_s)``.

    Parameters
    ----------
    model : LoadCellModel or None
        The cell; None for a meter without an HX711 (``ref_ok`` 0).
    force_at : callable
        ``force_at(t) -> force [N]`` for an array of times since START [s].
    t0_s, t1_s : float
        The window (time since START). [s]
    rng : numpy.random.Generator, optional
        Noise source.
    substeps : int
        Points averaged over each conversion period (the conversion integrates its period).

    Returns
    -------
    WindowReference
    """
    if model is None:
        return WindowReference(0, 0, 0)
    if not isinstance(model, LoadCellModel):
        raise ParameterError(f"must be a LoadCellModel or None, got {type(model).__name__}", parameter="model")
    if not callable(force_at):
        raise ParameterError(f"must be a function of time, got {type(force_at).__name__}", parameter="force_at")
    check_finite("t0_s", t0_s, scalar=True)
    check_finite("t1_s", t1_s, scalar=True)
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise ParameterError(f"must be a numpy.random.Generator or None, got {type(rng).__name__}", parameter="rng")
    substeps = check_int("substeps", substeps, 1)
    times = model.conversion_times(t0_s, t1_s)
    if times.size == 0:  # a slow HX711 between conversions: it still answers (ref_ok 1)
        return WindowReference(1, 0, 0)
    offsets = (np.arange(substeps) + 0.5) / substeps * model.period_s
    grid = times[:, None] - model.period_s + offsets[None, :]
    force = np.mean(np.asarray(force_at(np.maximum(grid, 0.0)), dtype=float).reshape(grid.shape), axis=1)
    counts = model.raw(force, times, rng)
    mean = math.floor(int(np.sum(counts)) / counts.size + 0.5)  # the firmware's rounding
    return WindowReference(1, int(counts.size), int(mean))


def raw_to_force(raw, offset_counts: float, scale_counts_per_n: float):
    """Force from raw counts: ``F = (raw − offset) / scale``, as the HX711 libraries' ``get_units()``.

    Parameters
    ----------
    raw : float or array_like
        HX711 counts (NaN where none). [count]
    offset_counts : float
        Tare. [count]
    scale_counts_per_n : float
        Scale factor. [count/N]

    Returns
    -------
    float or ndarray
        [N]; NaN where ``raw`` is NaN.
    """
    check_finite("offset_counts", offset_counts, scalar=True)
    check_positive("scale_counts_per_n", scale_counts_per_n, "count/N", scalar=True)
    force = (float_array("raw", raw) - offset_counts) / scale_counts_per_n
    return float(force) if force.ndim == 0 else force


def _readings(counts) -> np.ndarray:
    """The finite conversions of ``counts`` (None and NaN entries left out); one error naming ``counts`` for
    anything but a sequence of numbers. [count]"""
    if counts is None or isinstance(counts, (str, bytes, dict)) or np.ndim(counts) != 1:
        raise ParameterError(f"must be a sequence of HX711 conversions, got {type(counts).__name__}",
                             parameter="counts")
    c = float_array("counts", [math.nan if x is None else x for x in counts])
    return c[np.isfinite(c)]


def _stats(counts: Sequence[float]) -> tuple[float, float, int]:
    c = np.asarray([x for x in counts if x is not None and math.isfinite(x)], dtype=float)
    if c.size == 0:
        return math.nan, math.nan, 0
    return float(np.mean(c)), float(np.std(c, ddof=1)) if c.size > 1 else 0.0, int(c.size)


def _stability(counts: np.ndarray, span_counts: float | None) -> str | None:
    """None when the readings are steady (:data:`TARE_STABILITY`), else why not."""
    crit = TARE_STABILITY
    n = counts.size
    if n < crit["min_samples"]:
        return (f"only {n} load-cell readings (at least {crit['min_samples']} needed): is the HX711 connected "
                "and the reading long enough?")
    a, b = counts[: n // 2], counts[n // 2:]
    drift = float(np.mean(b) - np.mean(a))
    sd = float(np.std(counts, ddof=1))
    se = sd * math.sqrt(1.0 / a.size + 1.0 / b.size)
    if abs(drift) <= crit["max_drift_sigmas"] * se:
        return None
    if span_counts and abs(drift) <= crit["max_relative_spread"] * abs(span_counts):
        return None
    return (f"reading unstable: it moved by {drift:+.0f} counts between the first and second half of {n} "
            f"readings, more than {crit['max_drift_sigmas']:g} standard errors ({crit['max_drift_sigmas'] * se:.0f} "
            "counts)" + (f" and more than {crit['max_relative_spread']:.1%} of the span" if span_counts else "")
            + "; keep the cell unloaded and still, then tare again")


@dataclass(frozen=True)
class LoadCellCalibration:
    """The calibration of one load cell: ``force = (raw − offset) / scale``.

    Parameters
    ----------
    offset_counts : float
        Reading with nothing on the cell (the tare). [count]
    scale_counts_per_n : float or None
        Counts per newton; None until ``fsrlab loadcell scale`` (a tare only). [count/N]
    capacity_n : float or None
        Rated capacity of the cell, the span a scale mass is judged against. [N]
    created : str
        UTC date of the tare (ISO 8601).
    tare : dict
        ``{"date", "n", "mean_counts", "noise_counts"}``: the tare's readings.
    scale : dict or None
        ``{"date", "mass_kg", "gravity_m_s2", "force_n", "n", "mean_counts", "noise_counts",
        "noise_n"}``: the known mass and its readings.
    """

    offset_counts: float
    scale_counts_per_n: float | None = None
    capacity_n: float | None = None
    created: str = ""
    tare: dict = field(default_factory=dict)
    scale: dict | None = None

    FORMAT = "fsrlab-loadcell"
    VERSION = 1

    @property
    def scaled(self) -> bool:
        """Whether a scale factor is known (the calibration gives newtons)."""
        return self.scale_counts_per_n is not None

    def force(self, raw):
        """Force [N] for raw counts (NaN where ``raw`` is NaN); needs a scale factor."""
        if self.scale_counts_per_n is None:
            raise LoadCellError("the load-cell calibration has a tare but no scale factor: run fsrlab loadcell scale")
        return raw_to_force(raw, self.offset_counts, self.scale_counts_per_n)

    def to_dict(self) -> dict:
        """The JSON content (see docs/data-format.md, "Load-cell calibration")."""
        return {"format": self.FORMAT, "version": self.VERSION, "created": self.created,
                "offset_counts": self.offset_counts, "scale_counts_per_n": self.scale_counts_per_n,
                "capacity_n": self.capacity_n, "units": {"offset_counts": "count", "scale_counts_per_n": "count/N",
                                                         "capacity_n": "N"},
                "tare": self.tare, "scale": self.scale}

    def save(self, path) -> None:
        """Write the JSON file atomically (:func:`fsrlab.io.outputs.write_text_atomic`: a temporary file beside
        it, synced and renamed over it; an interrupted save leaves the old file and no temporary one)."""
        from fsrlab.io.outputs import write_text_atomic

        write_text_atomic(path, json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n")


def _number(d: dict, key: str, p: Path, positive: bool = False, optional: bool = False) -> float | None:
    v = d.get(key)
    if v is None and optional:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
        what = "a number > 0" if positive else "a finite number"
        raise LoadCellError(f"{p}: '{key}' must be {what}, got {v!r}", parameter="path")
    return float(v)


def load_loadcell(path) -> LoadCellCalibration:
    """Read a load-cell calibration written by ``fsrlab loadcell`` (:meth:`LoadCellCalibration.save`).

    Parameters
    ----------
    path : str or path-like
        The JSON file.

    Returns
    -------
    LoadCellCalibration

    Raises
    ------
    TypeError, ParameterError
        ``path`` is not a file name, or is empty.
    LoadCellError
        One line naming the file and the key for anything that is not a load-cell calibration; a directory or a
        missing file with ``parameter`` ``"path"``.
    OSError
        The file cannot be read.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: must be a file name, got {type(path).__name__}")
    if not os.fspath(path).strip():
        raise ParameterError("is empty; give the load-cell calibration's file", parameter="path")
    p = Path(path)
    if p.is_dir():
        raise LoadCellError(f"{p}: is a directory, not a load-cell calibration file", parameter="path")
    if not p.exists():
        raise LoadCellError(f"{p}: no such file; write one with fsrlab loadcell tare", parameter="path")
    try:
        d = json.loads(p.read_text(encoding="utf-8"), parse_constant=lambda c: math.nan)
    except UnicodeDecodeError:
        raise LoadCellError(f"{p}: not a load-cell calibration (not UTF-8 text)", parameter="path") from None
    except json.JSONDecodeError as exc:
        raise LoadCellError(f"{p}: not JSON ({exc.msg}, line {exc.lineno})", parameter="path") from None
    if not isinstance(d, dict) or d.get("format") != LoadCellCalibration.FORMAT:
        raise LoadCellError(f"{p}: not a load-cell calibration (\"format\" must be \"{LoadCellCalibration.FORMAT}\"; "
                            "write one with fsrlab loadcell tare)", parameter="path")
    if d.get("version") != LoadCellCalibration.VERSION:
        raise LoadCellError(f"{p}: 'version' must be {LoadCellCalibration.VERSION}, got {d.get('version')!r}",
                            parameter="path")
    offset = _number(d, "offset_counts", p)
    scale = _number(d, "scale_counts_per_n", p, positive=True, optional=True)
    capacity = _number(d, "capacity_n", p, positive=True, optional=True)
    for key in ("tare", "scale"):
        if d.get(key) is not None and not isinstance(d[key], dict):
            raise LoadCellError(f"{p}: '{key}' must be an object, got {type(d[key]).__name__}", parameter="path")
    created = d.get("created", "")
    return LoadCellCalibration(offset, scale, capacity, created if isinstance(created, str) else "",
                               d.get("tare") or {}, d.get("scale"))


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def tare_from_readings(counts: Sequence[float], capacity_n: float | None = None,
                       scale_hint_counts_per_n: float | None = None) -> LoadCellCalibration:
    """A tare (offset) from raw conversions taken with nothing on the cell.

    Parameters
    ----------
    counts : sequence of float
        The HX711 conversions (window means weighted alike; NaN entries are ignored). [count]
    capacity_n : float, optional
        Rated capacity of the cell, stored for the scale step. [N]
    scale_hint_counts_per_n : float, optional
        A known scale, to judge the drift against the span (:data:`TARE_STABILITY`). [count/N]

    Returns
    -------
    LoadCellCalibration
        Offset only (no scale factor yet).

    Raises
    ------
    LoadCellError
        Too few conversions or an unstable reading (the message says which and by how much).
    """
    c = _readings(counts)
    if capacity_n is not None:
        check_positive("capacity_n", capacity_n, "N", scalar=True)
    span = capacity_n * scale_hint_counts_per_n if capacity_n and scale_hint_counts_per_n else None
    why = _stability(c, span)
    if why:
        raise LoadCellError(f"tare refused: {why}", parameter="counts")
    mean, sd, n = _stats(c)
    date = _now()
    return LoadCellCalibration(mean, None, capacity_n, date,
                               {"date": date, "n": n, "mean_counts": mean, "noise_counts": sd})


def scale_from_readings(cal: LoadCellCalibration, counts: Sequence[float], mass_kg: float,
                        gravity_m_s2: float = STANDARD_GRAVITY) -> tuple[LoadCellCalibration, str | None]:
    """The scale factor from raw conversions with a known mass on the tared cell.

    ``scale = (mean − offset) / (m·g)`` [count/N], as the HX711 libraries' ``set_scale()``.

    Parameters
    ----------
    cal : LoadCellCalibration
        The tare (its offset).
    counts : sequence of float
        Conversions with the mass on the cell. [count]
    mass_kg : float
        The known mass (> 0). [kg]
    gravity_m_s2 : float
        Local acceleration of gravity (> 0), standard gravity 9.80665 by default. [m/s²]

    Returns
    -------
    (LoadCellCalibration, str or None)
        The calibration with its scale, and a warning when the mass is below 5 % of the cell's
        capacity (``capacity_n``; a scale from a small fraction of the span magnifies the noise and the
        cell's nonlinearity across the rest of it).

    Raises
    ------
    LoadCellError
        No conversions, an unstable reading, or a reading not above the tare.
    """
    if not isinstance(cal, LoadCellCalibration):
        raise ParameterError(f"must be a LoadCellCalibration (a tare), got {type(cal).__name__}", parameter="cal")
    check_positive("mass_kg", mass_kg, "kg", scalar=True)
    check_positive("gravity_m_s2", gravity_m_s2, "m/s²", scalar=True)
    c = _readings(counts)
    force = mass_kg * gravity_m_s2
    estimate = (float(np.mean(c)) - cal.offset_counts) / force if c.size else 0.0
    why = _stability(c, abs(estimate) * cal.capacity_n if cal.capacity_n else None)
    if why:
        raise LoadCellError(f"scale refused: {why.replace('unloaded', 'loaded').replace('tare again', 'try again')}",
                            parameter="counts")
    mean, sd, n = _stats(c)
    delta = mean - cal.offset_counts
    tare_noise = float(cal.tare.get("noise_counts") or 0.0) if isinstance(cal.tare, dict) else 0.0
    if not abs(delta) > 5 * max(sd, tare_noise, 1.0):
        raise LoadCellError(f"scale refused: the reading with {mass_kg * 1e3:g} g is {delta:+.0f} counts from the "
                "tare, "
                            f"within the noise ({max(sd, tare_noise):.0f} counts): is the mass on the cell?")
    if delta < 0:
        raise LoadCellError(f"scale refused: the reading fell by {-delta:.0f} counts with the mass on: the cell is "
                            "loaded the wrong way (or its signal wires A+/A- are swapped)")
    scale = delta / force
    warning = None
    if cal.capacity_n and force < 0.05 * cal.capacity_n:
        warning = (f"the scale mass ({mass_kg * 1e3:g} g, {force:.3g} N) is below 5 % of the load cell's capacity "
                   f"({cal.capacity_n:.3g} N): the scale factor's error is magnified across the rest of the span; "
                   "use a larger mass")
    date = _now()
    return LoadCellCalibration(cal.offset_counts, scale, cal.capacity_n, cal.created, dict(cal.tare),
                               {"date": date, "mass_kg": mass_kg, "gravity_m_s2": gravity_m_s2, "force_n": force,
                                "n": n, "mean_counts": mean, "noise_counts": sd,
                                "noise_n": sd / scale}), warning
