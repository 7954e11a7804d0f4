"""Loading and unloading branches and cycles of a run, and the hysteresis error (eq. 13) from data.

A run of a loading bench (paper §6.1: stepper motor and spring) goes up and down in stress. The
branches are found from the ``direction`` column when the run has one (+1 loading, -1 unloading,
0 hold), otherwise from the reference stress itself: a turning point is confirmed once the stress
has moved back from its running extremum by more than a threshold (a fraction of the run's stress
span), which ignores noise smaller than the threshold. A cycle is a loading branch followed by an
unloading branch; the turning-point reading belongs to both, so each branch spans the full range.

:func:`row_directions` and :func:`row_cycles` are the one rule for a run's branches and cycles
(its columns when present, else from the stress), used by :func:`split_cycles`.

The hysteresis error itself is eq. (13) as implemented by
:func:`fsrlab.metrics.hysteresis.hysteresis_error` (branches interpolated onto a common stress
axis); this module only feeds it the branches, per cycle and for the run as a whole.

References
----------
A. Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901, eq. (13), §6.1, Table 3.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fsrlab.errors import ParameterError
from fsrlab.physics.history import branch_directions, cycle_numbers
from fsrlab.physics.params import check_finite, float_array

__all__ = [
    "Cycle",
    "readout_directions",
    "split_cycles",
    "RunHysteresis",
    "run_hysteresis",
]


@dataclass(frozen=True)
class Cycle:
    """One loading-unloading cycle of a run.

    Parameters
    ----------
    number : int
        Cycle number (0, 1, ...; the ``cycle`` column's value when the run has one).
    load_index : ndarray of int
        Row indices of the loading branch, in time order.
    unload_index : ndarray of int
        Row indices of the unloading branch, in time order.
    """

    number: int
    load_index: np.ndarray
    unload_index: np.ndarray

    @property
    def index(self) -> np.ndarray:
        """All rows of the cycle (loading then unloading, the turning point once)."""
        return np.unique(np.concatenate([self.load_index, self.unload_index]))


def _column(name: str, value, n: int | None = None) -> np.ndarray:
    """``value`` as a 1-D float array (of ``n`` values when given); an error naming ``name`` when it is not."""
    x = float_array(name, value)
    if x.ndim != 1:
        raise ParameterError(f"must be a 1-D array, got shape {x.shape}", parameter=name)
    if n is not None and x.size != n:
        raise ParameterError(f"must have the same length as stress_pa ({n}), got {x.size}", parameter=name)
    return x


def readout_directions(x, sign: float = 1.0, threshold: float = 0.05) -> np.ndarray:
    """Label readings +1 (loading) / -1 (unloading) from a readout sequence alone, gaps included.

    Parameters
    ----------
    x : array_like, shape (n,)
        Readout in time order (frequency [Hz], ...); NaN readings get the label of the previous
        valid one (the first valid one's before it).
    sign : {+1, -1}
        +1 if the readout grows with stress, -1 if it falls.
    threshold : float
        Reversal threshold as a fraction of the readout span (see :func:`turning_points`). [1]

    Returns
    -------
    ndarray of int, shape (n,)
        +1 or -1 for every reading: :func:`branch_directions` of ``sign * x`` over the valid
        readings, where a sequence that never moves beyond the threshold counts as loading.
    """
    x = _column("x", x)
    check_finite("sign", sign, scalar=True)
    if sign == 0:
        raise ParameterError("must be non-zero (+1: the readout rises with the load, -1: it falls)", parameter="sign")
    ok = np.flatnonzero(np.isfinite(x))
    lab = np.ones(x.size, dtype=int)
    if ok.size == 0:
        return lab
    sub = branch_directions(sign * x[ok], threshold)
    lab[ok] = np.where(sub == 0, 1, sub)
    # NaN readings: carry the last label forward (and the first backward).
    idx = np.where(np.isfinite(x), np.arange(x.size), 0)
    np.maximum.accumulate(idx, out=idx)
    lab = lab[idx]
    lab[: ok[0]] = lab[ok[0]]
    return lab


def row_directions(stress_pa, direction=None, cycle=None, threshold: float = 0.05) -> np.ndarray:
    """Direction of every reading of a run: its ``direction`` column, else found from the stress.

    Parameters
    ----------
    stress_pa : array_like, shape (n,)
        Reference stress in time order (NaN where a reading has none). [Pa]
    direction : array_like, optional
        The run's ``direction`` column (+1 loading, -1 unloading, 0 hold, NaN unknown); when given
        it decides and the stress is not examined.
    cycle : array_like, optional
        The run's ``cycle`` column; without a direction column, the branches are then found within
        each recorded cycle (its own stress span sets the threshold).
    threshold : float
        Reversal threshold as a fraction of the stress span (see :func:`turning_points`). [1]

    Returns
    -------
    ndarray of int, shape (n,)
        +1, -1 or 0: the direction column with NaN as 0, or :func:`branch_directions` of the
        readings that have a stress (0 for those that have none, or no cycle number).

    Raises
    ------
    ValueError
        A column of the wrong length, or a direction other than -1, 0, +1.
    """
    x = _column("stress_pa", stress_pa)
    n = x.size
    if direction is not None:
        dirn = _column("direction", direction, n)
        dirn = np.nan_to_num(dirn, nan=0.0)
        if not np.all(np.isin(dirn, (-1, 0, 1))):
            raise ParameterError("must hold -1 (unloading), 0 (hold) or +1 (loading)", parameter="direction")
        return dirn.astype(int)
    ok = np.isfinite(x)
    if cycle is not None:
        cyc = _column("cycle", cycle, n)
        groups = [np.flatnonzero(ok & (cyc == v)) for v in dict.fromkeys(cyc[~np.isnan(cyc)].tolist())]
    else:
        groups = [np.flatnonzero(ok)]
    labels = np.zeros(n, dtype=int)
    for rows in groups:
        if rows.size:
            labels[rows] = branch_directions(x[rows], threshold)
    return labels


def row_cycles(stress_pa, direction=None, cycle=None, threshold: float = 0.05) -> np.ndarray:
    """Cycle number of every reading of a run: its ``cycle`` column, else numbered from its directions.

    Parameters
    ----------
    stress_pa : array_like, shape (n,)
        Reference stress in time order. [Pa]
    direction, cycle : array_like, optional
        The run's ``direction`` and ``cycle`` columns (see :func:`row_directions`).
    threshold : float
        Reversal threshold as a fraction of the stress span. [1]

    Returns
    -------
    ndarray of float, shape (n,)
        The cycle column as given (NaN where empty), or :func:`cycle_numbers` of
        :func:`row_directions`.
    """
    if cycle is not None:
        return _column("cycle", cycle, _column("stress_pa", stress_pa).size)
    return cycle_numbers(row_directions(stress_pa, direction, None, threshold)).astype(float)


def _runs(labels: np.ndarray) -> list[tuple[int, int, int]]:
    """(value, start, stop) of runs of equal non-zero labels (zeros are skipped, they split nothing)."""
    idx = np.flatnonzero(labels != 0)
    if idx.size == 0:
        return []
    vals = labels[idx]
    brk = np.flatnonzero(vals[1:] != vals[:-1]) + 1
    starts = np.concatenate([[0], brk])
    stops = np.concatenate([brk, [idx.size]])
    return [(int(vals[s]), int(idx[s]), int(idx[e - 1]) + 1) for s, e in zip(starts, stops, strict=True)]


def _pair(labels: np.ndarray, x: np.ndarray, number0: int = 0, rows: np.ndarray | None = None) -> list[Cycle]:
    """Pair each loading run with the unloading run that follows it.

    The reading at a turning point belongs to both branches: at the top, whichever of the last
    loading reading and the first unloading reading has the larger stress is shared; at the bottom,
    the reading before the loading run is shared when it lies lower than the run's first reading.
    """
    rows = np.arange(labels.size) if rows is None else rows
    runs = _runs(labels)
    cycles = []
    k = 0
    while k < len(runs) - 1:
        (v1, a1, b1), (v2, a2, b2) = runs[k], runs[k + 1]
        if v1 == 1 and v2 == -1:
            load = list(range(a1, b1))
            unload = list(range(a2, b2))
            if a1 > 0 and labels[a1 - 1] == -1 and x[a1 - 1] <= x[a1]:
                load.insert(0, a1 - 1)
            if a2 == b1:
                if x[b1 - 1] >= x[a2]:
                    unload.insert(0, b1 - 1)
                else:
                    load.append(a2)
            cycles.append(Cycle(number0 + len(cycles), rows[np.array(load)], rows[np.array(unload)]))
            k += 2
        else:
            k += 1
    return cycles


def split_cycles(stress_pa, direction=None, cycle=None, threshold: float = 0.05) -> list[Cycle]:
    """Split a run into loading-unloading cycles.

    Parameters
    ----------
    stress_pa : array_like, shape (n,)
        Reference stress in time order. [Pa]
    direction : array_like, optional
        The run's ``direction`` column (+1 loading, -1 unloading, 0 hold, NaN unknown); when given
        it decides the branches and the stress is not examined.
    cycle : array_like, optional
        The run's ``cycle`` column; when given, rows are grouped by it (each group one cycle,
        numbered by its value) and the branches are found within each group.
    threshold : float
        Reversal threshold as a fraction of the stress span when branches come from the stress. [1]

    Returns
    -------
    list of Cycle
        Complete cycles only (a loading branch followed by an unloading branch), in time order.
        A run that starts while unloading or ends while loading has that part left out.
    """
    x = _column("stress_pa", stress_pa)
    labels = row_directions(x, direction, cycle, threshold)
    if cycle is not None:
        cyc = _column("cycle", cycle, x.size)
        out = []
        for value in dict.fromkeys(cyc[~np.isnan(cyc)].tolist()):
            rows = np.flatnonzero(cyc == value)
            for c in _pair(labels[rows], x[rows], 0, rows):
                out.append(Cycle(int(value) if float(value).is_integer() else len(out), c.load_index, c.unload_index))
        return out
    return _pair(labels, x)


@dataclass(frozen=True)
class RunHysteresis:
    """Hysteresis error of a run (eq. 13), per cycle and overall.

    Parameters
    ----------
    percent : float
        Overall HE: eq. (13) on the mean loading and mean unloading curves (each cycle's branch
        interpolated onto a common stress grid, then averaged over the cycles). [%]
    stress_at_max_pa : float
        Stress of the largest branch difference of the overall curves. [Pa]
    cycles : list
        One :class:`~fsrlab.metrics.hysteresis.HysteresisResult` per cycle.
    cycle_numbers : list of int
        The cycles' numbers.
    method : str
        How the branches were found and combined.
    overall : HysteresisResult or None
        Eq. (13) on the mean curves, with those curves (for :meth:`plot`).
    """

    percent: float
    stress_at_max_pa: float
    cycles: list = field(default_factory=list)
    cycle_numbers: list = field(default_factory=list)
    method: str = ""
    overall: Any = field(default=None, repr=False, compare=False)

    def plot(self, ax=None, label: str = "Q", cycles: bool = True):
        """Draw the mean loading and unloading branches, the largest difference and each cycle's branches.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw (default: a new figure).
        label : str
            Name of the quantity, for the axis label.
        cycles : bool
            Also draw every cycle's own branches, faintly, before the mean curves.

        Returns
        -------
        matplotlib.axes.Axes
            The last three lines are the mean loading branch, the mean unloading branch and the
            difference at σd (see :meth:`HysteresisResult.plot`).
        """
        from fsrlab.metrics.hysteresis import _draw_branches

        if self.overall is None or self.overall.stress_pa is None:
            raise ParameterError("this result holds no branches to plot (no cycle was found)")
        if ax is None:
            import matplotlib.pyplot as plt

            _, ax = plt.subplots()
        if cycles:
            for c in self.cycles:
                ax.plot(c.stress_pa, c.q_load, "-", color="tab:blue", alpha=0.25, lw=0.8)
                ax.plot(c.stress_pa, c.q_unload, "-", color="tab:orange", alpha=0.25, lw=0.8)
        _draw_branches(ax, self.overall, label)
        ax.set_title(f"hysteresis error (eq. 13): {self.percent:.2f} % over {len(self.cycles)} cycles")
        return ax

    def to_dict(self) -> dict[str, Any]:
        """The CLI's JSON shape."""
        return {
            "hysteresis_error_percent": self.percent,
            "stress_at_max_difference_pa": self.stress_at_max_pa,
            "cycles": [{"hysteresis_error_percent": float(c.percent),
                        "stress_at_max_difference_pa": float(c.stress_at_max_pa)} for c in self.cycles],
        }


def mean_branches(stress_pa, q, cycles: list[Cycle], points: int = 201):
    """Mean loading and unloading curves over cycles on a common stress grid.

    Parameters
    ----------
    stress_pa, q : array_like, shape (n,)
        Reference stress [Pa] and readout quantity [any unit].
    cycles : list of Cycle
        From :func:`split_cycles`.
    points : int
        Grid points between the largest branch start and the smallest branch end.

    Returns
    -------
    grid : ndarray
        Stress grid. [Pa]
    q_load, q_unload : ndarray
        Mean over cycles of each branch linearly interpolated onto ``grid``.
    """
    x = np.asarray(stress_pa, dtype=float)
    y = np.asarray(q, dtype=float)
    lo, hi = -np.inf, np.inf
    prepared = []
    for c in cycles:
        br = []
        for idx in (c.load_index, c.unload_index):
            xs, ys = x[idx], y[idx]
            keep = np.isfinite(xs) & np.isfinite(ys)
            xs, ys = xs[keep], ys[keep]
            o = np.argsort(xs, kind="stable")
            br.append((xs[o], ys[o]))
            lo, hi = max(lo, xs.min()), min(hi, xs.max())
        prepared.append(br)
    if not prepared or not hi > lo:
        raise ParameterError("the branches share no stress range", parameter="cycles")
    grid = np.linspace(lo, hi, points)
    ql = np.mean([np.interp(grid, *b[0]) for b in prepared], axis=0)
    qu = np.mean([np.interp(grid, *b[1]) for b in prepared], axis=0)
    return grid, ql, qu


def run_hysteresis(stress_pa, q, direction=None, cycle=None, threshold: float = 0.05, name: str = "the readout",
                   **kwargs) -> RunHysteresis:
    """Hysteresis error (eq. 13) of a run, per cycle and overall.

    Parameters
    ----------
    stress_pa : array_like, shape (n,)
        Reference stress in time order. [Pa]
    q : array_like, shape (n,)
        Readout quantity (frequency [Hz], voltage [V], calibrated stress [Pa], ...); NaN rows are
        skipped, as are rows whose stress is NaN (no reference reading).
    direction, cycle : array_like, optional
        The run's ``direction`` and ``cycle`` columns (see :func:`split_cycles`).
    threshold : float
        Reversal threshold as a fraction of the stress span. [1]
    name : str
        The readout's name in messages.
    **kwargs
        Passed to :func:`fsrlab.metrics.hysteresis.hysteresis_error`.

    Returns
    -------
    RunHysteresis

    Raises
    ------
    ValueError
        If the run holds no complete loading-unloading cycle, or ``q`` does not respond to the
        stress (:func:`fsrlab.metrics.hysteresis.check_response`: a constant readout has no
        hysteresis error, not 0 %).
    """
    from fsrlab.metrics.hysteresis import check_response, hysteresis_error

    x = _column("stress_pa", stress_pa)
    y = _column("q", q, x.size)
    direction = None if direction is None else _column("direction", direction, x.size)
    cycle = None if cycle is None else _column("cycle", cycle, x.size)
    # Readings without a reference stress (empty cells) take no part.
    keep = np.isfinite(x)
    if not keep.all():
        x, y = x[keep], y[keep]
        direction = None if direction is None else direction[keep]
        cycle = None if cycle is None else cycle[keep]
    cycles = split_cycles(x, direction, cycle, threshold)
    if not cycles:
        raise ParameterError("the run holds no complete loading-unloading cycle (need the stress to rise and fall "
                             "back by more than the threshold, or a direction column with +1 then -1)",
                             parameter="stress_pa")
    check_response(x, y, name)
    results = []
    for c in cycles:
        li = c.load_index[np.isfinite(y[c.load_index])]
        ui = c.unload_index[np.isfinite(y[c.unload_index])]
        results.append(hysteresis_error(x[li], y[li], x[ui], y[ui], **kwargs))
    grid, ql, qu = mean_branches(x, y, cycles)
    overall = hysteresis_error(grid, ql, grid, qu, **kwargs)
    how = "direction column" if direction is not None else f"stress reversals beyond {threshold:.0%} of the span"
    method = (f"branches from {how}; per cycle: eq. (13) via hysteresis_error ({overall.method}); "
              f"overall: eq. (13) on the mean of the {len(cycles)} cycles' branches on a common stress grid")
    return RunHysteresis(percent=float(overall.percent), stress_at_max_pa=float(overall.stress_at_max_pa),
                         cycles=results, cycle_numbers=[c.number for c in cycles], method=method,
                         overall=overall)
