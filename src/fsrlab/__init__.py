"""fsrlab: force sensing with force-sensing resistors read through their piezocapacitance.

Built on A. Matute, L. Paredes-Madrid, G. Moreno, F. Cárdenas, C. A. Palacio, "A Novel and
Inexpensive Approach for Force Sensing Based on FSR Piezocapacitance Aimed at Hysteresis Error
Reduction", Journal of Sensors 2018, 6561901, doi:10.1155/2018/6561901.

All computation is in SI base units (Pa, m, V, A, Ω, F, s, Hz).

The public API is one flat namespace, imported lazily (PEP 562): ``import fsrlab`` loads no numpy, and
each name imports its module when first used::

    import fsrlab as fl
    cal = fl.calibrate(fl.load_run("bench.csv"), compensate=True)
    fl.save_calibration(cal, "bench-calibration.json")
    est = fl.apply(cal, fl.load_run("other.csv"))   # or cal.estimate(run); cal.estimator() steps one reading

The layers below it, each importing only from the ones under it, are described in ``docs/architecture.md``.
"""

from __future__ import annotations

import importlib

# Re-exported (redundant aliases: ``__all__`` below is computed, so a linter cannot read it).
from fsrlab.errors import FileFormatError as FileFormatError
from fsrlab.errors import FsrlabError as FsrlabError
from fsrlab.errors import ParameterError as ParameterError
from fsrlab.errors import ProvenanceError as ProvenanceError

#: The installed fsrlab's version (PEP 440), as `fsrlab --version` prints it.
__version__ = "0.1.0"

# Public name -> (module, attribute). The modules are imported on first use.
_LAZY = {
    # runs and files
    "Run": ("fsrlab.io.runformat", "Run"),
    "load_run": ("fsrlab.io.runformat", "load_run"),
    "write_run": ("fsrlab.io.runwriter", "write_run"),
    "RunWriter": ("fsrlab.io.runwriter", "RunWriter"),
    "load_calibration": ("fsrlab.calibration.document", "load_calibration"),
    "save_calibration": ("fsrlab.calibration.document", "save_calibration"),
    # the meter
    "SerialLink": ("fsrlab.acquisition.serial_link", "SerialLink"),
    "record": ("fsrlab.acquisition.recorder", "record"),
    # the virtual bench
    "VirtualDevice": ("fsrlab.virtual.device", "VirtualDevice"),
    "Twin": ("fsrlab.virtual.twin.twin", "Twin"),
    "twin_available": ("fsrlab.virtual.twin.process", "twin_available"),
    "synthetic_run": ("fsrlab.virtual.synthetic", "synthetic_run"),
    "VirtualFSR": ("fsrlab.physics.sensor", "VirtualFSR"),
    "paper_sensor": ("fsrlab.physics.paper_sensor", "paper_sensor"),
    "run_protocol": ("fsrlab.bench.protocols", "run_protocol"),
    # circuits
    "LM555Circuit": ("fsrlab.circuits.circuit", "LM555Circuit"),
    "OpAmpReadout": ("fsrlab.circuits.circuit", "OpAmpReadout"),
    "PAPER_CIRCUIT": ("fsrlab.circuits.circuit", "PAPER_CIRCUIT"),
    "PAPER_OPAMP": ("fsrlab.circuits.circuit", "PAPER_OPAMP"),
    "PAPER": ("fsrlab.physics.params", "PAPER"),
    # metrics
    "hysteresis_error": ("fsrlab.metrics.hysteresis", "hysteresis_error"),
    "hysteresis_of_run": ("fsrlab.bench.measurement", "hysteresis_of_run"),
    "repeatability": ("fsrlab.metrics.repeatability", "repeatability"),
    "iso376": ("fsrlab.metrics.iso376", "iso376"),
    "creep_of_run": ("fsrlab.metrics.creep", "creep_of_run"),
    # calibration
    "Calibration": ("fsrlab.calibration.result", "Calibration"),
    "calibrate": ("fsrlab.calibration.runs", "calibrate_runs"),
    "apply": ("fsrlab.calibration.apply", "apply_calibration"),
    "check_readout": ("fsrlab.calibration.apply", "check_readout"),
    "agreement": ("fsrlab.metrics.agreement", "agreement"),
    # reports
    "measure_run": ("fsrlab.bench.measurement", "measure_run"),
    "report": ("fsrlab.reports.run_report", "write_run_report"),
    "paper_report": ("fsrlab.reports.paper", "write_report"),
}

__all__ = sorted([*_LAZY, "FsrlabError", "ParameterError", "FileFormatError", "ProvenanceError", "__version__"])


def __getattr__(name: str):
    """Import a public name's module on first use (PEP 562)."""
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'fsrlab' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
