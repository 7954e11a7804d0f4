"""Realistic FSR recordings for tests and benchmarks, from a model that fsrlab does not fit.

Not measurements. The runs imitate a typical FSR calibration bench: an FSR in a voltage divider read by the
Arduino's 10-bit ``analogRead`` (averaged over a window), a load cell under it read by an HX711,
loaded by hand (irregular, reversals of every size, minor loops, holds) or by a motor (one clean
triangle). The sensor is deliberately *another* model than the calibration's:

* **hysteresis**: a Bouc–Wen state ``z`` driven by the force F,
  ``dz = dF·(A − (β·sgn(dF·z) + γ)·|z|^n)`` (A = 1, n = 1, β = γ, saturating at ±z_max =
  15 % of full scale), with the sensor seeing the effective force ``F_e = F·(1 − h·z/z_max)``
  (an FSR conducts more on unloading than on loading at the same force, and not at all at none);
  fsrlab compensates with play operators (:mod:`fsrlab.calibration.operators`), a different family;
* **creep**: ``F_e`` is multiplied by ``1 + κ·(0.6·F₃ + 0.4·F₄₀)/FS``, with ``F₃`` and ``F₄₀``
  first-order relaxations of F (time constants 3 s and 40 s), so a held load reads more and more
  and no load reads nothing;
* **dead zone**: below an activation force the FSR is open (the divider reads 0 V);
* **saturation**: the conductance saturates, ``G = G_p/(1 + G_p/G_sat)`` with the power law
  ``G_p = G_ref·(F_e/F_ref)^b``, and the divider compresses the top of the range;
* **readout**: divider ``V = Vcc·R_M·G/(1 + R_M·G)``, an electrical lag, additive noise, the mean
  over each row's window, then the 10-bit ADC (``Vcc/1023`` steps, clipped at 1023);
* **reference**: the HX711 samples at 10–80 SPS; each row holds the latest sample (a lag or a
  lead against the readout window), with noise and an offset drifting from about −30 g.

The simulation runs on a 1 ms grid; every random choice comes from one seeded generator, so a
seed gives the same run on every machine.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.params import check_at_least, check_between, check_finite, check_int, check_positive
from fsrlab.units import STANDARD_GRAVITY
from fsrlab.virtual.arguments import random_generator

__all__ = ["HandLoadedRun", "hand_loaded_force", "motor_cycle_force", "fsr_bench_run"]

_DT = 1e-3  # simulation step [s]
_G0 = STANDARD_GRAVITY  # for the offset stated in grams [m/s²]


@dataclass
class HandLoadedRun:
    """A simulated recording: run columns, sidecar, and the truth behind them.

    Parameters
    ----------
    columns : dict of str to ndarray
        ``time_s`` [s] (end of each readout window), ``voltage_v`` [V] (the divider through the
        ADC) and ``force_n`` [N] (the HX711's latest sample).
    metadata : dict
        Sidecar: ``divider`` (``r_m_ohm``, ``vcc_v``, ``adc_bits``), ``sensor`` (area), ``origin``.
    truth : dict of str to ndarray
        ``force_n``: the true force at each row's time (no noise, offset or lag) [N];
        ``active``: 1 where the sensor was above its activation force.
    """

    columns: dict
    metadata: dict
    truth: dict = field(default_factory=dict)

    def run(self, path="handloaded.csv"):
        """The recording as a :class:`fsrlab.io.runformat.Run` (not written; ``path`` only names it)."""
        from pathlib import Path

        from fsrlab.io.runformat import Run

        return Run(path=Path(path), columns={k: np.asarray(v, float) for k, v in self.columns.items()},
                   metadata=dict(self.metadata))

    def write(self, path):
        """Write the run and its sidecar (see :func:`fsrlab.io.runwriter.write_run`)."""
        from fsrlab.io.runwriter import write_run

        return write_run(path, self.columns, self.metadata)


def hand_loaded_force(duration_s: float, peak_n: float, rng: np.random.Generator) -> np.ndarray:
    """A hand-like force history on the 1 ms grid: turning points of every size, holds, tremor.

    Parameters
    ----------
    duration_s : float
        Length. [s]
    peak_n : float
        Largest force. [N]
    rng : numpy.random.Generator
        Source of the random choices.

    Returns
    -------
    ndarray
        Force ≥ 0 every millisecond. [N]
    """
    check_positive("duration_s", duration_s, "s", scalar=True)
    check_positive("peak_n", peak_n, "N", scalar=True)
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng: must be a numpy random Generator, got {type(rng).__name__}")
    n = int(round(duration_s / _DT))
    points = [0.0]
    times = [0.0]
    t, f = 0.0, 0.0
    while t < duration_s:
        r = rng.random()
        if r < 0.08:
            target = 0.0  # a full unload
        elif r < 0.16:
            target = peak_n * rng.uniform(0.85, 1.0)  # a press to near full scale
        else:
            # a reversal of any size: log-uniform from 1 % to 100 % of full scale
            size = peak_n * np.exp(rng.uniform(np.log(0.01), 0.0))
            direction = 1.0 if (rng.random() < 0.5 or f < 0.1 * peak_n) and f < 0.9 * peak_n else -1.0
            target = float(np.clip(f + direction * size, 0.0, peak_n))
        rate = peak_n * np.exp(rng.uniform(np.log(0.15), np.log(2.0)))  # N/s
        t += max(abs(target - f) / rate, 0.02)
        f = target
        points.append(f)
        times.append(t)
        if rng.random() < 0.25:  # a hold
            t += rng.uniform(0.3, 4.0)
            points.append(f)
            times.append(t)
    grid = np.arange(n) * _DT
    force = np.interp(grid, times, points)
    # Hands do not make corners: smooth over ~50 ms, then a small tremor (8–12 Hz).
    k = 50
    force = np.convolve(np.pad(force, (k, k), mode="edge"), np.ones(k) / k, mode="same")[k:-k]
    tremor = 0.003 * peak_n * np.sin(2 * np.pi * rng.uniform(8, 12) * grid + rng.uniform(0, 2 * np.pi))
    return np.clip(force + tremor * (force > 0.02 * peak_n), 0.0, None)


def motor_cycle_force(ramp_s: float, peak_n: float, cycles: int = 1) -> np.ndarray:
    """Motor-driven triangles 0 → peak → 0 on the 1 ms grid (a short rest at each end).

    Parameters
    ----------
    ramp_s : float
        Duration of each ramp. [s]
    peak_n : float
        Peak force. [N]
    cycles : int
        Number of triangles.

    Returns
    -------
    ndarray
        Force every millisecond. [N]
    """
    check_positive("ramp_s", ramp_s, "s", scalar=True)
    check_positive("peak_n", peak_n, "N", scalar=True)
    cycles = check_int("cycles", cycles, 1)
    m = int(round(ramp_s / _DT))
    up = np.linspace(0.0, peak_n, m, endpoint=False)
    rest = np.zeros(int(round(1.0 / _DT)))
    one = np.concatenate([up, np.full(1, peak_n), up[::-1]])
    return np.concatenate([rest] + [one] * cycles + [rest])


def _bouc_wen(force: np.ndarray, width_n: float) -> np.ndarray:
    """Bouc–Wen state z(F) (A = 1, n = 1, β = γ), saturating at ±``width_n``. [N]"""
    beta = gamma = 0.5 / width_n
    z = np.empty_like(force)
    zi = 0.0
    dfs = np.diff(force, prepend=force[0])
    for i, df in enumerate(dfs.tolist()):
        s = 1.0 if df * zi > 0 else (-1.0 if df * zi < 0 else 0.0)
        zi += df * (1.0 - (beta * s + gamma) * abs(zi))
        z[i] = zi
    return z


def _relax(target: np.ndarray, tau_s: float) -> np.ndarray:
    """First-order lag of ``target`` with time constant ``tau_s`` on the 1 ms grid."""
    from scipy.signal import lfilter

    a = np.exp(-_DT / tau_s)
    return lfilter([1 - a], [1, -a], target, zi=[a * target[0]])[0]


def fsr_bench_run(kind: str = "hand", seed: int = 0, duration_s: float = 60.0, peak_n: float = 20.0,
                  row_s: float = 0.02, reference_sps: float | None = None, hysteresis: float = 0.08,
                  creep: float = 0.04, activation: float = 0.03, adc_noise_lsb: float = 0.8,
                  reference_noise: float = 0.002, offset_g: float | None = None, ramp_s: float = 15.0,
                  r_m_ohm: float = 10e3, vcc_v: float = 5.0) -> HandLoadedRun:
    """Simulate one recording of the FSR bench (hand-loaded or one motor cycle).

    Parameters
    ----------
    kind : {"hand", "motor"}
        Irregular hand loading for ``duration_s``, or one clean triangle of ``ramp_s`` per ramp.
    seed : int
        Seed of every random choice (force history, HX711 rate and phase, noise, offset).
    duration_s : float
        Length of a hand-loaded run. [s]
    peak_n : float
        Full-scale force. [N]
    row_s : float
        Readout window = row period. [s]
    reference_sps : float, optional
        HX711 rate (default: drawn from 10–80 SPS). [1/s]
    hysteresis : float
        Relative half-width h of the effective force's Bouc–Wen loop. [1]
    creep : float
        Total creep κ of the effective force under a held load (split 60/40 between 3 s and 40 s). [1]
    activation : float
        Activation force, a fraction of ``peak_n``; below it the divider reads 0 V. [1]
    adc_noise_lsb : float
        Standard deviation of the voltage noise before the ADC, in ADC steps. [1]
    reference_noise : float
        Standard deviation of the HX711 reading, a fraction of ``peak_n``. [1]
    offset_g : float, optional
        Load-cell offset at the start (default: drawn from −40 to −20 g); it drifts linearly by a
        drawn −10..+10 g over the run. [g]
    ramp_s : float
        Ramp duration of the motor cycle. [s]
    r_m_ohm, vcc_v : float
        Divider's measuring resistor [Ω] and supply [V].

    Returns
    -------
    HandLoadedRun
    """
    if kind not in ("hand", "motor"):
        raise ParameterError(f"must be 'hand' or 'motor', got {kind!r}", parameter="kind")
    for name, value, unit in (("duration_s", duration_s, "s"), ("peak_n", peak_n, "N"), ("ramp_s", ramp_s, "s"),
                              ("r_m_ohm", r_m_ohm, "Ω"), ("vcc_v", vcc_v, "V")):
        check_positive(name, value, unit, scalar=True)
    check_between("row_s", row_s, 2 * _DT, duration_s if kind == "hand" else 2 * ramp_s, "s", scalar=True)
    if reference_sps is not None:
        check_between("reference_sps", reference_sps, 0.0, 1 / _DT, "1/s", lower_open=True, scalar=True)
    for name, value in (("hysteresis", hysteresis), ("activation", activation)):
        check_between(name, value, 0.0, 1.0, upper_open=True, scalar=True)
    for name, value in (("creep", creep), ("adc_noise_lsb", adc_noise_lsb), ("reference_noise", reference_noise)):
        check_at_least(name, value, 0.0, scalar=True)
    if offset_g is not None:
        check_finite("offset_g", offset_g, scalar=True)
    rng = random_generator("seed", seed)
    force = hand_loaded_force(duration_s, peak_n, rng) if kind == "hand" else motor_cycle_force(ramp_s, peak_n)
    n = force.size
    t = np.arange(n) * _DT
    # Sensor: Bouc–Wen hysteresis and creep of the effective force, then the conductance.
    # z saturates at ±15 % of full scale after a reversal; the effective force is F·(1 ∓ hysteresis).
    width = 0.15 * peak_n
    f_eff = force * (1 - hysteresis * _bouc_wen(force, width) / width)
    # Creep: the conductance of a held load keeps rising, in proportion to the load held.
    f_eff = f_eff * (1 + creep * (0.6 * _relax(force, 3.0) + 0.4 * _relax(force, 40.0)) / peak_n)
    f_act = activation * peak_n
    g_ref = 1.0 / 2e3  # 2 kΩ at full scale (before saturation) [S]
    b = 1.1
    g_p = g_ref * np.clip(f_eff / peak_n, 0.0, None) ** b
    g = np.where(f_eff > f_act, g_p / (1 + g_p / (1.5 * g_ref)), 0.0)
    v = vcc_v * r_m_ohm * g / (1 + r_m_ohm * g)
    v = _relax(v, 0.004)  # the divider's and the input's RC
    # Readout: noise, window mean, ADC.
    per = int(round(row_s / _DT))
    rows = n // per
    lsb = vcc_v / 1023
    v_noisy = v[: rows * per] + adc_noise_lsb * lsb * rng.standard_normal(rows * per)
    v_win = v_noisy.reshape(rows, per).mean(axis=1)
    counts = np.clip(np.round(v_win / lsb), 0, 1023)
    t_row = (np.arange(rows) + 1) * per * _DT
    # Reference: HX711 samples at its own rate and phase; each row holds the latest one.
    sps = float(rng.uniform(10, 80)) if reference_sps is None else float(reference_sps)
    t_hx = np.arange(rng.uniform(0, 1 / sps), t[-1], 1 / sps)
    f_hx = np.interp(t_hx, t, force)
    off0 = (rng.uniform(-40, -20) if offset_g is None else offset_g) * 1e-3 * _G0
    drift = rng.uniform(-10, 10) * 1e-3 * _G0
    f_hx = f_hx + off0 + drift * t_hx / t[-1] + reference_noise * peak_n * rng.standard_normal(t_hx.size)
    latest = np.searchsorted(t_hx, t_row, side="right") - 1
    ref = np.where(latest >= 0, f_hx[np.clip(latest, 0, None)], np.nan)
    cols = {"time_s": t_row, "voltage_v": counts * lsb, "force_n": ref}
    truth = {"force_n": np.interp(t_row, t, force), "active": np.interp(t_row, t, (f_eff > f_act).astype(float))}
    meta = {
        "divider": {"r_m_ohm": r_m_ohm, "vcc_v": vcc_v, "adc_bits": 10},
        "sensor": {"model": "simulated FSR (Bouc–Wen, creep, dead zone, saturation)", "area_m2": 1e-4},
        "origin": (f"synthetic: fsrlab.virtual.handloaded.fsr_bench_run(kind={kind!r}, seed={seed}, "
                   f"duration_s={duration_s}, peak_n={peak_n}, row_s={row_s}, reference_sps={sps:.1f}, "
                   f"hysteresis={hysteresis}, creep={creep}, activation={activation}, adc_noise_lsb={adc_noise_lsb}, "
                   f"reference_noise={reference_noise}, offset_g={off0 / 1e-3 / _G0:.1f})"),
        "notes": "synthetic data, not a measurement",
    }
    return HandLoadedRun(columns=cols, metadata=meta, truth=truth)
