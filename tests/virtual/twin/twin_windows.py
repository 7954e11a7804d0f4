"""The transient's own per-window values, matched to the firmware's windows (tests of the twin).

The firmware's windows tile the rising edges: window k holds ``periods_k`` whole periods, from the
rising edge where window k-1 ended. So once the first window's first edge is found (searched: the
frames carry no cycle count), every later window's edges follow from the periods counted before it.
For each window the reference is the transient's own value over exactly those periods:
f = periods / (r[j+p] − r[j]), duty = Σ high times / (r[j+p] − r[j]).

Quantization bound (simrun.bounds, the one of tests/firmware): the harness schedules each edge at
its time rounded to a CPU cycle and simavr applies it at the end of the instruction then running,
so a captured timestamp lies −0.5..+3.5 ticks (62.5 ns) from the ideal edge and a difference of two
is off by at most 4 ticks (simrun.EDGE_ERROR_TICKS). The sum of periods telescopes to one such
difference; the high-time sum gathers one per period: df = f·4/(S − 4), dduty = (4·p + duty·4)/(S − 4)
with S the window's sum of periods in ticks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import simrun

F_CPU = simrun.F_CPU


@dataclass(frozen=True)
class Window:
    """One window as the firmware reported it."""

    periods: int
    sum_period_ticks: float
    sum_high_ticks: float
    frequency_hz: float
    duty_cycle: float


def from_measurements(ms) -> list[Window]:
    return [Window(m.periods, m.sum_period_ticks, m.sum_high_ticks, m.frequency_hz, m.duty_cycle) for m in ms]


def from_rows(periods, frequency_hz, duty_cycle) -> list[Window]:
    """Windows from a run file's columns (the sums recovered from f and duty)."""
    out = []
    for p, f, d in zip(periods, frequency_hz, duty_cycle, strict=True):
        s = p * F_CPU / f
        out.append(Window(int(p), s, d * s, f, d))
    return out


def match(windows: list[Window], rising_s: np.ndarray, falling_s: np.ndarray, candidates: int = 200,
          end_hint_s: float | None = None):
    """Best chain of the windows over the edges: ``(worst, anchor)``.

    The first window's first edge is searched among the ``candidates`` best fits of its sum of
    periods; with ``end_hint_s`` (the device's clock at the window's end, ``t_ms``, which runs from
    the firmware's start like the simulated time, within a few ms) among all those that end within
    50 ms of it instead (a constant frequency fits everywhere equally well).

    ``worst`` is the largest error over all windows and both quantities, in units of the window's
    quantization bound (≤ 1: every window within its bound); ``anchor`` the first window's first
    rising edge index.
    """
    r = rising_s * F_CPU
    idx = np.searchsorted(falling_s, rising_s, side="right")
    n = r.size - 1
    ok = idx[:n] < falling_s.size
    fall = np.where(ok, falling_s[np.minimum(idx[:n], falling_s.size - 1)] * F_CPU, np.nan)
    high = np.where(fall < r[1:], fall - r[:-1], np.nan)
    cum_high = np.concatenate([[0.0], np.cumsum(high)])
    p0 = windows[0].periods
    s0 = r[p0:] - r[:-p0]
    fit = np.abs(s0 - windows[0].sum_period_ticks)
    if end_hint_s is not None:
        fit = np.where(np.abs(r[p0:] / F_CPU - end_hint_s) < 0.05, fit, np.inf)
    order = np.argsort(fit, kind="stable")
    order = order[np.isfinite(fit[order])] if end_hint_s is not None else order[:candidates]
    best = (np.inf, -1)
    for j0 in order:
        j, worst = int(j0), 0.0
        for w in windows:
            if j + w.periods > n:
                worst = np.inf
                break
            s = r[j + w.periods] - r[j]
            h = cum_high[j + w.periods] - cum_high[j]
            f_ref, d_ref = w.periods * F_CPU / s, h / s
            df, dd = simrun.bounds(f_ref, d_ref, w)
            worst = max(worst, abs(w.frequency_hz - f_ref) / df, abs(w.duty_cycle - d_ref) / dd)
            j += w.periods
        best = min(best, (worst, int(j0)))
    return best
