"""Calibration: model families, alignment, compensation, uncertainty, provenance, the fit, the estimator, apply.

:func:`fsrlab.calibration.fit.calibrate_run` turns a recorded run into a
:class:`~fsrlab.calibration.result.Calibration`; :func:`fsrlab.calibration.apply.apply_calibration` gives
another run's estimate; :func:`fsrlab.calibration.estimator.live_estimator` steps it one reading at a time.
"""
