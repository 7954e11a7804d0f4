"""Runs recorded from the virtual device with its emulated load cell: reference_raw, force_n, counts.

References: the virtual load cell's known parameters (fsrlab.acquisition.loadcell.LoadCellModel():
offset 8192 counts, 87 600 counts/N, noise 40 counts per conversion, 80 or 10 samples/s), the closed
form force = (raw − offset)/scale, and the sensor area of the preset (π·(12.7 mm)²/4, Interlink FSR
402 datasheet). These record in real time: two seconds each.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from clirun import run_cli
from fsrlab.acquisition.loadcell import LoadCellModel
from fsrlab.io.runformat import load_run

CELL = LoadCellModel()


def test_virtual_run_carries_force_from_the_load_cell(tmp_path):
    out = tmp_path / "run.csv"
    code, stdout, err = run_cli(["acquire", "--virtual", "--speed", "max", "--quiet", "--duration", "1.5", "--window",
                                 "50ms", "--profile", "hold", "--peak", "30k", "--sensor", "interlink-402",
                                 "-o", str(out),
                                 "--json"])
    assert code == 0, err
    run = load_run(out)
    area = math.pi * 12.7e-3**2 / 4
    assert run.metadata["sensor"]["area_m2"] == pytest.approx(area)
    assert run.metadata["load_cell"]["scale_counts_per_n"] == CELL.scale_counts_per_n
    raw, force, stress = run["reference_raw"], run["force_n"], run["stress_pa"]
    assert np.all(np.isfinite(raw)) and np.array_equal(force, (raw - CELL.offset_counts) / CELL.scale_counts_per_n)
    # Held stress: each window's mean of 4 conversions is within 5 σ/√4 counts of offset + scale·σ·A.
    bound = 5 * CELL.noise_counts / 2 / CELL.scale_counts_per_n
    assert np.all(np.abs(force - stress * area) < bound)
    assert '"no_reference": 0' in stdout


def test_slow_or_missing_hx711_leaves_cells_empty_and_counts_them(tmp_path):
    out = tmp_path / "slow.csv"
    code, stdout, err = run_cli(["acquire", "--virtual", "--speed", "max", "--quiet", "--duration", "1.5", "--window",
                                 "50ms", "--hx711-rate", "10", "-o", str(out), "--json"])
    assert code == 0, err
    run = load_run(out)
    empty = np.isnan(run["reference_raw"])
    # 10 samples/s in 50 ms windows: about every other window has none (never a 0 in its place).
    assert 0 < empty.sum() < run.n_rows and not np.any(run["reference_raw"] == 0)
    assert np.array_equal(np.isnan(run["force_n"]), empty)
    assert run.metadata["acquisition"]["no_reference"] == empty.sum()
    out = tmp_path / "none.csv"
    code, stdout, err = run_cli(["acquire", "--virtual", "--quiet", "--duration", "0.5", "--no-loadcell",
                                 "-o", str(out), "--json"])
    assert code == 0, err
    run = load_run(out)
    assert np.all(np.isnan(run["reference_raw"])) and np.all(np.isnan(run["force_n"]))
    assert f'"no_reference": {run.n_rows}' in stdout


def test_a_load_cell_that_stops_answering_is_said_and_its_cells_stay_empty(tmp_path):
    """The HX711 disconnected mid-run (the virtual device stops emulating it after 0.4 s): the
    recorder says so once, and the later windows have empty reference cells, counted."""
    import threading

    from fsrlab.acquisition.recorder import record
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.virtual.device import VirtualDevice

    said = []
    with VirtualDevice(seed=3) as dev, SerialLink(dev.port) as link:
        timer = threading.Timer(0.4, lambda: setattr(dev, "load_cell", None))
        timer.start()
        result = record(link, tmp_path / "run.csv", 1.0, window_ms=50, on_event=said.append)
        timer.cancel()
    run = load_run(tmp_path / "run.csv")
    empty = np.isnan(run["reference_raw"])
    assert 0 < empty.sum() < run.n_rows and not np.any(run["reference_raw"] == 0)
    assert np.all(empty[np.argmax(empty):])  # once gone, gone
    assert result.no_reference == empty.sum() == run.metadata["acquisition"]["no_reference"]
    assert len([s for s in said if s.startswith("no load cell")]) == 1


class _Version1Device:
    """A virtual device that speaks protocol version 1: ``ID`` says 1 and ``M`` frames have 8 fields
    (docs/protocol.md, version 1), as a meter flashed before version 2."""

    @staticmethod
    def make(**kwargs):
        from fsrlab.virtual.device import VirtualDevice

        class V1(VirtualDevice):
            def _send_frame(self, kind, fields, faults=True):
                fields = tuple(fields)
                if kind == "ID":
                    fields = fields[:2] + (1,) + fields[3:]
                elif kind == "M":
                    fields = fields[:8]
                return super()._send_frame(kind, fields, faults)

        return V1(**kwargs)


def test_a_version_1_meter_records_as_before(tmp_path):
    from fsrlab.acquisition.recorder import COLUMNS, record, result_dict
    from fsrlab.acquisition.serial_link import SerialLink

    with _Version1Device.make(seed=4) as dev, SerialLink(dev.port) as link:
        result = record(link, tmp_path / "run.csv", 0.4, window_ms=50)
    run = load_run(tmp_path / "run.csv")
    assert run.n_rows == result.frames > 0 and list(run.columns) == list(COLUMNS)
    assert run.metadata["acquisition"]["protocol_version"] == 1 and "no_reference" not in run.metadata["acquisition"]
    assert list(result_dict(result)) == ["frames", "dropped", "duration_s", "file"]
