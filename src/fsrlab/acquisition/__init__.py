"""Getting readings: the serial protocol, the link, the recorder and the virtual device."""
