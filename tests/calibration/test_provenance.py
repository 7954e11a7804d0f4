"""What a calibration was recorded with, and the differences that refuse a run (fsrlab.calibration.provenance).

Reference: the LM555 closed forms the differences stand for (fsrlab.circuits.lm555 via
LM555Circuit.astable): a difference is reported exactly when the same FSR state gives another
frequency, and C_off counts only on range 1 (LM555Circuit.on_range).
"""

from __future__ import annotations

import pytest

from fsrlab.calibration.provenance import mismatches
from fsrlab.circuits.circuit import PAPER_CIRCUIT, PAPER_OPAMP, OpAmpReadout
from fsrlab.io.recorded import RecordedWith

C0 = PAPER_CIRCUIT
C470 = PAPER_CIRCUIT.replace(c_off_farad=470e-12)


def _f(circuit, r=None):
    c = circuit if r is None else circuit.on_range(r)
    return float(c.astable(200e3, 1e-9).frequency_hz)


@pytest.mark.parametrize("cal, run, differs", [
    (RecordedWith(C0), RecordedWith(C0), False),
    (RecordedWith(C0), RecordedWith(PAPER_CIRCUIT.replace(r_ohm=4.7e3)), True),
    (RecordedWith(C470, ranges=(0,)), RecordedWith(C470, ranges=(1,)), True),
    (RecordedWith(C0, ranges=(0,)), RecordedWith(C0, ranges=(1,)), False),  # no C_off: range 1 = range 0
    (RecordedWith(C470, ranges=(0, 1)), RecordedWith(C470, ranges=(1,)), False),
    (RecordedWith(C470), RecordedWith(C470, ranges=(0,)), True),  # C_off in throughout vs out
])
def test_frequency_differences_are_those_that_change_the_frequency(cal, run, differs):
    found = mismatches("frequency_hz", cal, run)
    assert bool(found) == differs
    cal_f = {_f(cal.circuit, r) for r in (cal.ranges or (None,))}
    run_f = {_f(run.circuit, r) for r in (run.ranges or (None,))}
    assert (not run_f <= cal_f) == differs


def test_unknown_parts_are_not_compared_and_ranges_are_when_circuits_are_unknown():
    assert mismatches("frequency_hz", RecordedWith(), RecordedWith(C470, ranges=(1,))) == []
    assert mismatches("frequency_hz", RecordedWith(ranges=(0,)), RecordedWith(ranges=(1,))) == [
        ("range 1 (C_off in)", "range 0 (C_off out)")]


def test_decoded_capacitance_compares_the_circuit_only_and_voltage_the_opamp():
    cal = RecordedWith(C470, PAPER_OPAMP, (0,))
    assert mismatches("c_fsr_farad", cal, RecordedWith(C470, OpAmpReadout(r_f_ohm=10e3, vcc_v=-5.0), (1,))) == []
    assert mismatches("c_fsr_farad", cal, RecordedWith(C0, None, (0,))) == [("C_off = 0 F", "C_off = 470 pF")]
    assert (mismatches("voltage_v", cal, RecordedWith(C0, OpAmpReadout(r_f_ohm=10e3, vcc_v=-5.0)))
            == [("R_F = 10 kΩ", "R_F = 20 kΩ")])
    assert mismatches("stress_pa_estimate", cal, RecordedWith(C0, OpAmpReadout(r_f_ohm=10e3, vcc_v=-5.0))) == []


def test_round_trip_and_bad_range():
    r = RecordedWith(C470, PAPER_OPAMP, (0, 1))
    assert RecordedWith.from_dict(r.to_dict()) == r
    with pytest.raises(ValueError, match="recorded_with.range"):
        RecordedWith.from_dict({"range": [2]})
