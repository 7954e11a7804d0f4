"""``fsrlab loadcell`` and ``fsrlab measure`` on the virtual meter, and their bad input.

References: the virtual load cell's known parameters (fsrlab.acquisition.loadcell.LoadCellModel():
offset 8192 counts, 87 600 counts/N, 40 counts of noise per conversion, 5 kg capacity in the
file only through --capacity); the stated rules (a scale mass below 5 % of the capacity warns;
one line naming the option, exit 2). Real time: about 1 s per reading.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.io.runformat import load_run

ROOT = Path(__file__).resolve().parents[2]


def test_tare_then_scale_find_the_virtual_cells_parameters(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["loadcell", "tare", "--virtual", "--capacity", "5kg", "-o", "lc.json",
                              "--duration", "1s", "--seed", "1", "--json"])
    assert code == 0, err
    tare = json.loads(out)
    # 10 windows of 8 conversions: the mean of 80 conversions is within 5·40/√80 counts of 8192.
    assert abs(tare["offset_counts"] - 8192) < 5 * 40 / math.sqrt(80)
    assert tare["capacity_n"] == 5 * 9.80665
    code, out, err = run_cli(["loadcell", "scale", "--virtual", "--mass", "500g", "--cal", "lc.json",
                              "--duration", "1s", "--seed", "2", "--json"])
    assert code == 0 and "warning" not in err, err
    scale = json.loads(out)
    assert abs(scale["scale_counts_per_n"] - 87600) < 2 * 5 * 40 / math.sqrt(80) / (0.5 * 9.80665)
    saved = json.loads(Path("lc.json").read_text())
    assert saved["scale"]["mass_kg"] == 0.5 and saved["scale"]["gravity_m_s2"] == 9.80665
    assert saved["tare"]["noise_counts"] > 0 and saved["scale"]["noise_n"] > 0 and saved["created"]
    code, out, err = run_cli(["loadcell", "scale", "--virtual", "--mass", "100g", "--cal", "lc.json",
                              "-o", "small.json", "--duration", "1s", "--seed", "3"])
    assert code == 0 and "below 5 % of the load cell's capacity" in err, err  # 0.98 N < 2.45 N
    # The recorder turns raw counts into force with it (force = (raw − offset)/scale).
    code, out, err = run_cli(["acquire", "--virtual", "--quiet", "--duration", "0.5", "--loadcell", "lc.json",
                              "-o", "run.csv"])
    assert code == 0, err
    run = load_run("run.csv")
    expected = (run["reference_raw"] - saved["offset_counts"]) / saved["scale_counts_per_n"]
    assert np.allclose(run["force_n"], expected, rtol=1e-12) and run.metadata["load_cell"] == saved


def test_bad_input_one_line_naming_the_option(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("tare.json").write_text(json.dumps({"format": "fsrlab-loadcell", "version": 1, "offset_counts": 8192.0,
                                             "scale_counts_per_n": None}))
    for args, option in ((["loadcell", "tare", "--virtual"], "--out"),
                         (["loadcell", "weigh", "--virtual", "-o", "x.json"], "ACTION"),
                         (["loadcell", "scale", "--virtual", "--cal", "tare.json"], "--mass"),
                         (["loadcell", "scale", "--virtual", "--cal", "tare.json", "--mass", "5N"], "--mass"),
                         (["loadcell", "tare", "--virtual", "-o", "tare.json"], "--out"),  # exists
                         (["acquire", "--virtual", "--duration", "0.1", "--loadcell", "tare.json"], "--loadcell"),
                         (["acquire", "--virtual", "--duration", "0.1", "--sensor", "fsr-999"], "--sensor"),
                         (["acquire", "--virtual", "--duration", "0.1", "--area", "5kg"], "--area"),
                         (["measure", "--virtual", "--cal", "tare.json", "--duration", "0.1"], "--cal")):
        code, out, err = run_cli(args)
        assert code == 2 and err.count("\n") == 1 and option in err and "Traceback" not in err, (args, err)


def test_measure_records_the_estimate_beside_the_load_cell(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    shutil.copy(ROOT / "examples" / "bench.csv", "bench.csv")
    shutil.copy(ROOT / "examples" / "bench.meta.json", "bench.meta.json")
    code, out, err = run_cli(["calibrate", "bench.csv", "-o", "cal.json"])
    assert code == 0, err
    code, out, err = run_cli(["measure", "--virtual", "--cal", "cal.json", "--duration", "1s", "--quiet",
                              "-o", "live.csv", "--json"])
    assert code == 0, err
    info = json.loads(out)
    run = load_run("live.csv")
    assert run.n_rows == info["frames"] > 0 and info["estimated"] == np.sum(np.isfinite(run["stress_pa_estimate"]))
    area = run.metadata["sensor"]["area_m2"]
    ok = np.isfinite(run["stress_pa_estimate"])
    assert np.allclose(run["force_n_estimate"][ok], run["stress_pa_estimate"][ok] * area)  # force = stress × area
    assert np.all(np.isfinite(run["force_n"]))  # the emulated load cell beside it


@pytest.mark.parametrize("recorded, named", [
    ({"range": 1, "circuit": {}}, "range 1"),  # the virtual circuit, but C_off switched in
    ({"range": 0, "circuit": {"r_ohm": 4.7e3}}, "R = 4.7 kΩ"),  # another R on the same range
])
def test_measure_refuses_a_calibration_made_on_another_circuit_or_range(tmp_path, monkeypatch, recorded, named):
    # The provenance check of fsrlab apply (calibration.apply.readout_differences), before any window is read:
    # the virtual meter runs VIRTUAL_CIRCUIT on range 0.
    from fsrlab.calibration.document import save_calibration
    from fsrlab.calibration.runs import calibrate_runs
    from fsrlab.io.runwriter import write_run
    from fsrlab.virtual.sources import VIRTUAL_CIRCUIT
    from fsrlab.virtual.synthetic import synthetic_run

    monkeypatch.chdir(tmp_path)
    run = synthetic_run(cycles=2, points_per_ramp=60, seed=1)
    circuit = VIRTUAL_CIRCUIT.replace(**recorded["circuit"])
    write_run("cal-run.csv", {**run.columns, "range": np.full(len(run.columns["time_s"]), recorded["range"])},
              {"circuit": circuit.to_dict()})
    save_calibration(calibrate_runs("cal-run.csv", x="frequency_hz"), "cal.json")
    code, out, err = run_cli(["measure", "--virtual", "--cal", "cal.json", "--duration", "1s", "--quiet",
                              "-o", "live.csv"])
    assert code == 2 and err.count("\n") == 1 and "--cal" in err and named in err, err
    assert "the meter has" in err and not (tmp_path / "live.csv").exists()


def test_measure_ages_the_memory_by_the_rows_time_as_apply_does(tmp_path, monkeypatch):
    """A calibration with creep terms whose row step is not the meter's: ``measure`` steps its memory by
    each row's ``time_s``, so its estimates equal ``apply``'s on the run it wrote (which reads the
    times from the file). Stepped by the calibration's row step instead, the creep averages would age
    ten times too fast and the two would differ."""
    monkeypatch.chdir(tmp_path)
    shutil.copy(ROOT / "examples" / "bench.csv", "bench.csv")
    shutil.copy(ROOT / "examples" / "bench.meta.json", "bench.meta.json")
    code, out, err = run_cli(["calibrate", "bench.csv", "--x", "frequency_hz", "-o", "plain.json"])
    assert code == 0, err
    doc = json.loads(Path("plain.json").read_text())
    model = doc["calibration"]
    span = float(model["full_scale"])
    model.update({"time_constants_s": [0.5, 2.0], "weights": [0.3 * span, 0.2 * span],
                  "row_s": 10 * float(model["row_s"])})
    Path("cal.json").write_text(json.dumps(doc))
    code, out, err = run_cli(["measure", "--virtual", "--cal", "cal.json", "--duration", "2s",
                              "--quiet", "-o", "live.csv"])
    assert code == 0, err
    code, out, err = run_cli(["apply", "cal.json", "live.csv", "-o", "again.csv"])
    assert code == 0, err
    live, again = load_run("live.csv"), load_run("again.csv")
    ok = np.isfinite(live["stress_pa_estimate"])
    assert ok.sum() > 10
    assert np.allclose(live["stress_pa_estimate"][ok], again["stress_pa_estimate"][ok], rtol=1e-9, atol=1e-6 * span)


def _tree(root: Path) -> dict[str, str]:
    import hashlib

    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(root.iterdir()) if p.is_file()}


def test_scale_to_another_file_follows_the_output_policy(tmp_path, monkeypatch):
    # Reference: the output policy (fsrlab.io.outputs): an existing -o is replaced only with --overwrite, the
    # --cal input never; the sha256 of every file is the same after a refusal, and the meter is not read.
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(["loadcell", "tare", "--virtual", "-o", "lc.json", "--duration", "1s", "--seed", "1"])
    assert code == 0, err
    Path("mine.json").write_text("mine\n")
    scale = ["loadcell", "scale", "--virtual", "--mass", "500g", "--cal", "lc.json", "--duration", "1s", "--seed", "2"]
    for extra, said in ((["-o", "mine.json"], "mine.json exists; pass --overwrite"),
                        (["-o", "./lc.json", "--overwrite"], "is the --cal file; leave -o out"),
                        (["-o", "."], "is a directory, not a file"),
                        (["-o", "missing/x.json"], "does not exist")):
        before = _tree(tmp_path)
        code, out, err = run_cli(scale + extra)
        assert code == 2 and err.count("\n") == 1 and "--out" in err and said in err, (extra, err)
        assert _tree(tmp_path) == before, extra
    code, out, err = run_cli(scale + ["-o", "mine.json", "--overwrite", "--json"])
    assert code == 0, err
    assert json.loads(Path("mine.json").read_text())["scale_counts_per_n"] == json.loads(out)["scale_counts_per_n"]
    assert json.loads(Path("lc.json").read_text())["scale_counts_per_n"] is None  # the tare itself untouched


def test_an_interrupted_save_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    # Reference: the output policy's atomic write (fsrlab.io.outputs): the final name holds the old file or the
    # whole new one, and no temporary file is left beside it; a file the user has under any other name stays.
    from fsrlab.acquisition.loadcell import LoadCellCalibration

    cal = LoadCellCalibration(offset_counts=8192.0)
    target = tmp_path / "lc.json"
    cal.save(target)
    (tmp_path / "lc.json.tmp").write_text("mine\n")
    before = _tree(tmp_path)
    real_write = Path.write_text

    def half_then_interrupted(self, text, *args, **kwargs):
        real_write(self, text[: len(text) // 2], *args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(Path, "write_text", half_then_interrupted)
    with pytest.raises(KeyboardInterrupt):
        LoadCellCalibration(offset_counts=9000.0).save(target)
    monkeypatch.undo()
    assert _tree(tmp_path) == before
    assert {p.name for p in tmp_path.iterdir()} == {"lc.json", "lc.json.tmp"}
