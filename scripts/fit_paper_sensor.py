"""Fit the "paper sensor" preset (fsrlab.physics.paper_sensor) and print its parameters.

Each sensor's own parameters are fitted to its printed numbers (fsrlab.paper.preset_fit.preset_targets:
Figure 19a/b ranges, Table 4 mean readings, Table 3 row) by fsrlab.paper.preset_fit.fit_paper_sensor,
the shared ones held; then the three placement spreads shared by the four are fitted to the mean RE2 of
Tables 4 and 5 (linearised, fsrlab.paper.preset_fit.fit_placement_spread). The printed literal replaces
PAPER_SENSOR_PARAMETERS in src/fsrlab/physics/paper_sensor.py. Run: .venv/bin/python scripts/fit_paper_sensor.py
(about a minute). ``--joint`` fits the shared parameters and the spreads too
(fsrlab.paper.preset_fit.fit_paper_preset; slow: tens of minutes).
"""

from __future__ import annotations

import numpy as np

from fsrlab.paper.preset_fit import (
    FIT_PARAMETERS,
    SHARED_FIT_PARAMETERS,
    SPREADS,
    fit_paper_preset,
    fit_placement_spread,
    re2_design,
)


def main(joint: bool = False, max_nfev: int = 300) -> None:
    """Fit and print.

    Parameters
    ----------
    joint : bool
        Fit the four sensors jointly with the shared parameters and the spreads (slow).
    max_nfev : int
        Largest number of residual evaluations of the joint fit.
    """
    from fsrlab.paper.preset_fit import fit_paper_sensor, quick_response

    if joint:
        fitted, gots, wants = fit_paper_preset(max_nfev=max_nfev, repeatability=True)
        spreads = {n: getattr(fitted[0], n) for n in SPREADS}
    else:
        fitted, gots, wants = [], [], []
        for i in range(1, 5):
            best, got, want = fit_paper_sensor(i)
            fitted.append(best), gots.append(got), wants.append(want)
        spreads, _ = fit_placement_spread(fitted)
        fitted = [s.replace(**spreads) for s in fitted]
        gots = [quick_response(s) for s in fitted]
    for i, (got, want) in enumerate(zip(gots, wants, strict=True), start=1):
        print(f"# sensor {i}: " + ", ".join(f"{k} {got[k]:.4g} (printed {want[k]:.4g})" for k in want))
    a, printed, labels = re2_design(fitted)
    pred = np.sqrt(a @ np.array([spreads[n] for n in SPREADS]) ** 2)
    print("# mean RE2 (linearised): " + "; ".join(f"{k}: {q:.2f} (printed {r:g})"
                                               for k, q, r in zip(labels, pred, printed, strict=True)))
    print("PAPER_SENSOR_PARAMETERS: tuple = (")
    for s in fitted:
        vals = {k: getattr(s, k) for k in (*SHARED_FIT_PARAMETERS, *FIT_PARAMETERS, *SPREADS)}
        print("    {" + ", ".join(f'"{k}": {v!r}' for k, v in vals.items()) + "},")
    print(")")


if __name__ == "__main__":
    import sys

    main(joint="--joint" in sys.argv[1:])
