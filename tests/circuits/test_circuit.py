"""The circuit objects (fsrlab.circuits.circuit) and the model functions evaluated for them.

References: the model functions themselves (a method must give exactly what the function gives for
``**circuit.kwargs()``), the closed forms for the event-driven transient (1e-9, exact simulation),
ngspice for the same circuit (1e-3, as tests/circuits/test_spice.py), the paper's eqs. (23), (34)
and (38) retyped, and properties (to_dict/from_dict round trip, every part changes the result).
"""

from __future__ import annotations

import json
import math
from dataclasses import fields

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fsrlab.circuits.circuit import PAPER_CIRCUIT, LM555Circuit, OpAmpReadout, readout_from_metadata
from fsrlab.circuits.decode import decode
from fsrlab.circuits.lm555 import astable, sensitivity, thresholds_from_control
from fsrlab.circuits.spice import netlist, simulate_spice
from fsrlab.circuits.transient import simulate
from toolcheck import require_tool

#: Every part away from its default (with D1 the discharge resistance does not matter, see NO_DIODE).
FULL = LM555Circuit(r_ohm=12e3, c_off_farad=220e-12, diode=True, diode_drop_v=0.3, vcc_v=3.3,
                    lower_fraction=0.3, upper_fraction=0.7, discharge_ohm=40.0)
NO_DIODE = FULL.replace(diode=False, diode_drop_v=0.0)
RF, CF = 200e3, 1e-9


circuits = st.builds(
    lambda r, coff, diode, drop, vcc, lo, width, rd: LM555Circuit(
        r_ohm=r, c_off_farad=coff, diode=diode, diode_drop_v=drop if diode else 0.0, vcc_v=vcc,
        lower_fraction=lo, upper_fraction=min(lo + width, 0.95), discharge_ohm=rd),
    st.floats(1.0, 1e7), st.floats(0.0, 1e-6), st.booleans(), st.floats(0.0, 1.0), st.floats(1.0, 20.0),
    st.floats(0.05, 0.6), st.floats(0.02, 0.35), st.floats(0.0, 1e3))


@given(circuits)
def test_to_dict_from_dict_round_trip(circuit):
    d = circuit.to_dict()
    assert d["topology"] == "lm555-astable"
    assert LM555Circuit.from_dict(d) == circuit
    assert LM555Circuit.from_dict(json.loads(json.dumps(d))) == circuit  # through a sidecar file


def test_from_dict_defaults_and_unknown_parts():
    assert LM555Circuit.from_dict({"r_ohm": 22e3}) == LM555Circuit(r_ohm=22e3)
    with pytest.raises(ValueError, match="unknown LM555 part.*r_b_ohm"):
        LM555Circuit.from_dict({"r_b_ohm": 10e3})
    with pytest.raises(ValueError, match="mapping"):
        LM555Circuit.from_dict([10e3])


@pytest.mark.parametrize("parts, name", [
    (dict(r_ohm=0.0), "r_ohm"), (dict(c_off_farad=-1e-12), "c_off_farad"), (dict(diode="yes"), "diode"),
    (dict(diode=False, diode_drop_v=0.6), "diode_drop_v"), (dict(vcc_v=math.inf), "vcc_v"),
    (dict(lower_fraction=0.7), "lower_fraction"), (dict(discharge_ohm=-5.0), "discharge_ohm"),
    (dict(r_ohm="ten"), "r_ohm"),
])
def test_each_part_is_checked(parts, name):
    with pytest.raises(ValueError, match=name):
        LM555Circuit(**{"r_ohm": 10e3, **parts})
    with pytest.raises(ValueError, match=name):
        PAPER_CIRCUIT.replace(**parts)


def test_a_part_without_default_is_required_by_name():
    # Property: the paper's values are not defaults (they live in physics.params only).
    with pytest.raises(ValueError, match="r_ohm"):
        LM555Circuit.from_dict({"diode": True})
    with pytest.raises(ValueError, match="vcc_v"):
        OpAmpReadout.from_dict({"r_f_ohm": 20e3})


def test_with_control_and_on_range():
    c = LM555Circuit.with_control(4.0, r_ohm=10e3)
    assert (c.lower_fraction, c.upper_fraction) == thresholds_from_control(4.0, 5.0)
    with pytest.raises(ValueError, match="control_v"):
        LM555Circuit.with_control(5.5)
    assert FULL.on_range(1) is FULL and FULL.on_range(0) == FULL.replace(c_off_farad=0.0)


def test_kwargs_are_every_field():
    assert set(FULL.kwargs()) == {f.name for f in fields(LM555Circuit)}


def test_paper_circuit_against_eq23_and_eq34():
    # Eqs. (23) and (34) retyped, for fsrlab's R = 10 kΩ with the paper's ideal diode.
    r, rf, c = PAPER_CIRCUIT.r_ohm, RF, CF
    th = math.log((2 * r - 2 * rf) / (4 * r - rf)) * (2 * r * rf / (2 * r + rf)) * c
    tl = math.log(2) * rf * c
    assert PAPER_CIRCUIT.astable(rf, c).frequency_hz == pytest.approx(1 / (th + tl), rel=1e-12)


@pytest.mark.parametrize("circuit", [FULL, NO_DIODE], ids=["diode", "no-diode"])
def test_methods_are_the_functions(circuit):
    kw = circuit.kwargs()
    rf = np.array([150e3, 400e3])
    a = circuit.astable(rf, CF)
    assert_same(a, astable(r_fsr_ohm=rf, c_fsr_farad=CF, **kw))
    assert_same(circuit.sensitivity(rf, CF), sensitivity(r_fsr_ohm=rf, c_fsr_farad=CF, **kw))
    assert_same(circuit.decode(a.frequency_hz, a.duty_cycle, periods=4),
                decode(a.frequency_hz, a.duty_cycle, periods=4, **kw))
    assert_same(circuit.simulate(RF, CF, periods=20, waveform=True),
                simulate(r_fsr_ohm=RF, c_fsr_farad=CF, periods=20, waveform=True, **kw))


def assert_same(got, ref):
    """Result objects equal field by field, exactly (their fields are arrays)."""
    assert type(got) is type(ref)
    for f in fields(ref):
        np.testing.assert_array_equal(getattr(got, f.name), getattr(ref, f.name), err_msg=f.name)


@pytest.mark.parametrize("circuit", [FULL, NO_DIODE], ids=["diode", "no-diode"])
def test_transient_and_decode_honour_every_part(circuit):
    # The exact event-driven transient of this circuit agrees with its closed form (1e-9), and decoding
    # the transient's reading returns the parts (1e-8): each passes all of circuit.kwargs() along.
    sim = circuit.simulate(RF, CF, periods=50)
    ref = circuit.astable(RF, CF)
    assert sim.frequency_hz == pytest.approx(ref.frequency_hz, rel=1e-9)
    assert sim.duty_cycle == pytest.approx(ref.duty_cycle, rel=1e-9)
    d = circuit.decode(sim.frequency_hz, sim.duty_cycle, periods=50)
    assert d.r_fsr_ohm == pytest.approx(RF, rel=1e-8) and d.c_fsr_farad == pytest.approx(CF, rel=1e-8)


@pytest.mark.parametrize("base, change", [
    pytest.param(base, change, id=next(iter(change))) for base, change in [
        (FULL, dict(r_ohm=10e3)), (FULL, dict(c_off_farad=0.0)), (FULL, dict(diode_drop_v=0.0)),
        (FULL, dict(vcc_v=5.0)), (FULL, dict(lower_fraction=0.32)), (FULL, dict(upper_fraction=0.68)),
        (NO_DIODE, dict(discharge_ohm=0.0)), (NO_DIODE, dict(diode=True))]
])
def test_every_part_changes_the_result(base, change):
    # A part the functions silently dropped would leave the frequency unchanged.
    other = base.replace(**change)
    assert astable(r_fsr_ohm=RF, c_fsr_farad=CF, **other.kwargs()).frequency_hz != pytest.approx(
        astable(r_fsr_ohm=RF, c_fsr_farad=CF, **base.kwargs()).frequency_hz, rel=1e-6)
    assert other.simulate(RF, CF, periods=3).frequency_hz != pytest.approx(
        base.simulate(RF, CF, periods=3).frequency_hz, rel=1e-6)


def test_netlist_takes_every_part():
    text = netlist(r_fsr_ohm=RF, c_fsr_farad=CF, t_stop_s=1e-3, t_max_step_s=1e-7, **FULL.kwargs())
    gain = 1e4  # spice.GAIN: the switch thresholds are in amplified volts
    for needle in ("Vcc vcc 0 DC 3.3", "RA vcc dis 12000", "RB dis nb 12000", "Vdrop nb nd DC 0.3",
                   "COFF thr 0 2.2e-10", "RON=40", f"VT={gain * 3.3 * 0.5:.15g}", f"VH={gain * 3.3 * 0.2:.15g}"):
        assert needle in text
    with pytest.raises(ValueError, match="c_fsr_farad"):
        netlist(r_fsr_ohm=RF, c_fsr_farad=-CF, t_stop_s=1e-3, t_max_step_s=1e-7, **FULL.kwargs())
    with pytest.raises(ValueError, match="r_ohm"):
        netlist(r_fsr_ohm=RF, c_fsr_farad=CF, t_stop_s=1e-3, t_max_step_s=1e-7, **{**FULL.kwargs(), "r_ohm": -1.0})


@pytest.mark.parametrize("circuit", [FULL, NO_DIODE], ids=["diode", "no-diode"])
def test_simulate_spice_for_a_circuit(circuit):
    require_tool("ngspice")
    sim = circuit.simulate_spice(RF, CF, periods=8)
    assert_same(sim, simulate_spice(r_fsr_ohm=RF, c_fsr_farad=CF, periods=8, **circuit.kwargs()))
    ref = circuit.astable(RF, CF)
    assert sim.frequency_hz == pytest.approx(ref.frequency_hz, rel=1e-3)
    assert sim.duty_cycle == pytest.approx(ref.duty_cycle, rel=1e-3)


def test_opamp_readout_is_eq38():
    # Eq. (38) retyped: V_out = −(R_F/R_FSR)·Vcc, with the paper's R_F = 20 kΩ and Vcc = −5 V.
    amp = OpAmpReadout(r_f_ohm=20e3, vcc_v=-5.0)
    assert amp.output_v(100e3) == pytest.approx(-(20e3 / 100e3) * -5.0, rel=1e-15)
    assert amp.conductance_s(amp.output_v(100e3)) == pytest.approx(1 / 100e3, rel=1e-15)
    assert OpAmpReadout.from_dict(amp.to_dict()) == amp
    with pytest.raises(ValueError, match="vcc_v"):
        OpAmpReadout(r_f_ohm=20e3, vcc_v=0.0)


def test_readout_from_metadata_reads_current_and_earlier_sidecars():
    now = {"circuit": FULL.to_dict(), "opamp": OpAmpReadout(r_f_ohm=10e3, vcc_v=-5.0).to_dict()}
    assert readout_from_metadata(now) == (FULL, OpAmpReadout(r_f_ohm=10e3, vcc_v=-5.0))
    # Earlier sidecars: op-amp parts beside the LM555's (driven from −vcc_v), or under "traditional".
    old = {"circuit": {"r_ohm": 10e3, "vcc_v": 5.0, "r_f_ohm": 20e3, "topology": "LM555 + diode"}}
    assert readout_from_metadata(old) == (LM555Circuit(r_ohm=10e3), OpAmpReadout(20e3, -5.0))
    older = {"circuit": {"r_ohm": 10e3, "traditional": {"r_f_ohm": 15e3, "vcc_v": -3.3}}}
    assert readout_from_metadata(older)[1] == OpAmpReadout(15e3, -3.3)
    assert readout_from_metadata({}) == (None, None)


@pytest.mark.parametrize("vcc", [1e308, 1001.0, float("inf"), 0.0, -5.0])
def test_supply_beyond_any_555_is_refused_naming_vcc(vcc):
    # Fuzzer finding: Vcc = 1e308 overflowed the thresholds and the message spoke of N "short by -400 %".
    from fsrlab.circuits.checks import check_supply

    with pytest.raises(ValueError, match=r"vcc_v: must be a supply voltage > 0 V and ≤ 1000 V"):
        check_supply(False, 0.0, vcc)


def test_cli_oscillator_with_a_huge_supply_names_the_option():
    from clirun import run_cli

    code, _, err = run_cli(["oscillator", "--r", "10k", "--rfsr", "200k", "--cfsr", "1n", "--vcc", "1e308"])
    assert code == 2
    assert "--vcc" in err and "1000 V" in err and "short by" not in err
