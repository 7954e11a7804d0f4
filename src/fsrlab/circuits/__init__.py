"""Readout circuits of the paper's sections 5–6: the LM555 astable and the op-amp."""
