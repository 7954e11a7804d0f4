"""`fsrlab oscillator`, `fsrlab decode`, `fsrlab design` through fsrlab.cli.main.

References: the library functions they wrap (fsrlab.circuits.lm555; each of those is tested against
independent closed forms and ngspice in tests/circuits/), and the JSON keys the commands document.
"""

from __future__ import annotations

import json

import pytest

from clirun import run_cli
from fsrlab.circuits.decode import decode
from fsrlab.circuits.lm555 import astable
from toolcheck import require_tool


def test_oscillator_json_keys_and_values(capsys):
    code, out, _ = run_cli(["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--coff", "470p",
                        "--diode", "--json"], capsys)
    assert code == 0
    data = json.loads(out)
    assert set(data) == {"frequency_hz", "duty_cycle", "tau_high_s", "tau_low_s", "n_ratio",
                         "sensitivity_c", "sensitivity_r"}
    ref = astable(10e3, 200e3, 1e-9, 470e-12, diode=True)
    assert data["frequency_hz"] == pytest.approx(ref.frequency_hz, rel=1e-12)
    assert data["n_ratio"] == 20.0
    assert data["sensitivity_c"] == pytest.approx(-1 / 1.47, rel=1e-12)


def test_oscillator_diode_drop_implies_diode(capsys):
    code, out, _ = run_cli(["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--diode-drop", "0.6",
                        "--json"], capsys)
    assert code == 0
    ref = astable(10e3, 200e3, 1e-9, diode=True, diode_drop_v=0.6)
    assert json.loads(out)["duty_cycle"] == pytest.approx(ref.duty_cycle, rel=1e-12)


def test_oscillator_spice_keys(capsys):
    require_tool("ngspice")
    code, out, _ = run_cli(["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--spice", "--json"], capsys)
    data = json.loads(out)
    assert code == 0 and {"spice_frequency_hz", "spice_duty_cycle"} <= set(data)
    # as tests/circuits/test_spice.py
    assert data["spice_frequency_hz"] == pytest.approx(data["frequency_hz"], rel=1e-3)


def test_oscillator_text_output(capsys):
    code, out, _ = run_cli(["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--diode"], capsys)
    assert code == 0
    assert "6.4785 kHz" in out and "10.19 %" in out and "oscillates for N > 4" in out


def test_no_oscillation_exits_2_with_one_line(capsys):
    code, out, err = run_cli(["oscillator", "--r", "10k", "--rfsr", "35k", "--cfsr", "1n"], capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "no oscillation" in err and "N = R_FSR/R = 3.5 must exceed 4" in err


@pytest.mark.parametrize("args, needle", [
    (["oscillator", "--r", "ten", "--rfsr", "200k", "--cfsr", "1n"], "--r"),
    (["oscillator", "--r", "-10k", "--rfsr", "200k", "--cfsr", "1n"], "--r"),
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--diode-drop", "-1"], "--diode-drop"),
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--rdis", "-5"], "--rdis"),
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--coff", "-1n"], "--coff"),
    (["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--vctrl", "6"], "--vctrl"),
    (["decode", "--r", "10k", "--frequency", "6k", "--duty", "0.9", "--vcc", "-1"], "--vcc"),
    (["decode", "--r", "10k", "--frequency", "6478.5", "--duty", "0.5"], "--duty"),
    (["decode", "--r", "10k", "--frequency", "1M", "--duty", "0.5", "--coff", "1n", "--diode"], "--coff"),
    (["design", "--rfsr-min", "100k", "--rfsr-max", "2M", "--cfsr-min", "0.5n", "--cfsr-max", "1.5n",
      "--fmin", "9k", "--fmax", "10k", "--variant", "diode"], "span at least"),
    (["design", "--rfsr-min", "100k", "--rfsr-max", "2M", "--cfsr-min", "0.5n", "--cfsr-max", "1.5n",
      "--fmin", "1k", "--fmax", "20k", "--variant", "maybe"], "--variant"),
])
def test_bad_input_one_line_exit_2(args, needle, capsys):
    code, out, err = run_cli(args, capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and needle in err


def test_decode_json_round_trip(capsys):
    # The README's example: f = 6478.5 Hz, DC = 0.10189 with D1 and R = 10k is R_FSR ≈ 200k, C ≈ 1n
    # (to the 5 printed digits: 1e-4 relative).
    code, out, _ = run_cli(["decode", "--r", "10k", "--frequency", "6478.5", "--duty", "0.10189", "--diode",
                        "--json"], capsys)
    data = json.loads(out)
    assert code == 0
    assert set(data) == {"r_fsr_ohm", "c_fsr_farad", "r_fsr_std_ohm", "c_fsr_std_farad"}
    assert data["r_fsr_ohm"] == pytest.approx(200e3, rel=1e-4)
    assert data["c_fsr_farad"] == pytest.approx(1e-9, rel=1e-4)
    ref = decode(6478.5, 0.10189, 10e3, diode=True)
    assert data["r_fsr_std_ohm"] == pytest.approx(ref.r_fsr_std_ohm, rel=1e-12)


def test_design_text_and_json(capsys):
    args = ["design", "--rfsr-min", "100k", "--rfsr-max", "2M", "--cfsr-min", "0.5n", "--cfsr-max", "1.5n",
            "--fmin", "1k", "--fmax", "20k"]
    code, out, _ = run_cli(args, capsys)
    assert code == 0 and "Proposal:" in out and "Uno resolution" in out
    code, out, _ = run_cli(args + ["--json"], capsys)
    data = json.loads(out)
    assert code == 0
    assert 1e3 <= data["frequency_range_hz"][0] <= data["frequency_range_hz"][1] <= 20e3
    assert data["margin"] >= 0.25


def test_control_pin_option(capsys):
    code, out, _ = run_cli(["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n",
                            "--vctrl", "4", "--json"], capsys)
    ref = astable(10e3, 200e3, 1e-9, lower_fraction=0.4, upper_fraction=0.8)
    assert code == 0 and json.loads(out)["frequency_hz"] == pytest.approx(ref.frequency_hz, rel=1e-12)
    code, _, err = run_cli(["oscillator", "--r", "10k", "--rfsr", "70k", "--cfsr", "1n", "--vctrl", "4"], capsys)
    assert code == 2 and "must exceed 8" in err  # N = 7 < N_min = 8 with the moved threshold


def test_spice_failure_is_one_line_exit_1(monkeypatch):
    # The simulator failing is not the user's input (exit 1, not 2), and never a traceback.
    from fsrlab.circuits import circuit, spice

    def broken(self, *args, **kwargs):
        raise RuntimeError("ngspice failed (exit 1):\n  Error: no such vector time")

    monkeypatch.setattr(spice, "ngspice_available", lambda: True)
    monkeypatch.setattr(circuit.LM555Circuit, "simulate_spice", broken)
    code, out, err = run_cli(["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--spice"])
    assert code == 1 and out == ""
    assert err == "fsrlab: --spice: ngspice failed (exit 1): Error: no such vector time\n"
