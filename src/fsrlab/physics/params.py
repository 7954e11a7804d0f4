"""The paper's printed sensor parameters, in SI units: the one place they live.

The paper's circuits (Figs. 16 and 18) are values of the circuits layer:
:data:`fsrlab.circuits.circuit.PAPER_CIRCUIT` and :data:`fsrlab.circuits.circuit.PAPER_OPAMP`.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, Table 1.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

__all__ = ["PaperParameters", "PAPER", "check_positive", "check_finite"]

#: The electronvolt in joules: CODATA 2018, exact since the 2019 SI (e = 1.602176634e-19 C); equal to
#: ``scipy.constants.electron_volt``, written out so that importing the parameters does not import scipy.
electron_volt = 1.602176634e-19


def check_finite(name: str, value) -> None:
    """Raise ``ValueError`` naming ``name`` unless every element of ``value`` is finite.

    Parameters
    ----------
    name : str
        Parameter name for the message.
    value : float or array_like
        The value to check.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):  # a number: no numpy needed
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value!r}")
        return
    import numpy as np

    if not np.all(np.isfinite(np.asarray(value, dtype=float))):
        raise ValueError(f"{name} must be finite, got {value!r}")


def check_positive(name: str, value, unit: str = "") -> None:
    """Raise ``ValueError`` naming ``name`` unless ``value`` is finite and > 0 (every element).

    Parameters
    ----------
    name : str
        Parameter name for the message.
    value : float or array_like
        The value to check.
    unit : str
        Unit shown in the message.
    """
    check_finite(name, value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        positive = value > 0
    else:
        import numpy as np

        positive = bool(np.all(np.asarray(value, dtype=float) > 0))
    if not positive:
        raise ValueError(f"{name} must be > 0{(' ' + unit) if unit else ''}, got {value!r}")


@dataclass(frozen=True)
class PaperParameters:
    """Simulation parameters of the paper's Table 1 (Figures 4 and 8, Table 2).

    Parameters
    ----------
    modulus_pa : float
        Material stiffness M. [Pa]
    sigma_f_pa : float
        Final (largest) stress σf of the loading–unloading cycle. [Pa]
    u_v : float
        Voltage U across the composite. [V]
    s0_m : float
        Interparticle separation at zero stress s0. [m]
    phi0_j : float
        Barrier height φ0 (Table 1 prints 0.223 eV). [J]
    eps_r : float
        Relative permittivity of the polymer matrix. [-]
    k : float
        Unloading exponent. Not printed; k = 2 reproduces Table 2's capacitance column. [-]
    """

    modulus_pa: float = 4.73e6
    sigma_f_pa: float = 322e3
    u_v: float = 2.0
    s0_m: float = 4.418e-9
    phi0_j: float = 0.223 * electron_volt
    eps_r: float = 7.0
    k: float = 2.0

    def __post_init__(self) -> None:
        check_positive("s0_m", self.s0_m, "m")
        check_positive("sigma_f_pa", self.sigma_f_pa, "Pa")
        check_positive("modulus_pa", self.modulus_pa, "Pa")
        check_positive("u_v", self.u_v, "V")
        check_positive("phi0_j", self.phi0_j, "J")
        check_positive("eps_r", self.eps_r)
        check_finite("k", self.k)
        if not self.modulus_pa > self.sigma_f_pa:
            raise ValueError(f"modulus_pa must be > sigma_f_pa ({self.sigma_f_pa:g} Pa), got {self.modulus_pa:g}")
        if not self.k >= 1:
            raise ValueError(f"k must be >= 1, got {self.k!r}")

    def as_dict(self) -> dict:
        """Values keyed by name, plus the barrier height in eV for display."""
        d = asdict(self)
        d["phi0_ev"] = self.phi0_j / electron_volt
        return d


#: Table 1 of the paper, with k = 2.
PAPER = PaperParameters()
