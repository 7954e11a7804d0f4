"""Synthetic loading/unloading runs from the physics and oscillator models (test and demo data).

Not measurements. A run is made by driving :class:`fsrlab.physics.sensor.VirtualFSR` (hysteretic
separation, eqs. 1 and 9 with memory) along triangular stress ramps like the paper's stepper-motor
bench (§6.1), turning R_FSR and C_FSR into LM555 frequency and duty cycle with the closed forms of
:func:`fsrlab.circuits.lm555.astable` (paper Fig. 16: R = 10 kΩ, diode D1), and then measuring them
as the firmware does: whole periods counted in a window, their summed length quantized to Timer1
ticks of 62.5 ns (16 MHz), plus Gaussian noise. The traditional readout (paper Fig. 18, eq. 38:
V = R_F/R_FSR · |Vcc|, R_F = 20 kΩ, |Vcc| = 5 V) is added as ``voltage_v``, quantized to 10-bit ADC
steps of 5 V/1024.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TICK_S", "triangle_stress", "SyntheticRun", "synthetic_run"]

#: Timer1 tick at 16 MHz, prescaler 1 (protocol v1). [s]
TICK_S = 62.5e-9


def triangle_stress(cycles: int = 3, peak_pa: float = 50e3, points_per_ramp: int = 100, dwell_points: int = 0,
                    start_pa: float = 0.0) -> np.ndarray:
    """Stress of ``cycles`` triangular loading-unloading ramps start → peak → start.

    Parameters
    ----------
    cycles : int
        Number of cycles (≥ 1).
    peak_pa : float
        Largest stress. [Pa]
    points_per_ramp : int
        Readings per ramp (≥ 2).
    dwell_points : int
        Readings held at the peak.
    start_pa : float
        Lowest stress. [Pa]

    Returns
    -------
    ndarray
        Stress sequence. [Pa]
    """
    if cycles < 1:
        raise ValueError(f"cycles must be >= 1, got {cycles!r}")
    if points_per_ramp < 2:
        raise ValueError(f"points_per_ramp must be >= 2, got {points_per_ramp!r}")
    if not peak_pa > start_pa >= 0:
        raise ValueError(f"peak_pa must exceed start_pa >= 0 Pa, got {peak_pa!r}, {start_pa!r}")
    up = np.linspace(start_pa, peak_pa, points_per_ramp + 1)
    one = np.concatenate([up[:-1], np.full(dwell_points, peak_pa), up[::-1][:-1]])
    return np.concatenate([np.tile(one, cycles), [start_pa]])


@dataclass
class SyntheticRun:
    """A synthetic run: columns of the run format and its sidecar metadata.

    Parameters
    ----------
    columns : dict of str to ndarray
        ``time_s``, ``stress_pa``, ``frequency_hz``, ``duty_cycle``, ``voltage_v``, ``periods``,
        ``cycle``, ``direction`` and the noiseless truth ``c_fsr_farad``, ``r_fsr_ohm``.
    metadata : dict
        Sidecar content (circuit, sensor, origin with every setting).
    """

    columns: dict
    metadata: dict

    def write(self, path, include_truth: bool = False):
        """Write the run (see :func:`fsrlab.runformat.write_run`); the truth columns only if asked."""
        from fsrlab.runformat import write_run

        cols = {k: v for k, v in self.columns.items() if include_truth or k not in ("c_fsr_farad", "r_fsr_ohm")}
        return write_run(path, cols, self.metadata)


def synthetic_run(cycles: int = 3, peak_pa: float = 50e3, points_per_ramp: int = 100, dwell_points: int = 0,
                  window_s: float = 0.1, frequency_noise: float = 0.002, stress_noise_pa: float = 0.0,
                  voltage_noise_v: float = 0.002, r_ohm: float = 10e3, c_off_farad: float = 0.0,
                  diode: bool = True, diode_drop_v: float = 0.0, sensor=None, seed: int = 0,
                  stress_pa=None) -> SyntheticRun:
    """Make a loading/unloading run through the virtual sensor, the 555 and the timer.

    Parameters
    ----------
    cycles, peak_pa, points_per_ramp, dwell_points
        Stress profile, see :func:`triangle_stress`.
    window_s : float
        Measurement window per reading (firmware default 100 ms). [s]
    frequency_noise : float
        Relative standard deviation of the frequency (sensor and bench noise) before quantization. [1]
    stress_noise_pa : float
        Standard deviation of the reference stress reading (load cell noise). [Pa]
    voltage_noise_v : float
        Standard deviation of the op-amp voltage before ADC quantization. [V]
    r_ohm, c_off_farad, diode, diode_drop_v
        555 circuit (paper Fig. 16 defaults: 10 kΩ, no C_off, ideal D1).
    sensor : VirtualFSR, optional
        The sensor (default ``VirtualFSR()``).
    seed : int
        Random seed.
    stress_pa : array_like, optional
        Any stress history [Pa] instead of the triangles (e.g. minor loops); ``cycle`` and
        ``direction`` then come from :func:`fsrlab.analysis.cycles.branch_directions`.

    Returns
    -------
    SyntheticRun
    """
    from fsrlab.circuits.lm555 import astable
    from fsrlab.physics.sensor import VirtualFSR

    for name, v in (("window_s", window_s),):
        if not v > 0:
            raise ValueError(f"{name} must be > 0, got {v!r}")
    for name, v in (("frequency_noise", frequency_noise), ("stress_noise_pa", stress_noise_pa),
                    ("voltage_noise_v", voltage_noise_v)):
        if not v >= 0:
            raise ValueError(f"{name} must be >= 0, got {v!r}")
    rng = np.random.default_rng(seed)
    fsr = sensor if sensor is not None else VirtualFSR()
    stress = (triangle_stress(cycles, peak_pa, points_per_ramp, dwell_points) if stress_pa is None
              else np.asarray(stress_pa, dtype=float))
    n = stress.size
    resp = fsr.respond(stress)  # 555 swing: ~Vcc/2 across the FSR
    osc = astable(r_ohm, resp.r_fsr_ohm, resp.c_fsr_farad, c_off_farad=c_off_farad, diode=diode,
                  diode_drop_v=diode_drop_v)
    f_true = np.asarray(osc.frequency_hz) * (1 + frequency_noise * rng.standard_normal(n))
    dc_true = np.asarray(osc.duty_cycle)
    # Firmware: whole periods in the window; their summed length in 62.5 ns ticks (one quantization
    # of the total), high times summed per period (±1 tick per period, uniform).
    periods = np.floor(f_true * window_s).astype(int)
    total = np.where(periods > 0, periods / f_true, np.nan)
    ticks = np.round(total / TICK_S)
    high = np.round(dc_true * total / TICK_S + rng.uniform(-0.5, 0.5, n) * np.sqrt(np.maximum(periods, 1) / 3.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        freq = np.where(periods > 0, periods / (ticks * TICK_S), np.nan)
        duty = np.where(periods > 0, high / ticks, np.nan)
    # Traditional readout, eq. (38): |V| = R_F/R_FSR·|Vcc| with the FSR at |Vcc| = 5 V.
    r5 = fsr.respond(stress, voltage_v=5.0).r_fsr_ohm
    v = 20e3 / r5 * 5.0 + voltage_noise_v * rng.standard_normal(n)
    lsb = 5.0 / 1024
    v = np.clip(np.round(v / lsb), 0, 1023) * lsb
    if stress_pa is None:
        per_cycle = 2 * points_per_ramp + dwell_points
        cycle = np.minimum(np.arange(n) // per_cycle, cycles - 1)
        phase = np.arange(n) - cycle * per_cycle
        # direction of the move that led to each reading: the peak reading is +1, the dwell 0.
        direction = np.where(phase <= points_per_ramp, 1, -1)
        direction[(phase > points_per_ramp) & (phase <= points_per_ramp + dwell_points)] = 0
        direction[0] = 1
        direction[-1] = -1
    else:
        from fsrlab.analysis.cycles import branch_directions

        direction = branch_directions(stress)
        cycle = np.cumsum(np.concatenate([[0], (direction[1:] == 1) & (direction[:-1] == -1)]))
    cols = {
        "time_s": np.arange(n) * window_s,
        "stress_pa": stress + stress_noise_pa * rng.standard_normal(n),
        "frequency_hz": freq,
        "duty_cycle": duty,
        "voltage_v": v,
        "periods": periods,
        "cycle": cycle,
        "direction": direction,
        "c_fsr_farad": resp.c_fsr_farad,
        "r_fsr_ohm": resp.r_fsr_ohm,
    }
    meta = {
        "circuit": {"topology": "lm555-astable (paper Fig. 16)", "r_ohm": r_ohm, "c_off_farad": c_off_farad,
                    "diode": diode, "diode_drop_v": diode_drop_v, "vcc_v": 5.0,
                    "traditional": {"r_f_ohm": 20e3, "vcc_v": -5.0}},
        "sensor": {"model": "VirtualFSR (FlexiForce A201-like, fsrlab.physics.sensor)", "area_m2": fsr.area_m2},
        "origin": (f"synthetic: fsrlab.analysis.synthetic.synthetic_run(cycles={cycles}, peak_pa={peak_pa}, "
                   f"points_per_ramp={points_per_ramp}, dwell_points={dwell_points}, window_s={window_s}, "
                   f"frequency_noise={frequency_noise}, stress_noise_pa={stress_noise_pa}, seed={seed}); "
                   "VirtualFSR -> lm555.astable -> 62.5 ns timer quantization"),
        "notes": "synthetic data, not a measurement",
    }
    return SyntheticRun(columns=cols, metadata=meta)
