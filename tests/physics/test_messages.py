"""Model errors read as plain numbers, whatever number type the caller passed.

Reference: STYLE.md habit 2 (a ParameterError names the parameter and the allowed range); numpy >= 2
writes its scalars as ``np.float64(...)`` under ``repr``, which is not what a user typed.
"""

import numpy as np
import pytest

from fsrlab.errors import ParameterError
from fsrlab.physics.separation import separation_history, separation_unloading


def test_cycle_check_shows_plain_numbers():
    with pytest.raises(ValueError) as info:
        separation_unloading(0.0, sigma_f_pa=np.float64(322e3), s0_m=4.4e-9, modulus_pa=np.float64(100e3))
    assert str(info.value) == "modulus_pa: must be > sigma_f_pa (322000 Pa), got 100000"
    assert info.value.parameter == "modulus_pa"


@pytest.mark.parametrize("call", [
    lambda: separation_unloading(0.0, 322e3, 4.4e-9, 4.73e6, k=np.float64(0.5)),
    lambda: separation_history([0.0, 1e3], k=np.float64(0.5)),
])
def test_exponent_check_shows_plain_numbers(call):
    with pytest.raises(ParameterError, match=r"^k: must be >= 1, got 0\.5$"):
        call()
