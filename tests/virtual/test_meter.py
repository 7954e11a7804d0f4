"""The meter's model (fsrlab.virtual.meter): timer quantization, high-time noise, the 10-bit ADC.

References: independent closed forms of a timer that timestamps rising edges in 62.5 ns ticks (the
summed length of whole periods is one timestamp difference, so within one tick of periods/f); the
decoding model's uncertainty (fsrlab.circuits.decode: each edge uniform ±½ tick, independent, so a
sum of n high times has variance n/6 tick²); the ATmega328P datasheet, "ADC Conversion Result"
(ADC = floor(V·1024/Vref), by hand at Vref = 5 V).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from fsrlab.hardware import F_CPU, TICK_S
from fsrlab.virtual.meter import MeterState, adc_code, measure


@pytest.mark.parametrize("volts, code", [(2.5, 512), (4.999, 1023), (-0.1, 0), (5.2, 1023), (0.0, 0),
                                         (5.0 / 1024, 1), (5.0 / 1024 * 0.999, 0), (math.inf, 1023)])
def test_adc_floors_and_clips(volts, code):
    # By hand: 2.5·1024/5 = 512; 4.999·1024/5 = 1023.8 -> 1023; below 0 and above Vref: the end codes.
    assert adc_code(volts) == code


def test_adc_truncates_rather_than_rounds():
    # 1.0 V · 1024/5 = 204.8: truncation gives 204, rounding 205.
    assert adc_code(1.0) == 204
    assert list(adc_code([1.0, 2.0, 3.0])) == [204, 409, 614]


def test_adc_rejects_nan():
    with pytest.raises(ValueError, match="voltage_v"):
        adc_code(float("nan"))


@settings(max_examples=200, deadline=None)
@given(f=st.floats(50.0, 60e3), window_s=st.floats(0.01, 1.0), duty=st.floats(0.05, 0.95),
       phase=st.floats(0.0, 1.0, exclude_max=True), start_s=st.floats(0.0, 1e4))
def test_period_sum_is_within_one_tick_of_the_true_length(f, window_s, duty, phase, start_s):
    """Constant frequency, no noise: each window after the opening one counts the rising edges in
    it (floor(φ + f·w) − floor(φ), i.e. floor(f·w) or one more), its period sum is within one tick of
    round(periods/f / 62.5 ns), and the decoded frequency within one tick over the sum:
    |f_meas/f − 1| < 1/sum_period_ticks."""
    assume(f * window_s >= 2)  # every window holds a period
    r, _ = measure(np.full(4, f), duty, 1.0, window_s, MeterState(phase), rng=0, start_s=start_s)
    periods, sum_p = r.periods[1:], r.sum_period_ticks[1:]
    assert np.all((periods == math.floor(f * window_s)) | (periods == math.floor(f * window_s) + 1))
    expected = np.round(periods / f / TICK_S)
    assert np.all(np.abs(sum_p - expected) <= 1)
    assert np.all(np.abs(periods * F_CPU / sum_p / f - 1) < 1 / sum_p + 1e-12)


def test_the_first_edge_after_start_only_opens_a_period():
    # 5 kHz in 50 ms windows: 250 rising edges per window whatever the phase; the first window's
    # first edge has no period before it.
    r, _ = measure(np.full(3, 5000.0), 0.25, 1.0, 0.05, MeterState(0.5), rng=1)
    assert list(r.periods) == [249, 250, 250]
    r, _ = measure(5000.0, 0.25, 1.0, 0.05, MeterState(0.5).restarted(), rng=1)
    assert list(r.periods) == [249]


def test_window_by_window_equals_all_at_once():
    """One model: the carried state makes consecutive calls equal to one vectorised call (periods,
    period sums, final state; the noise draws differ in order, so the noisy fields are not compared)."""
    rng = np.random.default_rng(9)
    f = 3000 + 2000 * rng.random(40)
    duty = 0.5 + 0.1 * rng.random(40)
    w = rng.choice([0.01, 0.02, 0.05], 40)
    whole, end = measure(f, duty, 1.0, w, MeterState(0.3), rng=1, start_s=2.0)
    state, start, parts = MeterState(0.3), 2.0, []
    for fi, di, wi in zip(f, duty, w, strict=True):
        r, state = measure(fi, di, 1.0, wi, state, rng=2, start_s=start)
        parts.append(r)
        start += wi
    assert np.array_equal(whole.periods, np.concatenate([p.periods for p in parts]))
    assert np.array_equal(whole.sum_period_ticks, np.concatenate([p.sum_period_ticks for p in parts]))
    assert state.phase == pytest.approx(end.phase, rel=1e-12)
    assert state.last_edge_ticks == pytest.approx(end.last_edge_ticks, rel=1e-12)


def test_high_time_noise_has_variance_n_over_6_ticks2():
    """Monte-Carlo: 20 000 windows of exactly 50 periods (5 kHz, 10 ms, no other noise). The high-time
    sum minus its true value D·50/f has variance n/6 = 8.33 tick² (decode's model: two independent
    uniform edge errors of variance 1/12 per high time). Tolerance 5 %: the sample variance's standard
    error is √(2/N) = 1 %, and the final rounding to whole ticks adds at most 1/12 tick² (1 %)."""
    n_win, f, duty, w = 20_000, 5000.0, 0.3, 0.01
    r, _ = measure(np.full(n_win, f), duty, 1.0, w, MeterState(0.25), rng=123)
    periods = r.periods[1:]
    assert np.all(periods == 50)
    err = r.sum_high_ticks[1:] - duty * 50 / f / TICK_S
    assert abs(err.mean()) < 4 * math.sqrt(50 / 6 / n_win) + 0.5
    assert np.var(err) == pytest.approx(50 / 6, rel=0.05)


def test_frequency_noise_and_jitter_are_options():
    f = np.full(2000, 4000.0)
    clean, _ = measure(f, 0.4, 1.0, 0.02, MeterState(0.0), rng=5)
    noisy, _ = measure(f, 0.4, 1.0, 0.02, MeterState(0.0), rng=5, frequency_noise=1e-3, jitter_s=100e-9)
    rel = noisy.frequency_hz[1:] / 4000.0 - 1
    # 1e-3 per window, plus jitter: two edges of 100 ns over 80 periods of 250 µs (7e-6): ~1e-3.
    assert np.std(rel) == pytest.approx(1e-3, rel=0.1)
    assert np.std(clean.frequency_hz[1:] / 4000.0 - 1) < 1 / clean.sum_period_ticks.min()


def test_no_oscillation_counts_no_periods():
    r, state = measure([5000.0, math.nan, 0.0, 5000.0], 0.5, 1.0, 0.01, MeterState(0.0), rng=0)
    assert list(r.periods[1:3]) == [0, 0] and list(r.sum_period_ticks[1:3]) == [0, 0]
    assert np.all(np.isnan(r.frequency_hz[1:3])) and np.all(np.isnan(r.duty_cycle[1:3]))


@pytest.mark.parametrize("kw, name", [({"window_s": 0.0}, "window_s"), ({"frequency_noise": -1}, "frequency_noise"),
                                      ({"jitter_s": math.nan}, "jitter_s")])
def test_bad_parameters_name_themselves(kw, name):
    args = {"frequency_hz": 1000.0, "duty_cycle": 0.5, "voltage_v": 1.0, "window_s": 0.1, **kw}
    with pytest.raises(ValueError, match=name):
        measure(**args)
