"""``fsrlab acquire --port``: the meter's circuit as the user gives it, recorded for the provenance check.

References: the sidecar's circuit format (``LM555Circuit.to_dict``, ``OpAmpReadout.to_dict``;
docs/data-format.md); the provenance rule of fsrlab.calibration.provenance (for ``frequency_hz`` the LM555
circuit on each range the run uses, C_off only on range 1); examples/calibration.json, recorded with the
paper's circuit (R = 10 kΩ, ideal D1, 5 V, no C_off; examples/README.md). The meter is the virtual
device on a real pty, reached through --port as hardware is.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from clirun import run_cli
from fsrlab.circuits.circuit import LM555Circuit, OpAmpReadout
from fsrlab.io.runformat import load_run
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import ConstantSource

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_the_circuit_given_is_recorded_and_the_calibration_compares_it(tmp_path):
    with VirtualDevice(ConstantSource(), seed=1) as dev:
        code, _, err = run_cli(["acquire", "--port", dev.port, "--r", "4k7", "--c-off", "1n", "--diode", "--vcc", "5V",
                                "--r-f", "20k", "--duration", "0.5", "--quiet", "--out", tmp_path / "other.csv"])
        assert code == 0, err
        code, _, err = run_cli(["acquire", "--port", dev.port, "--r", "10k", "--c-off", "1n", "--diode",
                                "--duration", "0.5", "--quiet", "--out", tmp_path / "same.csv"])
        assert code == 0, err
    assert "no circuit recorded" not in err
    other = load_run(tmp_path / "other.csv")
    assert other.circuits() == (LM555Circuit(r_ohm=4.7e3, c_off_farad=1e-9, diode=True, vcc_v=5.0),
                               OpAmpReadout(r_f_ohm=20e3, vcc_v=-5.0))
    # A calibration recorded with the paper's circuit refuses the 4.7 kΩ run and takes the 10 kΩ one
    # (range 0: its C_off is out of circuit).
    cal = EXAMPLES / "calibration.json"
    code, _, err = run_cli(["apply", cal, tmp_path / "other.csv", "-o", tmp_path / "other-est.csv"])
    assert code == 2 and err.count("\n") == 1 and "R = 4.7 kΩ" in err and "R = 10 kΩ" in err, err
    assert not (tmp_path / "other-est.csv").exists()
    code, _, err = run_cli(["apply", cal, tmp_path / "same.csv", "-o", tmp_path / "same-est.csv"])
    assert code == 0, err


@pytest.mark.parametrize("args, option, said", [
    (["--r", "10k", "--range", "1"], "--c-off", "--range 1 switches C_off in"),
    (["--diode"], "--diode", "give --r too"),
    (["--c-off", "1n"], "--c-off", "give --r too"),
    (["--r", "10k", "--vcc", "-5"], "--vcc", "supply voltage > 0 V"),
    (["--r", "10k", "--diode-drop", "-0.6"], "--diode-drop", ">= 0 V"),
    (["--r", "1m"], "--r", "ambiguous"),
    (["--drive", "-5"], "--drive", "give --r-f too"),
    (["--r-f", "20k", "--drive", "0"], "--drive", "non-zero"),
])
def test_a_circuit_that_cannot_be_recorded_stops_before_the_device(tmp_path, args, option, said):
    with VirtualDevice(ConstantSource(), seed=2) as dev:
        sent = dev.frames_sent  # the boot ID frame
        code, _, err = run_cli(["acquire", "--port", dev.port, "--duration", "1", "--out", tmp_path / "x.csv", *args])
        assert dev.frames_sent == sent  # the device was never asked anything
    assert code == 2 and err.count("\n") == 1 and option in err and said in err and "Traceback" not in err, err
    assert not list(tmp_path.iterdir())


def test_the_virtual_meter_takes_no_hardware_circuit(tmp_path):
    code, _, err = run_cli(["acquire", "--virtual", "--r", "10k", "--duration", "0.2", "--out", tmp_path / "x.csv"])
    assert code == 2 and err.count("\n") == 1 and "--r" in err and "virtual meter's circuit" in err, err


def test_without_r_the_run_says_it_records_no_circuit(tmp_path):
    with VirtualDevice(ConstantSource(), seed=3) as dev:
        code, out, err = run_cli(["acquire", "--port", dev.port, "--duration", "0.5", "--quiet",
                                  "--out", tmp_path / "x.csv"])
    assert code == 0, err
    assert " windows, " in out and "no circuit recorded (give the meter's --r" in err
    assert load_run(tmp_path / "x.csv").circuits() == (None, None)
