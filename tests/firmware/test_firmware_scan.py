"""The firmware's channel scan (protocol v3: SCAN, DWELL, SETTLE) in simavr (firmware/build/fsrlab_sim).

References: docs/protocol.md (a scan: for each channel the first rising edge after the switch and
SETTLE periods are discarded, then DWELL ms are counted, ending at the first rising edge after them);
the square wave's own frequency and duty cycle within the quantization bound of each reading
(simrun.bounds, four ticks per timestamp difference in simavr); the closed form of the settling time
(SETTLE periods of 1/f); the select lines read back from PORTD at the end (S0..S2 = PD5..PD7).
fsrlab_sim has no multiplexer: every channel sees the same signal, so these tests check the scan's
timing and framing; the twin (tests/virtual/twin/test_twin_mux.py) checks eight different sensors.
"""

from __future__ import annotations

import numpy as np
import pytest
from simrun import Segment

F_HZ, DUTY = 5000.0, 0.25
PORTD = 0x2B  # data-space address of PORTD
PORTB = 0x25  # data-space address of PORTB (D9, the multiplexer's inhibit, is PB1)
DDRB = 0x24  # its direction register


def _scan(fw, settle: int, time_s: float = 0.12):
    cmds = [(0.005, "SCAN 3"), (0.006, "DWELL 5"), (0.007, f"SETTLE {settle}"), (0.01, "START")]
    r = fw.run([Segment(0.0, F_HZ, DUTY)], cmds, time_s=time_s, peeks=[PORTD])
    assert r.parser.bad_frames == 0 and r.parser.lost == 0
    acks = [f.fields for f in r.frames if f.kind == "ACK"]
    assert acks == [("SCAN", "3"), ("DWELL", "5"), ("SETTLE", str(settle)), ("START",)]
    return r


def test_scan_alternates_channels_with_exact_readings(fw):
    r = _scan(fw, 2)
    ms = r.measurements()
    assert len(ms) >= 15
    assert [m.channel for m in ms] == [k % 2 for k in range(len(ms))]
    assert [m.scan for m in ms] == [k // 2 for k in range(len(ms))]
    for m in ms:
        assert m.window_ms == 5 and m.missed == 0, m
        # DWELL 5 ms at 5 kHz, ended at the first rising edge after it: 25 or 26 whole periods
        assert m.periods in (25, 26), m
        df, dd = fw.bounds(F_HZ, DUTY, m)
        assert abs(m.frequency_hz - F_HZ) <= df and abs(m.duty_cycle - DUTY) <= dd, m
    # the last channel selected (0 or 1) is on S0..S2 = PD5..PD7; the other bits of PORTD are not the mux's
    port = r.peeks[PORTD][0]
    assert (port >> 5) & 7 in (0, 1)


def test_settle_discards_that_many_periods_after_the_first_edge(fw):
    # Each reading ends on a rising edge, the switch follows at once; the next reading starts after the first
    # rising edge and SETTLE periods more, so its end moves by SETTLE/f: 8 periods = 1.6 ms from 2 to 10.
    spacing = {}
    for settle in (2, 10):
        t = np.array([m.t_ms for m in _scan(fw, settle, time_s=0.2).measurements()], dtype=float)
        spacing[settle] = float(np.mean(np.diff(t)))
    assert spacing[10] - spacing[2] == pytest.approx(8 / F_HZ * 1000, abs=0.3)  # ms; t_ms counts whole ms
    assert 5.0 <= spacing[2] <= 7.0


def test_an_open_channel_is_reported_without_periods(fw):
    # no signal at all (every channel open): the scan goes on, each reading with periods 0
    cmds = [(0.005, "SCAN 5"), (0.01, "START")]
    r = fw.run([Segment(0.0, 0.0, DUTY)], cmds, time_s=0.12)
    ms = r.measurements()
    assert len(ms) >= 8
    assert [m.channel for m in ms] == [(0, 2)[k % 2] for k in range(len(ms))]
    assert all(m.periods == 0 and m.window_ms == 3 for m in ms)  # the boot dwell, 3 ms


def test_a_mask_of_one_is_the_single_channel_meter_on_that_channel(fw):
    cmds = [(0.005, "SCAN 4"), (0.006, "WINDOW 20"), (0.01, "START")]
    r = fw.run([Segment(0.0, F_HZ, DUTY)], cmds, time_s=0.15, peeks=[PORTD])
    ms = r.measurements()
    assert len(ms) >= 5
    assert all(m.channel == 2 and m.window_ms == 20 for m in ms)
    assert [m.scan for m in ms] == list(range(len(ms)))
    assert all(b.t_ms - a.t_ms == 20 for a, b in zip(ms, ms[1:], strict=False))  # contiguous windows, no settling
    assert (r.peeks[PORTD][0] >> 5) & 7 == 2


@pytest.mark.parametrize("stop_s", [0.100, 0.1033, 0.1071])
def test_a_sparse_mask_is_scanned_in_channel_order_with_its_select_lines(fw, stop_s):
    # SCAN 165 = 0b10100101: channels 0, 2, 5, 7, in increasing order, the scan number counting whole passes;
    # inhibit (D9 = PB1) low, enabled. The select lines hold the channel being read when the simulation stops:
    # the one after the last reading received (or the one after that, its frame still on the wire). Three stop
    # times land in different readings.
    order = (0, 2, 5, 7)
    cmds = [(0.005, "SCAN 165"), (0.006, "DWELL 3"), (0.01, "START")]
    r = fw.run([Segment(0.0, F_HZ, DUTY)], cmds, time_s=stop_s, peeks=[PORTD, PORTB, DDRB])
    ms = r.measurements()
    assert len(ms) >= 8
    assert [m.channel for m in ms] == [order[k % 4] for k in range(len(ms))]
    assert [m.scan for m in ms] == [k // 4 for k in range(len(ms))]
    assert all(m.missed == 0 and m.periods > 0 for m in ms)
    last = order.index(ms[-1].channel)
    assert (r.peeks[PORTD][0] >> 5) & 7 in (order[(last + 1) % 4], order[(last + 2) % 4])
    assert r.peeks[PORTB][0] & 0b10 == 0 and r.peeks[DDRB][0] & 0b10  # an output, driven low


@pytest.mark.parametrize("line", ["SCAN 0", "SCAN 256", "SCAN", "SCAN 1 2", "DWELL 0", "DWELL 60001", "SETTLE 101",
                                  "SETTLE -1"])
def test_bad_scan_values_get_error_2_naming_the_command(fw, line):
    r = fw.run([], [(0.01, line)], time_s=0.05)
    errs = [f.fields for f in r.frames if f.kind == "ERR"]
    assert errs == [("2", line.split()[0])]
