"""Several FSRs on one meter: a multi-channel run split by channel, calibrated per channel, and the
cross-talk check (docs/multiplexing.md).

A run recorded with ``acquire --channels`` is in the long format, one row per channel reading with a
``channel`` column and the channel map in its sidecar (``channels``: each channel's ``sensor_id``).
:func:`channel_runs` splits it into one :class:`~fsrlab.io.runformat.Run` per channel (its rows, and a
sidecar whose ``sensor`` is that channel's); :func:`calibrate_channels` calibrates each with the one
calibration engine (:func:`fsrlab.calibrate`) and keys the results by sensor id. Nothing here fits
anything itself.

:func:`crosstalk` is the cross-talk check: with every sensor unloaded, then with one channel at a
time loaded, it records a short scan and reports the 8×8 matrix of frequency changes, each row
normalised by the loaded channel's own change.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fsrlab.errors import ParameterError

__all__ = ["channel_runs", "ChannelCalibrations", "calibrate_channels", "Crosstalk", "crosstalk",
           "virtual_meter", "twin_meter",
           "SeveralSensors", "several_sensors"]


def channel_runs(run) -> dict[int, object]:
    """One run per channel of a multi-channel run.

    Parameters
    ----------
    run : Run or path
        A run with a ``channel`` column (``acquire --channels``).

    Returns
    -------
    dict of int to Run
        Channel → its rows (in time order) and a sidecar whose ``sensor`` and ``channel`` are that
        channel's entry of the channel map (``sensor_id`` included).
    """
    from fsrlab.io.runformat import Run, load_run

    if not isinstance(run, Run):
        run = load_run(run)
    if "channel" not in run.columns:
        raise ParameterError(f"{run.path} has no channel column: not a multi-channel run (acquire --channels)",
                             parameter="run")
    ch = run.columns["channel"]
    entries = {e.get("channel"): e for e in run.metadata.get("channels") or () if isinstance(e, dict)}
    out = {}
    for k in sorted({int(c) for c in ch[np.isfinite(ch)]}):
        rows = ch == k
        entry = entries.get(k, {"channel": k, "sensor_id": f"fsr{k}"})
        meta = dict(run.metadata)
        meta["channel"] = entry
        meta["sensor"] = {**(run.metadata.get("sensor") or {}), **(entry.get("sensor") or {}),
                          "sensor_id": entry.get("sensor_id", f"fsr{k}")}
        out[k] = replace(run, columns={name: col[rows] for name, col in run.columns.items()}, metadata=meta)
    return out


@dataclass(frozen=True)
class ChannelCalibrations:
    """Every channel's calibration of a multi-channel run, keyed by sensor id.

    Attributes
    ----------
    by_sensor : dict of str to Calibration
        Sensor id → its calibration (:func:`fsrlab.calibrate`'s result).
    channels : dict of str to int
        Sensor id → the channel it was recorded on.
    """

    by_sensor: dict
    channels: dict

    def apply(self, run) -> dict:
        """Each calibrated channel's estimate (:meth:`Calibration.estimate`) on a multi-channel run.

        Parameters
        ----------
        run : Run or path
            A multi-channel run; its channels are matched to the calibrations by sensor id (its channel map).

        Returns
        -------
        dict of str to Run
            Sensor id → that channel's rows with ``<reference>_estimate``, ``<reference>_uncertainty`` and
            ``in_range``; sensors of the run without a calibration are left out.
        """
        out = {}
        for sub in channel_runs(run).values():
            sid = sub.metadata["sensor"]["sensor_id"]
            if sid in self.by_sensor:
                out[sid] = self.by_sensor[sid].estimate(sub)
        if not out:
            raise ParameterError(f"no sensor of the run has a calibration here (calibrated: "
                                 f"{', '.join(sorted(self.by_sensor))})", parameter="run")
        return out

    def save(self, path, overwrite: bool = False, inputs=()) -> Path:
        """Write :meth:`to_dict` as JSON (the output policy of :mod:`fsrlab.io.outputs`: atomic, an existing
        file replaced only with ``overwrite``, never one of ``inputs``)."""
        import json

        from fsrlab.io.outputs import check_output, write_text_atomic

        out = check_output(path, "path", overwrite=overwrite, inputs=inputs)
        return write_text_atomic(out, json.dumps(self.to_dict(), indent=2, default=_jsonable) + "\n")

    def to_dict(self) -> dict:
        """``{"kind": "fsrlab multi-channel calibration", "sensors": {id: {"channel", "calibration"}}}``."""
        return {"kind": "fsrlab multi-channel calibration",
                "sensors": {sid: {"channel": self.channels[sid], "calibration": cal.to_dict()}
                            for sid, cal in self.by_sensor.items()}}


def _jsonable(value):
    """numpy scalars and arrays in a calibration's dictionary, as JSON numbers and lists."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def calibrate_channels(run, **options) -> ChannelCalibrations:
    """Calibrate each channel of a multi-channel run (one call of :func:`fsrlab.calibrate` per channel).

    Parameters
    ----------
    run : Run or path
        A run with a ``channel`` column and a reference (``stress_pa`` or ``force_n``) for the channels
        to calibrate; a channel whose reference column is empty throughout (the load cell sits under
        another channel) is left out.
    **options
        Passed to :func:`fsrlab.calibrate` (``x``, ``reference``, ``compensate``, ...).

    Returns
    -------
    ChannelCalibrations
    """
    from fsrlab.calibration.runs import calibrate_runs

    by_sensor, channels = {}, {}
    reference = options.get("reference")
    for k, sub in channel_runs(run).items():
        names = [reference] if reference else ["stress_pa", "force_n"]
        if not any(n in sub.columns and np.any(np.isfinite(sub.columns[n])) for n in names):
            continue
        sid = sub.metadata["sensor"]["sensor_id"]
        by_sensor[sid] = calibrate_runs(sub, **options)
        channels[sid] = k
    if not by_sensor:
        raise ParameterError("no channel has a reference (stress_pa or force_n) to calibrate against",
                             parameter="run")
    return ChannelCalibrations(by_sensor, channels)


@dataclass(frozen=True)
class Crosstalk:
    """The cross-talk check's result.

    Attributes
    ----------
    channels : tuple of int
        The channels, in matrix order.
    baseline_hz : ndarray, shape (n,)
        Each channel's mean frequency with every sensor unloaded. [Hz]
    loaded_hz : ndarray, shape (n, n)
        Row j: each channel's mean frequency with channel j loaded. [Hz]
    matrix : ndarray, shape (n, n)
        ``(loaded_hz[j, k] − baseline_hz[k]) / (loaded_hz[j, j] − baseline_hz[j])``: the diagonal is 1, an
        off-diagonal entry is the share of channel j's change that channel k shows. [1]
    resolution : ndarray, shape (n,)
        Each channel's relative standard deviation of single readings in the baseline: the scale below
        which an off-diagonal entry is noise (in units of the loaded channel's change). [1]
    """

    channels: tuple
    baseline_hz: np.ndarray
    loaded_hz: np.ndarray
    matrix: np.ndarray
    resolution: np.ndarray

    @property
    def worst(self) -> float:
        """Largest off-diagonal entry in magnitude. [1]"""
        m = np.abs(self.matrix.copy())
        np.fill_diagonal(m, 0.0)
        return float(m.max()) if m.size else math.nan

    def to_dict(self) -> dict:
        """JSON-ready: ``channels``, ``baseline_hz``, ``loaded_hz``, ``matrix``, ``worst``."""
        return {"channels": list(self.channels), "baseline_hz": self.baseline_hz.tolist(),
                "loaded_hz": self.loaded_hz.tolist(), "matrix": self.matrix.tolist(), "worst": self.worst}


def _scan_means(open_meter, source, channels, duration_s: float, path: Path):
    from fsrlab.acquisition.recorder import Scan, record
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.io.runformat import load_run

    with open_meter(source) as port, SerialLink(port) as link:
        result = record(link, path, duration_s, scan=Scan(tuple(channels)), clock="device", overwrite=True)
    if result.failed:
        raise RuntimeError(f"cross-talk recording failed: {result.message}")
    run = load_run(path)
    ch, f = run.columns["channel"], run.columns["frequency_hz"]
    empty = [k for k in channels if not np.any(np.isfinite(f[ch == k]))]
    if empty:
        raise RuntimeError(f"cross-talk: channel {empty[0]} gave no reading in {duration_s:g} s of simulated time; "
                           "give a longer duration (each channel needs its dwell and settling in every scan)")
    means = np.array([np.nanmean(f[ch == k]) for k in channels])
    spread = np.array([np.nanstd(f[ch == k]) / np.nanmean(f[ch == k]) for k in channels])
    return means, spread


def crosstalk(open_meter, channels=tuple(range(8)), load_pa: float = 50e3, duration_s: float = 0.5,
              workdir=None) -> Crosstalk:
    """Load one channel at a time, read all of them: the cross-talk matrix.

    Parameters
    ----------
    open_meter : callable
        ``open_meter(source)`` → a context manager yielding a serial port of a meter driven by that
        :class:`~fsrlab.virtual.sources.MuxSource` at the device's clock (the twin or the virtual device at
        ``speed="max"``; see :func:`virtual_meter`).
    channels : sequence of int
        The channels (0..7).
    load_pa : float
        Stress on the loaded channel (the others: none). [Pa]
    duration_s : float
        Simulated time per recording (one unloaded, one per channel). [s]
    workdir : path, optional
        Where the recordings are written (default a temporary folder, removed afterwards).

    Returns
    -------
    Crosstalk
    """
    import tempfile

    from fsrlab.virtual.sources import MuxSource, StressProfile

    chans = tuple(int(k) for k in channels)
    if not (math.isfinite(load_pa) and load_pa > 0):
        raise ParameterError(f"must be > 0 Pa, got {load_pa!r}", parameter="load_pa")
    n = max(chans) + 1
    rest = StressProfile("hold", peak_pa=1.0, period_s=1.0)  # (no load: 1 Pa, the profile needs a peak > 0)
    loaded = StressProfile("hold", peak_pa=load_pa, period_s=1.0)
    at_rest = MuxSource.scaled(1, rest).sources[0]  # (one sensor model, the same on every channel)
    under_load = MuxSource.scaled(1, loaded).sources[0]

    def bench(j: int | None):
        return MuxSource([under_load if k == j else at_rest for k in range(n)])

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(workdir) if workdir is not None else Path(tmp)
        base, spread = _scan_means(open_meter, bench(None), chans, duration_s, folder / "crosstalk-none.csv")
        rows = [_scan_means(open_meter, bench(j), chans, duration_s, folder / f"crosstalk-{j}.csv")[0] for j in chans]
    loaded_hz = np.vstack(rows)
    change = loaded_hz - base[None, :]
    matrix = change / np.diag(change)[:, None]
    return Crosstalk(chans, base, loaded_hz, matrix, spread / np.abs(np.diag(change) / base))


def virtual_meter(source):
    """``open_meter`` for :func:`crosstalk`: the Python virtual device at ``speed="max"``, no load cell.

    Parameters
    ----------
    source : MuxSource
        The sensors behind the multiplexer.

    Returns
    -------
    context manager
        Yields the meter's serial port (a pty path).
    """
    from contextlib import contextmanager

    from fsrlab.virtual.device import VirtualDevice

    @contextmanager
    def opened():
        with VirtualDevice(source, seed=0, speed="max", load_cell=None) as dev:
            yield dev.port

    return opened()


def twin_meter(source):
    """``open_meter`` for :func:`crosstalk`: the digital twin (the real firmware in simavr) at ``speed="max"``.

    Parameters
    ----------
    source : MuxSource
        The sensors behind the multiplexer.

    Returns
    -------
    context manager
        Yields the meter's serial port (a pty path).
    """
    from contextlib import contextmanager

    from fsrlab.virtual.twin import Twin

    @contextmanager
    def opened():
        with Twin(source, speed="max") as twin:
            yield twin.port
            if twin.failure is not None:
                raise RuntimeError(twin.failure)

    return opened()


@dataclass(frozen=True)
class SeveralSensors:
    """What :func:`several_sensors` did: a multi-channel run, its per-channel calibration and the cross-talk.

    Attributes
    ----------
    run : Path
        The long-format run (one row per channel reading).
    calibration : Path
        Every channel's calibration, keyed by sensor id (:meth:`ChannelCalibrations.save`).
    calibrations : ChannelCalibrations
    crosstalk : Crosstalk
    readings_per_s : ndarray, shape (n,)
        Each channel's readings per second of the device's clock. [1/s]
    peak_hz : ndarray, shape (n,)
        Each channel's highest frequency in the run. [Hz]
    """

    run: Path
    calibration: Path
    calibrations: ChannelCalibrations
    crosstalk: Crosstalk
    readings_per_s: np.ndarray
    peak_hz: np.ndarray


def several_sensors(out, channels: int = 8, duration_s: float = 2.0, peak_pa: float = 50e3, period_s: float = 1.0,
                    crosstalk_s: float = 0.3, overwrite: bool = False) -> SeveralSensors:
    """Several sensors on one meter, end to end on the Python virtual device at ``speed="max"``: record a scan,
    calibrate every channel from it, and run the cross-talk check.

    Channel k is under a triangle of ``peak_pa`` · (k + 1)/``channels``
    (:meth:`~fsrlab.virtual.sources.MuxSource.scaled`); the run's reference is the stress the device applied
    in each reading (``stress_pa``).

    Parameters
    ----------
    out : path-like
        Directory (created) for ``channels-run.csv`` (and its sidecar) and ``channels-calibration.json``.
    channels : int
        Sensors, 1..8, on channels 0..channels−1. [1]
    duration_s : float
        The run's length on the device's clock. [s]
    peak_pa : float
        The last channel's peak stress. [Pa]
    period_s : float
        Period of the triangle. [s]
    crosstalk_s : float
        Simulated time per cross-talk recording (one unloaded, one per channel). [s]
    overwrite : bool
        Replace the run and the calibration when they exist.

    Returns
    -------
    SeveralSensors
    """
    from fsrlab.acquisition.recorder import Scan, record
    from fsrlab.acquisition.serial_link import SerialLink
    from fsrlab.io.runformat import load_run
    from fsrlab.virtual.device import VirtualDevice
    from fsrlab.virtual.sources import MuxSource, StressProfile

    if isinstance(channels, bool) or not isinstance(channels, int) or not 1 <= channels <= 8:
        raise ParameterError(f"must be an integer 1..8, got {channels!r}", parameter="channels")
    if not (isinstance(duration_s, int | float) and math.isfinite(duration_s) and duration_s > 0):
        raise ParameterError(f"must be > 0 s, got {duration_s!r}", parameter="duration_s")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path, cal_path = out / "channels-run.csv", out / "channels-calibration.json"
    source = MuxSource.scaled(channels, StressProfile("triangle", peak_pa=peak_pa, period_s=period_s))
    scan = Scan(tuple(range(channels)))
    with VirtualDevice(source, seed=0, speed="max") as dev, SerialLink(dev.port) as link:
        result = record(link, path, duration_s, scan=scan, clock="device", metadata=source.metadata(),
                        reference=lambda f: dev.reference(f.seq), overwrite=overwrite)
    if result.failed:
        raise RuntimeError(f"the multi-channel recording failed: {result.message}")
    cals = calibrate_channels(path)
    cals.save(cal_path, overwrite=overwrite, inputs=(path,))
    run = load_run(path)
    ch, f = np.asarray(run.columns["channel"], dtype=int), np.asarray(run.columns["frequency_hz"])
    rates = np.array([np.sum(ch == k) / duration_s for k in scan.channels])
    peaks = np.array([np.nanmax(f[ch == k]) for k in scan.channels])
    talk = crosstalk(virtual_meter, scan.channels, peak_pa, crosstalk_s)
    return SeveralSensors(path, cal_path, cals, talk, rates, peaks)
