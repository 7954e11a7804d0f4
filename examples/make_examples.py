"""Write the example inputs of this folder (run from the repository root: python examples/make_examples.py).

Everything here is synthetic except repeatability.csv (the paper's printed Table 4). The synthetic
files come from fsrlab's virtual bench, fsrlab.analysis.synthetic.synthetic_run: the virtual FSR
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
    from fsrlab.analysis.synthetic import synthetic_run

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
    from fsrlab.analysis.synthetic import synthetic_run
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
    from fsrlab.analysis.synthetic import synthetic_run
    from fsrlab.physics.sensor import VirtualFSR

    area = VirtualFSR().area_m2
    ramp = np.concatenate([[0.0], ISO_FORCES_N])
    stress = np.concatenate([ramp, np.full(300, ISO_FORCES_N[-1])]) / area
    f = synthetic_run(stress_pa=stress, window_s=1.0, seed=15).columns["frequency_hz"]
    at_max = ramp.size - 1
    return round(float(f[at_max + 30]), 1), round(float(f[at_max + 300]), 1)


def calibration() -> None:
    """calibration.json: fsrlab calibrate examples/bench.csv --compensate -o examples/calibration.json."""
    import os

    from fsrlab.cli import main

    os.chdir(HERE.parent)
    try:
        main(["calibrate", "examples/bench.csv", "--compensate", "-o", "examples/calibration.json", "--json"])
    except SystemExit as exc:
        if exc.code:
            raise


if __name__ == "__main__":
    runs()
    repeatability()
    iso376()
    calibration()
    print("--creep {},{}".format(*creep_readings()))
