"""The report's fixed figure layout (fsrlab.reports.figures.fixed_layout).

Reference: matplotlib's own measurement of what it draws (each axes' tight bounding box, tick labels,
axis labels and titles included) must lie inside the figure: a property that fails when a margin is
too small for the report's style.
"""

from __future__ import annotations

import pytest

from fsrlab.reports.figures import fixed_layout, new_figure


@pytest.mark.parametrize("panels, title_lines, suptitle", [(1, 1, False), (2, 2, False), (2, 1, True)])
def test_labels_titles_and_ticks_stay_inside_the_figure(panels, title_lines, suptitle):
    fig, _ = new_figure(11.0 if panels == 2 else 6.4, 4.2)
    fig.clf()
    axes = fig.subplots(1, panels, squeeze=False)[0]
    for ax in axes:
        ax.plot([1e-3, 2e4], [-1.5e3, 9.9e4])  # wide tick labels on both axes
        ax.set_xlabel("N = R_FSR / R")
        ax.set_ylabel("separation s (nm)")
        ax.set_title("\n".join(["Figure 12: τH/τL vs N"] * title_lines))
    if suptitle:
        fig.suptitle("SYNTHETIC data, not the paper's measurements", fontsize=9)
    fixed_layout(fig)
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    for ax in axes:
        tight = ax.get_tightbbox(renderer)
        assert tight.x0 >= box.x0 and tight.y0 >= box.y0 and tight.x1 <= box.x1 and tight.y1 <= box.y1
    if panels == 2:  # the right panel's y label clears the left panel
        assert axes[1].get_tightbbox(renderer).x0 > axes[0].get_window_extent(renderer).x1
    if suptitle:
        assert fig._suptitle.get_window_extent(renderer).y0 > max(a.get_tightbbox(renderer).y1 for a in axes)


def test_plain_log_labels_name_the_decades_without_mathtext():
    # Reference: the decade values themselves; the labels are plain text (no "$...$" for mathtext to parse).
    from fsrlab.reports.figures import plain_log_labels

    fig, ax = new_figure()
    ax.semilogx([4.0, 1e4], [0.0, 1.0])
    plain_log_labels(ax.xaxis)
    fig.canvas.draw()
    lo, hi = ax.get_xlim()
    shown = [(t.get_position()[0], t.get_text()) for t in ax.get_xticklabels() if lo <= t.get_position()[0] <= hi]
    assert [text for _, text in shown] == ["10", "100", "1000", "10000"]
    assert all(float(text) == x for x, text in shown)


def _draw(kind: str, new, out):
    # Figures that leave much behind on their axes: log scale, fixed limits, spans, lines, a legend, titles.
    import numpy as np

    from fsrlab.reports.figures import plain_log_labels, save

    if kind == "log":
        fig, ax = new()
        ax.semilogx(np.geomspace(4, 1e4, 50), np.linspace(0, 1, 50), "C0-", label="a")
        plain_log_labels(ax.xaxis)
        ax.axhspan(0.2, 0.4, color="0.9")
        ax.set(ylim=(-1, 2), xlabel="N", ylabel="DC", title="two\nlines")
        ax.legend(fontsize=7)
    elif kind == "two":
        fig, axes = new(11.0, 4.2, ncols=2)
        for k, ax in enumerate(axes):
            ax.plot([0, 1, 2], [k, 3, 1], label=f"{k}")
            ax.axvline(1.5, color="C3")
            ax.set(title=f"panel {k}", xlim=(0, 3))
            ax.legend()
    else:
        fig, ax = new()
        for k in range(3):
            ax.plot([0, 10, 20], [k, 2 * k, k * k])  # the colour cycle from its start
        ax.set(xlabel="σ (kPa)", title="plain")
    return save(fig, out / f"{kind}.png").read_bytes()


def test_a_saved_figure_drawn_again_gives_the_png_of_a_new_one(tmp_path, monkeypatch):
    # Reference: the same figures on new matplotlib figures (the pool of saved figures emptied each time).
    import fsrlab.reports.figures as figures

    order = ["log", "plain", "two", "plain", "log", "two", "plain"]
    reused = [_draw(k, figures.new_figure, tmp_path) for k in order]

    def fresh(*args, **kwargs):
        figures._SAVED.clear()
        return figures.new_figure(*args, **kwargs)

    assert [_draw(k, fresh, tmp_path) for k in order] == reused


def test_report_figures_are_not_pyplots_and_survive_its_close_all(tmp_path):
    """A user's pyplot (a notebook, another test) never sees the report's figures: plt.gcf() after a report is
    not one of them, and pyplot's close("all"), which turns a figure of its own into the base canvas (it
    cannot render), leaves a kept figure drawable."""
    import matplotlib.pyplot as plt

    from fsrlab.reports.figures import save

    shown = plt.get_fignums()
    fig, ax = new_figure(5.1, 3.3)
    assert plt.get_fignums() == shown
    ax.plot([0, 1], [0, 1])
    save(fig, tmp_path / "a.png")
    current = plt.gcf()
    assert current is not fig
    plt.close("all")
    again, ax2 = new_figure(5.1, 3.3)
    assert hasattr(again.canvas, "get_renderer")
    ax2.plot([0, 1], [1, 0])
    assert save(again, tmp_path / "b.png").stat().st_size > 0
