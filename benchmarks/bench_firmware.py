"""Firmware: the highest input frequency at which every edge is captured, measured in simavr,
beside the bounds set by the edge handler's cycle counts.

The real firmware (``firmware/fsrlab_meter``) runs in simavr as an ATmega328P at 16 MHz
(``firmware/sim/fsrlab_sim``); a frequency is *clean* when every measurement window after the
first reports ``missed == 0``, the expected number of periods (+-3: a window ends at the first
rising edge at or after its due time) and frequency and duty cycle within the quantization bound
(``firmware/sim/stress.py``, ``check``). The search goes up in 4 % steps
from 1 kHz and stops at the first frequency that is not clean.

Two bounds, both from the handler's cycle counts (``firmware/fsrlab_meter/capture.S``):

* **CPU**: the profiling build (``make -C firmware PROFILE=1``) counts the background's main-loop
  turns. Against the turns without a signal they give the background's share ``s`` of the CPU at
  a frequency ``f``, so the edge handlers take ``(1 - s) * 16 MHz / f`` cycles per period (measured
  at ``F_PROFILE``, inside the clean range). At ``16 MHz`` divided by that, the handlers would take
  every cycle: no build of this handler can go faster.
* **Capture latency**: while the handler polls, it writes the new edge select at most
  ``FLIP_CYCLES`` cycles after the capture flag rises (static count of the wait loop and ``got``),
  so a phase shorter than that is lost whatever the CPU load: at duty cycle ``d`` the shorter phase
  is ``min(d, 1 - d) * 16 MHz / f`` cycles.

The background's share at 50 kHz (the supported range's top) shows the margin left there.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "firmware" / "sim"))
import simrun  # noqa: E402
import stress  # noqa: E402
from simrun import Segment  # noqa: E402

TITLE = "Firmware input capture (simavr, ATmega328P at 16 MHz)"
DUTIES = (0.05, 0.5, 0.95)
F_PROFILE = 20_000.0
"""Frequency at which the handler's cycles per period are measured [Hz]."""
F_TARGET = 50_000.0
FLIP_CYCLES = 12
"""Capture flag to edge select written, worst case while polling (capture.S: the flag is seen at
most 4 cycles late and reaches ``got`` 2 later; reading ICR1 and ``sts TCCR1B`` take 6)."""


def clean(freq: float, duty: float) -> bool:
    """True when every window after the first is complete and right (``firmware/sim/stress.py``)."""
    return stress.check(freq, duty, time_s=0.33) is None


def highest_clean(duty: float) -> float:
    """Last frequency before the first failure, going up from 1 kHz in 4 % steps (islands above
    the first failure do not count)."""
    good = 0.0
    f = 1000.0
    while f < 2e6 and clean(f, duty):
        good = f
        f *= 1.04
    return good


def background_share(freq: float, duty: float) -> float:
    """The background's share of the CPU at ``freq``, from the profiling build's loop count."""
    elf = simrun.BUILD / "profile" / "fsrlab_meter.elf"
    sim = simrun.BUILD / "profile" / "fsrlab_sim"
    addr = simrun.symbol_address("prof_loops", elf)

    def turns(f: float) -> int:
        segs = [Segment(0.0, f, duty)] if f else []
        r = simrun.run(segs, [(0.01, "START")], time_s=0.2, elf=elf, sim=sim, peeks=[addr, addr + 2])
        return r.peeks[addr][1] + (r.peeks[addr + 2][1] << 16)

    return turns(freq) / turns(0.0)


def run() -> str:
    t0 = time.perf_counter()
    simrun.build()
    simrun.build(profile=True)
    rows = []
    for duty in DUTIES:
        share = background_share(F_PROFILE, duty)
        per_period = (1.0 - share) * simrun.F_CPU / F_PROFILE
        cpu_bound = simrun.F_CPU / per_period
        flip_bound = min(duty, 1.0 - duty) * simrun.F_CPU / FLIP_CYCLES
        bound = min(cpu_bound, flip_bound)
        at_target = background_share(F_TARGET, duty)
        rows.append((duty, highest_clean(duty), per_period, cpu_bound, flip_bound, bound, at_target))
    lines = [
        "Highest frequency with every edge captured, searched upward in simavr in 4 % steps from 1 kHz",
        "(the last clean one before the first failure), against the bounds from the edge handler's",
        f"cycles: CPU (the handler's cycles per period, measured at {F_PROFILE / 1e3:.0f} kHz with the",
        "profiling build's count of background loop turns) and capture latency (the edge select is",
        f"written at most {FLIP_CYCLES} cycles after the capture flag while the handler polls, so the",
        "shorter phase must last longer). The last column is the CPU share left to the background",
        f"(USART, commands, frames, ADC) at {F_TARGET / 1e3:.0f} kHz.",
        "",
        "| duty cycle | highest clean [kHz] | handler cycles per period | CPU bound [kHz] "
        "| latency bound [kHz] | measured / bound | background share at 50 kHz |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for duty, f, per, cpu_b, flip_b, b, tgt in rows:
        lines.append(f"| {duty:.2f} | **{f / 1e3:.1f}** | {per:.0f} | {cpu_b / 1e3:.1f} | {flip_b / 1e3:.1f} "
                     f"| {f / b:.2f} | {tgt:.0%} |")
    lines += [
        "",
        f"_Search and profile took {time.perf_counter() - t0:.1f} s of host time._",
    ]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(run())
