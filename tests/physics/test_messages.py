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


# The checks every model uses: the parameter at fault is the error's ``parameter`` and leads its message; a value
# that is no number at all is a TypeError naming it (not numpy's "could not convert string to float").
@pytest.mark.parametrize("value", ["abc", None, {}, b"1"])
def test_a_value_that_is_no_number_is_a_type_error_naming_it(value):
    from fsrlab.physics.params import check_positive, float_array

    for check in (lambda: float_array("s0_m", value), lambda: check_positive("s0_m", value, "m")):
        with pytest.raises(TypeError, match=r"^s0_m: must be a number or an array of numbers, got "):
            check()


@pytest.mark.parametrize("call, parameter, message", [
    (lambda: separation_unloading(0.0, s0_m=np.array([4e-9, 5e-9])), "s0_m",
     "must be a single number, got an array of shape (2,)"),
    (lambda: separation_unloading(0.0, s0_m=-1.0), "s0_m", "must be > 0 m, got -1"),
    (lambda: separation_history([0.0, 1e3], k=float("nan")), "k", "must be finite, got nan"),
])
def test_a_model_parameter_out_of_its_domain_is_named(call, parameter, message):
    with pytest.raises(ParameterError) as info:
        call()
    assert info.value.parameter == parameter and info.value.reason == message
    assert str(info.value) == f"{parameter}: {message}"


def test_a_vectorised_model_keeps_nan_where_its_docstring_says():
    # separation_loading: "NaN where σ < 0 or σ ≥ M" — values, not arguments: no error, no warning.
    import warnings

    from fsrlab.physics.separation import separation_loading

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = separation_loading(np.array([-1.0, 0.0, np.nan, 1e12]))
    assert np.isnan(s[[0, 2, 3]]).all() and s[1] > 0
