"""Several FSRs on one meter: per-channel reading rate and frequency resolution, in the twin.

The twin (the real firmware 3.0.0 in simavr) scans 1, 4 and 8 sensors behind a CD74HC4051
(:class:`fsrlab.virtual.sources.MuxSource`), each held at its own stress (channel k at 50 kPa ·
(k + 1)/8, 1.2–9.2 kHz), for 1 s of simulated time per setting, with the default SETTLE (2) and dwells
of 3 ms (the default), 10 ms and 20 ms. One channel is the single-channel meter (a mask of one has no
dwell: it counts in windows, at least 10 ms, so its row for a dwell of 3 ms is left out).

Peer, per reading: the Timer1 quantisation bound. A reading's mean period is a difference of two
captured timestamps over its ``periods`` periods, so its relative resolution is one timestamp-difference
error over ``sum_period_ticks`` (1 tick of 62.5 ns on hardware; up to 4 in simavr, which applies an edge
at the end of the instruction then running: ``firmware/sim/simrun.py``). The observed figure is the
relative standard deviation of a held channel's readings.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

TITLE = "Several FSRs on one meter: per-channel rate and resolution (twin, CD74HC4051)"
SIM_S = 1.0
DWELLS_MS = (3, 10, 20)
EDGE_ERROR_TICKS = 4.0


def _record(n: int, dwell_ms: int, folder: Path):
    from fsrlab.acquisition.recorder import Scan, record
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.io.runformat import load_run
    from fsrlab.virtual.sources import MuxSource, PhysicsSource, StressProfile
    from fsrlab.virtual.twin import Twin

    bench = MuxSource.scaled(8, StressProfile("hold", peak_pa=50e3, period_s=1.0))
    source = MuxSource([bench.sources[8 - n + k] for k in range(n)])  # the top n stresses
    path = folder / f"mux-{n}-{dwell_ms}.csv"
    with Twin(source, speed="max") as twin, SerialLink(twin.port) as link:
        window = max(dwell_ms, 10)
        result = record(link, path, SIM_S, window_ms=window, scan=Scan(tuple(range(n)), dwell_ms=dwell_ms),
                        clock="device", overwrite=True)
    assert not result.failed, result.message
    assert isinstance(source.sources[0], PhysicsSource)
    return load_run(path)


def run() -> str:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 4, 8):
            for dwell in DWELLS_MS:
                if n == 1 and dwell < 10:
                    continue  # a mask of one counts windows of at least 10 ms
                run = _record(n, dwell, Path(tmp))
                ch = np.asarray(run["channel"], dtype=int)
                f = np.asarray(run["frequency_hz"])
                periods = np.asarray(run["periods"])
                rate, res, bound, fs = [], [], [], []
                for k in range(n):
                    sel = (ch == k) & np.isfinite(f)
                    fk = f[sel][1:]  # (the first reading after START)
                    ticks = periods[sel][1:] / fk * 16e6
                    rate.append(sel.sum() / SIM_S)
                    res.append(np.std(fk) / np.mean(fk))
                    bound.append(np.median(1.0 / ticks))
                    fs.append(np.mean(fk))
                setting = f"WINDOW {dwell} ms" if n == 1 else f"DWELL {dwell} ms"
                rows.append(f"| {n} | {setting} | {min(rate):.1f} | {fs[0]:.0f}–{fs[-1]:.0f} | "
                            f"{max(res):.1e} | {max(bound):.1e} | {max(res) / max(bound):.1f} | "
                            f"{EDGE_ERROR_TICKS * max(bound):.1e} |")
    return "\n".join([
        "| channels | setting | readings/s per channel (lowest) | frequencies [Hz] | "
        "resolution seen (largest rel. std) | 1-tick bound (hardware) | seen / 1-tick bound | "
        "4-tick bound (simavr) |",
        "|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        f"{SIM_S:g} s of simulated time per row; SETTLE 2. The rate is the lowest channel's; the resolution is the "
        "largest relative standard deviation of a held channel's readings, the bound one tick over the median "
        "reading's counted ticks (the channel whose bound is largest). The held sensors' own drift (creep) is part "
        "of what is seen.",
    ])


if __name__ == "__main__":
    print(run())
