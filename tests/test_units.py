"""Engineering notation as circuit people write it."""

import pytest
from hypothesis import given, strategies as st

from fsrlab.units import format_eng, parse_eng


@pytest.mark.parametrize("text, value", [
    ("10k", 10e3), ("4.7n", 4.7e-9), ("470p", 470e-12), ("1M", 1e6), ("1meg", 1e6), ("2.2u", 2.2e-6),
    ("2.2µ", 2.2e-6), ("5m", 5e-3), ("4k7", 4.7e3), ("2R2", 2.2), ("4.7nF", 4.7e-9), ("10kohm", 10e3),
    ("10 kΩ", 10e3), ("6478.5", 6478.5), ("1e-9", 1e-9), ("-3.3", -3.3), (".5", 0.5), ("5V", 5.0),
])
def test_parse(text, value):
    assert parse_eng(text) == pytest.approx(value, rel=1e-12)


@pytest.mark.parametrize("text", ["", "abc", "10x", "1..2", "nan", "inf", "k10"])
def test_bad_text_names_the_field(text):
    with pytest.raises(ValueError, match="--r"):
        parse_eng(text, name="--r")


@given(st.floats(1e-14, 1e11))
def test_format_then_parse_round_trips(x):
    # Property: parse(format(x)) = x to the printed digits.
    assert parse_eng(format_eng(x, digits=12).replace(" ", "")) == pytest.approx(x, rel=1e-10)
