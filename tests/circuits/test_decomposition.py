"""Frequency change split into capacitive and resistive parts (fsrlab.circuits.decomposition).

Reference: eq. (35) retyped from the paper (f with the ideal diode D1), and the invariants of the
split (a path where only one of R_FSR, C_FSR changes).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsrlab.circuits.decomposition import frequency_decomposition
from fsrlab.errors import ParameterError


def eq35(r, rf, c):
    """Eq. (35), retyped: f = 1/(ln((2R − 2R_FSR)/(4R − R_FSR))·2R·R_FSR/(2R + R_FSR)·C + ln 2·R_FSR·C)."""
    return 1 / (math.log((2 * r - 2 * rf) / (4 * r - rf)) * 2 * r * rf / (2 * r + rf) * c + math.log(2) * rf * c)


def test_with_diode_each_curve_follows_eq35():
    r = 10e3
    rf = np.array([2e6, 1.5e6, 1e6])
    cf = np.array([500e-12, 600e-12, 700e-12])
    d = frequency_decomposition(r, rf, cf, diode=True)
    np.testing.assert_allclose(d.frequency_hz, [eq35(r, a, b) for a, b in zip(rf, cf, strict=True)], rtol=1e-12)
    np.testing.assert_allclose(d.c_only_hz, [eq35(r, rf[0], b) for b in cf], rtol=1e-12)
    np.testing.assert_allclose(d.r_only_hz, [eq35(r, a, cf[0]) for a in rf], rtol=1e-12)
    # Falling R_FSR raises f with D1; growing C_FSR lowers it.
    assert d.r_only_hz[-1] > d.r_only_hz[0] and d.c_only_hz[-1] < d.c_only_hz[0]
    assert d.to_dict() == {"frequency_hz": [d.frequency_hz[0], d.frequency_hz[-1]],
                           "c_only_hz": [d.c_only_hz[0], d.c_only_hz[-1]],
                           "r_only_hz": [d.r_only_hz[0], d.r_only_hz[-1]]}


@pytest.mark.parametrize("diode", [False, True])
def test_a_purely_capacitive_path_is_all_capacitive(diode):
    rf = np.full(4, 1e6)
    cf = np.linspace(400e-12, 700e-12, 4)
    d = frequency_decomposition(10e3, rf, cf, diode=diode)
    np.testing.assert_array_equal(d.c_only_hz, d.frequency_hz)
    np.testing.assert_allclose(d.r_only_hz, d.frequency_hz[0], rtol=1e-15)


def test_paths_must_match():
    with pytest.raises(ParameterError, match="r_fsr_ohm's length") as info:
        frequency_decomposition(10e3, [1e6, 2e6], [1e-9], diode=True)
    assert info.value.parameter == "c_fsr_farad"
