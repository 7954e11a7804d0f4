"""ngspice netlists for the FSR-timed LM555 astable, a batch runner and the edge measurement.

ngspice ships no 555 model, so fsrlab writes its own behavioural one (:data:`SUBCKT_555`): the
555's two comparators and its SR latch act, in the astable, as one Schmitt trigger on the
capacitor voltage, which is exactly a voltage-controlled switch ``SW`` with hysteresis
(on above ``VT + VH`` = upper threshold, off below ``VT − VH`` = lower threshold). One switch is
the discharge transistor (pin 7 to ground), a second one with the same control pulls the output
low. The control is the capacitor voltage amplified by ``GAIN`` = 1e4 in a VCVS, because ngspice's
switch time-step control (``SWtrunc``) lets the control overshoot a threshold by up to 0.05 V;
amplified, that is 5 µV on the capacitor, i.e. threshold crossings accurate to ~1e-6 of the swing
without a tiny global time step.

The diode D1 is a SPICE diode with emission coefficient ``N = 1e-4`` (forward drop ≈ 60 µV at
the charge current, reverse leakage 1e-14 A), i.e. practically ideal; a real diode's constant drop
is a DC source in series with it, matching the constant-drop model of
:mod:`fsrlab.circuits.lm555`.

The netlist is independent of fsrlab's closed forms; only the simulated duration uses the closed
form's period estimate (:func:`fsrlab.circuits.lm555.astable`, or the phases of
:func:`fsrlab.circuits.phases.timing_per_rc` with R_FSR = ∞ when the closed form does not
oscillate), so that a run covers the requested number of periods.

Every function takes the circuit's parts as keywords, so ``simulate_spice(r_fsr_ohm=...,
c_fsr_farad=..., **circuit.kwargs())`` runs an :class:`fsrlab.circuits.circuit.LM555Circuit`
(see also :meth:`~fsrlab.circuits.circuit.LM555Circuit.simulate_spice`).

References
----------
ngspice manual, voltage-controlled switch ``S``/``SW`` model (VT, VH, RON, ROFF); Matute et al.,
J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, Figs. 9b, 13, 16.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fsrlab.circuits.checks import check_lm555, check_r_fsr, check_single
from fsrlab.circuits.lm555 import astable
from fsrlab.circuits.phases import timing_per_rc
from fsrlab.errors import ParameterError
from fsrlab.physics.params import (
    check_at_least,
    check_finite,
    check_int,
    check_positive,
    float_array,
    paired_series,
    plain,
)

__all__ = ["SUBCKT_555", "SpiceResult", "netlist", "read_raw", "run_ngspice", "simulate_spice", "simulate_spice_many",
           "start_spice_many", "SpiceBatch", "ngspice_available",
           "edges_from_waveform", "level_crossings"]

#: Control-voltage gain in front of the latch switches (see module docstring). [1]
GAIN = 1e4

#: Behavioural 555 for fsrlab: pins VCC, DIS (7), THR (6 and 2 tied), OUT (3). ``{vt}``/``{vh}``
#: are the switch threshold and hysteresis in control volts (GAIN × capacitor volts).
SUBCKT_555 = """\
* fsrlab behavioural LM555 (astable use): comparators + SR latch as one hysteresis switch.
* Switch closed (discharge on, output low) once V(thr) > upper threshold; open below lower threshold.
.subckt fsr555 vcc dis thr out
Ectl ctl 0 thr 0 {gain:g}
Sdis dis 0 ctl 0 swdis
Sout out 0 ctl 0 sw555
Rout vcc out 1k
.model sw555 SW(VT={vt:.15g} VH={vh:.15g} RON=1m ROFF=1e12)
.model swdis SW(VT={vt:.15g} VH={vh:.15g} RON={ron:.15g} ROFF=1e12)
.ends fsr555
"""


@dataclass(frozen=True)
class SpiceResult:
    """Edges measured on the ngspice output node.

    Attributes
    ----------
    frequency_hz : float
        Mean frequency over the measured complete periods (NaN: no oscillation seen). [Hz]
    duty_cycle : float
        Total high time over total period time. [1]
    rising_s, falling_s : ndarray
        Output edge times (after the skipped start-up periods). [s]
    n_periods : int
        Complete periods measured.
    n_points : int
        Time points ngspice computed.
    netlist : str
        The netlist that was run.
    """

    frequency_hz: float
    duty_cycle: float
    rising_s: np.ndarray
    falling_s: np.ndarray
    n_periods: int
    n_points: int
    netlist: str


def ngspice_available() -> bool:
    """True when an ``ngspice`` executable is on PATH."""
    return shutil.which("ngspice") is not None


def netlist(r_ohm: float, r_fsr_ohm: float, c_fsr_farad: float, c_off_farad: float = 0.0, diode: bool = False,
            diode_drop_v: float = 0.0, vcc_v: float = 5.0, lower_fraction: float = 1 / 3,
            upper_fraction: float = 2 / 3, *, t_stop_s: float, t_max_step_s: float,
            output_file: str = "fsrlab_out.raw", time_s=None, discharge_ohm: float = 1e-3) -> str:
    """ngspice netlist of the astable (paper Figs. 9b, 13, 16) with a ``.control`` block.

    Parameters
    ----------
    r_ohm : float
        R_A = R_B = R. [Ω]
    r_fsr_ohm : float or array_like
        FSR resistance (``inf``: left out); with ``time_s``, its value at each sample, held until
        the next one (a behavioural resistor driven by a stepped PWL source). [Ω]
    c_fsr_farad : float
        FSR capacitance. [F]
    c_off_farad : float
        Offset capacitor (0: left out). [F]
    diode : bool
        D1 in series with R_B.
    diode_drop_v : float
        Constant forward drop of D1, as a DC source in series with a near-ideal diode. [V]
    vcc_v : float
        Supply. [V]
    lower_fraction, upper_fraction : float
        Thresholds as fractions of Vcc. [1]
    t_stop_s : float
        Simulated time, starting from a discharged capacitor. [s]
    t_max_step_s : float
        Largest time step ngspice may take. [s]
    output_file : str
        File the ``.control`` block writes time, V(out), V(thr) into, as an ngspice binary raw file
        (``set filetype=binary``, ``write``; read by :func:`read_raw`): exact doubles, no text to format
        and parse.
    time_s : array_like, optional
        Sample times of a time-varying ``r_fsr_ohm`` (strictly increasing, starting at 0). [s]
    discharge_ohm : float
        On-resistance of the discharge transistor (pin 7, ≥ 0); 1 mΩ is practically ideal, as in the
        closed forms, and so is 0 (an ``LM555Circuit``'s default; ngspice accepts ``RON=0``). A real
        LM555 saturates at a few tens of ohms at these currents. [Ω]

    Returns
    -------
    str
        The netlist text.

    Raises
    ------
    ParameterError
        A part out of range (its ``parameter`` names it).
    TypeError
        A part that is not a number (the message names it).
    """
    check_single(("r_ohm", r_ohm), ("c_off_farad", c_off_farad), ("discharge_ohm", discharge_ohm),
                 ("t_stop_s", t_stop_s), ("t_max_step_s", t_max_step_s))
    check_lm555(r_ohm, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction, discharge_ohm)
    check_r_fsr(r_fsr_ohm)
    if time_s is None and np.ndim(r_fsr_ohm):
        raise ParameterError(f"must be a single value > 0 Ω (inf allowed) without time_s, got {plain(r_fsr_ohm)}",
                             parameter="r_fsr_ohm")
    check_at_least("c_fsr_farad", c_fsr_farad, 0.0, "F")
    if np.ndim(c_fsr_farad):
        raise ParameterError(f"must be a single finite value >= 0 F, got {plain(c_fsr_farad)}", parameter="c_fsr_farad")
    check_positive("t_stop_s", t_stop_s, "s")
    check_positive("t_max_step_s", t_max_step_s, "s")
    if not c_fsr_farad + c_off_farad > 0:
        raise ParameterError("the timing capacitance C_FSR + C_off must be > 0 F", parameter="c_fsr_farad")
    v_lo, v_hi = lower_fraction * vcc_v, upper_fraction * vcc_v
    lines = [
        "* fsrlab: LM555 astable with the FSR as timing element (Matute et al. 2018, Figs. 9b/13/16)",
        SUBCKT_555.format(gain=GAIN, vt=GAIN * (v_lo + v_hi) / 2, vh=GAIN * (v_hi - v_lo) / 2,
                          ron=discharge_ohm).rstrip(),
        f"Vcc vcc 0 DC {vcc_v:.15g}",
        f"RA vcc dis {r_ohm:.15g}",
    ]
    if diode:
        if diode_drop_v > 0:
            lines += [f"RB dis nb {r_ohm:.15g}", f"Vdrop nb nd DC {diode_drop_v:.15g}", "D1 nd thr dideal"]
        else:
            lines += [f"RB dis nb {r_ohm:.15g}", "D1 nb thr dideal"]
        lines.append(".model dideal D(IS=1e-14 N=1e-4)")
    else:
        lines.append(f"RB dis thr {r_ohm:.15g}")
    if time_s is not None:
        t = float_array("time_s", time_s)
        rs = np.broadcast_to(float_array("r_fsr_ohm", r_fsr_ohm), t.shape)
        if t.ndim != 1 or t.size < 2 or t[0] != 0 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(rs)):
            raise ParameterError("need strictly increasing sample times from 0 and finite r_fsr_ohm values",
                                 parameter="time_s")
        if np.any(rs <= 0):
            raise ParameterError("every sample must be > 0 Ω", parameter="r_fsr_ohm")
        # Zero-order hold as in fsrlab.circuits.transient: each value holds until 1e-9 of a step before the next.
        eps = 1e-9 * float(np.min(np.diff(t)))
        pts = []
        for k in range(t.size):
            pts.append(f"{t[k]:.15g} {rs[k]:.15g}")
            if k + 1 < t.size:
                pts.append(f"{t[k + 1] - eps:.15g} {rs[k]:.15g}")
        lines.append("Vrfsr rctl 0 PWL(" + " ".join(pts) + ")")
        lines.append("Bfsr thr 0 I=V(thr)/V(rctl)")
    elif math.isfinite(r_fsr_ohm):
        lines.append(f"RFSR thr 0 {r_fsr_ohm:.15g}")
    lines.append(f"CFSR thr 0 {c_fsr_farad:.15g}")
    if c_off_farad > 0:
        lines.append(f"COFF thr 0 {c_off_farad:.15g}")
    lines += [
        "X555 vcc dis thr out fsr555",
        ".ic v(thr)=0",
        ".options reltol=1e-6 vntol=1e-9 abstol=1e-15",
        ".control",
        "set filetype=binary",
        "set norefvalue",  # no time printed as it runs: ngspice reads the CPU clock at every point for it
        f"tran {t_max_step_s:.6g} {t_stop_s:.9g} 0 {t_max_step_s:.6g} uic",
        f"write {output_file} v(out) v(thr)",
        "quit",
        ".endc",
        ".end",
    ]
    return "\n".join(lines) + "\n"


def read_raw(data: bytes) -> np.ndarray:
    """Read an ngspice binary raw file (one real-valued plot, e.g. a transient analysis).

    Parameters
    ----------
    data : bytes
        The file's bytes: a text header (``No. Variables:``, ``No. Points:``, ``Flags: real``) ending
        in ``Binary:\\n``, then the points, each the variables as little-endian float64 (the first is
        the scale, time).

    Returns
    -------
    ndarray
        Shape (points, variables): column 0 time [s], then the written vectors in order.

    Raises
    ------
    RuntimeError
        When the header is not one of a real-valued binary plot or the data are cut short.
    """
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise TypeError(f"data: must be the raw file's bytes, got {type(data).__name__}")
    data = bytes(data)
    marker = data.find(b"Binary:\n")
    if marker < 0:
        raise RuntimeError("ngspice raw file: no 'Binary:' section (not a binary raw file)")
    header = {}
    for line in data[:marker].decode("ascii", "replace").splitlines():
        key, sep, value = line.partition(":")
        if sep:
            header[key.strip().lower()] = value.strip()
    if "complex" in header.get("flags", "real"):
        raise RuntimeError("ngspice raw file: complex data (expected a real-valued transient plot)")
    try:
        nvars, npoints = int(header["no. variables"]), int(header["no. points"])
    except (KeyError, ValueError):
        raise RuntimeError("ngspice raw file: header without 'No. Variables' / 'No. Points'") from None
    body = data[marker + len(b"Binary:\n"):]
    if len(body) < 8 * nvars * npoints:
        raise RuntimeError(f"ngspice raw file: {len(body)} bytes of data, {8 * nvars * npoints} expected")
    return np.frombuffer(body, dtype="<f8", count=nvars * npoints).reshape(npoints, nvars).copy()


class _NgspiceRun:
    """One ngspice process, started at once; :meth:`result` waits for it and reads its output.

    The process runs in a temporary directory; its console output goes to a file there (not a pipe, so
    no thread has to read it while it runs and a process forked meanwhile holds no end of it).
    """

    def __init__(self, text: str, output_file: str = "fsrlab_out.raw") -> None:
        exe = shutil.which("ngspice")
        if exe is None:
            raise FileNotFoundError("ngspice is not installed (`make sysdeps` installs it)")
        self._dir = tempfile.TemporaryDirectory(prefix="fsrlab-spice-")
        self._tmp = Path(self._dir.name)
        self.output_file = output_file
        cir = self._tmp / "circuit.cir"
        cir.write_text(text, encoding="ascii")
        try:
            with open(self._tmp / "ngspice.log", "wb") as log:
                self._proc = subprocess.Popen([exe, "-b", str(cir)], cwd=self._tmp, stdin=subprocess.DEVNULL,
                                              stdout=log, stderr=subprocess.STDOUT)
        except BaseException:
            self._dir.cleanup()
            raise

    def result(self, timeout_s: float = 300.0) -> np.ndarray:
        """Wait for ngspice (at most ``timeout_s``, then stop it) and read its binary raw output.

        Returns
        -------
        ndarray
            The table (first column time), one row per time point.

        Raises
        ------
        RuntimeError
            ngspice failed or wrote no data; the message carries the end of its log.
        subprocess.TimeoutExpired
            It ran longer than ``timeout_s`` (it is stopped).
        """
        try:
            try:
                code = self._proc.wait(timeout=timeout_s)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
                raise
            out = self._tmp / self.output_file
            if code != 0 or not out.exists():
                log = (self._tmp / "ngspice.log").read_text(encoding="utf-8", errors="replace")
                tail = " | ".join(log.strip().splitlines()[-8:])
                raise RuntimeError(f"ngspice failed (exit {code}): {tail}")
            return read_raw(out.read_bytes())
        finally:
            self._dir.cleanup()


def run_ngspice(text: str, output_file: str = "fsrlab_out.raw", timeout_s: float = 300.0) -> np.ndarray:
    """Run a netlist with ``ngspice -b`` in a temporary directory and read its binary raw output.

    Parameters
    ----------
    text : str
        Netlist whose ``.control`` block writes ``output_file`` as a binary raw file (as :func:`netlist`'s).
    output_file : str
        Name of that file.
    timeout_s : float
        Give up after this long. [s]

    Returns
    -------
    ndarray
        The table (first column time), one row per time point.

    Raises
    ------
    FileNotFoundError
        ngspice is not installed.
    RuntimeError
        ngspice failed or wrote no data; the message carries the end of its log.
    """
    return _NgspiceRun(text, output_file).result(timeout_s)


def level_crossings(t_s, v_v, level_v: float, rising: bool) -> np.ndarray:
    """Times a sampled waveform crosses a level, by linear interpolation between samples.

    Parameters
    ----------
    t_s : ndarray
        Sample times, increasing. [s]
    v_v : ndarray
        Waveform at ``t_s``. [V]
    level_v : float
        The level. [V]
    rising : bool
        True: upward crossings (from below to at or above); False: downward ones.

    Returns
    -------
    ndarray
        Crossing times. [s]
    """
    t, v = paired_series("t_s", t_s, "v_v", v_v)
    check_finite("level_v", level_v)
    if np.ndim(level_v):
        raise ParameterError(f"must be a single level, got {plain(level_v)}", parameter="level_v")
    s = v - level_v
    idx = np.nonzero((s[:-1] < 0) & (s[1:] >= 0))[0] if rising else np.nonzero((s[:-1] > 0) & (s[1:] <= 0))[0]
    return t[idx] - s[idx] * (t[idx + 1] - t[idx]) / (s[idx + 1] - s[idx])


def edges_from_waveform(t_s, v_out_v, vcc_v: float = 5.0, skip_periods: int = 2):
    """Output edge times (linear interpolation at Vcc/2), frequency and duty cycle.

    Parameters
    ----------
    t_s, v_out_v : array_like
        Output waveform. [s], [V]
    vcc_v : float
        Supply (edges are taken at Vcc/2). [V]
    skip_periods : int
        Start-up periods left out (the first charge starts from 0 V).

    Returns
    -------
    (rising, falling, frequency_hz, duty_cycle)
        Edge arrays in [s], mean frequency [Hz] and duty cycle [1] over the complete periods
        (NaN when fewer than one complete period remains).
    """
    t, v = paired_series("t_s", t_s, "v_out_v", v_out_v)
    check_positive("vcc_v", vcc_v, "V", scalar=True)
    skip_periods = check_int("skip_periods", skip_periods, 0)
    rising = level_crossings(t, v, vcc_v / 2, True)[skip_periods:]
    falling = level_crossings(t, v, vcc_v / 2, False)
    if rising.size < 2:
        return rising, falling[:0], math.nan, math.nan
    falling = falling[(falling > rising[0]) & (falling < rising[-1])]
    periods = rising.size - 1
    if falling.size != periods:
        return rising, falling, math.nan, math.nan
    total = rising[-1] - rising[0]
    return rising, falling, periods / total, float(np.sum(falling - rising[:-1]) / total)


@dataclass(frozen=True)
class _Plan:
    """One run of :func:`simulate_spice`: its netlist, how to measure it, and its expected work."""

    text: str
    periods: int
    skip_periods: int
    vcc_v: float
    timeout_s: float
    steps: float  # simulated time over the largest time step: the expected work of the run


def _plan(r_ohm: float, r_fsr_ohm: float, c_fsr_farad: float, c_off_farad: float = 0.0,
          diode: bool = False, diode_drop_v: float = 0.0, vcc_v: float = 5.0,
          lower_fraction: float = 1 / 3, upper_fraction: float = 2 / 3, *, periods: int = 20,
          skip_periods: int = 2, steps_per_phase: int = 50, timeout_s: float = 300.0,
          discharge_ohm: float = 1e-3) -> _Plan:
    """The netlist of :func:`simulate_spice`'s run (its parameters checked) and what measures it."""
    check_int("periods", periods, 1)
    check_int("skip_periods", skip_periods, 0)
    check_int("steps_per_phase", steps_per_phase, 10)
    check_positive("timeout_s", timeout_s, "s")
    est = astable(r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction,
                  upper_fraction, check=False)
    period = float(est.period_s)
    shortest = float(min(est.tau_high_s, est.tau_low_s))
    if not math.isfinite(period):
        # Does not oscillate by the closed form: simulate a few periods of the classic 555 with the same
        # thresholds (R_FSR = ∞, no diode) and let ngspice show it.
        th, tl = timing_per_rc(math.inf, vcc_v=vcc_v, lower_fraction=lower_fraction, upper_fraction=upper_fraction)
        rc = r_ohm * (c_fsr_farad + c_off_farad)
        period, shortest = float(th + tl) * rc, float(min(th, tl)) * rc
    # Start-up from 0 V takes longer than a steady period; allow for it.
    t_stop = period * (periods + skip_periods + 2)
    t_max_step = shortest / steps_per_phase
    text = netlist(r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction,
                   upper_fraction, t_stop_s=t_stop, t_max_step_s=t_max_step, discharge_ohm=discharge_ohm)
    return _Plan(text=text, periods=int(periods), skip_periods=int(skip_periods), vcc_v=vcc_v,
                 timeout_s=timeout_s, steps=t_stop / t_max_step)


def _measured(plan: _Plan, data: np.ndarray) -> SpiceResult:
    """Frequency and duty cycle of a run's output waveform (``data``: time, V(out), V(thr))."""
    periods = plan.periods
    rising, falling, f, dc = edges_from_waveform(data[:, 0], data[:, 1], plan.vcc_v, plan.skip_periods)
    if rising.size > periods + 1:
        rising = rising[: periods + 1]
        falling = falling[falling < rising[-1]]
        total = rising[-1] - rising[0]
        f, dc = periods / total, float(np.sum(falling - rising[:-1]) / total)
    n = max(rising.size - 1, 0) if math.isfinite(f) else 0
    return SpiceResult(frequency_hz=f, duty_cycle=dc, rising_s=rising, falling_s=falling, n_periods=n,
                       n_points=int(data.shape[0]), netlist=plan.text)


def simulate_spice(r_ohm: float, r_fsr_ohm: float, c_fsr_farad: float, c_off_farad: float = 0.0,
                   diode: bool = False, diode_drop_v: float = 0.0, vcc_v: float = 5.0,
                   lower_fraction: float = 1 / 3, upper_fraction: float = 2 / 3, *, periods: int = 20,
                   skip_periods: int = 2, steps_per_phase: int = 50, timeout_s: float = 300.0,
                   discharge_ohm: float = 1e-3) -> SpiceResult:
    """Simulate the astable in ngspice and measure frequency and duty cycle on the output.

    Parameters
    ----------
    r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction, upper_fraction
        As in :func:`fsrlab.circuits.lm555.astable` (single values). [Ω, Ω, F, F, -, V, V, 1, 1]
    periods : int
        Complete periods to measure after the start-up.
    skip_periods : int
        Start-up periods to leave out.
    steps_per_phase : int
        Largest time step = min(τH, τL)/steps_per_phase from the closed-form estimate (threshold
        crossings are refined by the switch's own step control regardless).
    timeout_s : float
        ngspice time limit. [s]
    discharge_ohm : float
        On-resistance of the discharge transistor (see :func:`netlist`). The default 1 mΩ is
        practically the closed forms' ideal switch; an ``LM555Circuit`` passes its own value (0). [Ω]

    Returns
    -------
    SpiceResult
        NaN frequency and duty cycle when no oscillation shows in the simulated time.
    """
    plan = _plan(r_ohm, r_fsr_ohm, c_fsr_farad, c_off_farad, diode, diode_drop_v, vcc_v, lower_fraction,
                 upper_fraction, periods=periods, skip_periods=skip_periods, steps_per_phase=steps_per_phase,
                 timeout_s=timeout_s, discharge_ohm=discharge_ohm)
    return _measured(plan, run_ngspice(plan.text, timeout_s=plan.timeout_s))


class SpiceBatch:
    """:func:`simulate_spice` runs started by :func:`start_spice_many`; :meth:`results` waits for them all.

    Parameters
    ----------
    plans : list
        The runs' netlists and measurement settings, in the order of the cases.
    jobs : int
        ngspice processes at a time (≥ 1); that many start at once, the longest first.
    """

    def __init__(self, plans: list, jobs: int) -> None:
        self._plans = plans
        self._queue = sorted(range(len(plans)), key=lambda i: -plans[i].steps)  # the longest first
        self._lock = threading.Lock()
        self._failed = False
        self._first = [run for run in (self._start_next() for _ in range(min(jobs, len(plans)))) if run]

    def _start_next(self):
        with self._lock:
            if self._failed or not self._queue:
                return None
            i = self._queue.pop(0)
        return i, _NgspiceRun(self._plans[i].text)

    def results(self) -> list[SpiceResult]:
        """Wait for every run (starting the waiting ones as others end); the results in the order of the cases.

        Returns
        -------
        list of SpiceResult
            The same results as :func:`simulate_spice` gives for each case alone.

        Raises
        ------
        RuntimeError, subprocess.TimeoutExpired
            As :func:`simulate_spice`, for the first run that fails (no further run is started).
        """
        out: list = [None] * len(self._plans)

        def work(item) -> None:
            while item is not None:
                i, run = item
                try:
                    out[i] = _measured(self._plans[i], run.result(self._plans[i].timeout_s))
                except BaseException:
                    self._failed = True
                    raise
                item = self._start_next()

        if len(self._first) == 1:
            work(self._first[0])
        else:
            from concurrent.futures import ThreadPoolExecutor

            # Threads suffice: each waits on its ngspice process, which does the work.
            with ThreadPoolExecutor(max_workers=len(self._first)) as pool:
                for done in [pool.submit(work, item) for item in self._first]:
                    done.result()
        return out


def start_spice_many(cases, jobs: int | None = None, **options) -> SpiceBatch:
    """Start several :func:`simulate_spice` runs as ngspice processes and return at once.

    Parameters
    ----------
    cases : iterable of dict
        Keyword arguments of :func:`simulate_spice` for each run (``r_ohm``, ``r_fsr_ohm``, ...); all are
        checked (and their netlists written) before any run starts.
    jobs : int, optional
        Processes at a time; by default the machine's cores (``os.cpu_count()``), the most that help:
        each ngspice run is one busy process.
    **options
        Keywords common to every run (``periods``, ``steps_per_phase``, ...).

    Returns
    -------
    SpiceBatch
        The first ``jobs`` runs are under way when it returns, the longest first (the most time steps:
        simulated time over the largest step), so that the last one to end is not a long one started
        late; :meth:`SpiceBatch.results` starts the others as runs end and returns every result. No thread
        runs until ``results`` is called (a process may fork meanwhile without inheriting one), and the
        runs' console output goes to files, not pipes.
    """
    import os

    plans = [_plan(**options, **dict(c)) for c in cases]
    return SpiceBatch(plans, max(1, jobs if jobs is not None else (os.cpu_count() or 1)))


def simulate_spice_many(cases, jobs: int | None = None, **options) -> list[SpiceResult]:
    """Several :func:`simulate_spice` runs at once, as concurrent ngspice processes.

    Parameters
    ----------
    cases : iterable of dict
        Keyword arguments of :func:`simulate_spice` for each run (``r_ohm``, ``r_fsr_ohm``, ...).
    jobs : int, optional
        Processes at a time; by default the machine's cores (``os.cpu_count()``), the most that help:
        each ngspice run is one busy process.
    **options
        Keywords common to every run (``periods``, ``steps_per_phase``, ...).

    Returns
    -------
    list of SpiceResult
        In the order of ``cases``; the same results as running them one after another. The longest
        runs start first (:func:`start_spice_many`).
    """
    cases = [dict(c) for c in cases]
    if jobs == 1 or len(cases) == 1:
        return [simulate_spice(**options, **c) for c in cases]
    return start_spice_many(cases, jobs, **options).results()
