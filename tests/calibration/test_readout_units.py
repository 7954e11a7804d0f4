"""A readout's unit is compared: runs in counts and in volts are not calibrated together, and a calibration in
counts is not applied to a run in volts without being forced.

Reference: the property (issue's rule: one readout per calibration; exit 2 with one line naming both), on two
runs of the same divider written with their units in the sidecar (``io.runwriter.write_run``'s metadata).
"""

from __future__ import annotations

import numpy as np
import pytest

import fsrlab as fl
from clirun import run_cli
from fsrlab.errors import ParameterError, ProvenanceError
from fsrlab.io.runwriter import write_run


def _divider_run(path, unit: str, scale: float):
    t = np.arange(400) * 0.05
    force = 10 * np.abs(((t / 5) % 2) - 1)
    volts = 5 * force / (force + 4.0)  # a divider's voltage rising with force
    reading = volts * scale  # volts, or analogRead counts of a 5 V reference
    write_run(path, {"time_s": t, "force_n": force, "reading": reading}, metadata={"units": {"reading": unit}})
    return path


@pytest.fixture
def runs(tmp_path):
    return {"counts": _divider_run(tmp_path / "counts.csv", "count", 1023 / 5),
            "counts2": _divider_run(tmp_path / "counts2.csv", "counts", 1023 / 5),
            "volts": _divider_run(tmp_path / "volts.csv", "V", 1.0)}


def test_runs_of_two_readout_units_are_not_calibrated_together(runs):
    with pytest.raises(ParameterError, match="in V.*in count|in count.*in V") as info:
        fl.calibrate([runs["counts"], runs["volts"]], x="reading", reference="force_n")
    assert info.value.parameter == "runs"
    # "count" and "counts" are one unit
    cal = fl.calibrate([runs["counts"], runs["counts2"]], x="reading", reference="force_n")
    assert cal.x_unit in ("count", "counts")


def test_a_counts_calibration_is_not_applied_to_volts_unless_forced(runs, tmp_path):
    cal = fl.calibrate(runs["counts"], x="reading", reference="force_n")
    with pytest.raises(ProvenanceError, match="reading in V"):
        fl.apply(cal, runs["volts"])
    assert np.isfinite(fl.apply(cal, runs["counts2"])["force_n_estimate"]).any()
    forced = fl.apply(cal, runs["volts"], force=True)
    assert "force_n_estimate" in forced
    fl.save_calibration(cal, tmp_path / "cal.json")
    code, _, err = run_cli(["apply", tmp_path / "cal.json", runs["volts"], "-o", tmp_path / "out.csv"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "in V" in err and "count" in err


def test_a_divider_calibration_is_not_applied_to_an_op_amp_voltage(runs, tmp_path):
    """voltage_v of a divider (no op-amp in the calibration's runs) and of the op-amp readout of
    examples/bench.csv (its sidecar names the op-amp) are different readouts: refused, naming both."""
    from pathlib import Path

    t = np.arange(400) * 0.05
    force = 10 * np.abs(((t / 5) % 2) - 1)
    write_run(tmp_path / "div.csv", {"time_s": t, "force_n": force, "voltage_v": 5 * force / (force + 4.0)})
    cal = fl.calibrate(tmp_path / "div.csv", x="voltage_v", reference="force_n")
    bench = Path(__file__).resolve().parents[2] / "examples" / "bench.csv"
    with pytest.raises(ProvenanceError, match="op-amp"):
        fl.apply(cal, bench)
