"""A virtual FSR: stress history in, R_FSR and C_FSR out, with hysteresis memory.

**Extension beyond the paper.** The paper's per-unit-area quantities (R_A ≈ 3 Ω·µm², C_A ≈ 14 mF/m²)
describe one film between two particles; a whole sensor is many films in series over an effective
area that grows with stress (the paper names both the conductive area A(σ) and its influence, and
leaves them out). This model puts those pieces together with stated, adjustable assumptions, so that
the readout chain can run without hardware. Its defaults are chosen to behave like a Tekscan
FlexiForce A201 read by the paper's LM555 circuit (R = 10 kΩ, diode): R_FSR ≈ 2 MΩ unloaded to
≈ 0.1 MΩ at 60 kPa, C_FSR ≈ 0.5–1 nF, 555 frequency ≈ 1.4–14 kHz. They are not fitted to a measured
sensor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsrlab.physics.electrical import capacitance, resistance_per_area
from fsrlab.physics.params import PAPER, check_at_least, check_between, check_positive, float_array
from fsrlab.physics.separation import separation_history

__all__ = ["VirtualFSR", "SensorResponse", "A201_AREA_M2"]

#: Sensing area of a FlexiForce A201 (9.53 mm diameter). [m²]
A201_AREA_M2 = np.pi * (9.53e-3 / 2) ** 2


@dataclass
class SensorResponse:
    """Electrical state of the sensor along a stress history.

    Parameters
    ----------
    stress_pa : ndarray
        The stress history. [Pa]
    separation_m : ndarray
        Interparticle separation (with memory). [m]
    direction : ndarray of int
        +1 loading, −1 unloading, 0 at rest before the first move.
    r_fsr_ohm : ndarray
        Sensor resistance R_FSR. [Ω]
    c_fsr_farad : ndarray
        Sensor capacitance C_FSR. [F]
    """

    stress_pa: np.ndarray
    separation_m: np.ndarray
    direction: np.ndarray
    r_fsr_ohm: np.ndarray
    c_fsr_farad: np.ndarray


@dataclass(frozen=True)
class VirtualFSR:
    """A virtual force-sensing resistor built from the paper's physics (an extension).

    Parameters
    ----------
    area_m2 : float
        Sensing area A_FSR; force = stress × area. [m²]
    s0_m : float
        Interparticle separation at zero stress. [m]
    modulus_pa : float
        Effective stiffness of the composite, softer than Table 1's 4.73 MPa so that a 60 kPa
        full scale moves the films by ≈ 6 %. [Pa]
    k : float
        Unloading exponent of eq. (9). [-]
    phi0_j : float
        Barrier height. [J]
    eps_r : float
        Relative permittivity. [-]
    layers : float
        Films in series between the electrodes (divides the voltage, multiplies R, divides C). [-]
    dielectric_fraction_0 : float
        Fraction of the area acting as capacitor at zero stress. [-]
    dielectric_half_pa : float
        Stress at which the capacitive area has grown half-way to the full area. [Pa]
    conductive_fraction_0 : float
        Fraction of the area carrying tunnelling current at zero stress. [-]
    conductive_growth_pa : float
        Stress per unit growth of the conductive area: A_c = A_c0 (1 + σ/σ_c). [Pa]

    Notes
    -----
    With separation s(σ) from :func:`fsrlab.physics.separation.separation_history` (eqs. 1 and 9
    with memory), ``n = layers`` and voltage V across the sensor:

    - ``C_FSR = ε_r ε0 A_d(σ) / (n s)`` (eq. 14 over n films in series), with
      ``A_d = A (a0 + (1 − a0) σ/(σ + σ_d))``;
    - ``R_FSR = n R_A(V/n, s) / A_c(σ)`` (eqs. 16–18 per film, films in series), with
      ``A_c = A c0 (1 + σ/σ_c)``.

    Hysteresis enters only through s(σ); the areas are reversible. The paper's §5 observation, a
    frequency that rises with stress, follows from R_FSR falling faster than C_FSR rises.
    """

    area_m2: float = A201_AREA_M2
    s0_m: float = PAPER.s0_m
    modulus_pa: float = 1.0e6
    k: float = PAPER.k
    phi0_j: float = PAPER.phi0_j
    eps_r: float = PAPER.eps_r
    layers: float = 1000.0
    dielectric_fraction_0: float = 0.5
    dielectric_half_pa: float = 20e3
    conductive_fraction_0: float = 0.004
    conductive_growth_pa: float = 12e3

    def __post_init__(self) -> None:
        for name in ("area_m2", "s0_m", "modulus_pa", "phi0_j", "eps_r", "layers",
                     "dielectric_fraction_0", "dielectric_half_pa", "conductive_fraction_0",
                     "conductive_growth_pa"):
            check_positive(name, getattr(self, name), scalar=True)
        check_at_least("k", self.k, 1.0, scalar=True)
        for name in ("dielectric_fraction_0", "conductive_fraction_0"):
            check_between(name, getattr(self, name), 0.0, 1.0, lower_open=True, scalar=True)

    def respond(self, stress_pa, voltage_v: float = 2.5) -> SensorResponse:
        """Electrical response along a stress history.

        Parameters
        ----------
        stress_pa : array_like
            Stress samples in time order, 0 ≤ σ < modulus_pa. [Pa]
        voltage_v : float
            Voltage across the sensor; 2.5 V is the middle of an LM555's Vcc/3–2Vcc/3 swing at
            Vcc = 5 V. [V]

        Returns
        -------
        SensorResponse
        """
        check_positive("voltage_v", voltage_v, "V", scalar=True)
        hist = separation_history(stress_pa, s0_m=self.s0_m, modulus_pa=self.modulus_pa, k=self.k)
        sigma = hist.stress_pa
        s = hist.separation_m
        n = self.layers
        a0 = self.dielectric_fraction_0
        area_c = self.area_m2 * (a0 + (1 - a0) * sigma / (sigma + self.dielectric_half_pa))
        c = capacitance(n * s, area_c, self.eps_r)  # Eq. (14), n films in series
        area_r = self.area_m2 * self.conductive_fraction_0 * (1 + sigma / self.conductive_growth_pa)
        r = n * np.asarray(resistance_per_area(voltage_v / n, s, self.phi0_j)) / area_r  # Eqs. (16)-(18)
        return SensorResponse(stress_pa=sigma, separation_m=s, direction=hist.direction,
                              r_fsr_ohm=np.asarray(r, dtype=float), c_fsr_farad=np.asarray(c, dtype=float))

    def force_to_stress(self, force_n):
        """Stress σ = F / A_FSR for force ``force_n`` [N]; returns [Pa]."""
        return float_array("force_n", force_n) / self.area_m2
