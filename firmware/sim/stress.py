"""Randomised stress of the meter firmware in simavr: random frequencies and duty cycles inside the
supported range, each run checked window by window (every edge captured, periods per window,
frequency and duty cycle within the quantization bound).

Rare timing coincidences (an edge that meets a particular instruction, a timer value at the wrap)
hide between the frequencies of a fixed grid; this found one (simavr loses Timer1 compare matches
just after the wrap, firmware/README.md) that the grid and the dense sweeps had missed.

    python firmware/sim/stress.py --runs 400 --seed 7        # about 2 minutes
    python firmware/sim/stress.py --runs 400 --seed 7 --hx 80   # with an HX711 read meanwhile
"""

from __future__ import annotations

import argparse
import random
import sys
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import simrun  # noqa: E402
from simrun import Segment  # noqa: E402

PERIOD_SLACK = 3
"""Periods per window may differ from f x window by this much (a boundary moves by up to a period)."""


@dataclass(frozen=True)
class Failure:
    freq_hz: float
    duty: float
    why: str


HX_SCK_HIGH_MAX_US = 60.0
"""The HX711 powers down when SCK stays high longer than this (datasheet). [us]"""


def check(freq: float, duty: float, time_s: float = 1.0, seed: int = 1,
          hx_sps: int | None = None) -> str | None:
    """Run one square wave, START at 10 ms; None if every window after the first (of 100 ms) is
    clean and all are there, else what went wrong. With ``hx_sps`` an HX711 (default values)
    converts meanwhile: its SCK high time must stay below 60 us, it must never power down, every
    conversion must be read, and each window after the first must count ``hx_sps / 10`` ± 1."""
    r = simrun.run([Segment(0.0, freq, duty)], [(0.01, "START")], time_s=time_s, seed=seed,
                   hx_sps=hx_sps)
    ms = r.measurements()[1:]
    if hx_sps is not None:
        if r.sck_max_high_us >= HX_SCK_HIGH_MAX_US or r.hx_powerdown or r.hx_lost or r.sck_stray:
            return (f"HX711: SCK high up to {r.sck_max_high_us:.2f} us, power-downs {r.hx_powerdown}, "
                    f"lost {r.hx_lost}, stray pulses {r.sck_stray}")
        for m in ms:
            if m.ref_ok != 1 or abs(m.ref_n - hx_sps * m.window_ms / 1000) > 1:
                return f"window ending {m.t_ms} ms: ref_ok {m.ref_ok}, ref_n {m.ref_n}"
    if r.parser.bad_frames or r.parser.lost:
        return f"frames: {r.parser.bad_frames} bad, {r.parser.lost} lost"
    if r.small_ocr != (0, 0):
        return f"compare values below 16 written (OCR1A, OCR1B): {r.small_ocr}"
    if len(ms) < int((time_s - 0.01) * 10) - 1:
        return f"only {len(ms)} windows"
    for m in ms:
        df, dd = simrun.bounds(freq, duty, m)
        if (m.missed or abs(m.periods - freq * m.window_ms / 1000) > PERIOD_SLACK
                or abs(m.frequency_hz - freq) > df or abs(m.duty_cycle - duty) > dd):
            return f"window ending {m.t_ms} ms: periods {m.periods}, missed {m.missed}, " \
                   f"f {m.frequency_hz:.3f} Hz, duty {m.duty_cycle:.5f}"
    return None


def stress(runs: int, seed: int, f_min: float = 100.0, f_max: float = 50_000.0,
           time_s: float = 1.0, hx_sps: int | None = None) -> list[Failure]:
    """``runs`` random signals: frequency log-uniform in [f_min, f_max]; duty cycle 5 %, 95 % or
    uniform in [5 %, 95 %], a third each."""
    rng = random.Random(seed)
    failures = []
    for i in range(runs):
        f = f_min * (f_max / f_min) ** rng.random()
        d = rng.choice([0.05, 0.95, rng.uniform(0.05, 0.95)])
        why = check(f, d, time_s, seed=i + 1, hx_sps=hx_sps)
        if why:
            failures.append(Failure(f, d, why))
    return failures


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=100, help="random signals (default 100)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--fmin", type=float, default=100.0, help="lowest frequency [Hz] (default 100)")
    ap.add_argument("--fmax", type=float, default=50_000.0, help="highest frequency [Hz] (default 50k)")
    ap.add_argument("--time", type=float, default=1.0, help="simulated seconds per run (default 1)")
    ap.add_argument("--hx", type=int, choices=(10, 80), default=None,
                    help="an HX711 at this many samples/s converting meanwhile (default: none)")
    a = ap.parse_args(argv)
    simrun.build()
    failures = stress(a.runs, a.seed, a.fmin, a.fmax, a.time, a.hx)
    for x in failures:
        print(f"FAIL {x.freq_hz!r} Hz, duty {x.duty!r}: {x.why}")
    print(f"{len(failures)} of {a.runs} runs failed")
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
