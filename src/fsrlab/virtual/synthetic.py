"""Synthetic loading/unloading runs from the physics, circuit and meter models (test and demo data).

Not measurements. A run is made by driving :class:`fsrlab.physics.sensor.VirtualFSR` (hysteretic
separation, eqs. 1 and 9 with memory) along triangular stress ramps like the paper's stepper-motor
bench (§6.1), turning R_FSR and C_FSR into LM555 frequency and duty cycle with the closed forms of
an :class:`~fsrlab.circuits.circuit.LM555Circuit` (default :data:`~fsrlab.circuits.circuit.PAPER_CIRCUIT`:
the paper's Fig. 16 with D1 ideal; R = 10 kΩ is fsrlab's choice, the paper prints no value for R)
and the FSR's resistance into the op-amp voltage of the traditional readout with an
:class:`~fsrlab.circuits.circuit.OpAmpReadout` (default :data:`~fsrlab.circuits.circuit.PAPER_OPAMP`:
Fig. 18, eq. 38, R_F = 20 kΩ, the FSR driven from −5 V). The meter's model
(:func:`fsrlab.virtual.meter.measure`, the same one the virtual device uses) then reports what
the Uno would: whole periods per window, their summed length and high time in 62.5 ns ticks, and
the 10-bit A0 reading.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fsrlab.circuits.circuit import PAPER_CIRCUIT, PAPER_OPAMP, LM555Circuit, OpAmpReadout
from fsrlab.errors import ParameterError
from fsrlab.io.runformat import Run
from fsrlab.physics.params import check_at_least, check_int, check_positive, float_array
from fsrlab.virtual.arguments import check_sensor, random_generator

__all__ = ["triangle_stress", "SyntheticRun", "synthetic_run"]


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
    cycles = check_int("cycles", cycles, 1)
    points_per_ramp = check_int("points_per_ramp", points_per_ramp, 2)
    dwell_points = check_int("dwell_points", dwell_points, 0)
    check_at_least("start_pa", start_pa, 0.0, "Pa", scalar=True)
    check_positive("peak_pa", peak_pa, "Pa", scalar=True)
    if not peak_pa > start_pa >= 0:
        raise ParameterError(f"must exceed start_pa >= 0 Pa, got {peak_pa!r}, {start_pa!r}", parameter="peak_pa")
    up = np.linspace(start_pa, peak_pa, points_per_ramp + 1)
    one = np.concatenate([up[:-1], np.full(dwell_points, peak_pa), up[::-1][:-1]])
    return np.concatenate([np.tile(one, cycles), [start_pa]])


class SyntheticRun(Run):
    """A synthetic run: a :class:`~fsrlab.io.runformat.Run` (in memory: its ``path``, ``synthetic.csv``, only
    names it) whose columns also hold the noiseless truth, left out when it is written.

    Parameters
    ----------
    path : Path
        The name the run goes by until it is written.
    columns : dict of str to ndarray
        ``time_s``, ``stress_pa``, ``frequency_hz``, ``duty_cycle``, ``voltage_v``, ``periods``,
        ``cycle``, ``direction`` and the noiseless truth ``c_fsr_farad``, ``r_fsr_ohm`` (:data:`TRUTH`).
    metadata : dict
        Sidecar content (circuit, sensor, origin with every setting).
    truncated, skipped
        As a loaded run's: False and none (nothing was read from a file).
    """

    TRUTH = ("c_fsr_farad", "r_fsr_ohm")
    """The truth columns: the sensor's C_FSR [F] and R_FSR [Ω] behind each reading, without noise."""

    def write(self, path, include_truth: bool = False):
        """Write the run (see :func:`fsrlab.io.runwriter.write_run`); the truth columns only if asked.

        Parameters
        ----------
        path : str or path-like
            The run's CSV (its sidecar is written beside it).
        include_truth : bool
            Also write :data:`TRUTH`.

        Returns
        -------
        Path
            The CSV written.
        """
        from fsrlab.io.runwriter import write_run

        cols = {k: v for k, v in self.columns.items() if include_truth or k not in self.TRUTH}
        return write_run(path, cols, self.metadata)


def synthetic_run(cycles: int = 3, peak_pa: float = 50e3, points_per_ramp: int = 100, dwell_points: int = 0,
                  window_s: float = 0.1, frequency_noise: float = 0.002, stress_noise_pa: float = 0.0,
                  voltage_noise_v: float = 0.002, jitter_s: float = 0.0, circuit: LM555Circuit = PAPER_CIRCUIT,
                  opamp: OpAmpReadout = PAPER_OPAMP, sensor=None, seed: int = 0, stress_pa=None) -> SyntheticRun:
    """Make a loading/unloading run through the virtual sensor, the 555, the op-amp and the meter.

    Parameters
    ----------
    cycles, peak_pa, points_per_ramp, dwell_points
        Stress profile, see :func:`triangle_stress`.
    window_s : float
        Measurement window per reading (firmware default 100 ms); the windows follow each other. [s]
    frequency_noise : float
        Relative standard deviation of the frequency per window (sensor and bench noise). [1]
    stress_noise_pa : float
        Standard deviation of the reference stress reading (load cell noise). [Pa]
    voltage_noise_v : float
        Standard deviation of the op-amp voltage before the 10-bit conversion. [V]
    jitter_s : float
        Standard deviation of each captured rising edge's time (0: none). [s]
    circuit : LM555Circuit
        The 555 readout (its R_FSR taken at Vcc/2, the middle of the capacitor's swing).
    opamp : OpAmpReadout
        The traditional readout (its R_FSR taken at :attr:`~OpAmpReadout.fsr_voltage_v`, ``|Vcc|``).
    sensor : VirtualFSR, optional
        The sensor (default ``VirtualFSR()``).
    seed : int
        Random seed: the meter's draws (:func:`fsrlab.virtual.meter.measure`: its noise, then the
        555's phase at START), then the reference stress noise.
    stress_pa : array_like, optional
        Any stress history [Pa] instead of the triangles (e.g. minor loops); ``direction`` then comes
        from :func:`fsrlab.physics.history.branch_directions`.

    Returns
    -------
    SyntheticRun
        A :class:`~fsrlab.io.runformat.Run` (``fl.calibrate`` and every function taking a run take it).
        Columns ``time_s`` (start of each window), ``stress_pa``, ``frequency_hz``, ``duty_cycle``,
        ``voltage_v``, ``periods``, ``cycle`` (:func:`fsrlab.physics.history.cycle_numbers`),
        ``direction`` and the truth; metadata with ``circuit`` and ``opamp`` (their ``to_dict``).
    """
    from fsrlab.physics.history import branch_directions, cycle_numbers
    from fsrlab.physics.sensor import VirtualFSR
    from fsrlab.virtual.meter import measure

    check_positive("window_s", window_s, "s", scalar=True)
    for name, v in (("frequency_noise", frequency_noise), ("stress_noise_pa", stress_noise_pa),
                    ("voltage_noise_v", voltage_noise_v), ("jitter_s", jitter_s)):
        check_at_least(name, v, 0.0, scalar=True)
    for name, obj, cls in (("circuit", circuit, LM555Circuit), ("opamp", opamp, OpAmpReadout)):
        if not isinstance(obj, cls):
            raise ParameterError(f"must be an {cls.__name__}, got {type(obj).__name__}", parameter=name)
    rng = random_generator("seed", seed)
    if sensor is not None:
        check_sensor("sensor", sensor)
    fsr = sensor if sensor is not None else VirtualFSR()
    stress = triangle_stress(cycles, peak_pa, points_per_ramp, dwell_points) if stress_pa is None \
        else float_array("stress_pa", stress_pa)
    if stress.ndim != 1 or stress.size < 2:
        raise ParameterError(f"must be a 1-D array of at least 2 stresses, got shape {stress.shape}",
                             parameter="stress_pa")
    n = stress.size
    resp = fsr.respond(stress, voltage_v=circuit.fsr_voltage_v)
    osc = circuit.astable(resp.r_fsr_ohm, resp.c_fsr_farad)
    volts = opamp.output_v(fsr.respond(stress, voltage_v=opamp.fsr_voltage_v).r_fsr_ohm)  # Eq. (38)
    meter, _ = measure(osc.frequency_hz, osc.duty_cycle, volts, window_s, rng=rng,
                       frequency_noise=frequency_noise, jitter_s=jitter_s, adc_noise_v=voltage_noise_v)
    if stress_pa is None:
        per_cycle = 2 * points_per_ramp + dwell_points
        phase = np.arange(n) % per_cycle
        # direction of the move that led to each reading: the peak reading is +1, the dwell 0.
        direction = np.where(phase <= points_per_ramp, 1, -1)
        direction[(phase > points_per_ramp) & (phase <= points_per_ramp + dwell_points)] = 0
        direction[-1] = -1
    else:
        direction = branch_directions(stress)
    cols = {
        "time_s": np.arange(n) * window_s,
        "stress_pa": stress + stress_noise_pa * rng.standard_normal(n),
        "frequency_hz": meter.frequency_hz,
        "duty_cycle": meter.duty_cycle,
        "voltage_v": meter.voltage_v,
        "periods": meter.periods,
        "cycle": cycle_numbers(direction),
        "direction": direction,
        "c_fsr_farad": resp.c_fsr_farad,
        "r_fsr_ohm": resp.r_fsr_ohm,
    }
    meta = {
        "circuit": circuit.to_dict(),
        "opamp": opamp.to_dict(),
        "sensor": {"model": "VirtualFSR (FlexiForce A201-like, fsrlab.physics.sensor)", "area_m2": fsr.area_m2},
        "origin": (f"synthetic: fsrlab.virtual.synthetic.synthetic_run(cycles={cycles}, peak_pa={peak_pa}, "
                   f"points_per_ramp={points_per_ramp}, dwell_points={dwell_points}, window_s={window_s}, "
                   f"frequency_noise={frequency_noise}, stress_noise_pa={stress_noise_pa}, "
                   f"voltage_noise_v={voltage_noise_v}, jitter_s={jitter_s}, seed={seed}); "
                   "VirtualFSR -> LM555 astable and op-amp (eq. 38) -> fsrlab.virtual.meter"),
        "notes": "synthetic data, not a measurement",
    }
    return SyntheticRun(path=Path("synthetic.csv"), columns=cols, metadata=meta)
