"""Write the example inputs of this folder (run from the repository root: python examples/make_examples.py).

Everything here is synthetic except repeatability.csv (the paper's printed Table 4). The synthetic
files come from fsrlab's virtual bench, fsrlab.virtual.synthetic.synthetic_run: the virtual FSR
(fsrlab.physics.sensor.VirtualFSR) read through the paper's LM555 circuit (R = 10 kΩ, ideal D1) and
op-amp, and the meter's model (100 ms windows, 62.5 ns ticks, 0.2 % frequency noise), with the
seeds given below. calibration.json is what `fsrlab calibrate` writes for bench.csv, so it carries
its creation time.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

#: The minimal run of docs/data-format.md (a hand-made file: no sidecar).
MINIMAL = "stress_pa,frequency_hz\n0,3012.5\n1000,3890.1\n2000,4630.7\n"

#: ISO 376 example: forces [N], and the series (label, rotation [°], with decreasing forces, seed).
ISO_FORCES_N = np.round(np.arange(1, 9) * 0.4, 1)
ISO_SERIES = (("1", 0, False, 11), ("2", 0, False, 12), ("3", 120, True, 13), ("4", 240, True, 14))


def runs() -> None:
    """bench.csv (2 cycles to 50 kPa, seed 1) and other.csv (1 cycle to 55 kPa, beyond bench's range, seed 7)."""
    from fsrlab.virtual.synthetic import synthetic_run

    synthetic_run(cycles=2, points_per_ramp=25, seed=1).write(HERE / "bench.csv")
    synthetic_run(cycles=1, points_per_ramp=25, peak_pa=55e3, seed=7).write(HERE / "other.csv")
    (HERE / "minimal.csv").write_text(MINIMAL, encoding="utf-8")


def repeatability() -> None:
    """The paper's Table 4: five readings per sensor and load (frequency, kHz by context)."""
    from fsrlab.reference import paper_values

    t = paper_values()["table4_repeatability_capacitive_kHz"]
    lines = ["load,sensor,reading"]
    for load in ("200g", "400g"):
        for sensor, readings in enumerate(t[load]["readings"], start=1):
            lines += [f"{load},{sensor},{r}" for r in readings]
    (HERE / "repeatability.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")


def iso376() -> None:
    """ISO 376 series of the virtual sensor: frequency readings at 8 forces, zero readings before and after."""
    from fsrlab.virtual.synthetic import synthetic_run
    from fsrlab.physics.sensor import VirtualFSR

    area = VirtualFSR().area_m2
    lines = ["series,rotation_deg,force_n,reading,direction"]
    for label, rotation, decreasing, seed in ISO_SERIES:
        forces = np.concatenate([[0.0], ISO_FORCES_N, ISO_FORCES_N[::-1][1:] if decreasing else [], [0.0]])
        f = synthetic_run(stress_pa=forces / area, seed=seed).columns["frequency_hz"]
        n = ISO_FORCES_N.size
        direction = [1] * (n + 1) + [-1] * (forces.size - n - 1)
        lines += [f"{label},{rotation},{force:g},{reading:.1f},{d}" for force, reading, d in zip(forces, f, direction)]
    (HERE / "iso376.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")


def creep_readings() -> tuple[float, float]:
    """Readings 30 s and 300 s after the largest ISO force (1 s windows, seed 15): the --creep example.

    The virtual sensor has no creep, so the two differ by the meter's noise only.
    """
    from fsrlab.virtual.synthetic import synthetic_run
    from fsrlab.physics.sensor import VirtualFSR

    area = VirtualFSR().area_m2
    ramp = np.concatenate([[0.0], ISO_FORCES_N])
    stress = np.concatenate([ramp, np.full(300, ISO_FORCES_N[-1])]) / area
    f = synthetic_run(stress_pa=stress, window_s=1.0, seed=15).columns["frequency_hz"]
    at_max = ramp.size - 1
    return round(float(f[at_max + 30]), 1), round(float(f[at_max + 300]), 1)


#: Creep example: (nominal force [N], seconds) of each stretch: ramps of 1 s between rests and holds.
CREEP_PROFILE = ((0.0, 5.0), (2.0, 30.0), (0.0, 8.0), (3.2, 45.0), (0.0, 5.0))
#: Creep of the example's sensor: the stress it feels grows by this fraction per decade of the time since
#: the load reached its level (sigma_eff = sigma * (1 + k * log10(1 + age / 1 s))). [1]
CREEP_PER_DECADE = 0.03


def creep() -> None:
    """creep.csv: holds at 2 N (30 s) and 3.2 N (45 s) with a log-time creep of 3 %/decade in the stress felt.

    The virtual sensor has no creep of its own, so the creep is put into the stress it is driven
    with (sigma_eff above); the force_n column is the applied force (nominal plus 3 mN of load-cell
    noise), written only every other 100 ms window, empty in between, as a load cell read more
    slowly than the readout (an HX711) would leave it. Seeds 21 (meter) and 22 (load cell).
    """
    from fsrlab.virtual.synthetic import synthetic_run
    from fsrlab.physics.sensor import VirtualFSR
    from fsrlab.io.runwriter import write_run

    window_s, ramp_s = 0.1, 1.0
    area = VirtualFSR().area_m2
    knots_t, knots_f, start = [0.0], [0.0], 0.0
    for force, length in CREEP_PROFILE:
        if force != knots_f[-1]:
            start += ramp_s
            knots_t.append(start)
            knots_f.append(force)
        start += length
        knots_t.append(start)
        knots_f.append(force)
    t = np.arange(0.0, knots_t[-1], window_s)
    force = np.interp(t, knots_t, knots_f)
    # age: time since the force last changed (0 on ramps and rests).
    moving = np.r_[True, np.abs(np.diff(force)) > 1e-12]
    last_change = np.maximum.accumulate(np.where(moving, t, 0.0))
    age = np.where(force > 0, t - last_change, 0.0)
    felt = force * (1 + CREEP_PER_DECADE * np.log10(1 + age / 1.0))
    c = synthetic_run(stress_pa=felt / area, window_s=window_s, seed=21).columns
    noisy = force + 0.003 * np.random.default_rng(22).standard_normal(t.size)
    force_n = np.where(np.arange(t.size) % 2 == 0, np.round(noisy, 4), np.nan)
    meta = {"sensor": {"model": "VirtualFSR (FlexiForce A201-like, fsrlab.physics.sensor)", "area_m2": area},
            "origin": ("synthetic: examples/make_examples.py creep(): VirtualFSR driven with the force of "
                       f"CREEP_PROFILE and a creep of {CREEP_PER_DECADE:g} per decade of the hold's age in the "
                       "stress it feels; synthetic_run(window_s=0.1, seed=21); force_n every other window, "
                       "3 mN noise (seed 22)"),
            "notes": "synthetic data, not a measurement"}
    write_run(HERE / "creep.csv", {"time_s": np.round(t, 3), "force_n": force_n,
                                   "frequency_hz": np.round(c["frequency_hz"], 1), "voltage_v": c["voltage_v"]}, meta)


def calibration() -> None:
    """calibration.json: fsrlab calibrate examples/bench.csv --compensate -o examples/calibration.json."""
    import os

    from fsrlab.cli import main

    os.chdir(HERE.parent)
    try:
        main(["calibrate", "examples/bench.csv", "--compensate", "-o", "examples/calibration.json", "--overwrite",
              "--json"])
    except SystemExit as exc:
        if exc.code:
            raise


if __name__ == "__main__":
    runs()
    repeatability()
    iso376()
    creep()
    calibration()
    print("--creep {},{}".format(*creep_readings()))
