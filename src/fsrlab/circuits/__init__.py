"""Readout circuits of the paper's sections 5–6: the LM555 astable and the op-amp.

* :mod:`~fsrlab.circuits.circuit`: the circuits as validated values (``LM555Circuit``,
  ``OpAmpReadout``), with the one parameter check and thin methods that call the models below.
* :mod:`~fsrlab.circuits.phases`: the Thevenin equivalents of the astable's charge and discharge
  phases and their durations per R·C, derived once for every model of the astable.
* :mod:`~fsrlab.circuits.lm555`: closed forms (τH, τL, f, DC), oscillation condition, sensitivities.
* :mod:`~fsrlab.circuits.decode`: (f, DC) → (R_FSR, C_FSR) with the timer-quantization uncertainty.
* :mod:`~fsrlab.circuits.design`: R, C_off and the variant for a sensor and a frequency band.
* :mod:`~fsrlab.circuits.transient`: exact event-driven simulation (time-varying parts).
* :mod:`~fsrlab.circuits.spice`: ngspice netlist and runner, the independent check.
* :mod:`~fsrlab.circuits.opamp`: the resistive readouts (eq. 38, divider).
* :mod:`~fsrlab.circuits.plotting`: the results' ``.plot()`` (matplotlib imported only when drawing).

The model functions are pure and vectorised and take the circuit's parts as keywords, so
``fn(..., **circuit.kwargs())`` evaluates them for an ``LM555Circuit``.
"""
