"""Helper of the calibration tests: what ``measure``/``live`` step equals what ``fsrlab apply`` writes."""

from __future__ import annotations

import numpy as np


def assert_steps_as_batch(cal, run, reference: str = "force_n") -> None:
    """``cal.estimator()`` fed ``run``'s readings one at a time (with their ``time_s``) gives the
    estimates and uncertainties ``apply_calibration(cal, run)`` writes, to 1e-9 (NaN where none)."""
    from fsrlab.calibration.apply import apply_calibration

    batch = apply_calibration(cal, run)
    est = cal.estimator()
    # C_FSR decoded when asked
    stepped = [est.step(x, t) for x, t in zip(cal.readout(batch), batch["time_s"], strict=True)]
    e = np.array([np.nan if s[0] is None else s[0] for s in stepped])
    u = np.array([np.nan if s[1] is None else s[1] for s in stepped])
    assert np.allclose(e, batch[f"{reference}_estimate"], rtol=0, atol=1e-9, equal_nan=True)
    assert np.allclose(u, batch[f"{reference}_uncertainty"], rtol=0, atol=1e-9, equal_nan=True)
