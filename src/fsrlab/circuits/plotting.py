"""Drawing for the circuits' result objects (``AstableResult.plot``, ``DecodeResult.plot``).

Values stay in SI; the axes show them in engineering notation (``kHz``, ``kΩ``, ``nF``) or as a
percentage, so a line's data are the result's own arrays. matplotlib is imported only when drawing.
"""

from __future__ import annotations

import numpy as np

from fsrlab.errors import ParameterError

__all__ = ["plot_twin"]


def plot_twin(x, left, right, ax=None, xlabel: str | None = None):
    """Two quantities against one abscissa, the second on a twin y axis, with optional ±1σ bands.

    Parameters
    ----------
    x : array_like
        Abscissa, one value per point (1-D).
    left, right : tuple
        ``(y, std, label, unit)`` of each quantity: the values (same length as ``x``), their standard
        deviation drawn as a ±1σ band (None: no band), the name for the axis and legend, and the
        unit of an engineering-notation axis (``"Hz"``, ``"Ω"``, ``"F"``) or ``"%"`` for a fraction
        shown in percent.
    ax : matplotlib.axes.Axes, optional
        Axes for ``left`` (default: a new figure); ``right`` goes on its twin.
    xlabel : str, optional
        Label of the x axis.

    Returns
    -------
    (matplotlib.axes.Axes, matplotlib.axes.Axes)
        The axes of ``left`` and of ``right``.

    Raises
    ------
    ParameterError
        ``x`` or a quantity is not 1-D, or their lengths differ.
    """
    import matplotlib.pyplot as plt
    from matplotlib.ticker import EngFormatter, PercentFormatter

    xs = np.atleast_1d(np.asarray(x, dtype=float))
    if xs.ndim != 1:
        raise ParameterError(f"needs one value per point (1-D), got shape {xs.shape}", parameter="x")
    if ax is None:
        _, ax = plt.subplots(layout="constrained")
    axes = (ax, ax.twinx())
    handles = []
    for axis, (y, std, label, unit), color, side in zip(axes, (left, right), ("C0", "C1"), ("left", "right"),
                                                        strict=True):
        ys = np.atleast_1d(np.asarray(y, dtype=float))
        if ys.shape != xs.shape:
            raise ParameterError(f"{label} needs one value per x ({xs.size}), got shape {ys.shape}", parameter=side)
        (line,) = axis.plot(xs, ys, color=color, marker="o" if xs.size == 1 else None, label=label)
        handles.append(line)
        if std is not None:
            sd = np.atleast_1d(np.asarray(std, dtype=float))
            axis.fill_between(xs, ys - sd, ys + sd, color=color, alpha=0.25, linewidth=0, label=f"{label} ±1σ")
        axis.yaxis.set_major_formatter(PercentFormatter(1.0) if unit == "%" else EngFormatter(unit=unit))
        axis.set_ylabel(label, color=color)
    if xlabel:
        ax.set_xlabel(xlabel)
    ax.legend(handles=handles, loc="best")
    return axes
