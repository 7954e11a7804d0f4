"""The firmware's HX711 reference (protocol v2: ``ref_ok``, ``ref_n``, ``ref_mean``), in simavr.

Reference: simavr ground truth. The C harness (firmware/sim/fsrlab_sim.c) models the HX711 bit by
bit on D2 (DOUT) and D3 (SCK): a conversion ready every 1/SPS, 24 data bits MSB first and the gain
pulse, power-down when SCK stays high for more than 60 us. It logs every conversion the firmware
read completely (cycle, raw value) and the longest SCK high time. The tests compare the firmware's
frames, decoded by the host's parser, with that log: the count and the mean of each window exactly,
the mean rounded as docs/protocol.md says, ``floor(sum / n + 1/2)``.

Window boundaries in simulated time: a window starts when the firmware handles ``START`` and lasts
``window_ms`` on the firmware's clock, which simavr runs at exactly 16 MHz; the handling takes a
fraction of a millisecond after the line's LF. So a conversion is assigned to a window by its logged
time with a tolerance of ``TOL_S``; the HX711's phase is chosen so that every conversion lies
farther than that from every boundary, and the tests assert it before comparing.
"""

from __future__ import annotations

import math
import sys
from fractions import Fraction
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "firmware" / "sim"))
import simrun  # noqa: E402
import stress  # noqa: E402
from simrun import Segment  # noqa: E402

F_CPU = simrun.F_CPU
START_S = 0.01
# "START\n" is 6 bytes spaced 100 us by the harness: the LF arrives 0.5 ms after the first byte;
# the main loop handles the line within a few hundred microseconds, even at 50 kHz.
START_HANDLED_S = START_S + 0.0006
TOL_S = 0.0015
HX711_MIN, HX711_MAX = -(2**23), 2**23 - 1
SCK_HIGH_MAX_US = 60.0  # the HX711 powers down when SCK stays high longer (datasheet)


def _rounded_mean(values) -> int:
    """docs/protocol.md: floor(sum / n + 1/2), exactly."""
    return math.floor(Fraction(sum(values), len(values)) + Fraction(1, 2))


def _check_reference(r, window_ms: int):
    """Each M frame's reference against the harness's log of conversions. Returns the frames."""
    ms = r.measurements()
    assert ms, r.raw
    w = window_ms / 1000
    first_start_ms = ms[0].t_ms - ms[0].window_ms
    conv = [(c / F_CPU, v) for c, v in r.hx]
    for m in ms:
        assert m.window_ms == window_ms
        start = START_HANDLED_S + (m.t_ms - window_ms - first_start_ms) / 1000
        end = start + w
        for t, _ in conv:
            assert min(abs(t - start), abs(t - end)) > TOL_S, \
                f"test set-up: a conversion at {t:.5f} s lies within {TOL_S} s of a boundary of {m}"
        expected = [v for t, v in conv if start <= t < end]
        assert m.ref_ok == 1, m
        assert m.ref_n == len(expected), (m, expected)
        if expected:
            assert m.ref_mean == _rounded_mean(expected), (m, expected)
        else:
            assert math.isnan(m.ref_mean), m
    return ms


def _hx_healthy(r):
    assert not r.hx_powerdown, f"HX711 powered down at cycles {r.hx_powerdown}"
    assert not r.hx_lost, f"conversions never read: {r.hx_lost}"
    assert r.sck_stray == 0, "SCK pulsed while no conversion was ready"
    assert r.sck_max_high_us < SCK_HIGH_MAX_US, r.sck_max_high_us
    # every pulse belongs to a complete read (24 bits and the gain pulse), but one cut by the end
    assert 0 <= r.sck_pulses - 25 * len(r.hx) < 25


def test_reference_at_10_sps_windows_with_one_conversion_and_with_none(fw):
    # 50 ms windows, a conversion every 100 ms (25 ms after the first window's start): windows
    # alternate between one conversion and none; raw values at the 24-bit extremes and negative
    values = [HX711_MIN, HX711_MAX, -1, 0, 1, -123456, 4_242_424, -8_000_001]
    r = fw.run([Segment(0.0, 5000, 0.25)], [(0.005, "WINDOW 50"), (START_S, "START")],
               time_s=START_S + 0.05 * 9 + 0.01, hx_sps=10, hx_first_s=START_HANDLED_S + 0.025,
               hx_values=values)
    assert r.parser.bad_frames == 0 and r.parser.lost == 0
    _hx_healthy(r)
    ms = _check_reference(r, 50)
    assert len(ms) >= 8
    assert [m.ref_n for m in ms[:8]] == [1, 0] * 4
    assert [int(m.ref_mean) for m in ms if m.ref_n] == [v for _, v in r.hx][: sum(m.ref_n for m in ms)]
    assert {HX711_MIN, HX711_MAX, -1, 0} <= {v for _, v in r.hx}
    # the frames on the wire: a window without a conversion says 1,0,0 (HX711 present, none read)
    assert any(f.fields[8:11] == ("1", "0", "0") for f in r.of_kind("M"))
    assert any(f.fields[10] == str(HX711_MIN) for f in r.of_kind("M"))


def test_reference_means_are_rounded_half_up_at_80_sps(fw):
    # 25 ms windows at 80 samples/s: two conversions per window, consecutive values of opposite
    # parity so that every mean ends in .5: (-3, 0) -> -1, (-1, 0) -> 0 (never "-0"),
    # (8388607, 8388606) -> 8388607, (-8388607, -8388608) -> -8388607, (5, -2) -> 2
    values = [-3, 0, -1, 0, HX711_MAX, HX711_MAX - 1, HX711_MIN + 1, HX711_MIN, 5, -2]
    r = fw.run([Segment(0.0, 5000, 0.5)], [(0.005, "WINDOW 25"), (START_S, "START")],
               time_s=START_S + 0.025 * 11 + 0.01, hx_sps=80, hx_first_s=START_HANDLED_S + 0.00625,
               hx_values=values)
    assert r.parser.bad_frames == 0 and r.parser.lost == 0
    _hx_healthy(r)
    ms = _check_reference(r, 25)
    assert len(ms) >= 10 and all(m.ref_n == 2 for m in ms)
    assert [int(m.ref_mean) for m in ms[:5]] == [-1, 0, HX711_MAX, HX711_MIN + 1, 2]


@pytest.mark.parametrize("duty", [0.05, 0.95])
def test_every_edge_and_every_conversion_at_50_khz_with_an_hx711_at_80_sps(fw, duty):
    # the edge handlers' heaviest load in the supported range while the background reads 80
    # conversions a second (the harness's default values: the whole 24-bit range): no edge missed,
    # frequency and duty exact, every conversion in its window, SCK never high for 60 us
    f = 50_000.0
    r = fw.run([Segment(0.0, f, duty)], [(START_S, "START")], time_s=0.45, hx_sps=80,
               hx_first_s=START_HANDLED_S + 0.004)
    assert r.parser.bad_frames == 0 and r.parser.lost == 0
    _hx_healthy(r)
    ms = _check_reference(r, 100)
    assert len(ms) >= 4 and all(m.ref_n == 8 for m in ms)
    assert any(v < 0 for _, v in r.hx) and any(v > 0 for _, v in r.hx)
    for m in ms:
        assert m.missed == 0, m
    for m in ms[1:]:  # (the first window may start mid-period)
        df, dd = simrun.bounds(f, duty, m)
        assert abs(m.periods - f * m.window_ms / 1000) <= 3, m
        assert abs(m.frequency_hz - f) <= df and abs(m.duty_cycle - duty) <= dd, m


def test_every_duty_cycle_at_50_khz_with_an_hx711_at_80_sps(fw):
    # 5..95 % in steps of 3 % (as test_firmware_sim.py without an HX711): the edge handler's regimes
    # (capture interrupt, wake-up before a short phase) each meet the pulses' 9 cycles with
    # interrupts disabled
    for k in range(5, 96, 3):
        assert stress.check(50_000.0, k / 100, time_s=0.33, hx_sps=80) is None, k


def test_no_hx711_connected_gives_clean_frames_with_ref_ok_0(fw):
    r = fw.run([Segment(0.0, 5000, 0.25)], [(START_S, "START")], time_s=0.35)
    assert r.parser.bad_frames == 0 and r.parser.lost == 0 and r.parser.garbage_bytes == 0
    frames = r.of_kind("M")
    assert len(frames) >= 3
    assert all(f.fields[8:11] == ("0", "0", "0") for f in frames)
    for m in r.measurements():
        assert (m.ref_ok, m.ref_n) == (0, 0) and math.isnan(m.ref_mean)
        assert m.missed == 0
    assert r.pd2 == (0, 1), "D2 must be an input with its pull-up on (a missing HX711 reads high)"
    assert r.sck_pulses == 0 and not r.hx


def test_an_unplugged_hx711_turns_ref_ok_off_after_one_second(fw):
    # conversions until 0.2 s, then none: ref_ok stays 1 until 1000 ms after the last one
    r = fw.run([], [(START_S, "START")], time_s=1.45, hx_sps=80, hx_stop_s=0.2)
    assert r.parser.bad_frames == 0
    last = r.hx[-1][0] / F_CPU
    assert 0.18 < last < 0.2
    ms = r.measurements()
    first_start_ms = ms[0].t_ms - ms[0].window_ms
    for m in ms:
        end = START_HANDLED_S + (m.t_ms - first_start_ms) / 1000
        if end < last - TOL_S:
            assert m.ref_ok == 1 and m.ref_n >= 7, m
        elif end - last < 1.0 - TOL_S:
            assert m.ref_ok == 1, m
        elif end - last > 1.0 + TOL_S:
            assert (m.ref_ok, m.ref_n) == (0, 0) and math.isnan(m.ref_mean), m
    assert ms[-1].ref_ok == 0 and ms[3].ref_ok == 1


def test_the_pull_up_and_the_sck_idle_level_at_boot(fw):
    # before any conversion the firmware must not pulse SCK (a pulse while DOUT is high is
    # ignored by the HX711 but would stretch the next read)
    r = fw.run([], [], time_s=0.05, hx_sps=10)  # first conversion at 100 ms
    assert r.sck_pulses == 0 and r.pd2 == (0, 1)


PROBE_C = r"""
#include <avr/io.h>
#include <util/delay.h>
int main(void) {
  PORTD |= _BV(PD2);
  DDRD |= _BV(PD3);
  _delay_ms(20);
  PORTD |= _BV(PD3);  /* SCK high for 100 us: more than the 60 us that power the HX711 down */
  _delay_us(100);
  PORTD &= (uint8_t)~_BV(PD3);
  for (;;) {
  }
}
"""


def test_the_harness_sees_a_long_sck_high_and_powers_the_hx711_down(fw, tmp_path):
    # the reference must be able to fail: a probe program (not the firmware) holds SCK high for
    # 100 us at 20 ms; the model powers down 60 us after the rising edge, powers up when SCK falls,
    # and converts again only after the 50 ms settling time of an 80 samples/s board
    src = tmp_path / "probe.c"
    src.write_text(PROBE_C)
    elf = tmp_path / "probe.elf"
    import subprocess

    subprocess.run(["avr-gcc", "-mmcu=atmega328p", "-DF_CPU=16000000UL", "-Os", str(src), "-o", str(elf)],
                   check=True, capture_output=True)
    r = fw.run([], [], time_s=0.1, elf=elf, hx_sps=80)
    (down,) = r.hx_powerdown
    (up,) = r.hx_powerup
    assert r.sck_pulses == 1 and r.sck_max_high_us > 99.0
    assert abs(down - up + r.sck_max_high - 960) <= 2  # 60 us after the rising edge
    assert abs(up / F_CPU - 0.0201) < 0.0005
    # before: conversions every 12.5 ms replaced unread; after power-up: none for 50 ms
    lost = [c / F_CPU for c, _ in r.hx_lost]
    assert lost and all(t < 0.0201 or t >= up / F_CPU + 0.05 + 0.0125 - 1e-6 for t in lost)
    assert any(t > up / F_CPU for t in lost)


@pytest.mark.parametrize("duty", [0.05, 0.95])
def test_15_ms_windows_at_50_khz_with_an_hx711_at_80_sps_keep_up(fw, duty):
    # the documented limit (firmware/README.md): with an HX711 at 80/s the background still sends
    # one frame per 15 ms window at 50 kHz; frames do not fall behind, every window is exact
    f = 50_000.0
    r = fw.run([Segment(0.0, f, duty)], [(0.005, "WINDOW 15"), (START_S, "START")], time_s=0.6,
               hx_sps=80, hx_first_s=START_HANDLED_S + 0.004)
    assert r.parser.bad_frames == 0 and r.parser.lost == 0
    _hx_healthy(r)
    ms = r.measurements()
    assert len(ms) >= 37  # 39 windows end before 0.6 s; at most a frame or two on the way
    ends = [m.t_ms for m in ms]
    assert all(b - a == 15 for a, b in zip(ends, ends[1:], strict=False))
    for m in ms[1:]:
        df, dd = simrun.bounds(f, duty, m)
        assert m.missed == 0 and abs(m.periods - f * m.window_ms / 1000) <= 3, m
        assert abs(m.frequency_hz - f) <= df and abs(m.duty_cycle - duty) <= dd, m
        assert m.ref_ok == 1 and 1 <= m.ref_n <= 2, m


def test_means_of_80_conversions_including_the_extremes(fw):
    # 1 s windows at 80/s: 80 conversions per window, the division's widest sums: all -2^23, 80
    # seeded random 24-bit values, all 2^23 - 1 (no signal on D8: the run is quick)
    import random

    rng = random.Random(11)
    values = [HX711_MIN] * 80 + [rng.randint(HX711_MIN, HX711_MAX) for _ in range(80)] + [HX711_MAX] * 80
    r = fw.run([], [(0.005, "WINDOW 1000"), (START_S, "START")], time_s=START_S + 3.02, hx_sps=80,
               hx_first_s=START_HANDLED_S + 0.00625, hx_values=values)
    _hx_healthy(r)
    ms = _check_reference(r, 1000)
    assert [m.ref_n for m in ms] == [80, 80, 80]
    assert ms[0].ref_mean == HX711_MIN and ms[2].ref_mean == HX711_MAX
    assert ms[1].ref_mean == _rounded_mean(values[80:160])
