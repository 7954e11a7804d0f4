"""
Table 2: hysteresis error of R_A and C_A
========================================

The paper's Table 2 gives the hysteresis error (eq. 13) of the resistance and the capacitance per area
over one cycle 0 → 322 kPa → 0 at u = 3, 2 and 1 V, for the parameters of its Table 1.
:func:`fsrlab.paper.table2.voltage_sweep` computes both over 1–4.2 V. The capacitance column equals the
printed 1.73 % because the unloading exponent k, which the paper does not print, is chosen (k = 2) to
give it: that agreement is a choice, not a test. The resistance column with the printed φ0 = 0.223 eV
differs from the printed values (see the errata, P1–P2).
"""

import json
from importlib.resources import files

import matplotlib.pyplot as plt

from fsrlab.paper.table2 import voltage_sweep

sweep = voltage_sweep()
printed = json.loads(files("fsrlab").joinpath("data/paper.json").read_text())["table2_hysteresis_error_percent"]

fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(sweep.table.u_v, sweep.table.resistance_percent, label="R_A (fsrlab)")
ax.plot(sweep.table.u_v, sweep.table.capacitance_percent, label="C_A (fsrlab, k = 2 chosen)")
ax.plot(printed["u_V"], printed["resistance_per_area"], "o", color="C0", label="R_A, Table 2")
ax.plot(printed["u_V"], printed["capacitance_per_area"], "s", color="C1", label="C_A, Table 2")
ax.set(xlabel="u [V]", ylabel="hysteresis error [%]", title="Table 2 and its voltage sweep")
ax.legend()
plt.show()
