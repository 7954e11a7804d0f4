"""Option parsers of cli/options.py, through ``fsrlab.cli.main`` as a user meets them.

Reference: the parsers' contract in cli/options.py and docs/architecture.md (one line on stderr that
names the option, exit code 2); spellings follow the SI Brochure and part labels (see test_units.py).
A probe command is added to the app for the duration of each test.
"""

import json

import numpy as np
import pytest
import typer

from clirun import run_cli
from fsrlab.cli import app
from fsrlab.cli.options import (
    electronvolts,
    emit_json,
    fail,
    farads,
    fraction,
    hertz,
    metres,
    number,
    ohms,
    option_names,
    pascals,
    plain_numbers,
    seconds,
    volts,
)
from fsrlab.errors import ParameterError

PARSERS = {"--r": ohms, "--c": farads, "--v": volts, "--f": hertz, "--p": pascals, "--s": metres,
           "--ev": electronvolts, "--t": seconds, "--duty": fraction, "--n": number}


@pytest.fixture
def probe():
    def command(
        r: float = typer.Option(None, "--r", parser=ohms), c: float = typer.Option(None, "--c", parser=farads),
        v: float = typer.Option(None, "--v", parser=volts), f: float = typer.Option(None, "--f", parser=hertz),
        p: float = typer.Option(None, "--p", parser=pascals), s: float = typer.Option(None, "--s", parser=metres),
        ev: float = typer.Option(None, "--ev", parser=electronvolts),
        t: float = typer.Option(None, "--t", parser=seconds),
        duty: float = typer.Option(None, "--duty", parser=fraction),
        n: float = typer.Option(None, "--n", parser=number),
        model_error: bool = typer.Option(False, "--model-error"),
        fail_numpy: bool = typer.Option(False, "--fail-numpy"),
        model_error_inside: bool = typer.Option(False, "--model-error-inside"),
    ) -> None:
        if model_error_inside:
            with option_names({"modulus_pa": "--modulus"}):  # an error that names no parameter of the mapping
                raise ParameterError(f"no solution: the film must be thinner than {np.float64(2.5)!r} nm")
        if model_error:
            with option_names({"modulus_pa": "--modulus", "sigma_f_pa": "--sigma-f"}):
                raise ParameterError(f"must be above the fracture stress ({np.float64(322e3)!r} Pa), "
                                     f"got {np.float64(37.8)!r}", parameter="modulus_pa")
        if fail_numpy:
            fail(f"must be > 0, got {np.float64(-1.5)!r}", "--r")
        emit_json({"r": r, "c": c, "v": v, "f": f, "p": p, "s": s, "ev": ev, "t": t, "duty": duty, "n": n})

    app.command("probe-units")(command)
    yield lambda *args: run_cli(["probe-units", *args])
    app.registered_commands[:] = [i for i in app.registered_commands if i.name != "probe-units"]


@pytest.mark.parametrize("option, text, key, value", [
    ("--r", "10k", "r", 10e3), ("--r", "10kohm", "r", 10e3), ("--r", "10kΩ", "r", 10e3), ("--r", "4k7", "r", 4.7e3),
    ("--r", "1M", "r", 1e6), ("--r", "1meg", "r", 1e6), ("--c", "4.7nF", "c", 4.7e-9), ("--c", "470p", "c", 470e-12),
    ("--v", "5V", "v", 5.0), ("--f", "6.4785kHz", "f", 6478.5), ("--p", "4.73MPa", "p", 4.73e6),
    ("--s", "4.418nm", "s", 4.418e-9), ("--ev", "223meV", "ev", 0.223),
    ("--t", "90", "t", 90.0), ("--t", "90s", "t", 90.0), ("--t", "1.5min", "t", 90.0), ("--t", "2h", "t", 7200.0),
    ("--t", "500ms", "t", 0.5), ("--t", "250us", "t", 250e-6),
    ("--duty", "10%", "duty", 0.1), ("--duty", "0.1", "duty", 0.1), ("--n", "7", "n", 7.0),
])
def test_accepted(probe, option, text, key, value):
    code, out, err = probe(option, text)
    assert (code, err) == (0, "")
    assert json.loads(out)[key] == value


@pytest.mark.parametrize("option, text, needles", [
    ("--r", "1m", ["'1m' is ambiguous", "1M or 1meg for 1 MΩ", "1e-3 for 1 mΩ"]),
    ("--c", "1m", ["'1m' is ambiguous", "1e-3"]),
    ("--r", "10kF", ["capacitance", "in Ω"]),
    ("--c", "1kohm", ["resistance", "in F"]),
    ("--v", "5Hz", ["in V"]), ("--f", "1kV", ["in Hz"]), ("--p", "10kohm", ["in Pa"]),
    ("--t", "1m", ["minutes or milliseconds", "1min", "1ms"]),
    ("--duty", "10", ["not a fraction", "10%", "0.1"]),
    ("--n", "2V", ["without a unit"]),
])
def test_refused_in_one_line_naming_the_option(probe, option, text, needles):
    code, out, err = probe(option, text)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith(f"fsrlab: error: Invalid value for {option}: ")
    for needle in needles:
        assert needle in err


@pytest.mark.parametrize("option", sorted(PARSERS))
@pytest.mark.parametrize("text", ["nan", "inf", "-inf"])
def test_non_finite_values_refused_everywhere(probe, option, text):
    code, out, err = probe(option, text)
    assert code == 2 and out == ""
    assert err == f"fsrlab: error: Invalid value for {option}: must be a finite number, got '{text}'\n"


def test_parsers_keep_numbers_given_as_defaults():
    # typer passes a float default through the parser: it is already in SI units.
    assert ohms(10e3) == 10e3 and seconds(0.1) == 0.1 and fraction(0.25) == 0.25


def test_library_errors_name_the_option_of_their_parameter_with_plain_numbers(probe):
    # Reference: numpy >= 2 writes np.float64(37.8); a user typed 37.8.
    code, _, err = probe("--model-error")
    assert code == 2
    assert err == ("fsrlab: error: Invalid value for --modulus: must be above the fracture stress (322000.0 Pa), "
                   "got 37.8\n")


def test_library_errors_of_no_option_are_one_plain_line(probe):
    # click's "Invalid value: ..." would read as if an option had been named.
    code, _, err = probe("--model-error-inside")
    assert code == 2 and err == "fsrlab: error: no solution: the film must be thinner than 2.5 nm\n"


def test_fail_shows_plain_numbers(probe):
    code, _, err = probe("--fail-numpy")
    assert code == 2 and err == "fsrlab: error: Invalid value for --r: must be > 0, got -1.5\n"


@pytest.mark.parametrize("text, plain", [
    ("got np.float64(37.8)", "got 37.8"), ("got np.int64(3) and numpy.float32(1.5)", "got 3 and 1.5"),
    ("got array([1., 2.])", "got [1., 2.]"), ("got np.str_('abc')", "got abc"), ("no numbers", "no numbers"),
])
def test_plain_numbers(text, plain):
    assert plain_numbers(text) == plain
