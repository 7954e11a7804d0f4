"""A fuzzer of the Python API: every public function and class called with wrong arguments.

For each public callable of the library's modules (and every name of ``fsrlab.__all__``, and the methods of
:data:`METHODS`) and each of its parameters, the call is made with that one argument wrong and every other one
valid (:data:`OVERRIDES` for that callable, else :data:`VALID` by the parameter's name, or left at its default),
in a directory holding a copy of ``examples/``. Wrong means a wrong type (a ``str`` where a number, an array, a
run or a calibration is expected; a ``dict``; ``None`` where the parameter is required), a bad path (a missing
file, a directory, an empty name) and an out-of-range number (negative, zero, nan, ±inf, ``'10%'``); the
modules of :data:`STRICT` also get arrays where one number is expected and must let out no RuntimeWarning.
What is not fuzzed says why (:data:`EXCLUDED_MODULES`, :data:`EXCLUDED`, :data:`NOT_FUZZED`); a case known to
fail names the module that owns its fix (:data:`XFAIL`, strict).

Accepted outcomes (the contract of ``fsrlab/errors.py`` and docs/architecture.md "Validate in the library"):

- a :class:`fsrlab.errors.FsrlabError` whose ``.parameter`` is the parameter passed wrong, or whose message
  names it;
- a ``TypeError`` whose message names the parameter;
- a normal return (a value the function legitimately accepts, such as nan propagating through a vectorised
  model).

Anything else fails: AttributeError, KeyError, IndexError, ZeroDivisionError, numpy and scipy errors, a bare
``ValueError``, an ``OSError``, an error naming another parameter or none, a call taking over
:data:`CALL_SECONDS`, and a call that changes or removes a file that was there (the inputs' SHA-256 before and
after: a wrong argument never replaces an input, its sidecar or an existing output).

Reference: the property above (an error's parameter is the argument that was wrong), checked on fixed,
deterministic inputs; no randomness. One test per (callable, parameter): its id reads
``module.name-parameter`` and a failure lists every bad value with the exception it gave. A test is skipped,
saying so, when no valid call is known (no value for a required parameter, or the valid call itself fails).

Run on its own: ``pytest tests/test_api_fuzz.py -q``.
"""

from __future__ import annotations

import enum
import hashlib
import importlib
import inspect
import math
import pkgutil
import shutil
import signal
import types
import warnings
from collections.abc import Callable
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import fsrlab
from fsrlab.errors import FsrlabError

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
CALL_SECONDS = 10.0
"""A call that takes longer is a failure (a loop that does not end on a bad value)."""
STRICT = ("fsrlab.physics.", "fsrlab.circuits.", "fsrlab.units.")
"""Modules held to more: a number parameter is also given an empty array and an array of two where one value may be
expected (:func:`bad_values`), and a call must let out no RuntimeWarning (numpy's overflow, invalid value): an
accepted value gives its result or its error quietly. Other layers join as they are made to."""

# ------------------------------------------------------------------------------------------------
# What is fuzzed and what is not
# ------------------------------------------------------------------------------------------------

PACKAGES = ["physics", "circuits", "metrics", "io", "virtual", "calibration", "bench", "acquisition"]
MODULES_ALSO = ["fsrlab.units"]

EXCLUDED_MODULES = {
    "fsrlab.calibration.scoring": "calibrate()'s held-out scoring of prepared recordings (covered through calibrate)",
    "fsrlab.acquisition.serial_link": "opens serial ports",
    "fsrlab.acquisition.ports": "lists and probes the host's serial ports",
    "fsrlab.acquisition.loadcell_reading": "reads a load cell through a serial link",
    "fsrlab.virtual.twin.build": "compiles the simavr harness",
    "fsrlab.virtual.twin.process": "starts the simavr twin process",
    "fsrlab.virtual.twin.twin": "starts the simavr twin process",
    "fsrlab.virtual.twin.edges": "the twin's edge feed, driven by a running twin",
    "fsrlab.bench.demo": "runs the whole demo chain (minutes)",
    "fsrlab.bench.doctor": "probes tools and serial ports",
    "fsrlab.bench.channels": "drives a meter (virtual or twin) for seconds per call",
    "fsrlab.circuits.plotting": "draws figures (matplotlib), no computation",
}
EXCLUDED = {
    "fsrlab.acquisition.recorder.record": "records from a serial link",
    "fsrlab.acquisition.stream.WindowStream": "reads windows from a serial link",
    "fsrlab.acquisition.stream.configure": "configures the meter on a serial link",
    "fsrlab.acquisition.firmware.flash": "runs avrdude on a serial port",
    "fsrlab.circuits.circuit.LM555Circuit.with_control": "its parts are **parts (LM555Circuit's own, fuzzed there)",
    "fsrlab.calibration.result.Calibration": "built by calibrate() from a fitted model (covered through calibrate)",
    "fsrlab.calibration.selection.Selection": "calibrate()'s record of its choices, built by it",
    "fsrlab.calibration.selection.calibrate_recordings": "calibrate()'s engine on prepared recordings",
    "fsrlab.calibration.monotone.bounded_solve": "a solver step on a Gram matrix calibrate() builds",
    "fsrlab.calibration.monotone.curve_system": "a solver step on a template calibrate() builds",
    "fsrlab.calibration.curves.static_system": "a solver step on arrays calibrate() builds",
    "fsrlab.calibration.model.clip_hysteresis": "a step of the fitted model on its own features",
    "fsrlab.calibration.uncertainty.LevelUncertainty": "a table built by calibrate()",
    "fsrlab.calibration.apply.readout_differences": "a step of check_readout on RecordedWith values",
    "fsrlab.calibration.provenance.mismatches": "a step of check_readout on RecordedWith values",
    "fsrlab.reports.run_report.write_run_report": "renders a report (reports/ is not fuzzed here)",
    "fsrlab.reports.paper.write_report": "runs the §6 experiment and renders its report (minutes)",
    "fsrlab.circuits.spice.run_ngspice": "runs ngspice (an external simulator, seconds per call)",
    "fsrlab.circuits.spice.simulate_spice": "runs ngspice",
    "fsrlab.circuits.spice.simulate_spice_many": "runs ngspice",
    "fsrlab.circuits.spice.start_spice_many": "starts ngspice processes",
    "fsrlab.circuits.spice.SpiceBatch": "a batch of ngspice processes",
    "fsrlab.circuits.paper_ratio.simulate_tau_ratios": "a long transient simulation per ratio",
    "fsrlab.circuits.paper_ratio.start_tau_ratios": "starts ngspice processes",
    "fsrlab.circuits.paper_ratio.TauRatioRuns": "a batch of ngspice processes",
    "fsrlab.bench.protocols.run_protocol": "runs a bench protocol on a device for seconds",
    "fsrlab.bench.protocols.open_bench": "opens a device (virtual, twin or serial)",
    "fsrlab.bench.protocols.twin_status": "probes the simavr twin",
    "fsrlab.bench.weights.WeightsProcedure": "an interactive procedure driven by a device",
    "fsrlab.io.outputs.OutputError": "an exception class",
}
RECORD_SUFFIXES = ("Result", "Error", "Stats", "Check", "Finding", "Ratios", "Table", "Minimum")
"""Classes named so are results or exceptions the library builds, not inputs a user gives."""
RECORDS = {
    "Hold", "LogDrift", "FirstOrder", "HoldCreep", "RunCreep", "Cycle", "RunHysteresis", "CycleErrors",
    "CalibrationSeries", "PrintedRowCheck", "ForceRepeatability", "GroupRepeatability", "LoadMean",
    "GroupedRepeatability", "Table", "Imported", "BadRow", "Sensitivity", "Thevenin", "FrequencyDecomposition",
    "SeparationHistory", "SensorResponse", "PaperResponse", "MeterReadings", "MeterState", "Signal",
    "HandLoadedRun", "SyntheticRun", "Agreement", "PolynomialCurve", "SplineCurve", "MonotoneCurve", "CurveSystem",
    "StaticCurve", "HeldoutCalibration", "Stepper", "RecordedWith", "LegacyModel",
    "Measurement", "Identity", "Ack", "DeviceError", "Frame", "FrameParser", "WindowReference",
    "LoadCellCalibration", "ReadoutHysteresis", "PlacementRepeatability", "RunReport", "Step", "ProtocolRun",
    "SignalSource", "MemoryState", "DelayLine", "Gap", "Scan", "RecordStatus", "SensorPreset",
    "Quantity", "TransientResult", "EdgeChunk", "FlashResult", "FirmwareInfo",
}
"""Result records and state objects the library builds from values it has already checked."""


def _modules() -> list[str]:
    names = []
    for pkg in PACKAGES:
        package = importlib.import_module(f"fsrlab.{pkg}")
        names += [m.name for m in pkgutil.walk_packages(package.__path__, f"{package.__name__}.")]
    return sorted(n for n in names + MODULES_ALSO if n not in EXCLUDED_MODULES)


def _public(module) -> list[tuple[str, Callable]]:
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n, obj in vars(module).items()
                 if not n.startswith("_") and getattr(obj, "__module__", None) == module.__name__]
    found = []
    for name in names:
        obj = getattr(module, name)
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        if getattr(obj, "__module__", None) != module.__name__:
            continue  # re-exported: fuzzed where it is defined
        if inspect.isclass(obj) and (issubclass(obj, (BaseException, enum.Enum))
                                     or name in RECORDS or name.endswith(RECORD_SUFFIXES)):
            continue
        found.append((f"{module.__name__}.{name}", obj))
    return found


def _qualname(obj) -> str:
    return f"{obj.__module__}.{obj.__qualname__}"


def _public_names() -> list[tuple[str, Callable]]:
    """The callables of ``fsrlab.__all__`` (exception classes aside), each named where it is defined."""
    found = []
    for name in fsrlab.__all__:
        obj = getattr(fsrlab, name)
        if callable(obj) and not (inspect.isclass(obj) and issubclass(obj, BaseException)):
            found.append((_qualname(obj), obj))
    return found


def _excluded(qualname: str) -> bool:
    module = qualname.rpartition(".")[0]
    return qualname in EXCLUDED or module in EXCLUDED_MODULES


def _callables() -> dict[str, Callable]:
    found = dict(_public_names())
    for module_name in _modules():
        for qualname, obj in _public(importlib.import_module(module_name)):
            found.setdefault(qualname, obj)
    for qualname in METHODS:
        module, cls, method = qualname.rsplit(".", 2)
        found[qualname] = getattr(getattr(importlib.import_module(module), cls), method)
    return {k: v for k, v in found.items() if not _excluded(k)}


def _lm555():
    return fsrlab.PAPER_CIRCUIT


METHODS: dict[str, Callable[[], object]] = {
    "fsrlab.physics.sensor.VirtualFSR.respond": lambda: fsrlab.VirtualFSR(),
    "fsrlab.physics.sensor.VirtualFSR.force_to_stress": lambda: fsrlab.VirtualFSR(),
    "fsrlab.physics.paper_sensor.PaperFSR.respond": lambda: fsrlab.paper_sensor(1),
    "fsrlab.physics.paper_sensor.PaperFSR.respond_many": lambda: fsrlab.paper_sensor(1),
    "fsrlab.physics.paper_sensor.PaperFSR.film_resistance": lambda: fsrlab.paper_sensor(1),
    "fsrlab.physics.paper_sensor.PaperFSR.force_to_stress": lambda: fsrlab.paper_sensor(1),
    "fsrlab.physics.paper_sensor.PaperFSR.placement": lambda: fsrlab.paper_sensor(1),
    "fsrlab.circuits.circuit.LM555Circuit.astable": _lm555,
    "fsrlab.circuits.circuit.LM555Circuit.sensitivity": _lm555,
    "fsrlab.circuits.circuit.LM555Circuit.decode": _lm555,
    "fsrlab.circuits.circuit.LM555Circuit.on_range": _lm555,
    "fsrlab.circuits.circuit.LM555Circuit.with_control": _lm555,
    "fsrlab.circuits.circuit.LM555Circuit.from_dict": _lm555,
    "fsrlab.circuits.circuit.OpAmpReadout.output_v": lambda: fsrlab.PAPER_OPAMP,
    "fsrlab.circuits.circuit.OpAmpReadout.conductance_s": lambda: fsrlab.PAPER_OPAMP,
    "fsrlab.circuits.circuit.OpAmpReadout.from_dict": lambda: fsrlab.PAPER_OPAMP,
    "fsrlab.circuits.mux.Multiplexer.timing_circuit": lambda: importlib.import_module("fsrlab.circuits.mux").CD74HC4051,
    "fsrlab.calibration.result.Calibration.estimate": lambda: _cal(),
    "fsrlab.calibration.result.Calibration.readout": lambda: _cal(),
    "fsrlab.calibration.result.Calibration.estimator": lambda: _cal(),
    "fsrlab.io.runformat.Run.circuit": lambda: _run(),
    "fsrlab.io.runformat.Run.readout_values": lambda: _run(),
    "fsrlab.io.runformat.Run.recorded_with": lambda: _run(),
}
"""Methods of the classes a user holds, each with the instance it is called on (built in the test's directory)."""


# ------------------------------------------------------------------------------------------------
# Valid values
# ------------------------------------------------------------------------------------------------

STRESS = [0.0, 5e4, 1e5, 2e5, 1e5, 5e4, 0.0]


def _run():
    return fsrlab.load_run("bench.csv")


@cache
def _sensor():
    return fsrlab.VirtualFSR()


def _cal():
    return fsrlab.load_calibration("calibration.json")


VALID: dict[str, Callable[[], object]] = {
    # files (copied into the test's own directory)
    "path": lambda: "bench.csv",
    "run": _run,
    "runs": lambda: [_run()],
    "cal": _cal,
    "calibration": _cal,
    # physics
    "stress_pa": lambda: np.array(STRESS),
    "stress_load_pa": lambda: np.array([0.0, 1e5, 2e5]),
    "stress_unload_pa": lambda: np.array([0.0, 1e5, 2e5]),
    "q_load": lambda: np.array([1.0, 2.0, 3.0]),
    "q_unload": lambda: np.array([1.2, 2.3, 3.0]),
    "q": lambda: np.array([1.0, 2.0, 3.0, 4.0, 3.2, 2.1, 1.0]),
    "sigma_f_pa": lambda: 2e5,
    "x_pa": lambda: np.array([0.0, 1e5]),
    "s_m": lambda: 4e-9,
    "u_v": lambda: 0.1,
    "area_m2": lambda: 7.13e-5,
    "k": lambda: 0.5,
    "hold_s": lambda: 10.0,
    "beta": lambda: 0.01,
    "tau_s": lambda: 5.0,
    "time_s": lambda: np.arange(7.0),
    "r_c0_ohm": lambda: 1e3,
    "sigma_c_pa": lambda: 1e5,
    "r_contact_ohm": lambda: 100.0,
    "voltage_v": lambda: 1.0,
    "fraction_0": lambda: 0.1,
    "growth_pa": lambda: 1e5,
    "direction": lambda: np.array([1, 1, 1, 1, -1, -1, -1]),
    "which": lambda: 1,
    "sensor": _sensor,
    "name": lambda: "FSR402",
    # circuits
    "r_ohm": lambda: 10e3,
    "r_fsr_ohm": lambda: 50e3,
    "c_fsr_farad": lambda: 1e-9,
    "c_off_farad": lambda: 0.0,
    "n_ratio": lambda: 5.0,
    "frequency_hz": lambda: 5000.0,
    "duty_cycle": lambda: 0.6,
    "diode": lambda: True,
    "diode_drop_v": lambda: 0.6,
    "vcc_v": lambda: 5.0,
    "lower_fraction": lambda: 1 / 3,
    "upper_fraction": lambda: 2 / 3,
    "control_v": lambda: 3.3,
    "r_f_ohm": lambda: 100e3,
    "r_m_ohm": lambda: 10e3,
    "r_fsr_range_ohm": lambda: (10e3, 1e6),
    "c_fsr_range_farad": lambda: (0.1e-9, 2e-9),
    "band_hz": lambda: (1e3, 40e3),
    "v0_v": lambda: 1.0,
    "off_s": lambda: 1e-3,
    "v_node_v": lambda: 1.0,
    "c_node_farad": lambda: 10e-12,
    "v_fsr_v": lambda: 0.5,
    "metadata": lambda: dict(_run().metadata),
    "t_s": lambda: np.linspace(0, 1e-3, 11),
    "v_out_v": lambda: np.array([0, 5, 5, 0, 0, 5, 5, 0, 0, 5, 5.0]),
    "v_v": lambda: np.linspace(0, 1, 11),
    "level_v": lambda: 0.5,
    "rising": lambda: True,
    "t_stop_s": lambda: 1e-3,
    "t_max_step_s": lambda: 1e-6,
    "data": lambda: b"",
    # metrics
    "reference": lambda: np.array(STRESS),
    "readout": lambda: np.array([1.0, 2.0, 3.0, 4.0, 3.2, 2.1, 1.0]),
    "elapsed_s": lambda: np.arange(1.0, 8.0),
    "x": lambda: np.array([1.0, 2.0, 3.0, 4.0, 3.2, 2.1, 1.0]),
    "readings": lambda: np.array([[1.0, 1.1, 0.9], [2.0, 2.1, 1.9]]),
    "forces": lambda: np.array([1.0, 2.0]),
    "forces_n": lambda: np.array([100.0, 200.0]),
    "load": lambda: ["100g", "100g", "200g", "200g"],
    "reading": lambda: [1.0, 1.1, 2.0, 2.1],
    "value_percent": lambda: 0.1,
    "u": lambda: np.array([0.0, 1.0, 2.0, 1.0, 0.0]),
    "t": lambda: np.arange(5.0),
    "y": lambda: np.array([0.0, 1.0, 2.0, 1.0, 0.0]),
    # acquisition (pure parts)
    "channels": lambda: [0, 1],
    "mask": lambda: 3,
    "text": lambda: "0,1",
    "payload": lambda: b"abc",
    "kind": lambda: "M",
    "seq": lambda: 1,
    "line": lambda: "1,2,3",
    "baud": lambda: 115200,
    "periods": lambda: 10,
    "sum_period_ticks": lambda: 32000,
    "sum_high_ticks": lambda: 16000,
    "raw": lambda: np.array([100.0, 200.0]),
    "offset_counts": lambda: 100.0,
    "scale_counts_per_n": lambda: 10.0,
    "counts": lambda: np.array([100.0, 101.0, 99.0]),
    "mass_kg": lambda: 0.5,
    "window_ms": lambda: 100,
    "adc": lambda: False,
    # units
    "value": lambda: 4.7e3,
    "quantity": lambda: "ohms",
    # virtual
    "duration_s": lambda: 1.0,
    "peak_n": lambda: 10.0,
    "ramp_s": lambda: 1.0,
    "rng": lambda: np.random.default_rng(0),
    "window_s": lambda: 0.1,
    "source": lambda: None,
    # io
    "columns": lambda: {"time_s": np.arange(3.0), "frequency_hz": np.array([1e3, 2e3, 3e3])},
    "cell": lambda: "1.5",
    "items": lambda: ["a", "b"],
    "obj": lambda: {"a": 1},
    "header": lambda: None,
    "lines": lambda: ["1,2", "3,4"],
    "required": lambda: ["time_s"],
    "delimiter": lambda: ",",
}
"""A valid value for a required parameter, by its name (a factory: every test gets a fresh value)."""

OVERRIDES: dict[str, dict[str, Callable[[], object]]] = {
    "fsrlab.units.parse_eng": {"text": lambda: "4k7"},
    "fsrlab.physics.params.paired_series": {"x_name": lambda: "time_s", "x": lambda: np.arange(3.0),
                                           "y_name": lambda: "reference", "y": lambda: np.ones(3)},
    "fsrlab.virtual.arguments.random_generator": {"value": lambda: 7, "name": lambda: "seed"},  # an int seed
    "fsrlab.units.parse_quantity": {"text": lambda: "4k7", "quantity": lambda: "resistance", "name": lambda: "r_ohm"},
    "fsrlab.calibration.document.save_calibration": {"path": lambda: "out.json"},
    "fsrlab.io.runwriter.write_run": {"path": lambda: "out.csv"},
    "fsrlab.io.runwriter.RunWriter": {"path": lambda: "out.csv", "columns": lambda: ["time_s", "frequency_hz"]},
    "fsrlab.io.calibration_file.write_calibration_document": {"path": lambda: "out.json",
                                                               "doc": lambda: _cal_document()},
    "fsrlab.io.calibration_file.read_calibration_document": {"path": lambda: "calibration.json"},
    "fsrlab.calibration.document.load_calibration": {"path": lambda: "calibration.json"},
    "fsrlab.io.tables.load_grouped_csv": {"path": lambda: "repeatability.csv"},
    "fsrlab.io.tables.load_iso376_csv": {"path": lambda: "iso376.csv"},
    "fsrlab.io.foreign.import_foreign": {"sensor": lambda: "foreign_fsr.csv"},
    "fsrlab.physics.history.cycle_numbers": {"direction": lambda: np.array([1, 1, -1, -1, 1, -1])},
    "fsrlab.physics.presets.sensor_preset": {"name": lambda: "interlink-402"},
    "fsrlab.bench.protocols.virtual_sensor": {"name": lambda: "interlink-402"},
    "fsrlab.physics.paper_sensor.memory_stress": {"k": lambda: 2.0},
    "fsrlab.physics.paper_sensor.series_contact": {"film_resistance": lambda: (lambda u: 1e4 / (1 + np.asarray(u)))},
    "fsrlab.circuits.decode.decode": {"duty_cycle": lambda: 0.8},
    "fsrlab.circuits.decomposition.frequency_decomposition": {"r_fsr_ohm": lambda: np.array([50e3, 60e3]),
                                                              "c_fsr_farad": lambda: np.array([1e-9, 1.2e-9]),
                                                              "diode": lambda: True},
    "fsrlab.circuits.transient.simulate": {"periods": lambda: 3},
    "fsrlab.circuits.paper_ratio.n_where_ratio_equals": {"value": lambda: 10.0},
    "fsrlab.circuits.paper_ratio.tau_ratio_table": {"n_ratio": lambda: [5.0, 10.0]},
    "fsrlab.circuits.spice.read_raw": {"data": lambda: _raw_file()},
    "fsrlab.physics.params.check_positive": {"name": lambda: "r_ohm", "value": lambda: 1.0},
    "fsrlab.physics.params.check_finite": {"name": lambda: "r_ohm", "value": lambda: 1.0},
    "fsrlab.physics.params.check_at_least": {"name": lambda: "r_ohm", "value": lambda: 1.0, "lower": lambda: 0.0},
    "fsrlab.physics.params.check_between": {"name": lambda: "r_ohm", "value": lambda: 1.0, "lower": lambda: 0.0,
                                            "upper": lambda: 2.0},
    "fsrlab.physics.params.check_int": {"name": lambda: "r_ohm", "value": lambda: 1},
    "fsrlab.physics.params.float_array": {"name": lambda: "r_ohm", "value": lambda: 1.0},
    "fsrlab.circuits.checks.check_supply": {"diode": lambda: True},
    "fsrlab.circuits.checks.check_fraction": {"name": lambda: "upper_fraction", "value": lambda: 0.5},
    "fsrlab.circuits.checks.check_lm555": {"c_off_farad": lambda: 0.0, "diode": lambda: True,
                                           "diode_drop_v": lambda: 0.6, "vcc_v": lambda: 5.0},
    "fsrlab.circuits.spice.edges_from_waveform": {"t_s": lambda: np.linspace(0, 1e-3, 11)},
    "fsrlab.metrics.hysteresis.check_response": {"q": lambda: np.array([1.0, 2.0, 3.0, 4.0, 3.2, 2.1, 1.0])},
    "fsrlab.metrics.iso376.class_reached": {"name": lambda: "b", "value_percent": lambda: 0.1},
    "fsrlab.metrics.repeatability.force_repeatability": {"readings": lambda: {"a": [[1.0, 1.1]], "b": [[2.0, 2.1]]},
                                                         "forces": lambda: {"a": 1.0, "b": 2.0}},
    "fsrlab.metrics.repeatability.grouped_repeatability": {"load": lambda: ["1", "1", "2", "2"],
                                                           "sensor": lambda: ["A", "A", "A", "A"]},
    "fsrlab.metrics.creep.creep": {"time_s": lambda: np.arange(100.0) * 0.1,
                                   "readout": lambda: 1.0 + 0.001 * np.arange(100.0),
                                   "reference": lambda: np.r_[np.zeros(10), np.full(80, 1e5), np.zeros(10)]},
    "fsrlab.metrics.holds.find_holds": {"time_s": lambda: np.arange(100.0) * 0.1,
                                        "reference": lambda: np.r_[np.zeros(10), np.full(80, 1e5), np.zeros(10)]},
    "fsrlab.metrics.creep.find_holds": {"time_s": lambda: np.arange(100.0) * 0.1,
                                        "reference": lambda: np.r_[np.zeros(10), np.full(80, 1e5), np.zeros(10)]},
    "fsrlab.metrics.creep.creep_of_run": {"run": lambda: fsrlab.load_run("creep.csv")},
    "fsrlab.acquisition.loadcell.tare_from_readings": {"counts": lambda: 100.0 + np.arange(10.0)},
    "fsrlab.metrics.hysteresis.hysteresis_error_curves": {"q_load": lambda: (lambda s: 1.0 + s / 1e5),
                                                          "q_unload": lambda: (lambda s: 1.1 + s / 1e5)},
    "fsrlab.metrics.agreement.agreement": {"estimate": lambda: np.array(STRESS) * 1.01},
    "fsrlab.calibration.delay.delayed": {"t": lambda: np.arange(7.0), "delay_s": lambda: 0.1},
    "fsrlab.calibration.monotone.readout_variable": {"name": lambda: "readout", "sign": lambda: 1},
    "fsrlab.calibration.curves.curve_template": {"family": lambda: "polynomial", "size": lambda: 3,
                                                 "variable": lambda: "readout", "sign": lambda: 1},
    "fsrlab.calibration.curves.fit_static": {"family": lambda: "polynomial", "size": lambda: 3,
                                             "variable": lambda: "readout", "sign": lambda: 1,
                                             "x": lambda: np.linspace(1, 2, 7), "y": lambda: np.linspace(0, 1, 7)},
    "fsrlab.io.runformat.Run.readout_values": {"x": lambda: "frequency_hz"},
    "fsrlab.calibration.runs.check_arguments": {"x": lambda: "frequency_hz"},
    "fsrlab.bench.weights.plan_steps": {"masses_kg": lambda: [0.1, 0.2]},
    "fsrlab.io.outputs.check_output": {"path": lambda: "out.csv", "option": lambda: "out"},
    "fsrlab.io.outputs.refuse_inputs": {"path": lambda: "out.csv", "option": lambda: "out",
                                        "inputs": lambda: ["bench.csv"]},
    "fsrlab.io.outputs.write_text_atomic": {"path": lambda: "new.txt"},
    "fsrlab.io.outputs.write_bytes_atomic": {"path": lambda: "new.bin"},
    "fsrlab.io.outputs.atomic_run": {"path": lambda: "new.csv"},
    "fsrlab.io.outputs.same_file": {"a": lambda: "bench.csv", "b": lambda: "other.csv"},
    "fsrlab.io.runformat.read_json_document": {"path": lambda: Path("bench.meta.json"),
                                               "format_name": lambda: "fsrlab-run", "version": lambda: 1,
                                               "what": lambda: "run sidecar"},
    "fsrlab.io.runcells.parse_cells": {"path": lambda: Path("bench.csv"), "body": lambda: ["0,1000"],
                                       "header": lambda: ["time_s", "frequency_hz"]},
    "fsrlab.physics.paper_sensor.PaperFSR.respond_many": {"requests": lambda: [{"stress_pa": STRESS}]},
    "fsrlab.physics.paper_sensor.PaperFSR.film_resistance": {"u_v": lambda: 1.0, "s_m": lambda: 4e-9,
                                                             "area_m2": lambda: 1e-6},
    "fsrlab.physics.sensor.VirtualFSR.force_to_stress": {"force_n": lambda: 10.0},
    "fsrlab.physics.paper_sensor.PaperFSR.force_to_stress": {"force_n": lambda: 10.0},
    "fsrlab.circuits.circuit.LM555Circuit.on_range": {"range_": lambda: 0},
    "fsrlab.circuits.circuit.LM555Circuit.from_dict": {"d": lambda: fsrlab.PAPER_CIRCUIT.to_dict()},
    "fsrlab.circuits.circuit.LM555Circuit.decode": {"duty_cycle": lambda: 0.55},
    "fsrlab.circuits.circuit.OpAmpReadout.from_dict": {"d": lambda: fsrlab.PAPER_OPAMP.to_dict()},
    "fsrlab.circuits.circuit.OpAmpReadout.conductance_s": {"v_out_v": lambda: 1.0},
    "fsrlab.circuits.mux.Multiplexer.timing_circuit": {"circuit": lambda: fsrlab.PAPER_CIRCUIT},
    "fsrlab.bench.measurement.placement_means": {"run": lambda: _weights_run()},
    "fsrlab.bench.measurement.placements_repeatability": {"placements": lambda: _placements(),
                                                          "quantity": lambda: "frequency_hz"},
    "fsrlab.bench.measurement.iso376_of_placements": {"placements": lambda: _placements()},
    "fsrlab.acquisition.firmware.avrdude_command": {"port": lambda: "/dev/ttyACM0"},
    "fsrlab.acquisition.firmware.check_intel_hex": {"path": lambda: str(
        importlib.import_module("fsrlab.acquisition.firmware").hex_path())},
    "fsrlab.acquisition.firmware.write_sketch": {"directory": lambda: "sketch"},
    "fsrlab.acquisition.protocol.parse_channels": {"text": lambda: "0,1"},
    "fsrlab.acquisition.protocol.encode_command": {"name": lambda: "WINDOW", "value": lambda: 100},
    "fsrlab.acquisition.protocol.parse_command": {"line": lambda: b"WINDOW 100\n"},
    "fsrlab.acquisition.protocol.check_fields": {"kind": lambda: "ACK", "fields": lambda: ("WINDOW",)},
    "fsrlab.acquisition.protocol.encode_frame": {"kind": lambda: "ACK", "fields": lambda: ("WINDOW",)},
    "fsrlab.virtual.bench_source.BenchSource": {"forces_n": lambda: [1.0, 2.0]},
    "fsrlab.virtual.sources.MuxSource": {"sources": lambda: [importlib.import_module("fsrlab.virtual.sources")
                                                             .PhysicsSource(), None]},
    "fsrlab.metrics.repeatability.recompute_printed_table": {"printed": lambda: _table4()},
    "fsrlab.metrics.repeatability.ddof_finding": {"tables": lambda: [importlib.import_module(
        "fsrlab.metrics.repeatability").recompute_printed_table(_table4())]},
    "fsrlab.metrics.iso376.iso376": {"forces_n": lambda: _iso376()[0], "series": lambda: _iso376()[1]},
    "fsrlab.io.outputs.replace_run": {"src": lambda: "bench.csv", "dst": lambda: "moved.csv"},
    "fsrlab.acquisition.loadcell.load_loadcell": {"path": lambda: _loadcell_file()},
    "fsrlab.acquisition.loadcell.scale_from_readings": {"cal": lambda: _loadcell_cal(),
                                                        "counts": lambda: 1100.0 + np.arange(10.0)},
    "fsrlab.acquisition.loadcell.window_reference": {"model": lambda: _loadcell_model(),
                                                     "force_at": lambda: (lambda t: 1.0 + 0 * t),
                                                     "t0_s": lambda: 0.0, "t1_s": lambda: 0.1},
    "fsrlab.io.shown.printable": {"text": lambda: "abc"},
    "fsrlab.io.shown.shown": {"text": lambda: "abc"},
    "fsrlab.io.csvtext.csv_cells": {"line": lambda: "1,2,3"},
    "fsrlab.io.jsonable.to_jsonable": {"obj": lambda: {"a": 1}},
    "fsrlab.io.runformat.read_table": {"required": lambda: ["time_s"]},
    "fsrlab.io.foreign.read_table": {"path": lambda: "foreign_fsr.csv"},
    "fsrlab.io.foreign.interpolate_reference": {"t": lambda: np.arange(5.0), "t_ref": lambda: np.arange(5.0),
                                                "values": lambda: np.arange(5.0)},
    "fsrlab.io.foreign.write_imported": {"imported": lambda: _imported(), "path": lambda: "out.csv"},
    "fsrlab.io.schema.where": {"row": lambda: 3, "column": lambda: "time_s"},
    "fsrlab.io.schema.sidecar_path": {"path": lambda: "bench.csv"},
    "fsrlab.io.schema.check_columns": {"columns": lambda: ["time_s", "frequency_hz"]},
    "fsrlab.calibration.delay.delay_trials": {"row_s": lambda: 0.1},
    "fsrlab.calibration.legacy.is_legacy": {"d": lambda: {}},
    "fsrlab.calibration.curves.curve_from_dict": {"d": lambda: _cal_document()["calibration"]["curve"]},
    "fsrlab.calibration.provenance.describe_range": {"ranges": lambda: (0, 1)},
    "fsrlab.calibration.result.as_margin": {"margin": lambda: 0.1},
    "fsrlab.io.outputs.protected_paths": {"inputs": lambda: ["bench.csv"]},
}
"""Valid values for one callable where the shared table's does not fit it."""


def _cal_document():
    import json

    return json.loads(Path("calibration.json").read_text())


def _raw_file():
    """A two-point, two-variable ngspice binary raw file (the layout read_raw's docstring gives)."""
    header = b"Title: t\nFlags: real\nNo. Variables: 2\nNo. Points: 2\nBinary:\n"
    return header + np.array([[0.0, 1.0], [1e-6, 2.0]], "<f8").tobytes()


def _loadcell_model():
    from fsrlab.acquisition.loadcell import LoadCellModel

    return LoadCellModel()


def _loadcell_cal():
    from fsrlab.acquisition.loadcell import LoadCellCalibration

    return LoadCellCalibration(offset_counts=100.0, scale_counts_per_n=10.0)


def _weights_run():
    """A small dead-weight run (three placement cycles 0 → 100 g → 200 g → 100 g → 0), written here."""
    loads = [0.0, 100.0, 200.0, 100.0, 0.0] * 3
    rows = [(k, g, 1.0 if k % 5 < 3 else -1.0, k // 5) for k, g in enumerate(loads) for _ in range(4)]
    step, load, direction, cycle = (np.array(c, dtype=float) for c in zip(*rows, strict=True))
    freq = 1000.0 + 20.0 * load + np.arange(step.size) % 4
    columns = {"time_s": 0.1 * np.arange(step.size), "frequency_hz": freq, "duty_cycle": np.full(step.size, 0.6),
               "step": step, "load": load, "direction": direction, "cycle": cycle,
               "force_nominal_n": load * 9.80665e-3}
    if not Path("weights.csv").exists():
        fsrlab.write_run("weights.csv", columns)
    return fsrlab.load_run("weights.csv")


def _placements():
    return importlib.import_module("fsrlab.bench.measurement").placement_means(_weights_run())


def _table4():
    from fsrlab.reference import paper_values

    return {k: v for k, v in paper_values()["table4_repeatability_capacitive_kHz"].items() if k != "note"}


def _iso376():
    from fsrlab.io.tables import load_iso376_csv

    return load_iso376_csv("iso376.csv")


def _loadcell_file():
    _loadcell_cal().save("loadcell.json")
    return "loadcell.json"


def _imported():
    from fsrlab.io.foreign import import_foreign

    return import_foreign("foreign_fsr.csv")


# ------------------------------------------------------------------------------------------------
# Wrong values
# ------------------------------------------------------------------------------------------------

NUMBER_SUFFIXES = ("_pa", "_ohm", "_farad", "_hz", "_s", "_v", "_m", "_m2", "_j", "_kg", "_n", "_ms", "_percent",
                   "_fraction", "_cycle", "_ratio", "_counts", "_sps", "_g", "_lsb", "_m_s2", "_ev", "_per_n",
                   "_per_s", "_deg")
NUMBER_NAMES = {"k", "beta", "n", "n_ratio", "margin", "threshold", "seed", "cycles", "periods", "points",
                "points_per_ramp", "iterations", "exponent", "layers", "eps_r", "band", "ddof", "jobs", "repeat",
                "speed", "frequency_noise", "reference_noise", "value", "which", "mask", "baud", "seq", "degree",
                "tolerance", "fraction", "lam", "size", "refine", "digits", "limit", "step", "rel_step",
                "skip_periods", "steps_per_phase", "points_per_segment", "capacitance_step", "dwell_points",
                "min_margin", "xatol", "full_scale", "hysteresis", "creep", "activation", "sign",
                "sum_period_ticks", "sum_high_ticks", "interpolation_degree", "substeps", "settle_windows",
                "max_drift", "dielectric_ratio", "raw", "counts"}
PATH_NAMES = {"path", "out", "directory", "file", "hex_file", "output_file", "workdir", "src", "dst"}
OBJECT_NAMES = {"run", "runs", "cal", "calibration", "sensor", "circuit", "opamp", "mux", "profile", "source",
                "params", "model", "weights_run", "imported", "doc", "d", "plan", "settings", "state", "loadcell",
                "quantity", "template", "curve", "static", "selection", "estimator", "result", "cycle", "placements"}
MISSING = "no-such-file.csv"


def _kind(param: inspect.Parameter) -> str:
    name, default, note = param.name, param.default, str(param.annotation)
    if name in PATH_NAMES or "PathLike" in note or (note.startswith("Path") and "Sequence" not in note):
        return "path"
    if name in OBJECT_NAMES:
        return "object"
    if isinstance(default, bool) or note in {"bool", "bool | None"}:
        return "bool"
    if (name in NUMBER_NAMES or name.endswith(NUMBER_SUFFIXES)
            or (isinstance(default, (int, float)) and not isinstance(default, bool))
            or any(t in note for t in ("float", "ArrayLike", "ndarray", "int"))):
        return "number"
    return "other"


def bad_values(param: inspect.Parameter, strict: bool = False) -> list[tuple[str, object]]:
    """The wrong values tried for one parameter, each with the label a failure shows (more when ``strict``)."""
    kind = _kind(param)
    required = param.default is inspect.Parameter.empty
    values: list[tuple[str, object]] = [("str 'abc'", "abc"), ("dict {}", {})]
    if required or param.default is not None:
        values.append(("None", None))
    if kind == "number":
        values += [("-1.0", -1.0), ("0.0", 0.0), ("nan", math.nan), ("inf", math.inf), ("-inf", -math.inf),
                   ("[nan, 1]", np.array([math.nan, 1.0])), ("'10%'", "10%")]
        if strict:
            values += [("empty array", np.array([])), ("array [1, 2]", np.array([1.0, 2.0]))]
    elif kind == "path":
        values += [(f"missing file {MISSING!r}", MISSING), ("a directory 'adir'", "adir"), ("empty ''", ""),
                   ("int 5", 5), ("an existing run 'other.csv'", "other.csv"),
                   ("a run's sidecar 'other.meta.json'", "other.meta.json")]
    elif kind == "object":
        values += [(f"missing path {MISSING!r}", MISSING), ("int 5", 5), ("a directory 'adir'", Path("adir"))]
    elif kind == "other":
        values += [("int -1", -1), ("float nan", math.nan)]
    return values


# ------------------------------------------------------------------------------------------------
# Running and judging one call
# ------------------------------------------------------------------------------------------------


class CallTimeout(BaseException):
    """A call ran past CALL_SECONDS (a BaseException, so the code under test cannot swallow it)."""


def _alarm(signum, frame):
    raise CallTimeout


def _call(fn: Callable, kwargs: dict):
    """Call ``fn(**kwargs)`` (iterating a returned generator): ``(value, exception, warnings)``.

    ``warnings`` are the texts of the RuntimeWarnings (numpy's overflow, invalid value, ...) the call let out.
    """
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, CALL_SECONDS)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            value = fn(**kwargs)
            if isinstance(value, types.GeneratorType):
                value = list(value)
            value, exc = value, None
        except CallTimeout as timeout:
            value, exc = None, timeout
        except Exception as error:  # noqa: BLE001 -- judged below
            value, exc = None, error
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)
    return value, exc, [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]


def verdict(exc: BaseException | None, parameter: str | tuple[str, ...]) -> str | None:
    """None when the outcome is accepted, else why not (``parameter``: the name, or the names, it may carry)."""
    if exc is None:
        return None
    if isinstance(parameter, tuple):
        whys = [verdict(exc, name) for name in parameter]
        return None if None in whys else whys[0]
    text = str(exc)
    if isinstance(exc, CallTimeout):
        return f"took over {CALL_SECONDS:g} s"
    if isinstance(exc, FsrlabError):
        if exc.parameter == parameter or parameter in text:
            return None
        return f"{type(exc).__name__} naming {exc.parameter!r}, not {parameter!r}: {text[:160]}"
    if type(exc) is TypeError and parameter in text:
        return None
    return f"{type(exc).__module__}.{type(exc).__name__}: {text[:160]}"


CALLABLES = _callables()


def _signature(fn) -> list[inspect.Parameter]:
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return []
    return [p for p in sig.parameters.values()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD) and p.name != "self"]


def _valid(qualname: str, param: inspect.Parameter):
    table = OVERRIDES.get(qualname, {})
    if param.name in table:
        return table[param.name]()
    if param.name in VALID:
        return VALID[param.name]()
    raise LookupError(param.name)


def _cases():
    cases = []
    for qualname, fn in sorted(CALLABLES.items()):
        for param in _signature(fn):
            if param.kind is param.POSITIONAL_ONLY or (qualname, param.name) in NOT_FUZZED:
                continue
            marks = [pytest.mark.xfail(strict=True, reason=XFAIL[(qualname, param.name)])] \
                if (qualname, param.name) in XFAIL else []
            cases.append(pytest.param(qualname, param.name, id=f"{qualname}-{param.name}", marks=marks))
    return cases


XFAIL: dict[tuple[str, str], str] = {
}
REPLACES = {
    "fsrlab.io.outputs.write_text_atomic": "the atomic write itself: its callers' output policy chose the path",
    "fsrlab.io.outputs.write_bytes_atomic": "the atomic write itself: its callers' output policy chose the path",
    "fsrlab.io.outputs.replace_run": "renames a run into place: its callers' output policy chose the path",
    "fsrlab.io.calibration_file.write_calibration_document": "the file's writer under save_calibration's policy",
}
"""Writers whose job is to replace their target (the output policy is their callers'): not held to the file hashes."""
NOT_FUZZED = {
    ("fsrlab.physics.params.check_at_least", "lower"): "a bound the library's own code passes",
    ("fsrlab.physics.params.check_between", "lower"): "a bound the library's own code passes",
    ("fsrlab.physics.params.check_between", "upper"): "a bound the library's own code passes",
    ("fsrlab.physics.params.check_int", "lower"): "a bound the library's own code passes",
    ("fsrlab.io.outputs.replace_run", "dst"): "the valid call moves its src away, so every later call meets a src "
                                              "that is gone (replace_run's src is fuzzed)",
}
"""(callable, parameter) pairs not fuzzed, with the reason: checks' arguments set by the library itself."""
ALIASES = {
    ("fsrlab.units.parse_eng", "text"): "value",
    ("fsrlab.units.parse_quantity", "text"): "r_ohm",
    ("fsrlab.physics.params.check_finite", "value"): "r_ohm",
    ("fsrlab.physics.params.check_positive", "value"): "r_ohm",
    ("fsrlab.physics.params.check_at_least", "value"): "r_ohm",
    ("fsrlab.physics.params.check_between", "value"): "r_ohm",
    ("fsrlab.physics.params.check_int", "value"): "r_ohm",
    ("fsrlab.physics.params.float_array", "value"): "r_ohm",
    ("fsrlab.physics.params.paired_series", "x"): "time_s",
    ("fsrlab.physics.params.paired_series", "y"): "reference",
    ("fsrlab.circuits.checks.check_fraction", "value"): "upper_fraction",
    ("fsrlab.virtual.arguments.random_generator", "value"): "seed",
    # A circuit's parts as a mapping: its errors name the sidecar's and the calibration file's key, circuit.
    ("fsrlab.circuits.circuit.LM555Circuit.from_dict", "d"): "circuit",
    ("fsrlab.circuits.circuit.OpAmpReadout.from_dict", "d"): "circuit",
    # The sensor's (low, high) ranges: a legitimate range the band cannot hold is the band's error.
    ("fsrlab.circuits.design.design", "r_fsr_range_ohm"): ("r_fsr_range_ohm", "band_hz"),
    ("fsrlab.circuits.design.design", "c_fsr_range_farad"): ("c_fsr_range_farad", "band_hz"),
    # Helpers of the command line whose errors name the option they check (the caller's name for it).
    ("fsrlab.acquisition.firmware.check_intel_hex", "path"): "hex_file",
    ("fsrlab.acquisition.recorder.channel_map", "given"): ("given", "channel_map"),
    ("fsrlab.io.outputs.check_output", "path"): ("out", "--out"),
    ("fsrlab.io.outputs.output_path", "text"): ("out", "--out"),
    # A document that is not of the format asked for is the file's fault: it names path.
    ("fsrlab.io.runformat.read_json_document", "format_name"): ("format_name", "path"),
}
"""(callable, parameter) -> the name (or names) its errors may carry instead, each with why."""
"""(callable, parameter) cases known to fail, each with the module that owns the fix."""


def _hashes(directory: Path) -> dict[str, str]:
    """SHA-256 of every file in ``directory`` (the examples' copies and what the calls wrote), by name."""
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in directory.iterdir() if p.is_file()}


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """The examples (runs, calibration, tables, foreign CSVs) copied into the test's own directory."""
    for item in EXAMPLES.iterdir():
        if item.is_file():
            shutil.copy(item, tmp_path / item.name)
    (tmp_path / "adir").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize(("qualname", "parameter"), _cases())
def test_a_wrong_argument_is_named(workdir, qualname, parameter):
    fn = CALLABLES[qualname]
    params = _signature(fn)
    if qualname in METHODS:
        fn = getattr(METHODS[qualname](), qualname.rpartition(".")[2])
    target = next(p for p in params if p.name == parameter)
    try:
        base = {p.name: _valid(qualname, p) for p in params
                if (p.default is inspect.Parameter.empty or p.name in OVERRIDES.get(qualname, {}))
                and p.name != parameter and p.kind is not p.POSITIONAL_ONLY}
    except LookupError as missing:
        pytest.skip(f"{qualname}: no valid value known for {missing.args[0]!r}")
    full = dict(base)  # the valid call: the target's valid value when required or given in OVERRIDES, else its default
    if target.default is inspect.Parameter.empty or parameter in OVERRIDES.get(qualname, {}):
        try:
            full[parameter] = _valid(qualname, target)
        except LookupError:
            pytest.skip(f"{qualname}: no valid value known for {parameter!r}")
    before = _hashes(workdir)
    _, exc, _ = _call(fn, full)
    if exc is not None:
        pytest.skip(f"{qualname}: the valid call raises {type(exc).__name__}: {str(exc)[:120]}")
    # Watched: the files that were there and the valid call left alone (what it wrote or moved is its business).
    after_valid = _hashes(workdir)
    for name in set(after_valid) - set(before):  # the valid call's own output: gone, so no wrong call meets it
        (workdir / name).unlink()
    after_valid = _hashes(workdir)
    before = {name: digest for name, digest in before.items() if after_valid.get(name) == digest}
    failures = []
    for label, value in bad_values(target, strict=qualname.startswith(STRICT)):
        _, exc, warned = _call(fn, {**base, parameter: value})
        why = verdict(exc, ALIASES.get((qualname, parameter), parameter))
        if not why and warned and qualname.startswith(STRICT):
            why = f"a RuntimeWarning let out: {warned[0][:120]}"
        after = _hashes(workdir)
        for name in set(after) - set(after_valid):  # what a wrong call wrote: gone before the next one
            (workdir / name).unlink()
        touched = sorted(name for name, digest in before.items() if after.get(name) != digest)
        if touched and qualname not in REPLACES:  # a wrong argument never changes or removes a file that was there
            why = f"{why + '; ' if why else ''}changed or removed {', '.join(touched)}"
            before = {name: digest for name, digest in before.items() if name not in touched}
        if why:
            failures.append(f"  {qualname}({parameter}={label}): {why}")
    assert not failures, f"{qualname}: {len(failures)} wrong value(s) of {parameter!r} not named:\n" + "\n".join(
        failures)


def test_the_fuzzer_covers_the_public_api():
    # Every callable of fsrlab.__all__ is fuzzed or excluded with a reason, and the lower layers are found.
    for qualname, _ in _public_names():
        assert qualname in CALLABLES or _excluded(qualname), qualname
    for layer in ("physics", "circuits", "metrics", "io", "virtual", "calibration", "bench", "acquisition"):
        assert any(q.startswith(f"fsrlab.{layer}.") for q in CALLABLES), layer
    assert "fsrlab.units.parse_eng" in CALLABLES


def test_the_verdict_accepts_only_an_error_naming_the_parameter():
    from fsrlab.errors import FileFormatError, ParameterError

    assert verdict(None, "r_ohm") is None
    assert verdict(ParameterError("must be > 0 Ω", parameter="r_ohm"), "r_ohm") is None
    assert verdict(FileFormatError("bench.csv: not a run (r_ohm missing)"), "r_ohm") is None  # named in the text
    assert verdict(TypeError("r_ohm: must be a number, got str"), "r_ohm") is None
    for wrong in (ParameterError("must be > 0", parameter="c_fsr_farad"), TypeError("must be real number, not str"),
                  ValueError("r_ohm: must be > 0"), KeyError("r_ohm"), AttributeError("'str' has no attribute 'x'"),
                  ZeroDivisionError("division by zero"), FileNotFoundError("r_ohm"), CallTimeout()):
        assert verdict(wrong, "r_ohm") is not None, repr(wrong)
