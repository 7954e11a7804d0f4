"""The bench: protocols (spring cycles, dead weights, creep holds), the known-weight procedure, the demo's chain."""
