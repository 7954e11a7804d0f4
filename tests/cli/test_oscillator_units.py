"""Units of the `oscillator`, `decode` and `design` options.

Reference: the quantity parsers' contract in cli/options.py and fsrlab.units.parse_quantity (their
own tests are tests/test_units.py and tests/cli/test_parsers.py); here each option of the three
commands must read its own quantity: ``1m`` is refused on resistances and capacitances (1 MΩ or
1 mΩ?), another quantity's unit is refused, ``10%`` is the fraction 0.10.
"""

from __future__ import annotations

import json

import pytest

from clirun import run_cli

BASE = {
    "oscillator": ["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n"],
    "decode": ["decode", "--r", "10k", "--frequency", "6478.5", "--duty", "0.10189", "--diode"],
    "design": ["design", "--rfsr-min", "100k", "--rfsr-max", "2M", "--cfsr-min", "0.5n", "--cfsr-max", "1.5n",
               "--fmin", "1k", "--fmax", "20k"],
}

# Every option of the three commands that takes a physical value, and the quantity it reads.
OPTIONS = {
    "oscillator": {"--r": "Ω", "--rfsr": "Ω", "--rdis": "Ω", "--cfsr": "F", "--coff": "F",
                   "--diode-drop": "V", "--vcc": "V", "--vctrl": "V"},
    "decode": {"--r": "Ω", "--rdis": "Ω", "--frequency": "Hz", "--duty": "1", "--coff": "F",
               "--diode-drop": "V", "--vcc": "V", "--vctrl": "V"},
    "design": {"--rfsr-min": "Ω", "--rfsr-max": "Ω", "--cfsr-min": "F", "--cfsr-max": "F", "--fmin": "Hz",
               "--fmax": "Hz", "--diode-drop": "V", "--vcc": "V", "--margin": "1", "--window": "s"},
}

# A value with another quantity's unit, and what the refusal must say.
WRONG = {"Ω": ("10kF", "in Ω"), "F": ("1kohm", "in F"), "V": ("5Hz", "in V"), "Hz": ("1kV", "in Hz"),
         "1": ("10", "not a fraction"), "s": ("1m", "minutes or milliseconds")}

CASES = [(cmd, opt, unit) for cmd, opts in OPTIONS.items() for opt, unit in opts.items()]


def _with(args: list[str], option: str, value: str) -> list[str]:
    """``args`` with ``option`` set to ``value`` (replaced if present, appended if not)."""
    args = list(args)
    if option in args:
        args[args.index(option) + 1] = value
    else:
        args += [option, value]
    return args


@pytest.mark.parametrize("command, option, unit", CASES, ids=[f"{c} {o}" for c, o, _ in CASES])
def test_each_option_refuses_another_quantitys_unit(command, option, unit):
    value, needle = WRONG[unit]
    code, out, err = run_cli(_with(BASE[command], option, value))
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith(f"fsrlab: error: Invalid value for {option}: ")
    assert needle in err


def test_oscillator_r_1m_is_refused_with_both_spellings():
    # "1m" was silently 1 mΩ.
    code, out, err = run_cli(_with(BASE["oscillator"], "--r", "1m"))
    assert code == 2 and out == ""
    assert err == ("fsrlab: error: Invalid value for --r: '1m' is ambiguous: write 1M or 1meg for 1 MΩ, "
                   "or 1e-3 for 1 mΩ\n")


@pytest.mark.parametrize("option", ["--cfsr", "--coff"])
def test_capacitances_refuse_lower_case_m(option):
    code, _, err = run_cli(_with(BASE["oscillator"], option, "1m"))
    assert code == 2 and f"Invalid value for {option}: '1m' is ambiguous" in err


def _json(args):
    code, out, err = run_cli(args + ["--json"])
    assert (code, err) == (0, ""), err
    return json.loads(out)


def test_decode_duty_in_percent_is_a_fraction():
    # "10.189%" is the duty cycle 0.10189 (the README's decode example), never 10.189.
    assert _json(_with(BASE["decode"], "--duty", "10.189%")) == _json(BASE["decode"])


@pytest.mark.parametrize("command, option, plain, spelled", [
    ("oscillator", "--r", "10k", "10kΩ"), ("oscillator", "--r", "10k", "10kohm"),
    ("oscillator", "--rfsr", "200k", "200kΩ"),
    ("oscillator", "--cfsr", "1n", "1nF"), ("oscillator", "--cfsr", "1n", "1000p"),
    ("oscillator", "--coff", "470p", "470pF"),
    ("oscillator", "--vcc", "5", "5V"), ("oscillator", "--vctrl", "3", "3000mV"),
    ("oscillator", "--rfsr", "1M", "1meg"),
    ("decode", "--frequency", "6478.5", "6.4785kHz"), ("decode", "--r", "10k", "10000"),
    ("design", "--margin", "0.3", "30%"), ("design", "--window", "0.5", "500ms"), ("design", "--fmax", "20k", "20kHz"),
    ("design", "--rfsr-max", "2M", "2meg"), ("design", "--cfsr-min", "0.5n", "500pF"),
])
def test_unit_spellings_give_the_same_result(command, option, plain, spelled):
    assert _json(_with(BASE[command], option, spelled)) == _json(_with(BASE[command], option, plain))
