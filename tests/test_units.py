"""Engineering notation as circuit people write it."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

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


# parse_quantity: one quantity at a time, refusing what could be misread.
# Reference: SI prefixes and unit symbols (BIPM SI Brochure, 9th ed., §3 and Table 5: the minute is
# "min", the hour "h"); the RKM code of IEC 60062; part labels, where "1M" is a megohm.

from fsrlab.units import QUANTITIES, parse_quantity  # noqa: E402


@pytest.mark.parametrize("text, quantity, value", [
    ("10k", "resistance", 10e3), ("10kohm", "resistance", 10e3), ("10kΩ", "resistance", 10e3),
    ("10 kΩ", "resistance", 10e3), ("10k\u2126", "resistance", 10e3), ("1M", "resistance", 1e6),
    ("1meg", "resistance", 1e6), ("4k7", "resistance", 4.7e3), ("2R2", "resistance", 2.2), ("1e-3", "resistance", 1e-3),
    ("4.7nF", "capacitance", 4.7e-9), ("4.7n", "capacitance", 4.7e-9), ("470p", "capacitance", 470e-12),
    ("4n7", "capacitance", 4.7e-9), ("1µF", "capacitance", 1e-6), ("2.2u", "capacitance", 2.2e-6),
    ("5", "voltage", 5.0), ("5V", "voltage", 5.0), ("600mV", "voltage", 0.6),
    ("6478.5", "frequency", 6478.5), ("6.4785k", "frequency", 6478.5), ("6.4785kHz", "frequency", 6478.5),
    ("322k", "stress", 322e3), ("322kPa", "stress", 322e3), ("4.73MPa", "stress", 4.73e6),
    ("4.418n", "length", 4.418e-9), ("4.418nm", "length", 4.418e-9),
    ("0.223", "energy", 0.223), ("0.223eV", "energy", 0.223), ("223meV", "energy", 0.223),
    ("90", "duration", 90.0), ("90s", "duration", 90.0), ("1.5min", "duration", 90.0), ("2h", "duration", 7200.0),
    ("500ms", "duration", 0.5), ("250us", "duration", 250e-6), ("250µs", "duration", 250e-6),
    ("1.5 min", "duration", 90.0),
    ("10%", "fraction", 0.1), ("0.1", "fraction", 0.1), ("1", "fraction", 1.0), ("150%", "fraction", 1.5),
    ("2", "number", 2.0), ("1e3", "number", 1e3), (7, "number", 7.0), (0.25, "fraction", 0.25),
])
def test_parse_quantity(text, quantity, value):
    assert parse_quantity(text, quantity) == value  # exact: a prefix scales the decimal digits


@pytest.mark.parametrize("text, quantity, needles", [
    # a lower-case m on a resistance or capacitance: mega or milli? Both spellings are shown.
    ("1m", "resistance", ["ambiguous", "1M", "1meg", "1 MΩ", "1e-3", "1 mΩ"]),
    ("4.7m", "resistance", ["4.7M", "4.7meg", "4.7e-3"]),
    ("1m5", "resistance", ["1.5M", "1.5meg", "1.5e-3"]),
    ("1mΩ", "resistance", ["ambiguous", "1M"]),
    ("1m", "capacitance", ["ambiguous", "1e-3", "mF", "1u", "µF"]),
    ("4.7mF", "capacitance", ["ambiguous", "4.7e-3", "4.7u"]),
    # another quantity's unit: the allowed one is named
    ("10kF", "resistance", ["capacitance", "Ω"]), ("10kΩ", "capacitance", ["resistance", "in F"]),
    ("5Hz", "voltage", ["frequency", "in V"]), ("1kV", "frequency", ["voltage", "in Hz"]),
    ("10kohm", "stress", ["resistance", "in Pa"]), ("5V", "duration", ["voltage", "in s"]),
    ("2V", "number", ["voltage", "without a unit"]), ("5V", "fraction", ["voltage"]),
    # minutes or milliseconds?
    ("1m", "duration", ["ambiguous", "minutes or milliseconds", "1min", "1ms"]),
    ("10k", "duration", ["cannot read", "1.5min", "500ms"]),
    # a fraction above 1 without % is refused, never read as percent
    ("10", "fraction", ["not a fraction", "10%", "0.1"]), (3.0, "fraction", ["not a fraction"]),
    ("5m", "length", ["ambiguous", "5mm", "0.005 m", "5 m"]),
    ("abc", "resistance", ["cannot read", "10k"]), ("", "voltage", ["cannot read"]),
])
def test_parse_quantity_refuses_with_a_way_out(text, quantity, needles):
    with pytest.raises(ValueError) as info:
        parse_quantity(text, quantity, name="--x")
    message = str(info.value)
    assert message.startswith("--x: ")
    for needle in needles:
        assert needle in message


@pytest.mark.parametrize("quantity", sorted(QUANTITIES))
@pytest.mark.parametrize("text", ["nan", "NaN", "inf", "-inf", "Infinity", "1e999", float("nan"), float("inf")])
def test_parse_quantity_refuses_non_finite_values(quantity, text):
    with pytest.raises(ValueError, match="--x: must be a finite number"):
        parse_quantity(text, quantity, name="--x")


def test_unknown_quantity_is_named():
    with pytest.raises(ValueError, match="quantity"):
        parse_quantity("1", "mass")


@pytest.mark.parametrize("text", [None, {}, [1, 2], b"10k"])
def test_a_value_that_is_neither_number_nor_text_is_a_type_error_naming_the_field(text):
    with pytest.raises(TypeError, match=r"^r_ohm: must be a number or a str"):
        parse_quantity(text, "resistance", name="r_ohm")
    with pytest.raises(TypeError, match=r"^value: must be a number or a str"):
        parse_eng(text)


def test_a_parse_error_carries_the_field_as_its_parameter():
    from fsrlab.errors import ParameterError

    with pytest.raises(ParameterError) as info:
        parse_quantity("10kF", "resistance", name="r_ohm")
    assert info.value.parameter == "r_ohm" and str(info.value).startswith("r_ohm: '10kF' is a capacitance")
    with pytest.raises(ParameterError) as info:
        parse_quantity("1", "mass")
    assert info.value.parameter == "quantity"


@pytest.mark.parametrize("digits, error", [(0, ValueError), (2.5, TypeError), ("3", TypeError)])
def test_format_eng_checks_its_digits(digits, error):
    with pytest.raises(error, match="digits"):
        format_eng(4.7e-9, "F", digits=digits)
