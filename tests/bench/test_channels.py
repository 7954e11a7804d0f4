"""Several FSRs on one meter, after the recording: a multi-channel run calibrated per channel from one
call, and the cross-talk check (src/fsrlab/bench/channels.py; issue 39).

References: the virtual bench's own applied stress (each reading's ``stress_pa``, the reference the
calibration engine is scored against); the engine itself (:func:`fsrlab.calibrate`) is tested in
tests/calibration. Cross-talk: the meter model has no coupling between channels but what a switch leaves
behind (the node's charge, shared with the next sensor; the twin models it), and the firmware discards the
first edge and SETTLE periods after each switch: every off-diagonal entry must stay within the readings'
own spread (seen: 4e-5 on the virtual device, 4e-6 in the twin, 50 kPa on one channel); a coupling of the loaded
channel's change into its neighbour would show as an entry of that size.
"""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.acquisition.recorder import Scan, record
from fsrlab.acquisition.serial_link import SerialLink
from fsrlab.bench.channels import calibrate_channels, channel_runs, crosstalk, twin_meter, virtual_meter
from fsrlab.errors import ParameterError
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import MuxSource, StressProfile


@pytest.fixture(scope="module")
def built():
    """The firmware and the twin's harness, built (as tests/virtual/twin/conftest.py)."""
    import subprocess
    from pathlib import Path

    from toolcheck import require_file, require_tool

    require_tool("avr-gcc")
    require_tool("make")
    require_file("/usr/include/simavr/sim_avr.h", "libsimavr-dev (simavr headers)")
    require_file("/usr/share/arduino/hardware/arduino/avr/cores/arduino/Arduino.h", "arduino-core-avr")
    subprocess.run(["make", "-s", "-C", str(Path(__file__).resolve().parents[2] / "firmware")], check=True,
                   capture_output=True, text=True)
    from fsrlab.virtual.twin import twin_available

    ok, reason = twin_available()
    assert ok, reason


@pytest.fixture(scope="module")
def four_channel_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("channels") / "run.csv"
    src = MuxSource.scaled(4, StressProfile("triangle", 40e3, 2.0))
    with VirtualDevice(src, seed=1, speed="max") as dev, SerialLink(dev.port) as link:
        result = record(link, path, 8.0, scan=Scan((0, 1, 2, 3)), clock="device", metadata=src.metadata(),
                        reference=lambda f: dev.reference(f.seq))
    assert result.ended == "duration"
    return path


def test_channel_runs_split_by_channel_with_their_sensor(four_channel_run):
    runs = channel_runs(four_channel_run)
    assert sorted(runs) == [0, 1, 2, 3]
    for k, run in runs.items():
        assert np.all(run.columns["channel"] == k)
        assert run.metadata["sensor"]["sensor_id"] == f"fsr{k}"
        assert run.metadata["channel"]["profile"]["peak_pa"] == pytest.approx(40e3 * (k + 1) / 4)
    from fsrlab.io.runformat import load_run

    assert sum(r.n_rows for r in runs.values()) == load_run(four_channel_run).n_rows


def test_every_channel_calibrated_from_one_call(four_channel_run):
    cals = calibrate_channels(four_channel_run)
    assert sorted(cals.by_sensor) == ["fsr0", "fsr1", "fsr2", "fsr3"]
    assert cals.channels == {"fsr0": 0, "fsr1": 1, "fsr2": 2, "fsr3": 3}
    doc = cals.to_dict()
    assert sorted(doc["sensors"]) == ["fsr0", "fsr1", "fsr2", "fsr3"]
    estimates = cals.apply(four_channel_run)
    for sid, est in estimates.items():
        truth, got = est.columns["stress_pa"], est.columns["stress_pa_estimate"]
        ok = np.isfinite(got)
        # each channel's calibration reads its own sensor: within 10 % of that channel's full scale
        assert ok.sum() > 0.9 * ok.size
        assert np.max(np.abs(got[ok] - truth[ok])) < 0.1 * truth.max(), sid


def test_a_run_without_channels_is_refused(tmp_path):
    with VirtualDevice(seed=1, speed="max") as dev, SerialLink(dev.port) as link:
        record(link, tmp_path / "one.csv", 0.5, clock="device")
    with pytest.raises(ParameterError) as err:
        channel_runs(tmp_path / "one.csv")
    assert err.value.parameter == "run"


def test_crosstalk_matrix_on_the_virtual_device():
    x = crosstalk(virtual_meter, duration_s=0.5)
    assert x.matrix.shape == (8, 8) and np.allclose(np.diag(x.matrix), 1.0)
    assert x.worst < 2e-3
    assert np.all(x.loaded_hz[np.arange(8), np.arange(8)] > x.baseline_hz * 1.5)  # each load moves its own channel


def test_crosstalk_matrix_in_the_twin(built):
    x = crosstalk(twin_meter, duration_s=0.4)
    assert x.matrix.shape == (8, 8)
    assert x.worst < 1e-3


def test_cli_calibrate_channels_writes_one_file_keyed_by_sensor(four_channel_run, tmp_path):
    import json

    from typer.testing import CliRunner

    import fsrlab.cli.channels  # noqa: F401 - registers the commands (until fsrlab.cli.COMMANDS lists them)
    from fsrlab.cli import app

    out = tmp_path / "channels.json"
    r = CliRunner().invoke(app, ["calibrate-channels", str(four_channel_run), "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    assert sorted(json.loads(out.read_text())["sensors"]) == ["fsr0", "fsr1", "fsr2", "fsr3"]
    again = CliRunner().invoke(app, ["calibrate-channels", str(four_channel_run), "--out", str(out)])
    assert again.exit_code == 2 and "--out" in again.output  # an existing file is replaced only when asked


def test_cli_crosstalk_json():
    import json

    from typer.testing import CliRunner

    import fsrlab.cli.channels  # noqa: F401
    from fsrlab.cli import app

    r = CliRunner().invoke(app, ["crosstalk", "--channels", "0-2", "--duration", "0.3s", "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.output)
    assert np.array(doc["matrix"]).shape == (3, 3) and doc["worst"] < 2e-3
