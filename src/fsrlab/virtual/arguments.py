"""Checks of the arguments the virtual instruments share: a seed or random generator, a sensor model.

The numbers themselves are checked with :mod:`fsrlab.physics.params` (``check_positive``, ``check_int``, ...).
"""

from __future__ import annotations

from numbers import Integral

import numpy as np

from fsrlab.errors import ParameterError

__all__ = ["random_generator", "check_sensor"]


def random_generator(name: str, value) -> np.random.Generator:
    """``value`` as a numpy random generator: a Generator as it is, a seed (int >= 0 or None) turned into one.

    Parameters
    ----------
    name : str
        The parameter's name, for the error.
    value : numpy.random.Generator, int or None
        A generator, or a seed.

    Returns
    -------
    numpy.random.Generator

    Raises
    ------
    TypeError
        If ``value`` is neither (the message names ``name``).
    fsrlab.errors.ParameterError
        If the seed is negative.
    """
    if isinstance(value, np.random.Generator):
        return value
    if value is not None and (not isinstance(value, Integral) or isinstance(value, bool)):
        raise TypeError(f"{name}: must be an int seed or a numpy random Generator, got {type(value).__name__}")
    if value is not None and value < 0:
        raise ParameterError(f"must be a seed >= 0, got {value}", parameter=name)
    return np.random.default_rng(value)


def check_sensor(name: str, sensor) -> None:
    """Raise a TypeError naming ``name`` unless ``sensor`` is a sensor model (it has ``respond`` and ``area_m2``).

    Parameters
    ----------
    name : str
        The parameter's name, for the error.
    sensor : object
        A sensor model: :class:`fsrlab.physics.sensor.VirtualFSR` or one of ``fsrlab.physics.paper_sensor``.
    """
    if not callable(getattr(sensor, "respond", None)) or not hasattr(sensor, "area_m2"):
        raise TypeError(f"{name}: must be a sensor model (fsrlab.physics.sensor.VirtualFSR or a paper sensor), "
                        f"got {type(sensor).__name__}")
