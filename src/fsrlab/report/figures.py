"""Matplotlib helpers for report figures (non-interactive backend, imported only when drawing)."""

from __future__ import annotations

from pathlib import Path


def new_figure(width: float = 6.4, height: float = 4.2):
    """Return ``(fig, ax)`` drawn with the Agg backend, no display needed."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(width, height), dpi=110)
    ax.grid(True, alpha=0.3)
    return fig, ax


def save(fig, path: Path) -> Path:
    """Save ``fig`` as PNG at ``path`` and close it."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, format="png")
    plt.close(fig)
    return path
