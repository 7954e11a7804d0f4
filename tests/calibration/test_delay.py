"""The reference's delay (calibration/delay.py and its step in selection.py).

References: a ramp delayed by τ is the ramp at t − τ (closed form); the one-reading-at-a-time line
equals the batch (property); a load cell that integrates over its 100 ms conversion and reports it at
the next row (an HX711 at 10 samples/s, simulated here sample by sample, not with the delay model)
describes the force half a reading earlier, so the held-out selection keeps a delay near 0.5 rows and
the estimate on a new recording is closer to the recorded reference; with an instantaneous reference
and a clean readout no delay is kept.
"""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.calibration import delay as dl
from fsrlab.calibration import selection as hm
from fsrlab.calibration.delay import DelayLine, delayed
from fsrlab.calibration.model import HeldoutCalibration
from fsrlab.calibration.scoring import ALIGNED, Recording, _rank_correlation
from fsrlab.calibration.selection import calibrate_recordings


def test_a_delayed_ramp_is_the_ramp_earlier():
    t = np.arange(50) * 0.1
    x = 3.0 + 2.0 * t
    d = delayed(t, x, 0.05)
    assert d[0] == x[0]  # before the first reading: the first reading
    assert np.allclose(d[1:], 3.0 + 2.0 * (t[1:] - 0.05), rtol=0, atol=1e-12)
    x[7] = np.nan
    d = delayed(t, x, 0.05)
    assert np.isnan(d[7]) and np.isclose(d[8], 3.0 + 2.0 * (t[8] - 0.05))  # interpolated across the gap
    assert delayed(t, x, 0.0) is not None and np.array_equal(delayed(t, x, 0.0), x, equal_nan=True)


def test_the_line_gives_the_batch_values_one_reading_at_a_time():
    rng = np.random.default_rng(4)
    t = np.cumsum(rng.uniform(0.05, 0.15, 400))
    x = np.sin(t) + rng.normal(0, 0.1, t.size)
    x[rng.choice(t.size, 20, replace=False)] = np.nan
    for delay in (0.03, 0.1, 0.27):
        line = DelayLine(delay)
        stepped = np.array([line.push(ti, xi) if np.isfinite(xi) else np.nan for ti, xi in zip(t, x, strict=True)])
        assert np.allclose(stepped, delayed(t, x, delay), rtol=0, atol=1e-12, equal_nan=True)
    # a millisecond clock at a high rate: many rows share a time, and delays of whole milliseconds land on them
    t = np.round(np.cumsum(rng.uniform(0.0, 0.003, 3000)), 3)
    x = rng.normal(size=t.size)
    for delay in (0.001, 0.0015, 0.004):
        line = DelayLine(delay)
        stepped = np.array([line.push(ti, xi) for ti, xi in zip(t, x, strict=True)])
        assert np.allclose(stepped, delayed(t, x, delay), rtol=0, atol=1e-12)


def _hx711_recording(seed: int, instant: bool = False, noise_counts: float = 2.0, n: int = 3000,
                     loop: float = 0.0) -> Recording:
    """Hand-like presses read at 10 rows/s: the readout is the divider's counts at the row's instant;
    the reference is the mean force over the 100 ms conversion that ends at the row (``instant``: the
    force at the row's instant). ``loop``: the sensor conducts more on unloading than on loading, as an
    FSR does (a play operator of 5 % of full scale on the force, this share of its output mixed in)."""
    rng = np.random.default_rng(seed)
    fine = np.arange(n * 100) * 1e-3  # 1 ms steps
    periods = rng.uniform(1.5, 4.0, 6)
    phases = rng.uniform(0, 2 * np.pi, 6)
    f = sum(np.sin(2 * np.pi * fine / p + ph) for p, ph in zip(periods, phases, strict=True))
    force = 12.0 * np.clip(f / 3.0, 0.0, None) ** 1.2
    t = (np.arange(n) + 1) * 0.1
    idx = np.round(t / 1e-3).astype(int) - 1
    sensed = force[idx]
    if loop:
        u, r = sensed / sensed.max(), 0.05
        p = np.empty_like(u)
        p[0] = u[0]
        for i in range(1, u.size):
            p[i] = min(max(p[i - 1], u[i] - r), u[i] + r)
        sensed = sensed.max() * np.clip(u + loop * (p - u), 0.0, None)
    g = (sensed / 10.0) ** 0.8
    x = np.round(1023 * g / (1 + g) + rng.normal(0, noise_counts, n))
    if instant:
        y = force[idx]
    else:
        y = force[: n * 100].reshape(n, 100).mean(axis=1)
    return Recording(t, x, y + rng.normal(0, 0.02, n))


def _rmse_on(cal: HeldoutCalibration, rec: Recording) -> float:
    est, _ = cal.run(rec.t, rec.x)
    return float(np.sqrt(np.nanmean((est - rec.y) ** 2)))


def test_a_reference_averaged_over_its_conversion_gets_a_delay_that_generalises(monkeypatch):
    rec, other = _hx711_recording(1), _hx711_recording(2)
    cal, sel = calibrate_recordings([rec], compensate=False)
    step = next(s for s in sel.steps if s["step"] == "delay")
    assert step["kept"] and 0.25 <= cal.delay_s / 0.1 <= 0.75
    monkeypatch.setattr(hm, "DELAY_ROWS", ())
    plain, sel0 = calibrate_recordings([rec], compensate=False)
    assert plain.delay_s == 0 and not any(s["step"] == "delay" for s in sel0.steps)
    assert _rmse_on(cal, other) < 0.8 * _rmse_on(plain, other)  # on a recording the calibration never saw


def test_an_instantaneous_reference_gets_no_delay():
    cal, sel = calibrate_recordings([_hx711_recording(3, instant=True, noise_counts=0.3)], compensate=False)
    step = next(s for s in sel.steps if s["step"] == "delay")
    assert not step["kept"] and cal.delay_s == 0


def test_an_fsr_loop_is_not_taken_for_a_delay():
    """A sensor whose loop leaves the estimate behind the force (more conductance on unloading), read
    against an instantaneous reference: a delay would widen the loop, so none is kept, while the
    memory step finds the loop."""
    cal, sel = calibrate_recordings([_hx711_recording(5, instant=True, noise_counts=0.3, loop=0.6)], compensate=True)
    step = next(s for s in sel.steps if s["step"] == "delay")
    assert not step["kept"] and cal.delay_s == 0
    assert next(s for s in sel.steps if s["step"] == "memory")["kept"]


def test_no_delay_when_a_lag_is_asked_for():
    """A lag aligns the reference (the estimate of the force at the readout's instant); the delay would
    undo it, so it is not tried then."""
    cal, sel = calibrate_recordings([_hx711_recording(1)], compensate=False, lag="auto")
    assert cal.delay_s == 0 and not any(s["step"] == "delay" for s in sel.steps)


def test_the_delay_survives_the_file_and_the_stepper():
    cal, _ = calibrate_recordings([_hx711_recording(1)], compensate=True)
    assert cal.delay_s > 0
    again = HeldoutCalibration.from_dict(cal.to_dict())
    other = _hx711_recording(2, n=600)
    batch, _ = again.run(other.t, other.x)
    assert np.array_equal(batch, cal.run(other.t, other.x)[0])
    st = cal.stepper()
    stepped = np.array([st.step(x, t)[0] for t, x in zip(other.t, other.x, strict=True)])
    assert np.allclose(stepped, batch, rtol=0, atol=1e-9)
    bad = cal.to_dict()
    bad["delay_s"] = -0.1
    with pytest.raises(ValueError, match="delay_s"):
        HeldoutCalibration.from_dict(bad)


def test_apply_and_the_live_estimator_agree_with_a_delay(tmp_path):
    """What ``fsrlab apply`` writes and what ``measure``/``live`` step (``live_estimator``) are the same
    estimates and uncertainties when the calibration holds a delay."""
    from fsrlab.calibration.runs import calibrate_runs
    from fsrlab.io.runwriter import write_run
    from stepping import assert_steps_as_batch

    paths = []
    for seed in (1, 2):
        r = _hx711_recording(seed, n=1500)
        paths.append(write_run(tmp_path / f"r{seed}.csv", {"time_s": r.t, "reading": r.x, "force_n": r.y},
                               {"units": {"time_s": "s", "reading": "counts", "force_n": "N"}}))
    cal = calibrate_runs([paths[0]], x="reading", reference="force_n", compensate=True)
    assert cal.model.delay_s > 0
    assert_steps_as_batch(cal, paths[1])


def test_the_run_report_names_the_delay(tmp_path):
    """A run's measurement report states the delay of the calibration it applied (the file's value)."""
    import json

    from fsrlab.calibration.runs import calibrate_runs
    from fsrlab.io.runwriter import write_run
    from fsrlab.reports.run_report import write_run_report

    r = _hx711_recording(1, n=1500)
    path = write_run(tmp_path / "r.csv", {"time_s": r.t, "reading": r.x, "force_n": r.y},
                     {"units": {"time_s": "s", "reading": "counts", "force_n": "N"}})
    cal = calibrate_runs([path], x="reading", reference="force_n")
    assert cal.model.delay_s > 0
    write_run_report(path, tmp_path / "rep", calibration=cal)
    doc = json.loads((tmp_path / "rep" / "report.json").read_text())
    assert doc["calibration"]["delay_s"] == cal.model.delay_s
    assert "delay of the reference" in (tmp_path / "rep" / "index.html").read_text()


def test_a_time_that_goes_back_starts_the_delay_again():
    """Two logs one after the other (the time restarts): each is delayed on its own, one reading at a
    time as in the batch, and no reading of one log is taken for the other's."""
    t = np.r_[np.arange(10) * 0.1, np.arange(10) * 0.1]
    x = np.r_[np.arange(10.0), 100 + np.arange(10.0)]
    d = delayed(t, x, 0.05)
    assert d[10] == 100.0 and np.allclose(d[11:], 100 + np.arange(1, 10) - 0.5)
    assert np.allclose(d[1:10], np.arange(1, 10) - 0.5)
    line = DelayLine(0.05)
    assert np.allclose([line.push(a, b) for a, b in zip(t, x, strict=True)], d, rtol=0, atol=1e-12)


def _half_row_late(seed: int, sigma: float, n: int = 8000, rate_hz: float = 100.0) -> Recording:
    """A readout linear in the force, beside a reference that reports the force half a row earlier with
    white noise of ``sigma`` newtons (the truth: a delay of 0.5 rows, closed form)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate_hz
    force = lambda tt: 10 + 8 * np.sin(2 * np.pi * 0.7 * tt) + 4 * np.sin(2 * np.pi * 0.23 * tt + 1)  # noqa: E731
    return Recording(t, 50 + 20 * force(t) + rng.normal(0, 0.5, n), force(t - 0.5 / rate_hz) + rng.normal(0, sigma, n))


def test_a_delay_that_saves_less_than_min_gain_of_the_error_is_not_kept():
    # quiet reference: the half-row delay is most of the error, and it is kept
    cal, sel = calibrate_recordings([_half_row_late(1, 0.05)], compensate=False)
    step = next(s for s in sel.steps if s["step"] == "delay")
    assert step["kept"] and cal.delay_s == pytest.approx(0.005)
    # noisy reference: the same delay still wins by several standard errors in every block, but saves
    # under MIN_GAIN (5 %) of the held-out MSE, so the simpler calibration is kept and the step says why
    cal, sel = calibrate_recordings([_half_row_late(1, 0.6)], compensate=False)
    step = next(s for s in sel.steps if s["step"] == "delay")
    assert step["gain"] > 3 * step["se"] and min(step["heldout_gain_by_part"]) > 0
    assert not step["kept"] and cal.delay_s == 0.0
    assert f"less than {100 * hm.MIN_GAIN:.0f} %" in step["why"]


def _rows_late(seed: int, rows: float, n: int = 6000, rate_hz: float = 100.0) -> Recording:
    """Presses read at ``rate_hz``; the reference logged ``rows`` readings late (a load cell on another
    logger joined by its time stamps): the force of ``rows / rate_hz`` before the row, by construction.
    The readout is a power law of the force (an FSR's conductance), not fsrlab's curve."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate_hz
    periods, phases = rng.uniform(1.0, 3.0, 4), rng.uniform(0, 2 * np.pi, 4)
    force = lambda tt: 10.0 * np.clip(sum(np.sin(2 * np.pi * tt / p + ph) for p, ph in  # noqa: E731
                                          zip(periods, phases, strict=True)) / 2.0, 0.0, None) ** 1.2
    g = (force(t) / 5.0) ** 0.8
    x = np.round(1023 * g / (1 + g) + rng.normal(0, 1.0, n))
    return Recording(t, x, force(t - rows / rate_hz) + rng.normal(0, 0.02, n))


@pytest.mark.parametrize("rows", [3.0, 5.5, 20.0])
def test_a_reference_many_readings_late_gets_its_delay(rows, monkeypatch):
    """Beyond the two readings fsrlab tried before: the delay found is the construction's within a
    quarter reading (20 rows: within the doubling grid's refinement, 1 row), and on a recording the
    calibration never saw the estimate is closer than with the old grid (0.25–2 readings), the ablation."""
    rec, other = _rows_late(1, rows), _rows_late(2, rows)
    cal, sel = calibrate_recordings([rec], compensate=False)
    step = next(s for s in sel.steps if s["step"] == "delay")
    assert step["kept"]
    assert abs(cal.delay_s * 100.0 - rows) <= (1.0 if rows > 16 else 0.25)
    monkeypatch.setattr(dl, "DELAY_ROWS", (0.25, 0.5, 0.75, 1.0, 1.5, 2.0))
    monkeypatch.setattr(dl, "DELAY_MAX_S", 0.0)
    old, _ = calibrate_recordings([rec], compensate=False)
    assert old.delay_s == pytest.approx(0.02)  # the old grid's last
    assert _rmse_on(cal, other) < 0.75 * _rmse_on(old, other)  # measured 0.57 at 3 rows, less beyond


def test_the_delays_tried():
    # at 10 readings/s the grid stops at 16 readings (1.6 s, beyond DELAY_MAX_S); at 1000/s it doubles on
    # to 512 readings, the first at or beyond 0.5 s
    assert dl.delay_trials(0.1) == list(dl.DELAY_ROWS)
    fast = dl.delay_trials(0.001)
    assert fast[-1] == 512.0 and fast[-2] * 0.001 < dl.DELAY_MAX_S <= fast[-1] * 0.001
    # the refinement: quarter, half and three-quarter points to each neighbour, in quarter readings
    assert dl.delay_trials(0.1, 3.0) == [2.25, 2.5, 2.75, 3.25, 3.5, 3.75]
    assert dl.delay_trials(0.1, 16.0) == [13.0, 14.0, 15.0]
    assert dl.delay_trials(0.1, 0.5) == []  # nothing between 0.25, 0.5 and 0.75 in quarter readings


def test_the_sign_of_a_reference_late_by_most_of_a_press_is_told_where_it_agrees():
    """60 readings late at 100/s (0.6 s, most of a press): the readout of a row hardly agrees with the
    reference of that row (rank correlation 0.00, or −0.41: the wrong sign), so the orientation is told
    from the reference the delays to be tried later; the readout rises with the force by construction."""
    rhos = []
    for seed in (1, 2, 3):
        rec = _rows_late(seed, 60.0)
        rhos.append(_rank_correlation(rec.x, rec.y))
        cal, sel = calibrate_recordings([rec], compensate=False)
        assert cal.static.sign == 1
        assert 48 <= cal.delay_s * 100.0 <= 64  # the grid's 64 readings and its refinement (56) around 60
    assert min(rhos) < 0 and max(abs(r) for r in rhos) < ALIGNED  # what the sign was taken from before


def test_a_reference_far_ahead_of_the_readout_keeps_the_right_sign():
    """The force 0.6 s after the readout's instant: no causal delay can follow it, but the curve still
    rises with the force (construction) instead of taking the sign of a row's poor agreement."""
    rec = _rows_late(1, 60.0)
    ahead = Recording(rec.t[:-120], rec.x[:-120], rec.y[120:])
    assert abs(_rank_correlation(ahead.x, ahead.y)) < 0.1  # the old rule refused it
    cal, _ = calibrate_recordings([ahead], compensate=False)
    assert cal.static.sign == 1
