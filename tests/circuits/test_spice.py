"""ngspice validation of the LM555 closed forms (fsrlab.circuits.spice).

Reference: ngspice (an independent circuit simulator) running fsrlab's behavioural 555 netlist.
Tolerance 0.1 % (fsrlab's stated agreement with ngspice); ngspice's own accuracy with the chosen step control is
~5e-5 (measured: worst 4e-5 on this grid), the rest is margin. The grid: without/with the ideal diode and with a
0.6 V drop, with and without C_off, N = R_FSR/R from 4.5 to 1000.
"""

from __future__ import annotations

import math

import pytest

from fsrlab.circuits.lm555 import astable
from fsrlab.circuits.spice import edges_from_waveform, level_crossings, netlist, simulate_spice
from toolcheck import require_tool

VARIANTS = [dict(), dict(diode=True), dict(diode=True, diode_drop_v=0.6)]
GRID = [(v, coff, n) for v in VARIANTS for coff in (0.0, 470e-12) for n in (4.5, 10, 100, 1000)
        if not (v.get("diode_drop_v") and n < 6.25 * 1.05)]  # with 0.6 V the minimum N is 6.25


@pytest.mark.parametrize("variant, c_off, n", GRID)
def test_ngspice_matches_closed_form(variant, c_off, n):
    require_tool("ngspice")
    r, c = 10e3, 1e-9
    sim = simulate_spice(r, n * r, c, c_off_farad=c_off, periods=8, **variant)
    ref = astable(r, n * r, c, c_off_farad=c_off, **variant)
    assert sim.n_periods == 8
    assert sim.frequency_hz == pytest.approx(ref.frequency_hz, rel=1e-3)
    assert sim.duty_cycle == pytest.approx(ref.duty_cycle, rel=1e-3)


def test_ngspice_moved_thresholds_and_other_supply():
    require_tool("ngspice")
    kw = dict(vcc_v=3.3, lower_fraction=0.3, upper_fraction=0.75)
    sim = simulate_spice(10e3, 200e3, 1e-9, periods=8, **kw)
    ref = astable(10e3, 200e3, 1e-9, **kw)
    assert sim.frequency_hz == pytest.approx(ref.frequency_hz, rel=1e-3)
    assert sim.duty_cycle == pytest.approx(ref.duty_cycle, rel=1e-3)


@pytest.mark.parametrize("diode", [False, True])
def test_ngspice_discharge_resistance(diode):
    # Extension: a 50 Ω discharge transistor lowers f by ~0.45 % without D1 and not at all with D1.
    require_tool("ngspice")
    sim = simulate_spice(10e3, 200e3, 1e-9, diode=diode, periods=8, discharge_ohm=50.0)
    ref = astable(10e3, 200e3, 1e-9, diode=diode, discharge_ohm=50.0)
    assert sim.frequency_hz == pytest.approx(ref.frequency_hz, rel=1e-4)
    assert sim.duty_cycle == pytest.approx(ref.duty_cycle, rel=1e-4)


@pytest.mark.parametrize("n", [3.5, 3.99])
def test_ngspice_confirms_no_oscillation_below_n_4(n):
    # Eq. (30): no oscillation for R ≥ R_FSR/4; ngspice shows no output edge at all.
    require_tool("ngspice")
    sim = simulate_spice(10e3, n * 10e3, 1e-9, periods=5)
    assert math.isnan(sim.frequency_hz) and sim.n_periods == 0


def test_netlist_contents():
    text = netlist(10e3, 200e3, 1e-9, 470e-12, diode=True, diode_drop_v=0.6, t_stop_s=1e-3, t_max_step_s=1e-7)
    for needle in (".subckt fsr555", "Vdrop nb nd DC 0.6", "D1 nd thr dideal", "COFF thr 0 4.7e-10",
                   "RFSR thr 0 200000", "VT=25000", "VH=8333.33333333333"):
        assert needle in text
    assert "RFSR" not in netlist(10e3, math.inf, 1e-9, t_stop_s=1e-3, t_max_step_s=1e-7)


def test_edges_from_waveform_square_wave():
    # A synthetic square wave: 1 kHz, 25 % high, sampled finely; linear interpolation is exact here.
    import numpy as np

    t = np.linspace(0, 10e-3, 100001)
    v = np.where((t % 1e-3) < 0.25e-3, 5.0, 0.0)
    _, _, f, dc = edges_from_waveform(t, v, 5.0, skip_periods=1)
    assert f == pytest.approx(1e3, rel=1e-4)
    assert dc == pytest.approx(0.25, rel=1e-3)


@pytest.mark.parametrize("diode", [False, True])
def test_ngspice_time_varying_r_fsr_matches_event_driven_simulation(diode):
    # R_FSR steps down 2M → 100k over 1 ms (20 samples, held constant in between) with C = 100 pF,
    # from power-up: every output edge of fsrlab's exact transient against ngspice (behavioural
    # resistor on a stepped PWL source). Tolerance per edge: 2e-3 of the shortest phase (ngspice's
    # crossing accuracy with a step limit of 1/50 of it) plus 1e-4 of the elapsed time (ngspice's
    # period error, ~1e-5 in the constant-parts grid above, accumulates over the periods).
    import numpy as np

    from fsrlab.circuits.spice import level_crossings, run_ngspice
    from fsrlab.circuits.transient import simulate

    require_tool("ngspice")
    r, c = 10e3, 100e-12
    t = np.linspace(0, 1e-3, 21)
    rf = np.geomspace(2e6, 100e3, t.size)
    ours = simulate(r, rf, c, diode=diode, time_s=t, v_initial_v=0.0)
    low = np.diff(ours.rising_s) - ours.high_times_s
    shortest = float(min(ours.high_times_s.min(), low.min()))
    text = netlist(r, rf, c, diode=diode, time_s=t, t_stop_s=1e-3, t_max_step_s=shortest / 50)
    data = run_ngspice(text)
    rising = level_crossings(data[:, 0], data[:, 1], 2.5, True)
    falling = level_crossings(data[:, 0], data[:, 1], 2.5, False)
    assert ours.rising_s.size > 20
    # An edge within the tolerance of t_stop may fall on either side of it.
    n_r, n_f = min(rising.size, ours.rising_s.size), min(falling.size, ours.falling_s.size)
    assert abs(rising.size - ours.rising_s.size) <= 1 and abs(falling.size - ours.falling_s.size) <= 1
    for got, ref in ((rising[:n_r], ours.rising_s[:n_r]), (falling[:n_f], ours.falling_s[:n_f])):
        assert np.all(np.abs(got - ref) <= 2e-3 * shortest + 1e-4 * ref)


def test_level_crossings_of_a_triangle_wave():
    # Piecewise linear between samples, so linear interpolation is exact: level 0.5 on a 0–2 V triangle
    # is crossed upward a quarter of the way up each rise and downward a quarter from the end of each fall.
    import numpy as np

    t = np.arange(5.0)
    v = np.array([0.0, 2.0, 0.0, 2.0, 0.0])
    np.testing.assert_array_equal(level_crossings(t, v, 0.5, rising=True), [0.25, 2.25])
    np.testing.assert_array_equal(level_crossings(t, v, 0.5, rising=False), [1.75, 3.75])
    # A sample exactly on the level counts once, on the side it is reached from.
    assert level_crossings(t, v, 2.0, rising=True).tolist() == [1.0, 3.0]
    assert level_crossings(t, v, 2.0, rising=False).size == 0


def test_binary_raw_output_equals_ngspice_own_text_output():
    # Reference: the same netlist written by ngspice as text (`wrdata`, 15 digits): the binary raw file
    # read by read_raw must give the same time points and voltages (to the text's 15 significant digits).
    import subprocess
    import tempfile
    from pathlib import Path

    import numpy as np

    from fsrlab.circuits.spice import read_raw

    require_tool("ngspice")
    text = netlist(10e3, 50e3, 1e-9, t_stop_s=2e-4, t_max_step_s=2e-7)
    as_text = text.replace("set filetype=binary\n", "set wr_singlescale\nset wr_vecnames\noption numdgt=15\n").replace(
        "write fsrlab_out.raw v(out) v(thr)", "wrdata fsrlab_out.txt v(out) v(thr)")
    assert as_text != text
    with tempfile.TemporaryDirectory() as tmp:
        for name, body in (("b.cir", text), ("t.cir", as_text)):
            (Path(tmp) / name).write_text(body)
            subprocess.run(["ngspice", "-b", name], cwd=tmp, capture_output=True, check=True)
        raw = read_raw((Path(tmp) / "fsrlab_out.raw").read_bytes())
        txt = np.loadtxt(Path(tmp) / "fsrlab_out.txt", skiprows=1, ndmin=2)
    assert raw.shape == txt.shape and raw.shape[0] > 100
    np.testing.assert_allclose(raw, txt, rtol=1e-13, atol=1e-15)


def test_read_raw_refuses_text_and_cut_files():
    import numpy as np

    from fsrlab.circuits.spice import read_raw

    with pytest.raises(RuntimeError, match="Binary"):
        read_raw(b"time v(out)\n0 1\n")
    header = b"Flags: real\nNo. Variables: 2\nNo. Points: 3\nBinary:\n"
    with pytest.raises(RuntimeError, match="48 expected"):
        read_raw(header + b"\0" * 40)
    assert read_raw(header + np.arange(6, dtype="<f8").tobytes()).tolist() == [[0, 1], [2, 3], [4, 5]]


def test_concurrent_runs_equal_sequential_runs():
    # Property: running ngspice processes side by side changes nothing in their results, and the order
    # of the results is the order of the cases.
    from fsrlab.circuits.spice import simulate_spice, simulate_spice_many

    require_tool("ngspice")
    cases = [{"r_ohm": 10e3, "r_fsr_ohm": n * 10e3, "c_fsr_farad": 1e-9} for n in (5, 20, 80)]
    together = simulate_spice_many(cases, jobs=3, periods=4)
    alone = [simulate_spice(**c, periods=4) for c in cases]
    assert [t.frequency_hz for t in together] == [a.frequency_hz for a in alone]
    assert [t.duty_cycle for t in together] == [a.duty_cycle for a in alone]
    for t, c in zip(together, cases, strict=True):  # in the order of the cases: each near its own closed form
        assert t.frequency_hz == pytest.approx(float(astable(**c).frequency_hz), rel=1e-3)


def test_a_started_batch_runs_the_longest_first_and_starts_no_thread():
    # start_spice_many returns with ngspice processes under way and no thread (a process may fork before
    # results() is called); the first started is the run with the most time steps (with D1 at large N: a
    # short charge phase sets the largest step, a long discharge the simulated time); results() gives the
    # numbers of the runs one after another, in the order of the cases.
    import threading

    from fsrlab.circuits.spice import simulate_spice, start_spice_many

    require_tool("ngspice")
    cases = [{"r_ohm": 10e3, "r_fsr_ohm": n * 10e3, "c_fsr_farad": 1e-9, "diode": d}
             for n, d in ((5, False), (60, True), (20, True), (80, False))]
    threads = threading.active_count()
    batch = start_spice_many(cases, jobs=2, periods=3)
    assert threading.active_count() == threads
    assert [i for i, _ in batch._first] == [1, 2]
    got = batch.results()
    alone = [simulate_spice(**c, periods=3) for c in cases]
    assert [g.duty_cycle for g in got] == [a.duty_cycle for a in alone]
    assert [g.frequency_hz for g in got] == [a.frequency_hz for a in alone]
