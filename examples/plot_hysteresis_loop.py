"""
The hysteresis loop of a virtual FSR
====================================

A virtual FlexiForce-like sensor (:class:`fsrlab.VirtualFSR`, built on the paper's separation,
tunnelling and capacitance equations) is loaded from 0 to 50 kPa and back. Its R_FSR and C_FSR set
the frequency of the paper's LM555 (:data:`fsrlab.PAPER_CIRCUIT`: R = 10 kΩ with D1), and the
hysteresis error of that frequency is eq. (13) (:func:`fsrlab.hysteresis_error`).
"""

import matplotlib.pyplot as plt
import numpy as np

import fsrlab as fl

up = np.linspace(0.0, 50e3, 101)                    # loading [Pa]
stress = np.concatenate([up, up[-2::-1]])           # 0 -> 50 kPa -> 0
response = fl.VirtualFSR().respond(stress)
frequency = fl.PAPER_CIRCUIT.astable(response.r_fsr_ohm, response.c_fsr_farad).frequency_hz

n = up.size
he = fl.hysteresis_error(stress[:n], frequency[:n], stress[n - 1:][::-1], frequency[n - 1:][::-1])
print(f"HE of the frequency: {he.percent:.2f} % at {he.stress_at_max_pa / 1e3:.1f} kPa")

fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(stress[:n] / 1e3, frequency[:n] / 1e3, label="loading")
ax.plot(stress[n - 1:] / 1e3, frequency[n - 1:] / 1e3, label="unloading")
ax.set(xlabel="stress [kPa]", ylabel="555 frequency [kHz]",
       title=f"Virtual FSR through the paper's 555: HE {he.percent:.1f} % (eq. 13)")
ax.legend()
plt.show()
