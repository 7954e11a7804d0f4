"""How the live page writes numbers and texts into its HTML."""

from __future__ import annotations

import math

__all__ = ["fmt", "html_text"]


def fmt(v, spec: str) -> str:
    """``v`` formatted by ``spec``; a dash for None, NaN or infinity (no reading yet, no oscillation).

    Parameters
    ----------
    v : float, int or None
        The value.
    spec : str
        A format specification, e.g. ``.2f``.
    """
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def html_text(text) -> str:
    """A text the page shows inside its HTML (messages, file names, the device, the event log, sensor ids): control
    characters as their escapes (:func:`fsrlab.io.shown.printable`, the one rendering boundary), then ``&``,
    ``<`` and ``>`` as entities, so that neither a terminal escape nor markup in a file name acts on the page.

    Parameters
    ----------
    text : object
        What to show (made a string first).
    """
    import html

    from fsrlab.io.shown import printable

    return html.escape(printable(str(text)), quote=False)
