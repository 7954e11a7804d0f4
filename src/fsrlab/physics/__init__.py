"""Sensor physics of the paper's sections 2–4: separation, tunnelling, capacitance."""
