"""
The twin's traces
=================

A spring protocol (cycles 0 → 10 kPa → 0, as on the paper's stepper-motor bench) recorded from the
digital twin: the meter's real firmware running in simavr, fed the 555's edges computed from the
virtual sensor, read over a pseudo-terminal like an Uno. Where the twin cannot run (no simavr or no
firmware build), the same protocol is recorded from the Python virtual device, and the title says so.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import fsrlab as fl
from fsrlab.bench.protocols import SpringPlan

device = "twin" if fl.twin_available().ok else "virtual"
out = Path(tempfile.mkdtemp()) / "spring.csv"
fl.run_protocol(SpringPlan(peak_pa=10e3, cycles=2, period_s=2.0), out, device=device, seed=1, speed="max")
run = fl.load_run(out)
print(f"{device}: {len(run['time_s'])} windows")

fig, axes = plt.subplots(3, 1, sharex=True, figsize=(7, 6))
axes[0].plot(run["time_s"], run["frequency_hz"] / 1e3)
axes[0].set_ylabel("frequency [kHz]")
axes[1].plot(run["time_s"], run["duty_cycle"] * 100)
axes[1].set_ylabel("duty cycle [%]")
axes[2].plot(run["time_s"], run["force_n"], label="load cell")
axes[2].set(xlabel="time [s]", ylabel="force [N]")
axes[0].set_title(f"Spring cycles recorded from the {'digital twin' if device == 'twin' else 'virtual device'}")
plt.show()
