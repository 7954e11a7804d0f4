"""Sensor presets: commercial FSRs by name, with their sensing areas (force = stress × area).

These are manufacturers' catalogue values, not the paper's: the paper's parameters live in
:mod:`fsrlab.physics.params` only. A preset names the sensor in a run's sidecar (``sensor.model``,
``sensor.area_m2``) and turns a reference force into a stress (``stress_pa = force_n / area_m2``).

Sources
-------
- ``flexiforce-a201``: Tekscan FlexiForce A201 datasheet, sensing area 9.53 mm (0.375 in) diameter;
  π·(4.765 mm)² = 71.3 mm² (the same value as :data:`fsrlab.physics.sensor.A201_AREA_M2`).
- ``interlink-402``: Interlink Electronics FSR 400 series datasheet, FSR 402 active area 12.7 mm
  (0.5 in) diameter; π·(6.35 mm)² = 126.7 mm².
- ``paper-a201-1`` … ``paper-a201-4``: the A201's area; their physics (a fitted
  :class:`~fsrlab.physics.paper_sensor.PaperFSR`) is ``fsrlab.physics.paper_sensor.paper_sensor(name)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fsrlab.errors import ParameterError

__all__ = ["SensorPreset", "SENSOR_PRESETS", "sensor_preset"]


@dataclass(frozen=True)
class SensorPreset:
    """A commercial FSR by name.

    Parameters
    ----------
    name : str
        Preset name on the command line (``--sensor``).
    model : str
        Manufacturer and part, as stored in a run's sidecar.
    diameter_m : float
        Diameter of the circular sensing (active) area. [m]
    source : str
        Where the dimension comes from.
    """

    name: str
    model: str
    diameter_m: float
    source: str

    @property
    def area_m2(self) -> float:
        """Sensing area, π·d²/4. [m²]"""
        return math.pi * self.diameter_m**2 / 4.0

    def to_dict(self) -> dict:
        """The sidecar's ``sensor``: ``{"model", "preset", "area_m2", "source"}``."""
        return {"model": self.model, "preset": self.name, "area_m2": self.area_m2, "source": self.source}


SENSOR_PRESETS: dict[str, SensorPreset] = {
    p.name: p for p in (
        SensorPreset("flexiforce-a201", "Tekscan FlexiForce A201", 9.53e-3,
                     "Tekscan FlexiForce A201 datasheet: sensing area 9.53 mm diameter"),
        SensorPreset("interlink-402", "Interlink Electronics FSR 402", 12.7e-3,
                     "Interlink FSR 400 series datasheet: FSR 402 active area 12.7 mm diameter"),
        # The fitted virtual sensors of the paper's §6 (physics: fsrlab.physics.paper_sensor.paper_sensor(name)).
        *(SensorPreset(f"paper-a201-{i}", f"Tekscan FlexiForce A201-1, paper sensor {i} (fitted model)", 9.53e-3,
                       "A201 datasheet area; model fitted to the paper's Tables 3-4 and Figure 19 "
                       "(fsrlab.physics.paper_sensor)") for i in range(1, 5)),
    )
}
"""The presets by name."""


def sensor_preset(name: str) -> SensorPreset:
    """The preset called ``name``.

    Parameters
    ----------
    name : str
        One of :data:`SENSOR_PRESETS` (case-insensitive).

    Returns
    -------
    SensorPreset

    Raises
    ------
    ParameterError
        For an unknown name; the message lists the presets.
    """
    key = name.strip().lower() if isinstance(name, str) else None
    if key not in SENSOR_PRESETS:
        raise ParameterError(f"must be one of {', '.join(SENSOR_PRESETS)}, got {name!r}", parameter="name")
    return SENSOR_PRESETS[key]
