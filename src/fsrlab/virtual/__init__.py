"""The virtual bench: the meter's model, the virtual device on a pty, the digital twin, synthetic and hand-loaded
runs."""
