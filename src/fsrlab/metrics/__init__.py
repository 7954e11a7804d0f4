"""Error metrics of readings: hysteresis (eq. 13), cycles and directions, repeatability (eq. 39), ISO 376, creep."""
