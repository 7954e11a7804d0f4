"""Creep under held loads: hold segments, drift per decade of time, time constant (analysis/creep.py, fsrlab creep).

References (independent closed forms, written here, not fsrlab's models):

* a readout r(t) = a + b·log10(t − t0) over a hold: the drift per decade is b, and 100·b/|a| in %
  of the reading at t0 + 1 s, exactly (noise-free: to rounding, 1e-9 relative);
* a first-order step r(t) = r∞ − Δ·exp(−(t − t0)/τ) with τ = 8 s, 0.5 % of Δ Gaussian noise: τ
  within 3 % (with 590 readings the fit's standard error is ≈ 0.4 %; the tolerance is ~7 of them)
  and within four of its own reported standard errors;
* the same step with τ = 500 s over a 40 s hold: τ not determined (no number);
* reference profiles made of flat stretches and ramps: the holds are the flat stretches, with
  their times to one reading (one reference interval where the reference has empty cells).

The CLI tests write these runs with fsrlab.io.runwriter.write_run and compare ``--json`` with the
library's result on the same file. examples/creep.csv is checked against the creep put into it
(examples/make_examples.py: 3 % of the stress felt per decade).
"""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.io.runformat import load_run, sidecar_path
from fsrlab.io.runwriter import write_run
from fsrlab.metrics.creep import creep, creep_of_run, first_order_fit, log_drift
from fsrlab.metrics.holds import find_holds

ROOT = Path(__file__).resolve().parents[2]
DT = 0.1  # readout window [s]


def _profile(knots):
    """Reference through (time [s], level) knots, linear in between, sampled every DT."""
    kt, kv = zip(*knots, strict=True)
    t = np.round(np.arange(0.0, kt[-1] + DT / 2, DT), 10)
    return t, np.interp(t, kt, kv)


# Rest 10 s, ramp 1 s, hold at 50 N from 11 s to 71 s, ramp down, rest.
ONE_HOLD = [(0, 0), (10, 0), (11, 50), (71, 50), (72, 0), (90, 0)]


def _log_readout(t, t0=11.0, t1=71.0, a=1000.0, b=30.0):
    s = np.maximum(t - t0, 1e-9)
    return np.where((t > t0) & (t <= t1), a + b * np.log10(s), 500.0)


def _write(path, t, ref, readout, ref_name="force_n", x="frequency_hz", area=None):
    meta = {"sensor": {"area_m2": area}} if area else {}
    write_run(path, {"time_s": t, ref_name: ref, x: readout}, meta)
    return path


# ------------------------------------------------------------------------------------------------
# Holds
# ------------------------------------------------------------------------------------------------

def test_flat_stretches_are_the_holds_and_short_ones_are_not_reported():
    # Holds of 60 s and 3 s at 50 N and 30 N; min_hold 5 s keeps the first only (and the rests at 0).
    t, ref = _profile([(0, 0), (10, 0), (11, 50), (71, 50), (72, 0), (80, 0), (81, 30), (84, 30), (85, 0), (95, 0)])
    holds = find_holds(t, ref, band=0.02, min_hold_s=5.0)
    loaded = [h for h in holds if h.level > 1]
    assert len(loaded) == 1
    h = loaded[0]
    # The ramp enters the band [48, 50] at 10.96 s: the first reading in it is at 11.0 s.
    assert (h.start_s, h.end_s, h.level) == pytest.approx((11.0, 71.0, 50.0))
    assert h.duration_s == pytest.approx(60.0)
    # With min_hold below 3 s the short hold is reported too.
    short = [h for h in find_holds(t, ref, min_hold_s=2.5) if h.level > 1]
    assert [round(h.level) for h in short] == [50, 30]
    assert short[1].start_s == pytest.approx(81.0) and short[1].end_s == pytest.approx(84.0)


def test_noise_within_the_band_does_not_split_a_hold_and_a_spike_is_ignored():
    rng = np.random.default_rng(3)
    t, ref = _profile(ONE_HOLD)
    ref = ref + rng.normal(0, 0.15, t.size)  # 0.3 % of full scale, band ±2 %
    ref[400] += 20.0  # one load-cell spike in the hold
    loaded = [h for h in find_holds(t, ref) if h.level > 25]
    assert len(loaded) == 1
    assert loaded[0].start_s == pytest.approx(11.0, abs=2 * DT) and loaded[0].end_s == pytest.approx(71.0, abs=2 * DT)


def test_reference_with_empty_cells_like_a_slow_hx711_still_finds_the_hold():
    # Readout every 12.5 ms (80 Hz), reference every 8th row (10 Hz), NaN in between.
    t = np.arange(0, 90, 0.0125)
    ref = np.interp(t, *zip(*ONE_HOLD, strict=True))
    ref[np.arange(t.size) % 8 != 3] = np.nan
    loaded = [h for h in find_holds(t, ref) if h.level > 25]
    assert len(loaded) == 1
    assert loaded[0].start_s == pytest.approx(11.0, abs=0.1) and loaded[0].end_s == pytest.approx(71.0, abs=0.1)
    assert loaded[0].n_reference == pytest.approx(600, abs=2)


def test_a_reference_that_never_holds_gives_no_hold():
    rng = np.random.default_rng(5)
    t = np.arange(0, 60, DT)
    ref = 25 + 25 * rng.uniform(-1, 1, t.size)  # white noise over the whole range
    assert find_holds(t, ref) == []


@pytest.mark.parametrize("kwargs, match", [({"band": 0.0}, "band"), ({"band": 0.5}, "band"),
                                           ({"min_hold_s": 0.0}, "min_hold_s"), ({"band": float("nan")}, "band")])
def test_find_holds_checks_its_parameters(kwargs, match):
    t, ref = _profile(ONE_HOLD)
    with pytest.raises(ValueError, match=match):
        find_holds(t, ref, **kwargs)


def test_reference_without_readings_or_zero_throughout_is_an_error():
    t = np.arange(10.0)
    with pytest.raises(ValueError, match="no readings"):
        find_holds(t, np.full(10, np.nan))
    with pytest.raises(ValueError, match="zero throughout"):
        find_holds(t, np.zeros(10))


# ------------------------------------------------------------------------------------------------
# Drift per decade and time constant
# ------------------------------------------------------------------------------------------------

def test_log_readout_gives_its_drift_per_decade_exactly():
    t, ref = _profile(ONE_HOLD)
    a, b = 1000.0, 30.0
    res = creep(t, _log_readout(t, a=a, b=b), ref)
    (h,) = res.holds
    assert h.log.b == pytest.approx(b, rel=1e-9)
    assert h.log.a == pytest.approx(a, rel=1e-9)
    assert h.drift_percent_per_decade == pytest.approx(100 * b / a, rel=1e-9)  # 3 %/decade
    # Total drift: medians of the first and last five readings from t0 + 0.5 s (settling) on.
    s = np.arange(5, 601) * DT  # t − t0 = 0.5 s (settled) to 60 s
    r = a + b * np.log10(s)
    assert h.total_drift_percent == pytest.approx(100 * (np.median(r[-5:]) - np.median(r[:5])) / np.median(r[:5]),
                                                  rel=1e-9)
    assert res.unloaded == 2  # the rests before and after


def test_a_falling_readout_reports_a_negative_drift():
    t, ref = _profile(ONE_HOLD)
    (h,) = creep(t, _log_readout(t, a=2.0, b=-0.05), ref).holds
    assert h.drift_percent_per_decade == pytest.approx(-2.5, rel=1e-9)
    assert h.total_drift_percent < 0


def test_log_drift_closed_form_on_arbitrary_times():
    s = np.array([0.3, 1.0, 2.0, 7.0, 40.0, 300.0])
    fit = log_drift(s, 5.0 - 0.2 * np.log10(s))
    assert (fit.a, fit.b, fit.percent_per_decade) == pytest.approx((5.0, -0.2, -4.0), rel=1e-12)
    assert fit.b_stderr == pytest.approx(0.0, abs=1e-12)
    assert np.isnan(log_drift([1.0], [2.0]).b)  # one reading: not determined


def test_first_order_time_constant_is_recovered_with_noise():
    rng = np.random.default_rng(7)
    t, ref = _profile(ONE_HOLD)
    tau, r_inf, delta = 8.0, 1050.0, 50.0
    s = t - 11.0
    r = np.where((s >= 0) & (s <= 60), r_inf - delta * np.exp(-s / tau), 500.0) + rng.normal(0, 0.005 * delta, t.size)
    (h,) = creep(t, r, ref).holds
    fo = h.first_order
    assert fo.determined
    assert fo.tau_s == pytest.approx(tau, rel=0.03)
    assert abs(fo.tau_s - tau) < 4 * fo.tau_stderr_s
    assert (fo.r_inf, fo.delta) == pytest.approx((r_inf, delta), rel=0.01)


def test_time_constant_beyond_the_hold_is_not_determined():
    t, ref = _profile([(0, 0), (10, 0), (11, 50), (51, 50), (52, 0), (60, 0)])
    s = t - 11.0
    r = np.where((s >= 0) & (s <= 40), 1000 + 50 * (1 - np.exp(-s / 500.0)), 500.0)
    (h,) = creep(t, r, ref).holds
    assert not h.first_order.determined and np.isnan(h.tau_s) and "beyond the hold" in h.first_order.note
    d = creep(t, r, ref).to_dict()["holds"][0]
    assert d["tau_s"] != d["tau_s"] and "beyond the hold" in d["tau_note"]  # NaN: JSON null


def test_a_readout_with_noise_only_has_no_time_constant():
    rng = np.random.default_rng(11)
    s = np.arange(0.5, 40, DT)
    fo = first_order_fit(s, 1000 + rng.normal(0, 1.0, s.size))
    assert not fo.determined and np.isnan(fo.tau_s)


def test_a_step_faster_than_the_readings_is_not_a_time_constant():
    # τ = 20 ms, readings every 100 ms from 0.1 s: all but the first have settled to within 5e-22·Δ.
    s = np.arange(1, 400) * DT
    fo = first_order_fit(s, 1000 + 5 * (1 - np.exp(-s / 0.02)))
    assert not fo.determined and "spacing" in fo.note


def test_no_loaded_hold_is_an_error_naming_why():
    t, ref = _profile([(0, 0), (30, 0)])
    with pytest.raises(ValueError, match="no loaded hold"):
        creep(t, np.ones_like(t), np.r_[ref[:-1], 1.0])  # only a rest at 0 (the band holds zero)


# ------------------------------------------------------------------------------------------------
# Runs and the command line
# ------------------------------------------------------------------------------------------------

@pytest.fixture()
def log_run(tmp_path):
    t, ref = _profile(ONE_HOLD)
    return _write(tmp_path / "hold.csv", t, ref, _log_readout(t))


def test_cli_json_equals_the_library(log_run):
    code, out, err = run_cli(["creep", log_run, "--json"])
    assert (code, err) == (0, ""), err
    got = json.loads(out)
    want = creep_of_run(load_run(log_run)).to_dict()
    assert got["holds"][0]["drift_percent_per_decade"] == pytest.approx(3.0, rel=1e-9)
    for key, value in want["holds"][0].items():
        if isinstance(value, float) and value != value:
            assert got["holds"][0][key] is None, key
        else:
            assert (got["holds"][0][key] == pytest.approx(value) if isinstance(value, float)
                    else got["holds"][0][key] == value)
    assert {k: v for k, v in got.items() if k != "holds"} == {k: v for k, v in want.items() if k != "holds"}
    assert "level_N" in got["holds"][0] and "full_scale_N" in got


def test_cli_table_shows_one_row_per_hold_with_units(log_run, tmp_path):
    code, out, err = run_cli(["creep", log_run, "--plot", tmp_path / "creep.png"])
    assert code == 0, err
    assert "force_n (N)" in out and "%/decade" in out and "τ (s)" in out
    assert re.search(r"\+3\.000", out)  # 3 %/decade
    assert (tmp_path / "creep.png").stat().st_size > 0


def test_cli_reads_the_readout_named_by_x_and_a_stress_reference(tmp_path):
    t, ref = _profile(ONE_HOLD)
    path = tmp_path / "v.csv"
    write_run(path, {"time_s": t, "stress_pa": ref * 1e3, "voltage_v": _log_readout(t, a=2.0, b=0.1),
                     "frequency_hz": np.full(t.size, 1000.0)})
    code, out, err = run_cli(["creep", path, "--x", "voltage_v", "--json"])
    assert code == 0, err
    got = json.loads(out)
    assert got["reference"] == "stress_pa" and "level_Pa" in got["holds"][0]
    assert got["holds"][0]["drift_percent_per_decade"] == pytest.approx(5.0, rel=1e-9)
    assert got["holds"][0]["drift_per_decade_V"] == pytest.approx(0.1, rel=1e-9)


def test_cli_min_hold_leaves_out_shorter_holds(log_run):
    code, _, err = run_cli(["creep", log_run, "--min-hold", "2min"])
    assert code == 2 and "no loaded hold" in err and err.count("\n") == 1


def test_noisy_reference_that_never_holds_exits_2_with_the_message(tmp_path):
    rng = np.random.default_rng(5)
    t = np.arange(0, 60, DT)
    path = _write(tmp_path / "noisy.csv", t, 25 + 25 * rng.uniform(-1, 1, t.size), np.full(t.size, 1000.0))
    code, out, err = run_cli(["creep", path])
    assert code == 2 and out == ""
    assert err.startswith("fsrlab: error: ") and "noisy.csv" in err and "no loaded hold found" in err
    assert "never stays within ±2 % of full scale" in err and err.count("\n") == 1


def test_cli_finds_the_hold_with_empty_reference_cells(tmp_path):
    t, ref = _profile(ONE_HOLD)
    ref[np.arange(t.size) % 2 == 1] = np.nan
    path = _write(tmp_path / "hx.csv", t, ref, _log_readout(t))
    code, out, err = run_cli(["creep", path, "--json"])
    assert code == 0, err
    (h,) = json.loads(out)["holds"]
    assert h["start_s"] == pytest.approx(11.0, abs=0.2)
    assert h["drift_percent_per_decade"] == pytest.approx(3.0, rel=0.01)


@pytest.mark.parametrize("args, names", [
    (["--band", "0"], "--band"), (["--band", "50%"], "--band"), (["--band", "0.7"], "--band"),
    (["--x", "nope"], "--x"), (["--x", "time_s"], "--x"), (["--x", "force_n"], "--x"),
    (["--reference", "stress_pa"], "--reference"), (["--reference", "voltage_v"], "--reference"),
    (["--min-hold", "0"], "--min-hold"), (["--settle", "10s"], "--settle"),
    (["--plot", "out.txt"], "--plot"),
])
def test_cli_bad_options_exit_2_naming_the_option(log_run, args, names):
    code, out, err = run_cli(["creep", log_run, *args])
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert names in err


def test_cli_run_without_reference_or_with_empty_readout_exits_2(tmp_path):
    t, ref = _profile(ONE_HOLD)
    bare = tmp_path / "bare.csv"
    write_run(bare, {"time_s": t, "frequency_hz": _log_readout(t)})
    code, _, err = run_cli(["creep", bare])
    assert code == 2 and "no reference column" in err and "bare.csv" in err
    empty = _write(tmp_path / "empty.csv", t, ref, np.full(t.size, np.nan))
    code, _, err = run_cli(["creep", empty])
    assert code == 2 and "'frequency_hz' has no readings" in err and err.count("\n") == 1
    no_time = tmp_path / "notime.csv"
    write_run(no_time, {"force_n": ref, "frequency_hz": _log_readout(t)})
    code, _, err = run_cli(["creep", no_time])
    assert code == 2 and "'time_s' missing" in err


def test_cli_skip_bad_rows_counts_them(log_run):
    lines = log_run.read_text().splitlines()
    lines[300] = lines[300].rsplit(",", 1)[0] + ",abc"
    log_run.write_text("\n".join(lines) + "\n")
    # The CSV changed after its sidecar was written: without the sidecar's digest of the old content, which
    # load_run would refuse before any cell (docs/data-format.md, csv_sha256).
    meta = json.loads(sidecar_path(log_run).read_text())
    del meta["csv_sha256"]
    sidecar_path(log_run).write_text(json.dumps(meta))
    code, _, err = run_cli(["creep", log_run])
    assert code == 2 and "non-numeric" in err
    code, out, err = run_cli(["creep", log_run, "--skip-bad-rows", "--json"])
    assert code == 0 and "skipped 1 bad row" in err
    assert json.loads(out)["skipped_rows"] == 1


# ------------------------------------------------------------------------------------------------
# Help and the example run
# ------------------------------------------------------------------------------------------------

def _help() -> str:
    code, out, err = run_cli(["creep", "--help"])
    assert (code, err) == (0, "")
    return out


def _options(help_text: str) -> dict[str, str]:
    """Option (with its value placeholder) -> its help text, from the rendered help (as test_cli_help.py reads it)."""
    entries: dict[str, str] = {}
    key = None
    for line in help_text.split("\nOptions:\n", 1)[1].splitlines():
        m = re.match(r"^  (-\S+(?:, -\S+)*(?: <?[\w.]+>?)?)(?:\s{2,}(.*))?$", line)
        if m:
            key = m.group(1)
            entries[key] = m.group(2) or ""
        elif key:
            entries[key] += " " + line.strip()
    return entries


def test_help_shows_a_unit_for_every_option_with_a_value():
    valued = {k: v for k, v in _options(_help()).items() if " " in k}
    assert {k.split()[0] for k in valued} >= {"--x", "--reference", "--min-hold", "--band", "--settle", "--plot"}
    for option, text in valued.items():
        assert re.search(r"\[[^\]]+\]", text), f"{option}: no unit in {text!r}"
    assert "[s]" in _help() and "[N or Pa]" in _help()


def test_help_ends_with_examples_that_run(tmp_path, monkeypatch):
    import shutil

    out = _help()
    description = out.split("\nArguments:")[0].split("\nOptions:")[0].rstrip()
    examples = [ln.strip() for ln in description.split("Examples", 1)[1].splitlines()
                if ln.strip().startswith("fsrlab ")]
    assert len(examples) == 2 and description.splitlines()[-1].strip() == examples[-1]
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    for line in examples:
        code, out, err = run_cli(shlex.split(line)[1:])
        assert (code, err) == (0, ""), f"{line}: {err}"


def test_example_run_shows_the_creep_put_into_it():
    # make_examples.creep(): the stress felt grows 3 % per decade of (1 + age/1 s); the frequency
    # rises with stress less than in proportion near full scale, so its drift is a few % per decade.
    res = creep_of_run(load_run(ROOT / "examples" / "creep.csv"))
    assert [round(h.hold.level, 1) for h in res.holds] == [2.0, 3.2]
    assert [h.hold.start_s for h in res.holds] == pytest.approx([6.0, 46.0], abs=0.25)
    for h in res.holds:
        assert 1.0 < h.drift_percent_per_decade < 6.0 and h.total_drift_percent > 0
    assert res.unloaded >= 1


def test_plot_draws_each_holds_readings_and_fits_in_percent_of_the_reading_at_1s():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(7)
    t, ref = _profile(ONE_HOLD)
    s = t - 11.0
    r = np.where((s >= 0) & (s <= 60), 1050 - 50 * np.exp(-s / 8.0), 500.0) + rng.normal(0, 0.25, t.size)
    res = creep(t, r, ref)
    (h,) = res.holds
    try:
        ax = res.plot()
        data, line, curve = ax.lines  # τ determined: the first-order curve is drawn too
        np.testing.assert_allclose(data.get_xdata(), res.elapsed[0])
        np.testing.assert_allclose(data.get_ydata(), 100 * (res.readings[0] - h.log.a) / abs(h.log.a))
        gx = line.get_xdata()
        np.testing.assert_allclose(line.get_ydata(), 100 * h.log.b * np.log10(gx) / abs(h.log.a), atol=1e-9)
        assert ax.get_xscale() == "log"
    finally:
        plt.close("all")


def test_default_settling_is_half_a_second_at_most_a_fifth_of_min_hold(tmp_path):
    t, ref = _profile(ONE_HOLD)
    assert creep(t, _log_readout(t), ref).settle_s == 0.5
    assert creep(t, _log_readout(t), ref, min_hold_s=1.0).settle_s == pytest.approx(0.2)
    code, out, err = run_cli(["creep", _write(tmp_path / "h.csv", t, ref, _log_readout(t)),
                              "--min-hold", "1s", "--json"])
    assert code == 0, err
    assert json.loads(out)["settle_s"] == pytest.approx(0.2)


def test_drift_needs_three_readings_after_settling():
    fit = log_drift([1.0, 2.0], [3.0, 4.0])
    assert np.isnan(fit.percent_per_decade) and "3" in fit.note
    fit = log_drift([1.0, 10.0, 100.0], [3.0, 4.0, 5.0])
    assert fit.percent_per_decade == pytest.approx(100 / 3) and fit.b_stderr == pytest.approx(0.0, abs=1e-12)

