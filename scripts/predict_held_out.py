"""Prediction tests of the paper-sensor preset (fsrlab.paper.holdout); results recorded in docs/experiment.md.

1. Each sensor refitted to Table 3 and Figure 19's ranges only (Table 4's readings left out), then
   Tables 4 and 5's mean readings predicted (closed forms).
2. The placement spreads fitted to one table's mean RE2, the other table's predicted.
3. The supply-voltage sensitivity of both readouts (the cause §6.2 names for Table 5's spread).

Run: .venv/bin/python scripts/predict_held_out.py (a few seconds).
"""

from __future__ import annotations

import numpy as np


def main() -> None:
    """Run the three tests and print their results as Markdown."""
    from fsrlab.paper.holdout import cross_readout_spreads, held_out_fit, supply_sensitivities
    from fsrlab.paper.preset_fit import re2_design_per_sensor
    from fsrlab.physics.paper_sensor import paper_sensors

    for start in ("neutral", "stored"):
        h = held_out_fit(start=start)
        print(f"## held-out fit, start {start}")
        for i, f in enumerate(h.fits, start=1):
            print(f"sensor {i}: HE_TM {f['he_tm']:.2f} HE_PM {f['he_pm']:.2f} f0 {f['f0'] / 1e3:.2f} kHz "
                  f"f10 {f['f10'] / 1e3:.2f} kHz V0(0) {f['v0']:.3f} V V0(10) {f['v10']:.3f} V")
        print("| printed number | printed | held-out fit | error | stored preset |")
        print("|---|---|---|---|---|")
        for r in h.rows:
            print(f"| {r['id']} | {r['printed']:.4g} | {r['held_out']:.4g} | {100 * r['relative_error']:+.0f} % | "
                  f"{r['preset']:.4g} |")
    sensors = paper_sensors()
    a, printed, labels, per = re2_design_per_sensor(sensors)
    for fit_on in ("table5", "table4"):
        c = cross_readout_spreads(a, printed, labels, fit_on=fit_on)
        print(f"## spreads fitted on {fit_on}: " + ", ".join(f"{k} {v:.4f}" for k, v in c["spreads"].items()))
        for lab, r in c["rows"].items():
            print(f"{lab}: printed {r['printed']:g}, {'fitted' if r['used'] else 'predicted'} {r['predicted']:.2f}")
    sd = np.array([getattr(sensors[0], n) for n in ("placement_stress_sd", "placement_contact_sd",
                                                     "placement_area_sd")])
    print("## expected RE2 per sensor (stored spreads): "
          + "; ".join(f"{lab}: " + ", ".join(f"{v:.2f}" for v in np.sqrt(per[j] @ sd**2))
                      for j, lab in enumerate(labels)))
    s = supply_sensitivities(sensors)
    for load, d in s.items():
        print(f"## d ln/d ln Vcc at {load}: frequency " + ", ".join(f"{v:.3f}" for v in d["frequency"])
              + "; voltage " + ", ".join(f"{v:.3f}" for v in d["voltage"]))
        # a supply spread alone, set by Table 5's printed mean RE2 at this load, predicts Table 4's
        rms_v = np.sqrt(np.mean(np.square(d["voltage"])))
        rms_f = np.sqrt(np.mean(np.square(d["frequency"])))
        j5, j4 = labels.index(f"table5 {load}"), labels.index(f"table4 {load}")
        sd_v = printed[j5] / 100 / rms_v
        print(f"   supply spread alone from Table 5 ({printed[j5]:g} %): sd_Vcc {100 * sd_v:.2f} %, "
              f"Table 4 mean RE2 predicted {100 * rms_f * sd_v:.2f} % (printed {printed[j4]:g} %)")


if __name__ == "__main__":
    main()
