"""`fsrlab design` and the meter's capture limit.

Reference: fsrlab.hardware.CAPTURE_MAX_HZ, the firmware's highest frequency with every
edge captured (50 kHz supported; 52.5 kHz measured in simavr, docs/performance.md), and the
closed forms of fsrlab.circuits.lm555 to check a proposal independently.
"""

from __future__ import annotations

import json

import numpy as np

from clirun import run_cli
from fsrlab.circuits.lm555 import astable
from fsrlab.hardware import CAPTURE_MAX_HZ

SENSOR = ["design", "--rfsr-min", "100k", "--rfsr-max", "2M", "--cfsr-min", "0.5n", "--cfsr-max", "1.5n"]


def _independent_range(d: dict) -> tuple[float, float]:
    rf, cf = np.meshgrid(np.geomspace(100e3, 2e6, 200), np.linspace(0.5e-9, 1.5e-9, 20))
    f = astable(d["r_ohm"], rf, cf, d["c_off_farad"], diode=d["diode"]).frequency_hz
    return float(f.min()), float(f.max())


def test_band_beyond_the_meter_exits_2_naming_the_limit():
    # This band used to give a 1–1.85 MHz proposal.
    code, out, err = run_cli(SENSOR + ["--fmin", "1M", "--fmax", "2M"])
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("fsrlab: error: Invalid value for --fmin/--fmax: 1 MHz … 2 MHz is beyond what the "
                          "fsrlab meter captures: every edge only up to 50 kHz")
    assert "--max-frequency" in err


def test_default_proposal_stays_within_what_the_meter_captures():
    code, out, err = run_cli(SENSOR + ["--fmin", "1k", "--fmax", "10M", "--json"])
    assert code == 0 and err == ""
    d = json.loads(out)
    assert d["max_frequency_hz"] == CAPTURE_MAX_HZ and d["band_hz"] == [1e3, CAPTURE_MAX_HZ]
    lo, hi = _independent_range(d)
    assert 1e3 <= lo and hi <= CAPTURE_MAX_HZ


def test_text_output_says_the_band_was_lowered():
    code, out, _ = run_cli(SENSOR + ["--fmin", "1k", "--fmax", "10M"])
    assert code == 0
    assert "band 1 kHz … 50 kHz, --fmax 10 MHz lowered to what the counter captures" in out


def test_max_frequency_designs_for_another_counter():
    code, out, err = run_cli(SENSOR + ["--fmin", "1M", "--fmax", "2M", "--max-frequency", "5MHz", "--json"])
    assert code == 0 and err == ""
    d = json.loads(out)
    lo, hi = _independent_range(d)
    assert 1e6 <= lo and hi <= 2e6
    code, _, err = run_cli(SENSOR + ["--fmin", "1M", "--fmax", "2M", "--max-frequency", "1M"])
    assert code == 2 and "beyond what the counter captures: every edge only up to 1 MHz (--max-frequency)" in err
    code, _, err = run_cli(SENSOR + ["--fmin", "1k", "--fmax", "2k", "--max-frequency", "0"])
    assert code == 2 and err == "fsrlab: error: Invalid value for --max-frequency: must be > 0 Hz, got 0\n"
