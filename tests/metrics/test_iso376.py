"""ISO 376:2011 quantities (fsrlab.metrics.iso376) on constructed calibrations with known errors.

Reference: closed forms of the ISO 376 definitions applied to series built here so that each
quantity has a known value (e.g. series 2 = series 1 × (1 + 4e-4) gives b' = 0.04 % up to the
mean's 2e-4 relative shift); class limits from the ISO 376:2011 table.
"""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.errors import ParameterError
from fsrlab.metrics.iso376 import CLASS_LIMITS, CalibrationSeries, class_reached, iso376

F = np.linspace(1e3, 10e3, 10)  # ten forces 10 %..100 % of 10 kN
SENS = 2e-4  # reading per newton (e.g. mV/V per N)


def ideal(scale=1.0, zero=0.0):
    return zero + scale * SENS * F


def full_calibration(rep=4e-4, rot=(0.0, 6e-4, -6e-4), rev=1e-3, zero_drift=1e-4):
    s1 = CalibrationSeries(0, ideal(1 + rot[0]), zero_before=0.0, zero_after=0.0)
    s2 = CalibrationSeries(0, ideal((1 + rot[0]) * (1 + rep)), zero_before=0.0, zero_after=zero_drift * SENS * F[-1])
    s3 = CalibrationSeries(120, ideal(1 + rot[1]), ideal((1 + rot[1]) * (1 + rev)), 0.0, 0.0)
    s5 = CalibrationSeries(240, ideal(1 + rot[2]), ideal((1 + rot[2]) * (1 + rev)), 0.0, 0.0)
    return [s1, s2, s3, s5]


def test_known_values_and_class():
    r = iso376(F, full_calibration())
    # b' = 2|x2-x1|/(x1+x2) = 2·4e-4/(2+4e-4) → 0.039992 %
    np.testing.assert_allclose(r.b_prime, 100 * 2 * 4e-4 / (2 + 4e-4), rtol=1e-9)
    # b over rotations 0, +6e-4, -6e-4: range 1.2e-3 over mean 1 → 0.12 %
    np.testing.assert_allclose(r.b, 0.12, rtol=1e-9)
    np.testing.assert_allclose(r.v, 0.1, rtol=1e-9)
    x_n = SENS * F[-1] * (1 + (1 + 4e-4) + (1 + 6e-4) + (1 - 6e-4)) / 4  # mean deflection at the largest force
    assert r.f0 == pytest.approx(100 * 1e-4 * SENS * F[-1] / x_n, rel=1e-9)
    np.testing.assert_allclose(r.fc, 0.0, atol=1e-9)  # linear instrument: no interpolation error
    assert r.classes == {"b": "1", "b_prime": "0.5", "fc": "00", "f0": "00", "v": "0.5"}
    assert r.instrument_class == "1"  # worst of the required quantities
    assert "c" in r.missing


def test_nonlinear_instrument_interpolation_error():
    # Readings with a cubic term are interpolated exactly by degree 3 and not by degree 1.
    x = SENS * F * (1 + 0.01 * (F / F[-1]) ** 2)
    s = [CalibrationSeries(0, x), CalibrationSeries(0, x)]
    assert np.max(np.abs(iso376(F, s, interpolation_degree=3).fc)) < 1e-9
    assert np.max(np.abs(iso376(F, s, interpolation_degree=1).fc)) > 0.05


def test_missing_quantities_are_named():
    r = iso376(F, [CalibrationSeries(0, ideal())])
    assert r.b is None and r.b_prime is None and r.v is None and r.f0 is None
    assert "same mounting position" in r.missing["b_prime"]
    assert "rotations" in r.missing["b"]
    assert "decreasing" in r.missing["v"]
    assert "zero readings" in r.missing["f0"]
    assert r.instrument_class == "incomplete"


def test_creep_replaces_reversibility_for_increasing_only():
    s = full_calibration()
    s = [CalibrationSeries(x.rotation_deg, x.increasing, None, x.zero_before, x.zero_after) for x in s]
    r = iso376(F, s, creep_readings=(SENS * F[-1], SENS * F[-1] * (1 + 3e-4)))
    x_n = SENS * F[-1] * (1 + (1 + 4e-4) + (1 + 6e-4) + (1 - 6e-4)) / 4
    assert r.c == pytest.approx(100 * 3e-4 * SENS * F[-1] / x_n, rel=1e-9) and r.classes["c"] == "0.5"
    assert r.instrument_class == "1"


def test_class_table_edges():
    for cls, lim in CLASS_LIMITS.items():
        for name, value in lim.items():
            assert class_reached(name, value) == cls
    assert class_reached("b", 0.41) == "none"
    with pytest.raises(ParameterError, match="name: must be"):
        class_reached("q", 1.0)


def test_fsr_repeatability_far_beyond_class_2(paper):
    """The paper's Table 4 (capacitive readout, 200 g, five re-placements) treated as
    reproducibility: the FSR's spread is an order of magnitude beyond class 2's b = 0.40 %."""
    readings = np.array(paper["table4_repeatability_capacitive_kHz"]["200g"]["readings"][0])
    spread = 100 * (readings.max() - readings.min()) / readings.mean()
    assert class_reached("b", spread) == "none" and spread > 5 * CLASS_LIMITS["2"]["b"]


def test_validation():
    with pytest.raises(ValueError, match="forces_n"):
        iso376([2.0, 1.0], [CalibrationSeries(0, [1, 2])])
    with pytest.raises(ValueError, match="series\\[0\\].increasing"):
        iso376(F, [CalibrationSeries(0, [1, 2])])
    with pytest.raises(ValueError, match="interpolation_degree"):
        iso376(F, full_calibration(), interpolation_degree=4)


def test_csv_loader_and_cli(tmp_path, capsys):
    import json

    from fsrlab.cli import main
    from fsrlab.io.tables import load_iso376_csv

    lines = ["series,rotation_deg,force_n,reading,direction"]
    for label, s in zip("1235", full_calibration(), strict=True):
        lines.append(f"{label},{s.rotation_deg},0,{s.zero_before},1")
        lines += [f"{label},{s.rotation_deg},{float(f)!r},{float(x)!r},1" for f, x in zip(F, s.increasing, strict=True)]
        if s.decreasing is not None:
            lines += [f"{label},{s.rotation_deg},{float(f)!r},{float(x)!r},-1"
                      for f, x in zip(F, s.decreasing, strict=True)]
        lines.append(f"{label},{s.rotation_deg},0,{float(s.zero_after)!r},-1")
    p = tmp_path / "cal.csv"
    p.write_text("\n".join(lines) + "\n")
    forces, series = load_iso376_csv(p)
    ref = iso376(F, full_calibration())
    got = iso376(forces, series)
    np.testing.assert_allclose(got.b, ref.b, rtol=1e-12)
    assert got.classes == ref.classes
    with pytest.raises(SystemExit) as info:
        main(["iso376", str(p), "--json"])
    assert info.value.code == 0
    d = json.loads(capsys.readouterr().out)
    assert d["instrument_class"] == "1" and "c" in d["missing"]
    p.write_text("series,rotation_deg,force_n,reading\n1,0,1000,abc\n")
    with pytest.raises(SystemExit) as info:
        main(["iso376", str(p)])
    err = capsys.readouterr().err
    assert info.value.code == 2 and "row 1 (line 2), column 'reading'" in err and err.count("\n") == 1


def test_no_numpy_warning_on_valid_input_with_partial_decreasing_series():
    # Reference: the ISO 376 definition of v (mean over the series with a decreasing reading at
    # each force); a force with none has no v. Before, numpy printed "Mean of empty slice".
    import warnings

    s = full_calibration()
    dec = np.full(F.size, np.nan)
    dec[[3, 7]] = ideal(1 + 6e-4)[[3, 7]] * (1 + 1e-3)
    s[2] = CalibrationSeries(120, s[2].increasing, dec, 0.0, 0.0)
    s[3] = CalibrationSeries(240, s[3].increasing, None, 0.0, 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = iso376(F, s)
    assert np.isnan(r.v[[0, 1, 2, 4, 5, 6, 8, 9]]).all()
    np.testing.assert_allclose(r.v[[3, 7]], 0.1, rtol=1e-9)
    assert r.worst("v") == pytest.approx(0.1, rel=1e-9)
    assert r.notes == [] and "b_note" not in r.missing


def test_creep_readings_must_be_finite():
    for creep in ((float("nan"), 1.0), (1.0, float("inf")), (1e308, -1e308)):
        with pytest.raises(ValueError, match="creep_readings: must be two finite readings"):
            iso376(F, full_calibration(), creep_readings=creep)


def test_two_rotations_give_b_with_a_note():
    s = full_calibration()[:3]
    r = iso376(F, s)
    assert r.b is not None and r.notes == ["b from 2 mounting rotations (ISO 376 asks for 3)"]
    assert set(r.missing) == {"c"}
