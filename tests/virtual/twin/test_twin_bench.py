"""Bench protocols on the digital twin: the virtual bench's placed masses (BenchSource) drive the real firmware.

References: properties that must hold for any sensor whose frequency rises with load (the virtual
FSR's, :class:`fsrlab.physics.sensor.VirtualFSR`): the frequency the firmware measures at each
placement rises with the mass; no window dropped, no missed edge; the load cell's
force (HX711 model in the harness) equals m·g within its noise.
"""

from __future__ import annotations

import csv

import numpy as np

from fsrlab.bench.protocols import WeightsPlan, run_protocol
from fsrlab.io.runformat import load_run
from fsrlab.physics.sensor import VirtualFSR
from fsrlab.units import STANDARD_GRAVITY
from fsrlab.virtual.bench_source import BenchSource


def test_bench_source_parts_are_what_its_windows_average():
    # parts() holds the same samples window() averages: a window inside a steady placement gives the
    # 555 of parts() at that time (closed form of the astable on the same R_FSR and C_FSR).
    src = BenchSource([0.5, 2.0], sensor=VirtualFSR())
    src.place(1, 1.0)
    r, c, v = src.parts(np.array([0.5, 2.0]))
    sig = src.window(1.9, 2.0, 0)
    osc = src.circuit.on_range(0).astable(r[1], c[1], check=False)  # range 0: C_off out
    assert np.isclose(sig.frequency_hz, 1 / (osc.tau_high_s + osc.tau_low_s), rtol=1e-12)
    assert np.isclose(sig.voltage_v, v[1], rtol=1e-12)
    assert r[1] < r[0]  # more force, lower resistance


def test_weights_protocol_on_the_twin(built, tmp_path):
    out = tmp_path / "w.csv"
    plan = WeightsPlan(masses_kg=(0.2, 0.4), repeat=1)
    run = run_protocol(plan, out, device="twin", seed=3, settle={"hold_s": 0.3}, speed="max")
    assert run.device == "twin" and not run.result.failed
    assert run.result.dropped == 0
    data = load_run(out)
    assert np.nansum(data["missed"]) == 0  # (the procedure keeps only the windows of each placement's hold)
    assert "simavr" in data.metadata["origin"]
    with open(run.placements, newline="") as fh:
        rows = [r for r in csv.DictReader(fh)]
    reading = {float(r["load"]): float(r["reading"]) for r in rows}
    assert reading[0] < reading[200] < reading[400]
    # The load cell (HX711 model fed by the twin) reads m·g at the steady end of each placement.
    steady = np.isfinite(data["force_n"]) & (np.asarray(data["step"], dtype=float) == 2)
    assert steady.any()
    np.testing.assert_allclose(np.median(np.asarray(data["force_n"])[steady]), 0.4 * STANDARD_GRAVITY, rtol=0.02)
