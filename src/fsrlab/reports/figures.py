"""Matplotlib helpers for report figures (non-interactive backend, imported only when drawing)."""

from __future__ import annotations

from pathlib import Path


def preload() -> None:
    """Import matplotlib with the Agg backend, and pyplot, now.

    The report imports them before it forks its second process (:func:`fsrlab.reports.paper.build_sections`),
    which then shares them instead of importing them again (about half a second of CPU).
    """
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot  # noqa: F401


def new_figure(width: float = 6.4, height: float = 4.2, ncols: int = 1, sharey: bool = False):
    """Return ``(fig, ax)`` drawn with the Agg backend, no display needed; ``(fig, axes)`` for ``ncols`` > 1.

    Parameters
    ----------
    width, height : float
        Figure size. [in]
    ncols : int
        Panels side by side.
    sharey : bool
        The panels share their y axis.
    """
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, ncols, figsize=(width, height), dpi=110, sharey=sharey)
    for ax in axes if ncols > 1 else [axes]:
        ax.grid(True, alpha=0.3)
    return fig, axes


def plain_log_labels(axis) -> None:
    """Label a logarithmic axis's decades as plain numbers (10, 100, 1000), not as powers (10², by mathtext).

    The same ticks and values; mathtext's parser costs about 0.15 s to build in each process and a few
    milliseconds per label in each figure (its cache belongs to the figure's renderer).

    Parameters
    ----------
    axis : matplotlib.axis.Axis
        E.g. ``ax.xaxis`` after ``ax.semilogx(...)``.
    """
    from matplotlib.ticker import LogFormatter

    axis.set_major_formatter(LogFormatter())


#: Fixed margins of every report figure [in]: room for the tick labels and axis labels on the left and
#: bottom, an axes title on top (more with a figure title), and the gap between side-by-side panels.
MARGINS_IN = {"left": 0.85, "right": 0.2, "bottom": 0.6, "top": 0.15, "title_line": 0.22, "suptitle": 0.3, "gap": 0.85}


def fixed_layout(fig) -> None:
    """Place the axes with :data:`MARGINS_IN`: a fixed layout, without ``tight_layout``'s extra draw.

    ``tight_layout`` renders every figure once more to measure its labels (about as long as saving it);
    the report's figures share one style, so fixed margins in inches fit them all (the top grows with the
    number of lines of the axes' titles and with a figure title).
    """
    width, height = fig.get_size_inches()
    m = MARGINS_IN
    lines = max((len(ax.get_title().splitlines()) for ax in fig.axes), default=0)
    top = m["top"] + m["title_line"] * lines + (m["suptitle"] if getattr(fig, "_suptitle", None) is not None else 0.0)
    cols = max((ax.get_subplotspec().get_gridspec().ncols for ax in fig.axes if ax.get_subplotspec()), default=1)
    panel = (width - m["left"] - m["right"] - (cols - 1) * m["gap"]) / cols
    fig.set_layout_engine("none")
    fig.subplots_adjust(left=m["left"] / width, right=1 - m["right"] / width, bottom=m["bottom"] / height,
                        top=1 - top / height, wspace=m["gap"] / panel if cols > 1 else 0.2)


def save(fig, path: Path) -> Path:
    """Save ``fig`` as PNG at ``path`` (fixed layout, :func:`fixed_layout`) and close it.

    Written under a temporary name and renamed (:func:`fsrlab.io.outputs.atomic_path`): an interrupted
    report leaves the old figure or the whole new one under ``path``, never half of one.
    """
    import matplotlib.pyplot as plt

    from fsrlab.io.outputs import atomic_path

    fixed_layout(fig)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png")
    finally:
        plt.close(fig)
    return path
