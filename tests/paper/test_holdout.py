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
    # Spreads fitted to Table 5's printed mean RE2 (5 %, 6 %) meet them; Table 4's (printed 1 %, 1 %) come out
    # 1.8 / 2.9 %.
    a, printed, labels = re2_design(paper_sensors())
    c = cross_readout_spreads(a, printed, labels, fit_on="table5")
    assert c["rows"]["table5 200g"]["predicted"] == pytest.approx(5.0, rel=1e-3)
    assert c["rows"]["table5 400g"]["predicted"] == pytest.approx(6.0, rel=1e-3)
    assert c["rows"]["table4 200g"]["predicted"] == pytest.approx(1.80, abs=0.01)
    assert c["rows"]["table4 400g"]["predicted"] == pytest.approx(2.92, abs=0.01)
    with pytest.raises(ValueError, match="fit_on"):
        cross_readout_spreads(a, printed, labels, fit_on="table3")


class _PowerLawFSR:
    """A sensor whose resistance goes as V^-k at any stress, its capacitance fixed: not the preset."""

    def __init__(self, k):
        self.k = k

    def respond(self, stress_pa, voltage_v):
        from types import SimpleNamespace

        n = np.size(stress_pa)
        return SimpleNamespace(r_fsr_ohm=np.full(n, 1e6 * voltage_v ** -self.k), c_fsr_farad=np.full(n, 1e-9))


def test_supply_sensitivities_of_a_power_law_sensor():
    # Closed form (eq. 38): V0 ∝ Vcc / R_FSR(Vcc), so d ln V0/d ln Vcc = 1 + k for R ∝ V^-k, exactly
    # (central difference of a power law); the 555's thresholds scale with Vcc, so its frequency moves
    # only through R_FSR: k = 0 leaves it unmoved.
    from fsrlab.paper.holdout import supply_sensitivities

    out = supply_sensitivities([_PowerLawFSR(0.0), _PowerLawFSR(0.5)])
    for label in ("200g", "400g"):
        assert out[label]["voltage"] == pytest.approx([1.0, 1.5], abs=1e-9)
        assert out[label]["frequency"][0] == pytest.approx(0.0, abs=1e-9)
        assert out[label]["frequency"][1] > 0  # less resistance at a higher voltage: a faster 555
