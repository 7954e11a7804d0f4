"""The automatic lag of ``calibrate_run`` on runs whose lag is known by construction.

Three kinds of run, each with its reference lag:

* the virtual bench's spring cycles (:func:`fsrlab.bench.protocols.run_protocol`, 10 kPa
  triangles, as ``fsrlab bench spring --virtual`` and the demo record them): the virtual device
  takes the stress and its HX711 sample in the same window as the readout, so the lag is 0; the
  same run with the reference (or the readout) delayed by 50 ms and 120 ms by interpolation, so
  the lag is −50/−120 ms (or +50/+120 ms);
* the hand-loaded generator (:func:`fsrlab.virtual.handloaded.fsr_bench_run`): the readout is the
  mean of a 20 ms window ending at the row's time behind a 4 ms RC (the force 10 + 4 ms earlier),
  the reference the HX711's latest sample (on average half a sample period old), so the lag is
  0.014 s − 1/(2·SPS): +7.75 ms at 80 SPS, −36 ms at 10 SPS (closed form from the generator);
* periodic drives of :func:`fsrlab.virtual.synthetic.synthetic_run` (readout and stress of the
  same row, lag 0), the reference delayed by 50 and 120 ms: triangles (the lag is identifiable at
  the sharp reversals) and a sine (a phase shift of a sine is an elliptic loop, which the play
  operators reproduce: the search must say the lag is not identifiable and assume none).

"Within one row" is the tolerance the search's grid (whole rows, then quarter rows) can promise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fsrlab.calibration.alignment import _memory_settled, estimate_lag
from fsrlab.calibration.fit import calibrate_run
from fsrlab.io.runformat import Run, load_run

ROW_S = 0.02  # the virtual bench's and the generators' row period [s]


def _delayed(run: Run, column: str, delay_s: float) -> Run:
    """The run with ``column`` delayed by ``delay_s`` (linear interpolation; the first value held)."""
    cols = {k: np.asarray(run[k], float) for k in run.columns}
    t = cols["time_s"]
    cols[column] = np.interp(t - delay_s, t, cols[column])
    return Run(path=Path(f"delayed-{column}.csv"), columns=cols, metadata=dict(run.metadata))


@pytest.fixture(scope="module")
def spring(tmp_path_factory):
    """4 spring cycles of 4 s to 10 kPa on the virtual bench (the demo's calibration run), faster than real time."""
    from fsrlab.bench.protocols import SpringPlan, run_protocol

    path = tmp_path_factory.mktemp("spring") / "spring.csv"
    res = run_protocol(SpringPlan(peak_pa=10e3, cycles=4, period_s=4.0), path, device="virtual", seed=1, speed="max")
    assert res.result.frames == 800  # 16 s of 20 ms windows on the device's clock
    return load_run(path)


@pytest.mark.slow
@pytest.mark.parametrize("reference", ["stress_pa", "force_n"])
def test_virtual_spring_run_has_no_lag(spring, reference):
    cal = calibrate_run(spring, compensate=True, reference=reference)
    # Reference: the virtual device takes the reference in the readout's own window: lag 0.
    assert abs(cal.lag_s) <= ROW_S
    assert cal.extra["lag_search"]["identifiable"] is True
    # The compensated estimate's hysteresis error stays near the one with the lag set to 0 (it was
    # 29 % when the search took the first cycle's extrapolation for a lag of -0.235 s).
    he = cal.compensation_he_percent[1]
    he0 = calibrate_run(spring, compensate=True, reference=reference, lag=0.0).compensation_he_percent[1]
    assert he < he0 + 1.0


@pytest.mark.slow
@pytest.mark.parametrize("delay_s", [0.05, 0.12])
@pytest.mark.parametrize("column, reference, sign", [("force_n", "force_n", -1.0), ("frequency_hz", "stress_pa", 1.0)])
def test_virtual_spring_run_with_a_lag_added(spring, delay_s, column, reference, sign):
    # Reference: the delay added by construction; a delayed reference is a negative lag (the
    # convention of shift_reference), a delayed readout a positive one.
    cal = calibrate_run(_delayed(spring, column, delay_s), reference=reference)
    assert cal.lag_s == pytest.approx(sign * delay_s, abs=ROW_S)


@pytest.mark.parametrize("sps", [80.0, 10.0])
def test_hand_loaded_runs_find_the_generators_lag(sps):
    from fsrlab.virtual.handloaded import fsr_bench_run

    run = fsr_bench_run("hand", seed=1, duration_s=120, reference_sps=sps).run()
    known = 0.010 + 0.004 - 0.5 / sps  # window centre + RC − half the HX711's sample period (module docstring)
    cal = calibrate_run(run, x="voltage_v")
    assert cal.lag_s == pytest.approx(known, abs=ROW_S)


def _periodic(shape: str, delay_s: float):
    """6 cycles of 8 s to 10 kPa through the synthetic chain (0.02 s rows, 0.05 % frequency noise)."""
    from fsrlab.virtual.synthetic import synthetic_run, triangle_stress

    n = 200  # rows per ramp
    stress = triangle_stress(cycles=6, peak_pa=10e3, points_per_ramp=n)
    if shape == "sine":
        stress = 5e3 * (1 - np.cos(np.pi * np.arange(stress.size) / n))
    s = synthetic_run(window_s=ROW_S, seed=1, stress_pa=stress, frequency_noise=5e-4)
    t = np.asarray(s.columns["time_s"], float)
    x = np.asarray(s.columns["frequency_hz"], float)
    y = np.interp(t - delay_s, t, np.asarray(s.columns["stress_pa"], float))
    return t, x, y, (t // (2 * n * ROW_S)).astype(int)


@pytest.mark.parametrize("delay_s", [0.0, 0.05, 0.12])
def test_periodic_triangles_with_a_lag_added(delay_s):
    # Reference: readout and stress of a synthetic row belong to the same instant (lag 0); the
    # reference delayed by construction.
    found = estimate_lag(*_periodic("triangle", delay_s))
    assert found.identifiable
    assert found.lag_s == pytest.approx(-delay_s, abs=ROW_S)


@pytest.mark.parametrize("delay_s", [0.0, 0.12])
def test_a_sine_drive_does_not_identify_the_lag(delay_s):
    # Property: on a sine a phase shift is an elliptic loop; the play operators fit either, so the
    # lags the cycles cannot tell apart span most of the range, and no lag is assumed (said).
    found = estimate_lag(*_periodic("sine", delay_s))
    assert not found.identifiable and found.lag_s == 0.0
    lo, hi = found.plausible_s
    assert hi - lo > 0.3 * 2 * 0.25
    assert "not identifiable" in found.to_dict()["note"]


def test_memory_settles_after_a_swing_both_ways():
    # Property: the play operators up to r hold their starting state until the readout has risen
    # by 2r and fallen by 2r (or the reverse); the lag search leaves those rows out.
    z = np.concatenate([np.linspace(0, 1, 101), np.linspace(1, 0, 101)[1:], np.linspace(0, 1, 101)[1:]])
    i = _memory_settled(z, 0.64)
    assert z[i] == pytest.approx(0.36) and i == 164
    assert _memory_settled(np.linspace(0, 1, 50), 0.64) == 50  # one ramp: never
    assert _memory_settled(np.array([np.nan, 1.0, 0.3, 0.95]), 0.64) == 3  # fell first, then rose


def test_one_motor_cycle_does_not_identify_the_lag():
    # Property: one triangle has one reversal; along its ramps a lag is an offset by direction that the
    # play operators reproduce (the search used to find -150 ms for the generator's +7.75 ms).
    from fsrlab.virtual.handloaded import fsr_bench_run

    cal = calibrate_run(fsr_bench_run("motor", seed=3, reference_sps=80).run(), x="voltage_v")
    search = cal.extra["lag_search"]
    assert cal.lag_s == 0.0 and search["identifiable"] is False and "reversal" in search["note"]


@pytest.mark.parametrize("method", ["memory", "cv", "xcorr"])
def test_every_lag_criterion_finds_a_known_delay(method):
    # Reference: a readout-free construction: the reference is the readout delayed by 60 ms (3 rows of
    # 20 ms) through a linear map; every criterion must find that shift (the sign convention of
    # shift_reference: the reference lags, the lag found is negative).
    t = np.arange(2000) * 0.02
    x = np.sin(1.3 * t) + 0.5 * np.sin(0.37 * t)
    y = 3.0 * np.interp(t - 0.06, t, x) + 1.0
    found = estimate_lag(t, x, y, np.arange(2000) // 200, method=method)
    assert found.lag_s == pytest.approx(-0.06, abs=1e-9)
