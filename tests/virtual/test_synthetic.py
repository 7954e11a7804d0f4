"""Synthetic runs (fsrlab.virtual.synthetic): circuits as objects in and in the sidecar, eq. (38) on
the voltage column, the meter's quantization, the cycle numbering.

References: the paper's eq. (38) evaluated by hand (R_F = 20 kΩ, |Vcc| = 5 V, the FSR's resistance
at 5 V) through the Uno's truncating 10-bit ADC (ATmega328P datasheet, "ADC Conversion Result"); the LM555 closed form
(fsrlab.circuits.lm555.astable) with the timer's one-tick bound (docs/protocol.md); the run format's
sidecar (docs/data-format.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsrlab.circuits.circuit import PAPER_CIRCUIT, PAPER_OPAMP, LM555Circuit, OpAmpReadout
from fsrlab.io.runformat import load_run
from fsrlab.physics.history import cycle_numbers
from fsrlab.physics.sensor import VirtualFSR
from fsrlab.virtual.synthetic import synthetic_run


def test_sidecar_stores_the_circuits_and_the_run_gives_them_back(tmp_path):
    circuit = LM555Circuit(r_ohm=22e3, c_off_farad=1e-9, diode=True, diode_drop_v=0.3)
    opamp = OpAmpReadout(r_f_ohm=33e3, vcc_v=-3.3)
    run = synthetic_run(cycles=1, points_per_ramp=10, circuit=circuit, opamp=opamp)
    assert run.metadata["circuit"] == circuit.to_dict() and run.metadata["opamp"] == opamp.to_dict()
    run.write(tmp_path / "r.csv")
    assert load_run(tmp_path / "r.csv").circuits() == (circuit, opamp)
    default = synthetic_run(cycles=1, points_per_ramp=10)
    assert default.metadata["circuit"] == PAPER_CIRCUIT.to_dict()
    assert default.metadata["opamp"] == PAPER_OPAMP.to_dict()


def test_voltage_is_eq38_at_5_v_through_the_truncating_adc():
    stress = np.linspace(0, 50e3, 21)
    c = synthetic_run(stress_pa=stress, voltage_noise_v=0.0).columns
    r5 = VirtualFSR().respond(stress, voltage_v=5.0).r_fsr_ohm
    volts = 20e3 / r5 * 5.0  # Eq. (38) by hand
    assert np.array_equal(c["voltage_v"], np.floor(volts * 1024 / 5.0) * 5.0 / 1024)


def test_frequency_is_the_closed_form_within_one_tick():
    """Constant stress, no frequency noise: every window after the first (which only opens a period)
    decodes to the 555's closed-form frequency within one 62.5 ns tick over the window's period sum,
    f·q/periods relative."""
    c = synthetic_run(stress_pa=np.full(12, 20e3), frequency_noise=0.0, window_s=0.05).columns
    resp = VirtualFSR().respond(np.array([20e3]), voltage_v=2.5)
    f = float(PAPER_CIRCUIT.astable(resp.r_fsr_ohm, resp.c_fsr_farad).frequency_hz[0])
    periods = c["periods"][1:]
    assert np.all(np.abs(periods - f * 0.05) <= 1)
    assert np.all(np.abs(c["frequency_hz"][1:] / f - 1) <= f * 62.5e-9 / periods * 1.001)
    assert c["periods"][0] in (math.floor(f * 0.05) - 1, math.floor(f * 0.05))


def test_cycles_come_from_the_directions():
    c = synthetic_run(cycles=3, points_per_ramp=5, dwell_points=2).columns
    assert np.array_equal(c["cycle"], cycle_numbers(c["direction"]))
    assert list(np.bincount(c["cycle"].astype(int))) == [12, 12, 13]  # 2·5 + 2 per cycle, the last reading
    # Any stress history (here a minor loop inside a major one): directions from the stress.
    s = np.concatenate([np.linspace(0, 40e3, 20), np.linspace(40e3, 5e3, 20), np.linspace(5e3, 20e3, 10),
                        np.linspace(20e3, 10e3, 10), np.linspace(10e3, 0, 10)])
    c = synthetic_run(stress_pa=s).columns
    assert np.array_equal(c["cycle"], cycle_numbers(c["direction"]))
    assert list(np.unique(c["cycle"])) == [0, 1]


def test_same_seed_same_run_and_noise_options():
    a, b = synthetic_run(cycles=1, seed=4).columns, synthetic_run(cycles=1, seed=4).columns
    assert all(np.array_equal(a[k], b[k], equal_nan=True) for k in a)
    c = synthetic_run(cycles=1, seed=5).columns
    assert not np.array_equal(a["frequency_hz"], c["frequency_hz"])


@pytest.mark.parametrize("kw, name", [({"circuit": {"r_ohm": 1e4}}, "circuit"), ({"opamp": 20e3}, "opamp"),
                                      ({"jitter_s": -1.0}, "jitter_s"), ({"window_s": 0.0}, "window_s")])
def test_bad_arguments_name_themselves(kw, name):
    with pytest.raises(ValueError, match=name):
        synthetic_run(cycles=1, points_per_ramp=5, **kw)


def test_a_synthetic_run_is_a_run_and_calibrates_as_its_file_does(tmp_path):
    """One run type: the synthetic run is an ``fl.Run``; ``fl.calibrate`` takes it in memory and gives the
    numbers it gives for the same run written and loaded back (reference: the run file)."""
    import fsrlab as fl

    run = fl.synthetic_run(cycles=2, points_per_ramp=30, seed=3)
    assert isinstance(run, fl.Run)
    cal = fl.calibrate(run)
    assert isinstance(cal, fl.Calibration)
    loaded = load_run(run.write(tmp_path / "r.csv"))
    assert "c_fsr_farad" not in loaded and "c_fsr_farad" in run  # the truth stays in memory
    from_file = fl.calibrate(loaded)
    est = cal.estimate(loaded).columns
    est_file = from_file.estimate(loaded).columns
    key = next(k for k in est if k.endswith("_estimate"))
    assert np.array_equal(est[key], est_file[key], equal_nan=True)
    assert np.isfinite(est[key]).sum() > run.n_rows // 2


def test_a_runs_repr_is_a_summary():
    """A run's repr names it, its rows and its columns, not its numbers (property: its length does not grow
    with the rows)."""
    short = repr(synthetic_run(cycles=1, points_per_ramp=5))
    long = repr(synthetic_run(cycles=20, points_per_ramp=200))
    assert short.startswith("SyntheticRun('synthetic.csv', 11 rows, columns time_s, stress_pa")
    assert "8001 rows" in long and len(long) == len(short) + 2
