"""Matplotlib helpers for report figures (non-interactive backend, imported only when drawing)."""

from __future__ import annotations

from pathlib import Path


def preload() -> None:
    """Import matplotlib's figure and its Agg canvas now (what :func:`new_figure` uses; not pyplot).

    The report imports them before it forks its second process (:func:`fsrlab.reports.paper.build_sections`),
    which then shares them instead of importing them again (about 0.4 s of CPU).
    """
    import matplotlib.backends.backend_agg  # noqa: F401
    import matplotlib.figure  # noqa: F401


#: Figures saved by :func:`save` and ready to be drawn again, by (width, height, ncols, sharey): drawing on
#: a used figure keeps its axes and their tick objects, which a new figure would make again.
_SAVED: dict = {}


def new_figure(width: float = 6.4, height: float = 4.2, ncols: int = 1, sharey: bool = False):
    """Return ``(fig, ax)`` drawn with the Agg backend, no display needed; ``(fig, axes)`` for ``ncols`` > 1.

    The figure is not pyplot's (``plt.gcf()`` never returns it). A figure of the same layout that
    :func:`save` has saved is cleared and handed out again: its axes
    and their tick objects stay (making them is about a fifth of a report figure's time), everything
    drawn on them goes, and the PNGs are the same to the byte as from a new figure
    (tests/reports/test_figures.py).

    Parameters
    ----------
    width, height : float
        Figure size. [in]
    ncols : int
        Panels side by side.
    sharey : bool
        The panels share their y axis.
    """
    key = (float(width), float(height), int(ncols), bool(sharey))
    fig = None
    while _SAVED.get(key) and fig is None:
        fig = _SAVED[key].pop()
        if type(fig.canvas).__name__ != "FigureCanvasAgg":  # closed elsewhere (plt.close("all")): not reused
            fig = None
    if fig is not None:
        for ax in fig.axes:
            _clear(ax)
    else:
        # A figure of its own Agg canvas, not pyplot's: pyplot never makes it the current figure (a user's
        # plt.plot() after a report lands on a figure of theirs) nor closes it (plt.close("all")).
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        fig = Figure(figsize=(width, height), dpi=110)
        FigureCanvasAgg(fig)
        fig.subplots(1, ncols, sharey=sharey)
        fig._fsrlab_layout = key
        for ax in fig.axes:
            ax.grid(True, alpha=0.3)
    return fig, (fig.axes if ncols > 1 else fig.axes[0])


def _clear(ax) -> None:
    """Everything drawn on ``ax`` removed and its settings back to a new axes' (the grid kept)."""
    for artist in [*ax.lines, *ax.patches, *ax.collections, *ax.texts, *ax.images, *ax.tables, *ax.artists]:
        artist.remove()
    if ax.get_legend() is not None:
        ax.get_legend().remove()
    for loc in ("left", "center", "right"):
        ax.set_title("", loc=loc)
    ax.set_xlabel("")
    ax.set_ylabel("")
    ax.set_prop_cycle(None)
    ax.set_xscale("linear")
    ax.set_yscale("linear")
    ax.ignore_existing_data_limits = True
    ax.relim()
    ax.set_autoscale_on(True)
    ax.autoscale_view()


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
    """Save ``fig`` as PNG at ``path`` (fixed layout, :func:`fixed_layout`); a figure of :func:`new_figure`
    is kept to be drawn again, a figure of pyplot's closed.

    Written under a temporary name and renamed (:func:`fsrlab.io.outputs.atomic_path`): an interrupted
    report leaves the old figure or the whole new one under ``path``, never half of one.
    """
    from fsrlab.io.outputs import atomic_path

    fixed_layout(fig)
    saved = False
    try:
        with atomic_path(path) as tmp:
            # zlib level 3, not PIL's 6: the same pixels, about a third less time to compress, 3 % more bytes.
            fig.savefig(tmp, format="png", pil_kwargs={"compress_level": 3})
        saved = True
    finally:
        layout = getattr(fig, "_fsrlab_layout", None)
        if saved and layout is not None and fig.get_suptitle() == "" and not fig.texts and not fig.legends:
            _SAVED.setdefault(layout, []).append(fig)
        elif layout is None:  # a figure of pyplot's (a result's .plot()): pyplot lets it go
            import matplotlib.pyplot as plt

            plt.close(fig)
    return path
