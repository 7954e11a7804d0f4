"""What a user does with readings: hysteresis and repeatability errors, calibration."""
