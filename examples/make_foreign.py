"""Write the two foreign-CSV examples of ``fsrlab import`` (examples/README.md); not measurements.

An FSR in a divider (FSR to 5 V, 10 kΩ to ground, read by a 10-bit analogRead) pressed in two
triangles 0 → 10 N → 0 over 20 s, logged by a sketch at 20 rows/s; its conductance follows
G = 1e-5 S·(F / 1 N)^0.9 (a power law of the Interlink 402's datasheet shape) with 1 count of noise.
A load cell logged by another program at 12.5 rows/s, in newtons with 5 mN of noise.
"""

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
G0 = 9.80665


def force(t):
    phase = (t % 10.0) / 10.0
    return 10.0 * (1.0 - np.abs(2.0 * phase - 1.0))


def main():
    rng = np.random.default_rng(26)
    t = np.arange(0, 20.0, 0.05)
    f = force(t)
    g = 1e-5 * np.maximum(f, 0.0) ** 0.9
    v = 5.0 * 10e3 * g / (1 + 10e3 * g)
    counts = np.clip(np.round(v / 5.0 * 1023 + rng.normal(0, 1, t.size)), 0, 1023).astype(int)
    lines = ["# fsr_logger.ino: analogRead(A0) every 50 ms, FSR to 5 V, 10k to ground",
             "# load in grams from the kitchen scale's HX711 on the same board",
             "time_ms;fsr_a0;load_g"]
    lines += [f"{int(round(1000 * ti))};{c};{1000 * fi / G0:.1f}".replace(".", ",") for ti, c, fi in zip(t, counts, f)]
    (HERE / "foreign_fsr.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    tr = np.arange(0.0, 20.0, 0.08)
    fr = force(tr) + rng.normal(0, 0.005, tr.size)
    lines = ["t_s,force_N"] + [f"{ti:.2f},{fi:.4f}" for ti, fi in zip(tr, fr)]
    (HERE / "foreign_loadcell.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
