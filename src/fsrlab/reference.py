"""The numbers the paper prints, as transcribed in the package data file ``fsrlab/data/paper.json``.

One file holds the transcription (provenance in ``fsrlab/data/PROVENANCE.md``); the reproduction
report and the tests read it through :func:`paper_values`. The model's parameters (Table 1 in SI
units) live in :mod:`fsrlab.physics.params`; this file is what results are compared against.

References
----------
Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901.
"""

from __future__ import annotations

import copy
import json
from functools import cache
from importlib.resources import files

__all__ = ["paper_values"]


@cache
def _load() -> dict:
    text = files("fsrlab").joinpath("data", "paper.json").read_text(encoding="utf-8")
    return json.loads(text)


def paper_values() -> dict:
    """Every number the paper prints, keyed as in ``fsrlab/data/paper.json``.

    Returns
    -------
    dict
        A fresh copy (the file is read once per process), so callers may modify it. Keys include
        ``table1_simulation_parameters``, ``table2_hysteresis_error_percent``,
        ``table3_hysteresis_error_percent``, ``table4_repeatability_capacitive_kHz``,
        ``table5_repeatability_traditional_V``, ``figure17_fit_r2``, ``experiment``,
        ``section5_tau_ratio_claims`` and ``figure4_axis_ranges``. Units are in the key names.
    """
    return copy.deepcopy(_load())
