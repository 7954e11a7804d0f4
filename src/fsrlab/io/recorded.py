"""What a run was recorded with: its sidecar's readout circuits and the ranges of its readings.

A calibration file keeps the same record of the run it was fitted on (its ``"recorded_with"``);
:mod:`fsrlab.calibration.provenance` compares the two.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fsrlab.circuits.circuit import LM555Circuit, OpAmpReadout, readout_from_metadata
from fsrlab.errors import FileFormatError
from fsrlab.physics.params import float_array

__all__ = ["RecordedWith", "recorded_with"]


@dataclass(frozen=True)
class RecordedWith:
    """The readout a calibration's data were recorded with.

    Parameters
    ----------
    circuit : LM555Circuit or None
        The run's LM555 circuit (its sidecar's), or None when the run's sidecar has none.
    opamp : OpAmpReadout or None
        The run's op-amp readout, or None.
    ranges : tuple of int or None
        The values of the run's ``range`` column among the readings used (0: C_off out, 1: in);
        None for a run without a ``range`` column (C_off in circuit throughout).
    """

    circuit: LM555Circuit | None = None
    opamp: OpAmpReadout | None = None
    ranges: tuple[int, ...] | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON form (the calibration file's ``"recorded_with"``)."""
        return {"circuit": None if self.circuit is None else self.circuit.to_dict(),
                "opamp": None if self.opamp is None else self.opamp.to_dict(),
                "range": None if self.ranges is None else list(self.ranges)}

    @classmethod
    def from_dict(cls, d: dict) -> RecordedWith:
        """Inverse of :meth:`to_dict`."""
        if not isinstance(d, dict):
            raise FileFormatError(f"recorded_with: expected a mapping, got {type(d).__name__}")
        ranges = d.get("range")
        if ranges is not None and not (isinstance(ranges, list) and set(ranges) <= {0, 1}):
            raise FileFormatError(f"recorded_with.range: must be a list of 0 and 1, got {ranges!r}")
        return cls(None if d.get("circuit") is None else LM555Circuit.from_dict(d["circuit"]),
                   None if d.get("opamp") is None else OpAmpReadout.from_dict(d["opamp"]),
                   None if ranges is None else tuple(sorted(int(r) for r in ranges)))


def recorded_with(metadata: dict, range_column=None, used=None) -> RecordedWith:
    """The readout of a run, from its sidecar and its ``range`` column.

    Parameters
    ----------
    metadata : dict
        The run's sidecar (:attr:`fsrlab.io.runformat.Run.metadata`).
    range_column : array_like, optional
        The run's ``range`` column (NaN where empty); None for a run without one.
    used : array_like of bool, optional
        The readings that count (e.g. those with a readout and a reference); default all.

    Returns
    -------
    RecordedWith
    """
    circuit, opamp = readout_from_metadata(metadata)
    ranges = None
    if range_column is not None:
        r = float_array("range_column", range_column)
        if used is not None:
            r = r[np.asarray(used, dtype=bool)]
        ranges = tuple(int(v) for v in np.unique(r[np.isfinite(r)]))
    return RecordedWith(circuit, opamp, ranges)
