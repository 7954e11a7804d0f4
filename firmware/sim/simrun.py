"""Run the fsrlab meter firmware in simavr through ``firmware/build/fsrlab_sim`` (the C harness).

Shared by the firmware tests (``tests/firmware``) and the benchmark (``benchmarks/bench_firmware.py``).
The firmware's output is decoded with the host package's own parser,
:class:`fsrlab.acquisition.protocol.FrameParser`, so the tests check firmware and host against each
other.

Timing model of the harness (the source of the tolerances used with it): each edge is scheduled at
its ideal time rounded to a CPU cycle, and simavr applies it at the end of the instruction then
running, so a captured timestamp lies between -0.5 and +3.5 ticks (62.5 ns) from the ideal edge;
a difference of two timestamps is off by at most :data:`EDGE_ERROR_TICKS`.
"""

from __future__ import annotations

import subprocess
from dataclasses import dataclass, field
from pathlib import Path

FIRMWARE_DIR = Path(__file__).resolve().parents[1]
BUILD = FIRMWARE_DIR / "build"
ELF = BUILD / "fsrlab_meter.elf"
SIM = BUILD / "fsrlab_sim"
F_CPU = 16_000_000
EDGE_ERROR_TICKS = 4.0
"""Largest error of a difference of two simulated capture timestamps [ticks] (see module doc)."""


def build(target: str = "all-sim", profile: bool = False) -> None:
    """Build firmware and harness with ``make -C firmware`` (incremental)."""
    cmd = ["make", "-s", "-C", str(FIRMWARE_DIR), target]
    if profile:
        cmd.append("PROFILE=1")
    subprocess.run(cmd, check=True, capture_output=True, text=True)


@dataclass(frozen=True)
class Segment:
    """From ``t0_s`` on, a square wave of ``freq_hz`` (0: line low) and ``duty`` with edge jitter
    of ``jitter`` periods (uniform, each edge independently)."""

    t0_s: float
    freq_hz: float
    duty: float = 0.5
    jitter: float = 0.0

    def arg(self) -> str:
        return f"{self.t0_s!r}:{self.freq_hz!r}:{self.duty!r}:{self.jitter!r}"


@dataclass
class SimResult:
    """What the firmware sent and what the harness saw."""

    raw: bytes
    frames: list = field(default_factory=list)
    parser: object = None
    pd4: list[tuple[int, int]] = field(default_factory=list)  # (cycle, level) changes of D4
    edges: tuple[int, int] = (0, 0)  # rising, falling edges generated on D8
    peeks: dict[int, tuple[int, int]] = field(default_factory=dict)  # addr -> (byte, word)
    small_ocr: tuple[int, int] = (0, 0)  # OCR1A, OCR1B set below 16 (simavr loses those matches)
    cycles: int = 0
    hx: list[tuple[int, int]] = field(default_factory=list)  # (cycle, raw value) conversions read
    hx_lost: list[tuple[int, int]] = field(default_factory=list)  # (cycle, value) never read
    hx_powerdown: list[int] = field(default_factory=list)  # cycles: SCK high > 60 us
    hx_powerup: list[int] = field(default_factory=list)
    sck_max_high: int = 0  # longest SCK high time [cycles]
    sck_pulses: int = 0
    sck_stray: int = 0  # SCK pulses while no conversion was ready (or no HX711)
    pd2: tuple[int, int] = (0, 0)  # D2 (DOUT) at the end: (DDR bit, PORT bit); (0, 1) = pull-up

    @property
    def sck_max_high_us(self) -> float:
        """Longest SCK high time in the run. [us]"""
        return self.sck_max_high / F_CPU * 1e6

    def of_kind(self, kind: str) -> list:
        return [f for f in self.frames if f.kind == kind]

    def measurements(self) -> list:
        from fsrlab.acquisition.messages import Measurement

        return [Measurement.from_frame(f) for f in self.of_kind("M")]


def run(segments=(), commands=(), time_s: float = 1.0, adc_mv: int = 0, seed: int = 1,
        elf: Path = ELF, sim: Path = SIM, peeks=(), hx_sps: int | None = None,
        hx_first_s: float | None = None, hx_values=None, hx_stop_s: float | None = None) -> SimResult:
    """Run the firmware for ``time_s`` simulated seconds.

    Parameters
    ----------
    segments : sequence of Segment
        The D8 signal.
    commands : sequence of (float, str)
        ``(time_s, line)``: command lines sent to USART0 (``\\n`` is appended).
    time_s : float
        Simulated time. [s]
    adc_mv : int
        Voltage on A0. [mV]
    hx_sps : int or None
        An HX711 on D2/D3 converting 10 or 80 times a second; None: no HX711 connected (DOUT high,
        as the pull-up holds it). [1/s]
    hx_first_s : float or None
        Time the first conversion is ready (default ``1/hx_sps``). [s]
    hx_values : sequence of int or None
        Raw values of the successive conversions (24-bit two's complement), repeated; None: the
        harness's formula over the whole range.
    hx_stop_s : float or None
        From this time on the HX711 is unplugged. [s]
    """
    from fsrlab.acquisition.protocol import FrameParser

    args = [str(sim), str(elf), "--time", repr(time_s), "--adc-mv", str(int(adc_mv)), "--seed", str(seed)]
    for s in segments:
        args += ["--seg", s.arg()]
    for t, line in commands:
        args += ["--cmd", f"{t!r}:{line}"]
    for a in peeks:
        args += ["--peek", hex(a)]
    if hx_sps is not None:
        args += ["--hx", f"{int(hx_sps)}" + ("" if hx_first_s is None else f":{hx_first_s!r}")]
        if hx_values is not None:
            args += ["--hx-values", ",".join(str(int(v)) for v in hx_values)]
        if hx_stop_s is not None:
            args += ["--hx-stop", repr(hx_stop_s)]
    proc = subprocess.run(args, capture_output=True, check=True, timeout=600)
    res = SimResult(raw=proc.stdout)
    parser = FrameParser()
    res.frames = parser.feed(proc.stdout)
    res.parser = parser
    for line in proc.stderr.decode("ascii", "replace").splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "#PD4":
            res.pd4.append((int(parts[1]), int(parts[2])))
        elif parts[0] == "#OCR_SMALL":
            res.small_ocr = (int(parts[1]), int(parts[2]))
        elif parts[0] == "#EDGES":
            res.edges = (int(parts[1]), int(parts[2]))
        elif parts[0] == "#PEEK":
            res.peeks[int(parts[1], 16)] = (int(parts[2]), int(parts[3]))
        elif parts[0] == "#HX":
            res.hx.append((int(parts[1]), int(parts[2])))
        elif parts[0] == "#HX_LOST":
            res.hx_lost.append((int(parts[1]), int(parts[2])))
        elif parts[0] == "#HX_POWERDOWN":
            res.hx_powerdown.append(int(parts[1]))
        elif parts[0] == "#HX_POWERUP":
            res.hx_powerup.append(int(parts[1]))
        elif parts[0] == "#HX_SCK":
            res.sck_max_high, res.sck_pulses, res.sck_stray = (int(x) for x in parts[1:4])
        elif parts[0] == "#PD2":
            res.pd2 = (int(parts[1]), int(parts[2]))
        elif parts[0] == "#END":
            res.cycles = int(parts[1])
    return res


def symbol_address(name: str, elf: Path = ELF) -> int:
    """Data-space address of a RAM symbol of the firmware (``avr-nm``)."""
    out = subprocess.run(["avr-nm", str(elf)], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == name:
            return int(parts[0], 16) - 0x800000
    raise KeyError(name)


def bounds(freq_hz: float, duty: float, m) -> tuple[float, float]:
    """Largest frequency and duty-cycle errors that quantization allows for window ``m``.

    The sum of periods telescopes (last minus first rising edge of the window), so it is off by
    at most one timestamp-difference error; each high time is off by at most one as well.
    Returns ``(df_hz, dduty)``.
    """
    e = EDGE_ERROR_TICKS
    sum_p = m.sum_period_ticks
    df = freq_hz * e / (sum_p - e)
    dduty = (e * m.periods + duty * e) / (sum_p - e)
    return df, dduty


