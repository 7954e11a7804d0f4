"""Fit the "paper sensor" preset (fsrlab.physics.paper_sensor) and print its parameters.

The four sensors are fitted jointly to their printed numbers (fsrlab.analysis.experiment.preset_targets:
Figure 19a/b ranges, Table 4 mean readings, Table 3 row) by fsrlab.analysis.experiment.fit_paper_preset;
with them, the three placement spreads shared by the four are fitted to the mean RE2 of Tables 4 and 5
(linearised, fsrlab.analysis.experiment.re2_design). The printed literal replaces
PAPER_SENSOR_PARAMETERS in src/fsrlab/physics/paper_sensor.py. Run: .venv/bin/python scripts/fit_paper_sensor.py
(about 10 minutes on one core).
"""

from __future__ import annotations

import numpy as np

from fsrlab.analysis.experiment import (FIT_PARAMETERS, SHARED_FIT_PARAMETERS, SPREADS, fit_paper_preset,
                                        fit_placement_spread, re2_design)


def main(max_nfev: int = 300, repeatability: bool = True) -> None:
    """Fit and print.

    Parameters
    ----------
    max_nfev : int
        Largest number of residual evaluations of the joint fit.
    repeatability : bool
        Fit the placement spreads jointly (else afterwards, on the fitted sensors).
    """
    fitted, gots, wants = fit_paper_preset(max_nfev=max_nfev, repeatability=repeatability)
    for i, (got, want) in enumerate(zip(gots, wants), start=1):
        print(f"# sensor {i}: " + ", ".join(f"{k} {got[k]:.4g} (printed {want[k]:.4g})" for k in want))
    if repeatability:
        spreads = {n: getattr(fitted[0], n) for n in SPREADS}
    else:
        spreads, _ = fit_placement_spread(fitted)
    a, printed, labels = re2_design(fitted)
    pred = np.sqrt(a @ np.array([spreads[n] for n in SPREADS]) ** 2)
    print("# mean RE2 (linearised): " + "; ".join(f"{k}: {q:.2f} (printed {r:g})"
                                               for k, q, r in zip(labels, pred, printed)))
    print("PAPER_SENSOR_PARAMETERS: tuple = (")
    for s in fitted:
        vals = {k: getattr(s, k) for k in (*SHARED_FIT_PARAMETERS, *FIT_PARAMETERS)}
        vals.update(spreads)
        print("    {" + ", ".join(f'"{k}": {v:.6g}' for k, v in vals.items()) + "},")
    print(")")


if __name__ == "__main__":
    main()
