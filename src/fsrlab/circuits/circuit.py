"""The readout circuits as values: the LM555 astable and the op-amp (eq. 38), validated once.

A circuit is a frozen dataclass: what a run's sidecar and a saved calibration store
(:meth:`LM555Circuit.to_dict`), what the meter model, the synthetic runs, the virtual device and the
calibration pipeline pass along, and what the model functions of :mod:`fsrlab.circuits.lm555`,
:mod:`fsrlab.circuits.phases`, :mod:`fsrlab.circuits.decode`, :mod:`fsrlab.circuits.transient` and
:mod:`fsrlab.circuits.spice` are evaluated for (:meth:`LM555Circuit.kwargs`: every one of them
accepts ``**circuit.kwargs()``). The model functions themselves stay pure and vectorised (a design
sweep passes an array of R), so they take the same parameters as keywords; this module holds the
one check of those parameters (:func:`~fsrlab.circuits.checks.check_lm555`). The methods :meth:`LM555Circuit.astable`,
:meth:`~LM555Circuit.sensitivity`, :meth:`~LM555Circuit.decode`, :meth:`~LM555Circuit.simulate` and
:meth:`~LM555Circuit.simulate_spice` are thin delegations to those functions.

The paper's circuits are :data:`PAPER_CIRCUIT` (Fig. 16) and :data:`PAPER_OPAMP` (Fig. 18, eq. 38).

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, §5 (Figs. 9b, 13, 16), §6 (eq. 38).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import MISSING, asdict, dataclass, fields, replace
from typing import TYPE_CHECKING

from fsrlab.circuits.checks import check_lm555
from fsrlab.errors import ParameterError
from fsrlab.physics.params import float_array

if TYPE_CHECKING:  # numpy is imported where it is used: the paper's circuit is built without it (start-up)
    import numpy as np

__all__ = ["LM555Circuit", "OpAmpReadout", "readout_from_metadata", "decode_capacitance",
           "PAPER_CIRCUIT", "PAPER_OPAMP"]



def _from_dict(cls, d: dict, kind: str):
    if not isinstance(d, dict):
        raise ParameterError(f"expected a mapping of {kind} parts, got {type(d).__name__}", parameter="circuit")
    names = {f.name for f in fields(cls)}
    unknown = sorted(set(d) - names - {"topology"})
    if unknown:
        raise ParameterError(f"unknown {kind} part(s) {', '.join(unknown)} (known: "
                f"{', '.join(sorted(names))})", parameter="circuit")
    missing = [f.name for f in fields(cls) if f.default is MISSING and f.name not in d]
    if missing:
        raise ParameterError(f"the {kind} part(s) {', '.join(missing)} must be given", parameter="circuit")
    return cls(**{k: v for k, v in d.items() if k in names})


@dataclass(frozen=True)
class LM555Circuit:
    """The LM555 astable with the FSR as timing element (paper Figs. 9b, 13, 16).

    Parameters
    ----------
    r_ohm : float
        R_A = R_B = R (> 0). [Ω]
    c_off_farad : float
        Offset capacitor in parallel with the FSR (≥ 0); the meter switches it in on range 1. [F]
    diode : bool
        D1 in series with R_B (paper Figs. 13 and 16; default False, the plain astable of Fig. 9b).
    diode_drop_v : float
        Constant forward drop of D1 during the charge (0: the paper's ideal diode; needs ``diode``). [V]
    vcc_v : float
        Supply (> 0). [V]
    lower_fraction, upper_fraction : float
        Trigger and threshold levels as fractions of Vcc (1/3 and 2/3; a voltage on the control pin
        moves both, see :meth:`with_control`). [1]
    discharge_ohm : float
        On-resistance of the discharge transistor (≥ 0; 0 is the paper's ideal switch). [Ω]

    Notes
    -----
    The defaults are the LM555's own (5 V supply, internal 1/3–2/3 divider, ideal switch); the
    paper's circuit is :data:`fsrlab.circuits.circuit.PAPER_CIRCUIT`.
    """

    r_ohm: float
    c_off_farad: float = 0.0
    diode: bool = False
    diode_drop_v: float = 0.0
    vcc_v: float = 5.0
    lower_fraction: float = 1 / 3
    upper_fraction: float = 2 / 3
    discharge_ohm: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "diode":
                if not (isinstance(v, bool) or type(v).__name__ == "bool_"):  # Python's or numpy's
                    raise ParameterError(f"must be true or false, got {v!r}", parameter="diode")
                object.__setattr__(self, "diode", bool(v))
            else:
                try:
                    object.__setattr__(self, f.name, float(v))
                except (TypeError, ValueError):
                    raise ParameterError(f"must be a number, got {v!r}", parameter=f.name) from None
        check_lm555(self.r_ohm, self.c_off_farad, self.diode, self.diode_drop_v, self.vcc_v,
                    self.lower_fraction, self.upper_fraction, self.discharge_ohm)

    @classmethod
    def with_control(cls, control_v: float, **parts) -> LM555Circuit:
        """A circuit whose control pin (5) is driven to ``control_v``.

        Parameters
        ----------
        control_v : float
            Voltage on the control pin, 0 < control_v < vcc_v. [V]
        **parts
            The other fields (``vcc_v`` default 5 V).

        Returns
        -------
        LM555Circuit
            Thresholds ``control_v`` and half of it (the LM555's internal divider).
        """
        vcc = float(parts.get("vcc_v", 5.0))
        if not (math.isfinite(vcc) and vcc > 0):
            raise ParameterError(f"must be a finite supply voltage > 0 V, got {vcc!r}", parameter="vcc_v")
        if not (0 < control_v < vcc):
            raise ParameterError(f"must be between 0 and Vcc = {vcc:g} V, got {control_v!r}", parameter="control_v")
        upper = control_v / vcc
        return cls(**{**parts, "lower_fraction": upper / 2, "upper_fraction": upper})

    def replace(self, **changes) -> LM555Circuit:
        """A copy with some parts changed (validated again)."""
        return replace(self, **changes)

    @property
    def fsr_voltage_v(self) -> float:
        """Typical voltage across the FSR: the middle of the capacitor's swing between the thresholds. [V]"""
        return 0.5 * (self.lower_fraction + self.upper_fraction) * self.vcc_v

    def on_range(self, range_) -> LM555Circuit:
        """The circuit as the meter runs it on ``range_`` (0: FSR alone, 1: C_off switched in)."""
        return self if range_ else self.replace(c_off_farad=0.0)

    def kwargs(self) -> dict:
        """Keyword arguments for the model functions (``astable``, ``decode``, ``simulate``...)."""
        return asdict(self)

    def astable(self, r_fsr_ohm, c_fsr_farad, check: bool = True):
        """Steady-state timing for an FSR state (:func:`fsrlab.circuits.lm555.astable`)."""
        from fsrlab.circuits.lm555 import astable

        return astable(r_fsr_ohm=r_fsr_ohm, c_fsr_farad=c_fsr_farad, check=check, **self.kwargs())

    def sensitivity(self, r_fsr_ohm, c_fsr_farad, check: bool = True):
        """Logarithmic sensitivities of f and DC to the FSR's parts (:func:`fsrlab.circuits.lm555.sensitivity`)."""
        from fsrlab.circuits.lm555 import sensitivity

        return sensitivity(r_fsr_ohm=r_fsr_ohm, c_fsr_farad=c_fsr_farad, check=check, **self.kwargs())

    def decode(self, frequency_hz, duty_cycle, periods=1, check: bool = True):
        """R_FSR and C_FSR from a reading (:func:`fsrlab.circuits.decode.decode`)."""
        from fsrlab.circuits.decode import decode

        return decode(frequency_hz, duty_cycle, periods=periods, check=check, **self.kwargs())

    def simulate(self, r_fsr_ohm, c_fsr_farad, **options):
        """Event-driven transient of this circuit (:func:`fsrlab.circuits.transient.simulate`).

        Parameters
        ----------
        r_fsr_ohm, c_fsr_farad : float or array_like
            The FSR's parts, constant or one value per ``time_s`` sample. [Ω], [F]
        **options
            ``periods``, ``t_stop_s``, ``time_s``, ``v_initial_v``, ``waveform``,
            ``points_per_segment``, ``capacitance_step``, as in the function.

        Returns
        -------
        fsrlab.circuits.transient.TransientResult
        """
        from fsrlab.circuits.transient import simulate

        return simulate(r_fsr_ohm=r_fsr_ohm, c_fsr_farad=c_fsr_farad, **options, **self.kwargs())

    def simulate_spice(self, r_fsr_ohm, c_fsr_farad, **options):
        """This circuit in ngspice (:func:`fsrlab.circuits.spice.simulate_spice`; needs ngspice).

        Parameters
        ----------
        r_fsr_ohm, c_fsr_farad : float
            The FSR's parts. [Ω], [F]
        **options
            ``periods``, ``skip_periods``, ``steps_per_phase``, ``timeout_s``, as in the function.

        Returns
        -------
        fsrlab.circuits.spice.SpiceResult
            Run with this circuit's ``discharge_ohm`` (0 by default: an ideal switch, where the
            function's own default is 1 mΩ).
        """
        from fsrlab.circuits.spice import simulate_spice

        return simulate_spice(r_fsr_ohm=r_fsr_ohm, c_fsr_farad=c_fsr_farad, **options, **self.kwargs())

    def to_dict(self) -> dict:
        """JSON-ready parts, with ``topology`` naming the circuit (for sidecars and calibrations)."""
        return {"topology": "lm555-astable", **asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> LM555Circuit:
        """Inverse of :meth:`to_dict` (missing parts with a default take it; unknown parts are an error)."""
        return _from_dict(cls, d, "LM555")


@dataclass(frozen=True)
class OpAmpReadout:
    """The traditional readout: an inverting amplifier with the FSR as input resistor (paper Fig. 18).

    Parameters
    ----------
    r_f_ohm : float
        Feedback resistor (> 0; 20 kΩ in the paper). [Ω]
    vcc_v : float
        Drive voltage at the FSR's input (finite, not 0; −5 V in the paper, so that V_out > 0). [V]

    Notes
    -----
    ``V_out = −(R_F/R_FSR)·Vcc`` (eq. 38). The FSR sits between ``Vcc`` and the virtual ground, so it
    sees ``|Vcc|`` whatever its resistance: its resistance is the one at ``|Vcc|``
    (:attr:`fsr_voltage_v`).
    """

    r_f_ohm: float
    vcc_v: float

    def __post_init__(self) -> None:
        for name in ("r_f_ohm", "vcc_v"):
            try:
                object.__setattr__(self, name, float(getattr(self, name)))
            except (TypeError, ValueError):
                raise ParameterError(f"must be a number, got {getattr(self, name)!r}", parameter=name) from None
        if not (math.isfinite(self.r_f_ohm) and self.r_f_ohm > 0):
            raise ParameterError(f"must be finite and > 0 Ω, got {self.r_f_ohm!r}", parameter="r_f_ohm")
        if not (math.isfinite(self.vcc_v) and self.vcc_v != 0):
            raise ParameterError(f"must be a finite non-zero voltage, got {self.vcc_v!r}", parameter="vcc_v")

    @property
    def fsr_voltage_v(self) -> float:
        """Voltage across the FSR, ``|Vcc|``. [V]"""
        return abs(self.vcc_v)

    def output_v(self, r_fsr_ohm):
        """Output voltage for an FSR resistance taken at :attr:`fsr_voltage_v` (eq. 38). [V]"""
        from fsrlab.circuits.opamp import inverting_amplifier

        return inverting_amplifier(r_fsr_ohm, self.r_f_ohm, self.vcc_v).v_out_v

    def conductance_s(self, v_out_v):
        """FSR conductance from the output voltage, ``G = −V_out/(R_F·Vcc)`` (eq. 38 inverted). [S]"""

        v = float_array("v_out_v", v_out_v)
        g = -v / (self.r_f_ohm * self.vcc_v)
        return g[()] if g.ndim == 0 else g

    def to_dict(self) -> dict:
        """JSON-ready parts, with ``topology``."""
        return {"topology": "opamp-inverting", **asdict(self)}

    @classmethod
    def from_dict(cls, d: dict) -> OpAmpReadout:
        """Inverse of :meth:`to_dict`."""
        return _from_dict(cls, d, "op-amp")


def readout_from_metadata(metadata: dict) -> tuple[LM555Circuit | None, OpAmpReadout | None]:
    """The readout circuits a run's sidecar (or a calibration) describes.

    Parameters
    ----------
    metadata : dict
        Sidecar content: ``circuit`` (an :meth:`LM555Circuit.to_dict`) and ``opamp`` (an
        :meth:`OpAmpReadout.to_dict`). Earlier sidecars are read too: op-amp parts as
        ``circuit.traditional`` or as ``r_f_ohm`` beside the LM555's parts (with the FSR driven
        from ``−vcc_v``), and a free-text ``topology``.

    Returns
    -------
    (LM555Circuit or None, OpAmpReadout or None)
        None where the sidecar says nothing of that circuit.

    Raises
    ------
    ParameterError
        A part out of range or unknown (its ``parameter`` names it).
    TypeError
        ``metadata`` is not a mapping.
    """
    if metadata is not None and not isinstance(metadata, Mapping):
        raise TypeError(f"metadata: must be a mapping (a run's sidecar), got {type(metadata).__name__}")
    raw = dict((metadata or {}).get("circuit") or {})
    opamp = (metadata or {}).get("opamp")
    legacy = raw.pop("traditional", None)
    if "r_f_ohm" in raw:
        legacy = {"r_f_ohm": raw.pop("r_f_ohm"), "vcc_v": -abs(float(raw.get("vcc_v", 5.0)))}
    if opamp is None and legacy is not None:
        opamp = legacy
    raw.pop("topology", None)
    circuit = LM555Circuit.from_dict(raw) if raw else None
    return circuit, (OpAmpReadout.from_dict(opamp) if opamp is not None else None)


#: The proposed readout of the paper's Fig. 16: LM555 with R_A = R_B = R, D1 in series with R_B as an
#: ideal diode (§5), thresholds 1/3 and 2/3 of a 5 V supply, no C_off. The paper prints no value for R:
#: R = 10 kΩ is fsrlab's choice (it keeps N = R_FSR/R well above 4 over the sensor's range).
PAPER_CIRCUIT = LM555Circuit(r_ohm=10e3, c_off_farad=0.0, diode=True, diode_drop_v=0.0, vcc_v=5.0)

#: The traditional readout of the paper's Fig. 18 and eq. (38): R_F = 20 kΩ, the FSR driven from −5 V.
PAPER_OPAMP = OpAmpReadout(r_f_ohm=20e3, vcc_v=-5.0)


def decode_capacitance(frequency_hz, duty_cycle, circuit: LM555Circuit | None = None, range_=None) -> np.ndarray:
    """C_FSR of every reading, decoded from frequency and duty cycle (physics-informed calibration variable).

    Parameters
    ----------
    frequency_hz, duty_cycle : array_like
        555 readings (NaN where missing).
    circuit : LM555Circuit, optional
        The circuit (default :data:`fsrlab.circuits.circuit.PAPER_CIRCUIT`).
    range_ : array_like, optional
        The run's ``range`` column: 1 where C_off was switched in, 0 where it was out
        (:meth:`LM555Circuit.on_range`). Without it, the circuit's C_off applies to every reading.

    Returns
    -------
    ndarray
        C_FSR [F] by :meth:`LM555Circuit.decode`; NaN where a reading or its range is missing, or
        the reading is impossible for the circuit (e.g. one noisy duty cycle outside the reachable
        range), so that one bad window does not stop a whole run.

    Raises
    ------
    ParameterError
        A range other than 0 or 1, or columns of different lengths.
    TypeError
        A column that is not numbers, or a circuit that is not an :class:`LM555Circuit`.
    """
    import numpy as np

    if circuit is None:
        circuit = PAPER_CIRCUIT
    if not isinstance(circuit, LM555Circuit):
        raise TypeError(f"circuit: must be an LM555Circuit, got {type(circuit).__name__}")
    f = float_array("frequency_hz", frequency_hz)
    d = float_array("duty_cycle", duty_cycle)
    if f.shape != d.shape:
        raise ParameterError("must have one value per frequency_hz reading", parameter="duty_cycle")
    ok = np.isfinite(f) & np.isfinite(d)
    if range_ is None:
        states = [(circuit, ok)]
    else:
        r = float_array("range_", range_)
        if r.shape != f.shape:
            raise ParameterError("must have one value per reading", parameter="range_")
        bad = np.isfinite(r) & ~np.isin(r, (0.0, 1.0))
        if bad.any():
            raise ParameterError(f"must be 0 (C_off out) or 1 (C_off in), got {r[bad][0]:g}", parameter="range_")
        states = [(circuit.on_range(0), ok & (r == 0)), (circuit.on_range(1), ok & (r == 1))]
    out = np.full(f.shape, np.nan)
    for circ, m in states:
        if m.any():
            out[m] = np.asarray(circ.decode(f[m], d[m], check=False).c_fsr_farad, dtype=float)
    return out
