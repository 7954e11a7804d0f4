"""Prediction tests of the preset (fsrlab.paper.holdout).

References: the printed mean readings of Tables 4 and 5 and mean RE2 (fsrlab/data/paper.json); the
held-out results recorded in docs/experiment.md ("A prediction test"), produced by
`python scripts/predict_held_out.py`; the closed form d ln V0/d ln Vcc = 1 − d ln R_FSR/d ln V (eq. 38).
"""

import numpy as np
import pytest

from fsrlab.paper.holdout import cross_readout_spreads, held_out_fit
from fsrlab.paper.preset_fit import re2_design
from fsrlab.physics.paper_sensor import paper_sensors


@pytest.fixture(scope="module")
def held():
    return held_out_fit()


def test_held_out_fit_meets_its_own_targets(held, paper):
    # Table 3's rows are still fitted without Table 4 (residual in units of 2 pp, six parameters, six residuals).
    t3 = paper["table3_hysteresis_error_percent"]
    assert [f["he_tm"] for f in held.fits] == pytest.approx(t3["traditional"], abs=0.05)
    assert [f["he_pm"] for f in held.fits] == pytest.approx(t3["proposed"], abs=0.05)


def test_held_out_predictions_as_recorded(held):
    # docs/experiment.md records these relative errors (rounded to 1 %); the 200 g frequencies are predicted
    # 9-36 % low and alike for all four sensors, Table 5 ≈ 2.4-4.4x the printed voltages.
    err = {r["id"]: r["relative_error"] for r in held.rows}
    recorded = {"table4.200g.sensor1.mean_reading": -0.36, "table4.200g.sensor2.mean_reading": -0.23,
                "table4.200g.sensor3.mean_reading": -0.34, "table4.200g.sensor4.mean_reading": -0.09,
                "table4.400g.sensor1.mean_reading": -0.19, "table5.200g.sensor2.mean_reading": 2.66}
    for k, v in recorded.items():
        assert err[k] == pytest.approx(v, abs=0.01), k
    f200 = [r["held_out"] for r in held.rows if r["id"].startswith("table4.200g")]
    assert np.ptp(f200) / np.mean(f200) < 0.01  # no sensor-to-sensor pattern predicted


def test_cross_readout_prediction():
    # Spreads fitted to Table 5's printed mean RE2 (5 %, 6 %) meet them; Table 4's (printed 1 %, 1 %) come out 1.8 / 2.9 %.
    a, printed, labels = re2_design(paper_sensors())
    c = cross_readout_spreads(a, printed, labels, fit_on="table5")
    assert c["rows"]["table5 200g"]["predicted"] == pytest.approx(5.0, rel=1e-3)
    assert c["rows"]["table5 400g"]["predicted"] == pytest.approx(6.0, rel=1e-3)
    assert c["rows"]["table4 200g"]["predicted"] == pytest.approx(1.80, abs=0.01)
    assert c["rows"]["table4 400g"]["predicted"] == pytest.approx(2.92, abs=0.01)
    with pytest.raises(ValueError, match="fit_on"):
        cross_readout_spreads(a, printed, labels, fit_on="table3")
