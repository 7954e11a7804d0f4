"""Calibration: one engine, every choice scored on held-out recordings, and one result type.

:func:`fsrlab.calibration.runs.calibrate_runs` (``fsrlab.calibrate``) turns recorded runs into a
:class:`~fsrlab.calibration.result.Calibration`, whose ``estimate(run)`` and ``estimator()`` give a run's
estimate or one reading's; :func:`fsrlab.calibration.apply.apply_calibration` checks the run's provenance
first. docs/calibration.md.
"""
