"""
Designing the 555 for a sensor
==============================

:func:`fsrlab.circuits.design.design` proposes R, C_off and the variant (with or without D1) that keep a
sensor's whole R_FSR/C_FSR range inside a wanted frequency band, with the frequency reading C_FSR as
much as it can. Here: R_FSR from 100 kΩ to 2 MΩ, C_FSR from 0.5 to 1.5 nF, a band of 1 to 20 kHz
(the example of ``fsrlab design --help``). The figure shows the proposal's frequency over the range.
"""

import matplotlib.pyplot as plt
import numpy as np

import fsrlab as fl
from fsrlab.circuits.design import design

proposal = design((100e3, 2e6), (0.5e-9, 1.5e-9), (1e3, 20e3))
circuit = fl.LM555Circuit(r_ohm=proposal.r_ohm, c_off_farad=proposal.c_off_farad, diode=proposal.diode)
print(f"R = {proposal.r_ohm:.3g} Ω, C_off = {proposal.c_off_farad:.3g} F, D1: {proposal.diode}; "
      f"{proposal.frequency_range_hz[0]:.0f} … {proposal.frequency_range_hz[1]:.0f} Hz")

r_fsr = np.geomspace(100e3, 2e6, 60)
fig, ax = plt.subplots(figsize=(6, 4))
for c_fsr in (0.5e-9, 1.0e-9, 1.5e-9):
    f = circuit.astable(r_fsr, np.full_like(r_fsr, c_fsr)).frequency_hz
    ax.semilogx(r_fsr, f / 1e3, label=f"C_FSR = {c_fsr * 1e9:.1f} nF")
ax.axhspan(1, 20, color="0.9", zorder=0, label="wanted band")
ax.set(xlabel="R_FSR [Ω]", ylabel="frequency [kHz]",
       title=f"Proposal: R = {proposal.r_ohm / 1e3:.2g} kΩ, C_off = {proposal.c_off_farad * 1e9:.2g} nF, "
             f"{'with' if proposal.diode else 'no'} D1")
ax.legend()
plt.show()
