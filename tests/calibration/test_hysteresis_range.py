"""The hysteresis features are clipped to the range they had on the calibration data.

Reference: a generator that is not the model fitted -- a divider reading of a film whose effective
force has a Bouc–Wen loop (a smooth loop, not a sum of play operators) and a first-order creep --
loaded only upwards in a staircase with small wobbles for the calibration, then up and down for the
test. Properties: the stored range is the least and largest of the features the fit saw (closed
form, recomputed here with :func:`memory_features`); on the unloading, which the calibration never
saw, the clipped hysteresis is closer to the truth than the same fit extrapolated; the creep
columns are never clipped; the live stepper and a file give the batch's numbers.
"""

import dataclasses
import json

import numpy as np
import pytest

from fsrlab.calibration.model import HeldoutCalibration, clip_hysteresis
from fsrlab.calibration.operators import CREEP_TIME_CONSTANTS_S, PLAY_THRESHOLDS, memory_features
from fsrlab.calibration.scoring import Part, Recording
from fsrlab.calibration.selection import _Choice, _fit

RATE_HZ = 20.0


def _bouc_wen(force: np.ndarray, width: float) -> np.ndarray:
    beta = gamma = 0.5 / width
    z = np.empty_like(force)
    zi = 0.0
    for i, df in enumerate(np.diff(force, prepend=force[0])):
        zi += df * (1.0 - (beta * np.sign(df * zi) + gamma) * abs(zi))
        z[i] = zi
    return z


def _film(force: np.ndarray, rng) -> np.ndarray:
    """Counts of a divider: effective force with a Bouc–Wen loop (±10 %) and a 5 s creep."""
    a = np.exp(-1 / RATE_HZ / 5.0)
    held = np.zeros_like(force)
    s = 0.0
    for k, f in enumerate(force):
        s = a * s + (1 - a) * f
        held[k] = s
    f_eff = force * (1 - 0.1 * _bouc_wen(force, 4.0) / 4.0) + 0.05 * held
    return 1023 * f_eff / (f_eff + 15.0) + rng.normal(0, 0.7, force.size)


def _staircase(levels, rng) -> np.ndarray:
    """2 s at rest, then a 1 s ramp and a 6 s hold per level, with a ±1 N wobble of 1.5 s while loaded."""
    parts, cur = [np.zeros(int(2 * RATE_HZ))], 0.0
    for lv in levels:
        parts += [np.linspace(cur, lv, int(RATE_HZ)), np.full(int(6 * RATE_HZ), lv)]
        cur = lv
    f = np.concatenate(parts)
    t = np.arange(f.size) / RATE_HZ
    return np.clip(f + 1.0 * np.sin(2 * np.pi * t / 1.5) * (f > 0.5) + rng.normal(0, 0.02, f.size), 0, None)


def _case(seed: int):
    rng = np.random.default_rng(seed)
    f_cal = _staircase(np.sort(np.linspace(1, 30, 15) * rng.uniform(0.9, 1.1, 15)), rng)
    cal_rec = Recording(np.arange(f_cal.size) / RATE_HZ, _film(f_cal, rng), f_cal + rng.normal(0, 0.05, f_cal.size))
    up = np.sort(np.linspace(1, 30, 10) * rng.uniform(0.9, 1.1, 10))
    f_new = _staircase(np.concatenate([up, up[::-1][1:], [0.0]]), rng)
    return cal_rec, np.arange(f_new.size) / RATE_HZ, _film(f_new, rng), f_new


def _hysteresis_fit(rec: Recording) -> HeldoutCalibration:
    return _fit([Part(rec, rec.usable)], _Choice("readout", 4, thresholds=PLAY_THRESHOLDS, ridge=1e-3), 1, None)


def test_the_range_is_that_of_the_features_the_fit_saw():
    rec, *_ = _case(0)
    cal = _hysteresis_fit(rec)
    feats = memory_features(cal.level(rec.x), rec.t, PLAY_THRESHOLDS, ())
    assert cal.hysteresis_range.shape == (2, len(PLAY_THRESHOLDS))
    np.testing.assert_allclose(cal.hysteresis_range[0], feats.min(axis=0), atol=1e-6)
    np.testing.assert_allclose(cal.hysteresis_range[1], feats.max(axis=0), atol=1e-6)
    # loaded upwards only: the wide operators never swung to their unloading side (+r)
    assert cal.hysteresis_range[1, -1] < 0.5 * PLAY_THRESHOLDS[-1]


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_an_unloading_never_calibrated_is_not_extrapolated(seed):
    rec, t, x, force = _case(seed)
    cal = _hysteresis_fit(rec)
    unclipped = dataclasses.replace(cal, hysteresis_range=None)
    plain = _fit([Part(rec, rec.usable)], _Choice("readout", 4), 1, None)
    down = (np.arange(force.size) > np.argmax(force)) & (force > 1.0)

    def rmse(c):
        return float(np.sqrt(np.mean((c.run(t, x)[0][down] - force[down]) ** 2)))

    # seeds 1-6 gave 0.65-0.74 of the unclipped error (seeds 0 and 7 fit a zero weight to the widest
    # operator, the one that extrapolates, and gain nothing); the loop is still corrected where it was seen
    assert rmse(cal) < 0.85 * rmse(unclipped)
    assert rmse(cal) < 0.8 * rmse(plain)  # 0.61-0.70 with seeds 1-6


def test_only_the_hysteresis_columns_are_clipped():
    f = np.array([[-0.5, 0.5, -3.0, 3.0], [0.1, -0.1, 0.2, -0.2]])
    rng = np.array([[-0.2, -0.2], [0.2, 0.2]])
    out = clip_hysteresis(f, rng)
    np.testing.assert_array_equal(out[:, :2], [[-0.2, 0.2], [0.1, -0.1]])
    np.testing.assert_array_equal(out[:, 2:], f[:, 2:])  # creep columns as they were
    np.testing.assert_array_equal(clip_hysteresis(f, None), f)
    assert out is not f and f[0, 0] == -0.5  # the input is left alone


def test_the_stepper_and_a_file_give_the_batch_numbers():
    rec, t, x, _ = _case(1)
    ch = _Choice("readout", 4, thresholds=PLAY_THRESHOLDS, time_constants=CREEP_TIME_CONSTANTS_S, ridge=1e-3)
    cal = _fit([Part(rec, rec.usable)], ch, 1, None)
    batch, _ = cal.run(t, x)
    again = HeldoutCalibration.from_dict(json.loads(json.dumps(cal.to_dict())))
    np.testing.assert_allclose(again.run(t, x)[0], batch, rtol=1e-12, atol=1e-9)
    st = again.stepper()
    live = np.array([st.step(float(v), float(s))[0] for v, s in zip(x, t, strict=True)])
    np.testing.assert_allclose(live, batch, rtol=1e-9, atol=1e-6)
    old = cal.to_dict()
    old.pop("hysteresis_range")  # a file written before the range: read, not clipped
    assert HeldoutCalibration.from_dict(old).hysteresis_range is None
    bad = dict(cal.to_dict(), hysteresis_range=[[0.1] * 5, [0.0] * 5])
    with pytest.raises(ValueError, match="hysteresis_range"):
        HeldoutCalibration.from_dict(bad)
