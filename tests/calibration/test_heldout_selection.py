"""Selection by held-out recordings or blocks: the rules checked on data whose truth is known.

The data come from :mod:`fsrlab.virtual.handloaded` (a Bouc–Wen sensor with creep, dead zone and
saturation behind a divider read by a 10-bit ADC, an HX711 reference): not the model fitted here
(play operators on a monotone curve). The truth is the generator's own force (``truth["force_n"]``).
"""

import numpy as np
import pytest

from fsrlab.calibration.scoring import Recording
from fsrlab.calibration.selection import LevelUncertainty, calibrate_recordings
from fsrlab.virtual.handloaded import fsr_bench_run


def _counts(run):
    """The divider's voltage as the Arduino's analogRead counts (5 V reference)."""
    return np.round(run.columns["voltage_v"] / 5.0 * 1023)


def _recording(kind, seed, **kw):
    run = fsr_bench_run(kind, seed=seed, **kw)
    return Recording(run.columns["time_s"], _counts(run), run.columns["force_n"]), run.truth["force_n"]


@pytest.fixture(scope="module")
def hand():
    return _recording("hand", 1)


@pytest.fixture(scope="module")
def motor():
    return _recording("motor", 3)


def _rmse_loaded(est, truth):
    loaded = truth > 0.05 * truth.max()
    return float(np.sqrt(np.mean((est[loaded] - truth[loaded]) ** 2)))


def test_compensation_is_kept_where_it_generalises_to_another_loading(hand, motor):
    """Hand-loaded → one slow motor triangle: the hysteresis held out is real, so it must be kept and
    must lower the error against the generator's true force on the other recording."""
    rec, _ = hand
    cal, sel = calibrate_recordings([rec], compensate=True)
    memory = next(s for s in sel.steps if s["step"] == "memory")
    assert memory["kept"] and "hysteresis" in memory["tried"] and 0 < memory["weight"] <= 1
    assert sel.scheme.startswith("forward chaining")
    other, truth = motor
    plain = _rmse_loaded(cal.without_memory().run(other.t, other.x)[0], truth)
    comp = _rmse_loaded(cal.run(other.t, other.x)[0], truth)
    assert comp < 0.8 * plain  # measured 0.40-0.45x on these seeds; 0.8 leaves room for other seeds


def test_do_no_harm_keeps_the_plain_curve_when_memory_does_not_generalise():
    """A sensor with no memory at all (a power law and noise): extra memory terms lower the error on
    the rows they are fitted on -- an in-sample rule would take them -- but not held out, so the
    calibration written is the plain curve, and the selection says why."""
    rng = np.random.default_rng(7)
    t = np.arange(3000) * 0.02
    force = 10 * np.abs(np.sin(2 * np.pi * t / 7.3)) * (1 + 0.3 * np.sin(2 * np.pi * t / 23))
    counts = np.round(1023 * (force / 12) ** 0.7 / (1 + (force / 12) ** 0.7)) + rng.normal(0, 3, t.size)
    y = force + rng.normal(0, 0.3, t.size)
    rec = Recording(t, counts, y)
    cal, sel = calibrate_recordings([rec], compensate=True)
    assert not cal.has_memory
    memory_steps = [s for s in sel.steps if s["step"] == "memory"]
    assert len(memory_steps) == 1 and not memory_steps[0]["kept"]
    assert "simpler calibration is kept" in memory_steps[0]["why"]
    # the rejected candidate did fit its own rows better: the rule, not the fit, made the choice
    from fsrlab.calibration.scoring import Part
    from fsrlab.calibration.selection import PLAY_THRESHOLDS, _Choice, _fit

    ch = _Choice(cal.curve.variable, cal.curve.size, family=cal.curve.family)
    part = [Part(rec, rec.usable)]
    plain = _fit(part, ch, 1, 1023.0)
    mem = _fit(part, ch.but(thresholds=PLAY_THRESHOLDS), 1, 1023.0)
    in_plain = np.sqrt(np.mean((plain.run(t, counts)[0] - y) ** 2))
    in_mem = np.sqrt(np.mean((mem.run(t, counts)[0] - y) ** 2))
    assert in_mem < in_plain


def test_lag_zero_is_kept_unless_a_shift_wins():
    rng = np.random.default_rng(3)
    t = np.arange(4000) * 0.05
    force = 5 + 5 * np.sin(2 * np.pi * t / 3.1) * np.sin(2 * np.pi * t / 17)
    x = 200 + 60 * force + rng.normal(0, 2, t.size)
    y = force + rng.normal(0, 0.05, t.size)
    _, sel = calibrate_recordings([Recording(t, x, y)], compensate=False, lag="auto")
    assert sel.lag_rows == 0
    delayed = np.r_[np.full(2, np.nan), y[:-2]]  # the reference 2 rows behind the readout
    _, sel = calibrate_recordings([Recording(t, x, delayed)], compensate=False)
    assert sel.lag_rows == 0 and not any(s["step"] == "lag" for s in sel.steps)  # not searched unless asked
    _, sel = calibrate_recordings([Recording(t, x, delayed)], compensate=False, lag="auto")
    assert sel.lag_rows == -2
    lag_step = next(s for s in sel.steps if s["step"] == "lag")
    assert lag_step["kept"]


def test_several_recordings_are_scored_leaving_one_out(hand, motor):
    recs = [hand[0], motor[0], _recording("hand", 2, duration_s=40)[0]]
    cal, sel = calibrate_recordings(recs, compensate=True)
    assert sel.scheme == "leave one recording out"
    assert sel.gain_spread is not None and sel.gain_spread >= 0
    assert cal.uncertainty.relative >= sel.gain_spread


def test_uncertainty_covers_the_errors_on_another_recording(hand):
    """±2u from held-out errors (and the between-recording term) covers at least 90 % of the errors
    against the true force on a recording the calibration never saw."""
    rec, _ = hand
    cal, _ = calibrate_recordings([rec], compensate=True)
    other, truth = _recording("hand", 5, duration_s=40)
    est, d = cal.run(other.t, other.x)
    u = cal.uncertainty(est, d)
    loaded = truth > 0.05 * truth.max()
    covered = np.abs(est[loaded] - truth[loaded]) <= 2 * u[loaded]
    assert covered.mean() >= 0.90


def test_uncertainty_table_round_trips_and_refuses_a_negative_value():
    table = LevelUncertainty.fit(np.r_[np.ones(50), -2 * np.ones(50)], np.linspace(0, 1, 100), np.zeros(100, int))
    again = LevelUncertainty.from_dict(table.to_dict())
    assert np.array_equal(again(np.linspace(0, 1, 7), np.zeros(7, int)), table(np.linspace(0, 1, 7), np.zeros(7, int)))
    bad = table.to_dict()
    bad["u_by_direction"][0][0] = -1.0
    with pytest.raises(ValueError, match="non-negative"):
        LevelUncertainty.from_dict(bad)


def test_the_memory_is_weighted_by_stacking_and_the_blend_is_exact(hand):
    """Stacking: the memory's correction enters with the weight in [0, 1] that minimises the held-out
    error of ``static + w·(memory − static)``, so the blend's held-out RMSE is at most the plain
    estimate's (w = 0) and at most the full correction's (w = 1), a property of the least-squares
    weight; and the calibration written is that blend exactly (its curve a monotone one)."""
    from fsrlab.calibration.scoring import Part
    from fsrlab.calibration.selection import PLAY_THRESHOLDS, _blend, _Choice, _fit

    rec, _ = hand
    cal, sel = calibrate_recordings([rec], compensate=True)
    memory = next(s for s in sel.steps if s["step"] == "memory")
    full = memory["heldout_rmse_at_weight_1"]
    assert sel.heldout_rmse <= sel.heldout_rmse_plain + 1e-12 and sel.heldout_rmse <= full + 1e-12
    # the blend of two fitted calibrations equals the blend of their estimates (closed form)
    part = [Part(rec, rec.usable)]
    ch = _Choice("conductance", 4)
    plain, mem = _fit(part, ch, 1, 1023.0), _fit(part, ch.but(thresholds=PLAY_THRESHOLDS, ridge=1e-2), 1, 1023.0)
    blend = _blend(plain, mem, 0.37)
    e0, e1, eb = (c.run(rec.t, rec.x)[0] for c in (plain, mem, blend))
    assert np.allclose(eb, e0 + 0.37 * (e1 - e0), rtol=0, atol=1e-9 * np.ptp(e0))
    assert np.all(blend.curve.coef[1:] >= 0)  # still monotone


def test_a_gain_under_five_percent_of_the_mse_is_not_worth_a_memory(monkeypatch):
    """A memory that wins by more than one standard error but by less than MIN_GAIN of the plain curve's
    held-out MSE is not kept, and the step says which test it failed; with MIN_GAIN = 0 the same memory
    is kept, so the rule made the choice."""
    from fsrlab.calibration import selection as hm

    monkeypatch.setattr(hm, "DELAY_ROWS", ())  # the memory's rule alone (a delay also averages the noise)
    rng = np.random.default_rng(11)
    t = np.arange(6000) * 0.02
    force = 10 * np.abs(np.sin(2 * np.pi * t / 7.3)) * (1 + 0.3 * np.sin(2 * np.pi * t / 23))
    u = force / 12
    p = np.zeros_like(u)  # a small true loop: a play operator of 0.05 FS under a large noise
    p[0] = max(u[0] - 0.05, 0.0)
    for i in range(1, u.size):
        p[i] = min(max(p[i - 1], u[i] - 0.05), u[i] + 0.05)
    rec = Recording(t, 100 + 600 * u + 12 * (p - u) + rng.normal(0, 3, t.size), force)
    _, sel = calibrate_recordings([rec], compensate=True)
    step = next(s for s in sel.steps if s["step"] == "memory")
    assert step["se"] < step["gain"] < hm.MIN_GAIN * sel.heldout_rmse_plain ** 2
    assert not step["kept"] and "5 %" in step["why"]
    old = hm.MIN_GAIN
    try:
        hm.MIN_GAIN = 0.0
        _, sel0 = calibrate_recordings([rec], compensate=True)
    finally:
        hm.MIN_GAIN = old
    assert next(s for s in sel0.steps if s["step"] == "memory")["kept"]


def _ramp_parts(seed: int, ramp_s: float = 15.0) -> dict:
    """One motor triangle of the generator, and its loading and unloading halves as recordings of their own
    (the unloading one starts at the peak)."""
    run = fsr_bench_run("motor", seed=seed, ramp_s=ramp_s)
    rec, truth = Recording(run.columns["time_s"], _counts(run), run.columns["force_n"]), run.truth["force_n"]
    top = int(np.argmax(truth))
    out = {"triangle": (rec, truth)}
    for name, k in (("loading", np.arange(truth.size) <= top), ("unloading", np.arange(truth.size) >= top)):
        out[name] = (Recording(rec.t[k] - rec.t[k][0], rec.x[k], rec.y[k]), truth[k])
    return out


def _comp_over_plain(cal, rec, truth) -> float:
    k = np.isfinite(truth)
    plain = np.sqrt(np.mean((cal.without_memory().run(rec.t, rec.x)[0][k] - truth[k]) ** 2))
    return float(np.sqrt(np.mean((cal.run(rec.t, rec.x)[0][k] - truth[k]) ** 2)) / plain)


@pytest.mark.parametrize("train,seed", [(("hand", 1), 101), (("hand", 7), 107), (("motor", 3), 203)])
def test_a_memory_does_no_harm_on_loading_only_and_unloading_only_runs(train, seed):
    """Issue 37 item 5: compensated at most 1.05× the plain curve on a new recording, runs that only load or
    only unload (from the peak) included. Measured: hand 1 → 0.62 (loading), 0.38 (unloading), 0.64
    (triangle); hand 7 → 0.77, 0.52, 0.75; one triangle → 0.44, 0.67, 0.48 (with the creep averages
    started at the first level, as before CREEP_START: unloading 0.88, 1.10 and 2.27)."""
    rec, _ = _recording(*train)
    cal, _ = calibrate_recordings([rec], compensate=True)
    assert cal.has_memory and cal.creep_start == 0.5
    for name, (other, truth) in _ramp_parts(seed).items():
        assert _comp_over_plain(cal, other, truth) <= 1.05, name
    other, _ = _ramp_parts(seed)["unloading"]
    stepper = cal.stepper()
    stepped = [stepper.step(x, t)[0] for x, t in zip(other.x, other.t, strict=True)]
    np.testing.assert_allclose(stepped, cal.run(other.t, other.x)[0], rtol=0, atol=1e-9)


def _plate(name: str, column: str) -> Recording:
    import csv
    from pathlib import Path

    path = Path("/work/shared/data/real/force-plate-fsr") / name
    if not path.exists():
        pytest.skip("the force-plate recordings are not on this machine")
    rows = list(csv.DictReader(path.open()))
    return Recording(*(np.array([float(r[c]) for r in rows]) for c in ("Time(s)", column, "Force(N)")))


PLATE = {"7a": ("experiment7a_clean_20250626_153404.csv", "FSR3"),
         "12b": ("experiment12b_clean_20250626_160438.csv", "FSR1"),
         "13a": ("experiment13a_clean_20250626_154702.csv", "FSR3"),
         "13c": ("experiment13cQ2_clean_20250626_160853.csv", "FSR2")}


@pytest.mark.parametrize("train,test", [("7a", "13a"), ("13a", "7a"), ("12b", "13c"), ("12b", "7a"), ("7a", "12b")])
def test_on_real_force_plate_recordings_the_memory_does_no_harm(train, test):
    """Real hand presses (PROVENANCE.md there: a loose reference, the plate's total force). Measured,
    compensated/plain against the plate: 0.77, 0.95, 1.00 (no memory kept; it was kept at 1 standard error:
    1.005), 1.00 (kept before: 1.001), 0.86."""
    cal, _ = calibrate_recordings([_plate(*PLATE[train])], compensate=True)
    other = _plate(*PLATE[test])
    assert _comp_over_plain(cal, other, other.y) <= 1.05


@pytest.mark.parametrize("seed", [3, 4])
def test_a_memory_that_fails_in_one_held_out_block_is_not_kept(seed):
    """Property: the memory's held-out gain must hold in every held-out block. A hand-loaded recording whose
    last fifth comes from the same film without hysteresis (its readout the loop's mid-line at the true force):
    the memory helps in the earlier held-out blocks -- overall by more than MEMORY_Z standard errors -- and
    makes the last one worse, so the plain curve is written and the selection says why."""
    from fsrlab.calibration.selection import MEMORY_Z

    run = fsr_bench_run("hand", seed=seed)
    x, truth = _counts(run), run.truth["force_n"]
    order = np.argsort(truth)
    mid_line = np.convolve(x[order], np.ones(51) / 51, mode="same")  # loading and unloading averaged
    cut = int(0.8 * x.size)
    x[cut:] = np.round(np.interp(truth[cut:], truth[order], mid_line))
    _, sel = calibrate_recordings([Recording(run.columns["time_s"], x, run.columns["force_n"])], compensate=True)
    memory = next(s for s in sel.steps if s["step"] == "memory")
    by_part = memory["heldout_gain_by_part"]
    assert memory["gain"] > MEMORY_Z * memory["se"] and min(by_part[:-1]) > 0 > by_part[-1]
    assert not memory["kept"] and "higher in 1 held-out part" in memory["why"]
    assert sel.heldout_rmse == sel.heldout_rmse_plain


@pytest.mark.parametrize("seed", [3, 4])
def test_a_memory_that_fails_on_the_earliest_block_scored_backward_is_not_kept(seed):
    """Property: the memory's gain must also hold backward in time. The mirror of the test above: the FIRST fifth
    of a hand-loaded recording comes from the film without hysteresis. Forward chaining never scores that block,
    and the memory wins in every forward part by more than MEMORY_Z standard errors; fitted on the later blocks
    it makes the earliest one worse (measured -0.71 and -4.06 of its MSE), so the plain curve is written and
    the selection says why."""
    from fsrlab.calibration.selection import MEMORY_Z

    run = fsr_bench_run("hand", seed=seed)
    x, truth = _counts(run), run.truth["force_n"]
    order = np.argsort(truth)
    mid_line = np.convolve(x[order], np.ones(51) / 51, mode="same")  # loading and unloading averaged
    cut = int(0.2 * x.size)
    x[:cut] = np.round(np.interp(truth[:cut], truth[order], mid_line))
    _, sel = calibrate_recordings([Recording(run.columns["time_s"], x, run.columns["force_n"])], compensate=True)
    memory = next(s for s in sel.steps if s["step"] == "memory")
    assert memory["gain"] > MEMORY_Z * memory["se"] and min(memory["heldout_gain_by_part"]) > 0
    earlier = memory["heldout_gain_by_earlier_part"]
    assert earlier[0] < 0 < min(earlier[1:])
    assert not memory["kept"] and "higher in 1 of 3 earlier" in memory["why"]
    assert sel.heldout_rmse == sel.heldout_rmse_plain


def test_one_recording_measures_the_gain_spread_of_its_held_out_blocks():
    """Property: with one recording the relative term between recordings is at least the RMS gain error of its
    held-out blocks. Triangles through a power law, the sensor's sensitivity tripling over the run (each later
    block reads higher than the earlier ones predict; measured spread 0.20 on three seeds): the spread exceeds the
    assumed 15 % and becomes the term; the same run without the drift keeps the assumed floor."""
    from fsrlab.calibration.uncertainty import REPEATABILITY

    rng = np.random.default_rng(5)
    t = np.arange(4000) * 0.05
    force = 10 * np.abs(((t / 20) % 2) - 1)  # 40 s triangles up to 10 N
    for drift, above in ((2.0, True), (0.0, False)):
        gain = 1 + drift * t / t[-1]
        x = (gain * force) ** 0.7 + rng.normal(0, 0.01, t.size)
        cal, sel = calibrate_recordings([Recording(t, x, force)], compensate=False)
        assert sel.gain_spread is not None
        if above:
            assert sel.gain_spread > REPEATABILITY and cal.uncertainty.relative == sel.gain_spread
        else:
            assert sel.gain_spread < 0.05 and cal.uncertainty.relative == REPEATABILITY


def test_a_held_out_block_whose_estimate_collapses_counts_as_a_whole_gain_error(tmp_path):
    """Property: a held-out block read far outside what the earlier blocks calibrated (its estimate near zero:
    a least-squares gain of about -76 on a real Velostat run) counts as the largest relative gain error a
    calibration holds (RELATIVE_MAX), not 77, so the saved file loads; the other blocks' errors are small, so
    the spread is RELATIVE_MAX/sqrt(3) to within them."""
    from fsrlab.calibration.model import HeldoutCalibration
    from fsrlab.calibration.uncertainty import RELATIVE_MAX

    rng = np.random.default_rng(2)
    t = np.arange(3000) * 0.05
    force = 20 * np.abs(((t / 15) % 2) - 1) + 1
    x = force ** 0.8 + rng.normal(0, 0.01, t.size)
    x[2400:] = 0.0  # the last block reads nothing (the film unplugged): its estimate has no gain at all
    cal, sel = calibrate_recordings([Recording(t, x, force)], compensate=False)
    assert sel.gain_spread == pytest.approx(RELATIVE_MAX / np.sqrt(3), rel=0.02)
    assert cal.uncertainty.relative == sel.gain_spread
    assert HeldoutCalibration.from_dict(cal.to_dict()).uncertainty.relative == cal.uncertainty.relative
