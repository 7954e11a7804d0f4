"""Fit the "paper sensor" preset (fsrlab.physics.paper_sensor) and print its parameters.

The four sensors are fitted jointly to their printed numbers (fsrlab.analysis.experiment.preset_targets:
Figure 19a/b ranges, Table 4 mean readings, Table 3 row) by fsrlab.analysis.experiment.fit_paper_preset;
then the two placement spreads shared by the four are fitted to the mean RE2 of Tables 4 and 5
(fsrlab.analysis.experiment.fit_placement_spread). The printed literal replaces
PAPER_SENSOR_PARAMETERS in src/fsrlab/physics/paper_sensor.py. Run: .venv/bin/python scripts/fit_paper_sensor.py
"""

from __future__ import annotations

from fsrlab.analysis.experiment import FIT_PARAMETERS, SHARED_FIT_PARAMETERS, fit_paper_preset, fit_placement_spread


def main() -> None:
    """Fit and print."""
    fitted, gots, wants = fit_paper_preset()
    for i, (got, want) in enumerate(zip(gots, wants), start=1):
        print(f"# sensor {i}: " + ", ".join(f"{k} {got[k]:.4g} (printed {want[k]:.4g})" for k in want))
    sd_s, sd_c, re2 = fit_placement_spread(fitted)
    print("# placement spread fit: " + "; ".join(f"{k}: {v['predicted_re2']:.2f} (printed {v['printed_re2']:g})"
                                             for k, v in re2.items()))
    print("PAPER_SENSOR_PARAMETERS: tuple = (")
    for s in fitted:
        vals = {k: getattr(s, k) for k in (*SHARED_FIT_PARAMETERS, *FIT_PARAMETERS)}
        vals.update(placement_stress_sd=sd_s, placement_contact_sd=sd_c)
        print("    {" + ", ".join(f'"{k}": {v:.6g}' for k, v in vals.items()) + "},")
    print(")")


if __name__ == "__main__":
    main()
