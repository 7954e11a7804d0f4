"""
Calibrating a run and its ±2u band
==================================

A calibration run and a test run from the synthetic bench (the virtual sensor through the 555 and the
meter model: 62.5 ns timer ticks, a 10-bit ADC, noise). :func:`fsrlab.calibrate` fits the readout →
stress curve, every choice scored on data it was not fitted on; :func:`fsrlab.apply` estimates the test
run with a standard uncertainty u per reading; :func:`fsrlab.agreement` compares the estimate with the
test run's own reference.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import fsrlab as fl

folder = Path(tempfile.mkdtemp())
bench = fl.load_run(fl.synthetic_run(cycles=3, points_per_ramp=40, seed=1).write(folder / "bench.csv"))
test = fl.load_run(fl.synthetic_run(cycles=2, points_per_ramp=40, seed=7).write(folder / "test.csv"))
cal = fl.calibrate(bench)
print(cal)

est = fl.apply(cal, test)
t, ref = est["time_s"], est["stress_pa"] / 1e3
x, u = est["stress_pa_estimate"] / 1e3, est["stress_pa_uncertainty"] / 1e3
print(fl.agreement(est["stress_pa"], est["stress_pa_estimate"], est["stress_pa_uncertainty"]))

fig, ax = plt.subplots(figsize=(7, 4))
ax.fill_between(t, x - 2 * u, x + 2 * u, color="C0", alpha=0.25, label="estimate ± 2u")
ax.plot(t, x, color="C0", label="estimate")
ax.plot(t, ref, "k--", lw=1, label="applied stress")
ax.set(xlabel="time [s]", ylabel="stress [kPa]", title="A calibration applied to a run it never saw")
ax.legend()
plt.show()
