"""``measure``, ``live``, ``bench`` and ``weights`` on --port: the meter's circuit as the user gives it, recorded and
checked as ``acquire`` does (tests/acquisition/test_acquire_circuit.py).

References: the sidecar's circuit format (``LM555Circuit.to_dict``; docs/data-format.md); the provenance rule of
fsrlab.calibration.provenance (for ``frequency_hz`` the LM555 circuit on each range, C_off only on range 1);
examples/calibration.json, recorded with the paper's circuit (R = 10 kΩ, ideal D1, 5 V, C_off 0 throughout: its
run has no range column; examples/README.md); the CLI's one-line error contract (exit 2, the option named). The
meter is the virtual device on a real pty, reached through --port as hardware is; standard input is closed
under pytest, so every prompt of a person is answered "go on".
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from clirun import run_cli
from fsrlab.circuits.circuit import LM555Circuit
from fsrlab.io.runformat import load_run
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import ConstantSource

CAL = Path(__file__).resolve().parents[2] / "examples" / "calibration.json"
PAPER_AS_BUILT = ["--r", "10k", "--diode"]  # the circuit examples/calibration.json was recorded with (range 0)


def _untouched(dev, sent):
    return dev.frames_sent == sent  # nothing but the boot ID frame: the device was never asked anything


def test_measure_records_the_circuit_and_refuses_a_calibration_of_another(tmp_path):
    with VirtualDevice(ConstantSource(), seed=1) as dev:
        sent = dev.frames_sent
        code, _, err = run_cli(["measure", "--port", dev.port, "--r", "4k7", "--diode", "--cal", CAL,
                                "--duration", "0.5", "--quiet", "-o", tmp_path / "other.csv"])
        assert code == 2 and err.count("\n") == 1 and "--cal" in err and "Traceback" not in err, err
        assert "the meter has range 0 (C_off out): R = 4.7 kΩ" in err and "R = 10 kΩ" in err
        assert _untouched(dev, sent) and not list(tmp_path.iterdir())
        code, _, err = run_cli(["measure", "--port", dev.port, *PAPER_AS_BUILT, "--cal", CAL, "--duration", "0.5",
                                "--quiet", "-o", tmp_path / "same.csv"])
    assert code == 0 and "warning" not in err, err
    assert load_run(tmp_path / "same.csv").circuits()[0] == LM555Circuit(r_ohm=10e3, diode=True)
    code, _, err = run_cli(["apply", CAL, tmp_path / "same.csv", "-o", tmp_path / "est.csv"])
    assert code == 0, err  # the run says the circuit the calibration was made on


def test_measure_without_r_says_nothing_is_checked(tmp_path):
    with VirtualDevice(ConstantSource(), seed=2) as dev:
        code, _, err = run_cli(["measure", "--port", dev.port, "--cal", CAL, "--duration", "0.5", "--quiet",
                                "-o", tmp_path / "x.csv"])
    assert code == 0, err
    assert "no circuit recorded (give the meter's --r" in err and f"{CAL} cannot be checked against the meter" in err
    assert load_run(tmp_path / "x.csv").circuits() == (None, None)


def test_live_refuses_a_calibration_of_another_circuit_before_the_device(tmp_path):
    with VirtualDevice(ConstantSource(), seed=3) as dev:
        sent = dev.frames_sent
        code, _, err = run_cli(["live", "--port", dev.port, "--r", "4k7", "--c-off", "1n", "--diode", "--cal", CAL,
                                "--http-port", "0", "--duration", "1s"])
        assert _untouched(dev, sent)
    assert code == 2 and err.count("\n") == 1 and "--cal" in err and "R = 4.7 kΩ" in err and "R = 10 kΩ" in err, err


def test_live_records_the_circuit_and_blanks_the_estimate_on_a_range_it_does_not_fit(tmp_path, monkeypatch):
    # The page's commands (start recording, switch to range 1) sent as the page sends them, once the meter
    # has shown five windows on range 0. On range 1 the meter's C_off (1 nF) is in circuit, which the
    # calibration's run did not have (C_off 0): those windows get no estimate. (The calibration gives stress:
    # the sensor's area makes it the force the page shows.)
    from fsrlab.live.session import LiveSession

    sessions, start = [], LiveSession.start

    def start_and_command(self):
        sessions.append(self)
        estimator = self.estimator

        def estimate(row):
            if len(self._rows) == 5:
                self.command("range", 1)
            return estimator(row)
        self.estimator = estimate
        self.command("record", str(tmp_path / "rec.csv"))
        return start(self)

    monkeypatch.setattr(LiveSession, "start", start_and_command)
    source = ConstantSource(frequency_hz=5000.0)  # inside the calibration's readout range (1.3 to 9.8 kHz)
    with VirtualDevice(source, seed=4) as dev:
        code, out, err = run_cli(["live", "--port", dev.port, *PAPER_AS_BUILT, "--c-off", "1n", "--cal", CAL,
                                  "--sensor", "flexiforce-a201", "--out", tmp_path / "rec.csv",
                                  "--http-port", "0", "--duration", "2s", "--json"])
    assert code == 0 and "warning" not in err, err
    assert load_run(tmp_path / "rec.csv").circuits()[0] == LM555Circuit(r_ohm=10e3, c_off_farad=1e-9, diode=True)
    rows = list(sessions[0]._rows)
    on = {r: [row["estimate"] for row in rows if row["range"] == r] for r in (0, 1)}
    assert on[0] and on[1], json.loads(out.strip().splitlines()[-1])
    assert all(math.isfinite(e) for e in on[0]) and not any(math.isfinite(e) for e in on[1])


def test_bench_and_weights_on_a_port_record_the_circuit(tmp_path):
    with VirtualDevice(ConstantSource(), seed=5) as dev:
        code, _, err = run_cli(["bench", "spring", "--port", dev.port, "--r", "4k7", "--diode", "--cycles", "1",
                                "--period", "0.5s", "--quiet", "-o", tmp_path / "spring.csv"])
        assert code == 0 and "warning" not in err, err
        code, _, err = run_cli(["weights", "--port", dev.port, "--r", "4k7", "--diode", "--vcc", "3.3V",
                                "--masses", "0,100g", "--window", "20ms", "--settle-windows", "2", "--hold", "100ms",
                                "-o", tmp_path / "w.csv"])
        assert code == 0 and "warning" not in err, err
        code, _, err = run_cli(["bench", "creep", "--port", dev.port, "--mass", "100g", "--hold", "0.2s", "--quiet",
                                "-o", tmp_path / "creep.csv"])
    assert code == 0 and "no circuit recorded (give the meter's --r" in err, err
    assert load_run(tmp_path / "spring.csv").circuits()[0] == LM555Circuit(r_ohm=4.7e3, diode=True)
    assert load_run(tmp_path / "w.csv").circuits()[0] == LM555Circuit(r_ohm=4.7e3, diode=True, vcc_v=3.3)
    assert load_run(tmp_path / "creep.csv").circuits() == (None, None)
    # What the sidecar says is what apply checks: the paper-circuit calibration refuses the 4.7 kΩ run.
    code, _, err = run_cli(["apply", CAL, tmp_path / "spring.csv", "-o", tmp_path / "est.csv"])
    assert code == 2 and "R = 4.7 kΩ" in err and "R = 10 kΩ" in err, err


@pytest.mark.parametrize("args, option, said", [
    (["measure", "--cal", CAL, "--diode"], "--diode", "give --r too"),
    (["measure", "--cal", CAL, "--r", "10k", "--vcc", "-5"], "--vcc", "supply voltage > 0 V"),
    (["live", "--r", "10k"], "--c-off", "the page's range switch puts C_off in"),
    (["live", "--drive", "-5"], "--drive", "give --r-f too"),
    (["bench", "spring", "--r", "1m"], "--r", "ambiguous"),
    (["weights", "--masses", "0,100g", "--r", "10k", "--diode-drop", "-0.6"], "--diode-drop", ">= 0 V"),
])
def test_a_circuit_that_cannot_be_recorded_stops_before_the_device(tmp_path, args, option, said):
    with VirtualDevice(ConstantSource(), seed=6) as dev:
        sent = dev.frames_sent
        code, _, err = run_cli([*args, "--port", dev.port, "-o", tmp_path / "x.csv"])
        assert _untouched(dev, sent)
    assert code == 2 and err.count("\n") == 1 and option in err and said in err and "Traceback" not in err, err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("args, option", [
    (["measure", "--virtual", "--cal", CAL, "--r", "10k"], "--r"),
    (["live", "--virtual", "--r-f", "20k"], "--r-f"),
    (["bench", "spring", "--virtual", "--c-off", "1n"], "--c-off"),  # its virtual meter takes no C_off
    (["weights", "--virtual", "--masses", "0,100g", "--diode"], "--diode"),
])
def test_a_virtual_meter_takes_no_hardware_circuit(tmp_path, args, option):
    code, _, err = run_cli([*args, "-o", tmp_path / "x.csv"])
    assert code == 2 and err.count("\n") == 1 and option in err and "virtual meter's circuit" in err, err
    assert not list(tmp_path.iterdir())
