"""Where a change of the oscillator's frequency comes from: the FSR's capacitance or its resistance.

The FSR times the LM555 astable as R_FSR in parallel with C_FSR (paper §5). Under load both change:
C_FSR grows (eqs. 14–15), which lowers f, and R_FSR falls (eqs. 16–18), which with the diode D1
raises f through τL = ln 2·R_FSR·C (eq. 34). :func:`frequency_decomposition` evaluates f along a
path of (R_FSR, C_FSR) three times: as given, with R_FSR held at its first value (only C_FSR
changes) and with C_FSR held at its first value (only R_FSR changes). An extension beyond the paper,
which reads the frequency of its Figure 19a as a capacitive measurement.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eqs. (23), (26), (27), (34),
(35), Figures 16 and 19a.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.circuits.checks import check_single
from fsrlab.circuits.lm555 import astable
from fsrlab.errors import ParameterError
from fsrlab.physics.params import float_array

__all__ = ["FrequencyDecomposition", "frequency_decomposition"]


@dataclass(frozen=True)
class FrequencyDecomposition:
    """Frequency along a path of (R_FSR, C_FSR), and with only one of them changing.

    Parameters
    ----------
    frequency_hz : ndarray
        f with R_FSR and C_FSR as given. [Hz]
    c_only_hz : ndarray
        f with R_FSR held at its first value: the capacitive part. [Hz]
    r_only_hz : ndarray
        f with C_FSR held at its first value: the resistive part. [Hz]
    """

    frequency_hz: np.ndarray
    c_only_hz: np.ndarray
    r_only_hz: np.ndarray

    def to_dict(self) -> dict:
        """First and last value of each curve (the report's JSON shape). [Hz]"""
        return {name: [float(v[0]), float(v[-1])] for name, v in
                (("frequency_hz", self.frequency_hz), ("c_only_hz", self.c_only_hz), ("r_only_hz", self.r_only_hz))}


def frequency_decomposition(r_ohm: float, r_fsr_ohm, c_fsr_farad, diode: bool,
                            c_off_farad: float = 0.0) -> FrequencyDecomposition:
    """Split the frequency change along a load path into its capacitive and resistive parts.

    Parameters
    ----------
    r_ohm : float
        R_A = R_B = R. [Ω]
    r_fsr_ohm : array_like, shape (n,)
        FSR resistance along the path, e.g. versus stress. [Ω]
    c_fsr_farad : array_like, shape (n,)
        FSR capacitance along the same path. [F]
    diode : bool
        With the ideal diode D1 in series with R_B (paper Figs. 13 and 16).
    c_off_farad : float
        Offset capacitor in parallel with the FSR. [F]

    Returns
    -------
    FrequencyDecomposition

    Raises
    ------
    ParameterError
        If the paths are not 1-D of the same length ≥ 1, or as :func:`fsrlab.circuits.lm555.astable`
        (e.g. the circuit does not oscillate somewhere on the path).

    Notes
    -----
    Each curve is the closed form ``f = 1/(τH + τL)`` (eqs. 27 and 35) of
    :func:`fsrlab.circuits.lm555.astable`. The parts do not add up to the whole: f is not linear in
    R_FSR and C_FSR.
    """
    check_single(("r_ohm", r_ohm), ("c_off_farad", c_off_farad))
    rf = float_array("r_fsr_ohm", r_fsr_ohm)
    cf = float_array("c_fsr_farad", c_fsr_farad)
    if rf.ndim != 1 or rf.size == 0:
        raise ParameterError(f"must be a 1-D path of at least one value, got shape {rf.shape}", parameter="r_fsr_ohm")
    if cf.shape != rf.shape:
        raise ParameterError(f"must be a path of r_fsr_ohm's length ({rf.size}), got shape {cf.shape}",
                             parameter="c_fsr_farad")
    return FrequencyDecomposition(
        frequency_hz=astable(r_ohm, rf, cf, c_off_farad, diode=diode).frequency_hz,
        c_only_hz=astable(r_ohm, rf[0], cf, c_off_farad, diode=diode).frequency_hz,
        r_only_hz=astable(r_ohm, rf, cf[0], c_off_farad, diode=diode).frequency_hz,
    )
