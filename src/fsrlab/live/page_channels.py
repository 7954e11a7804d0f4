"""The live page for several sensors behind the meter's multiplexer: a sensor map and each channel's frequency.

The sensor map draws each scanned channel at its position (the channel map's ``x_m``, ``y_m``; in a grid
of four columns when a position is missing), coloured by its latest frequency (or, with a calibration,
its estimated force), with its link health (readings, missed edges, readings without oscillation) in
the hover and in a line under the map. Beside it, one plot holds every channel's frequency against time,
a line per channel, its colour shown before the sensor's id in the health line.

Rates are bounded whatever the scan delivers: the channels' new readings go out as one
``ColumnDataSource.stream`` per plot redraw (:data:`fsrlab.live.page.PLOT_S`: every channel in one source, a
row per scan), and the map is one ``ColumnDataSource.patch`` with the status line
(:data:`fsrlab.live.page.STATUS_S`), sent only when a channel has a new reading; the sources and glyphs are
made once. Measured in headless Chromium on this machine, a stream per channel and a patch at every redraw
(90 messages a second) slowed the page's script calls from tens of milliseconds to seconds.
"""

from __future__ import annotations

import math

from fsrlab.live.page_text import fmt, html_text

__all__ = ["ChannelPlots", "map_columns", "GRID_COLUMNS", "CHANNEL_POINTS"]

GRID_COLUMNS = 4
"""Sensors per row of the map when the channel map gives no positions."""
CHANNEL_POINTS = 2000
"""Scans the frequency plot keeps (the oldest roll over). [1]"""
PALETTE = "Viridis256"
"""The map's colours, low to high."""


def map_columns(channels: list[dict], estimated: bool) -> dict[str, list]:
    """The sensor map's columns from :meth:`~fsrlab.live.session.LiveSession.channels`.

    Parameters
    ----------
    channels : list of dict
        Each channel's latest reading and health.
    estimated : bool
        Colour by the estimate [N] rather than the frequency [kHz].

    Returns
    -------
    dict of list
        ``channel``, ``sensor_id``, ``x``, ``y`` (metres, or grid slots when a position is missing),
        ``frequency_khz``, ``estimate``, ``value`` (what the colour shows; NaN: no reading or no oscillation,
        drawn grey), ``readings``, ``missed``, ``no_oscillation``.
    """
    placed = all(c.get("x_m") is not None and c.get("y_m") is not None for c in channels)
    cols: dict[str, list] = {k: [] for k in ("channel", "sensor_id", "x", "y", "frequency_khz", "estimate", "value",
                                             "readings", "missed", "no_oscillation")}
    for i, c in enumerate(channels):
        f_khz = c["frequency_hz"] / 1e3 if math.isfinite(c["frequency_hz"]) else math.nan
        cols["channel"].append(c["channel"])
        cols["sensor_id"].append(c["sensor_id"])
        cols["x"].append(float(c["x_m"]) if placed else float(i % GRID_COLUMNS))
        cols["y"].append(float(c["y_m"]) if placed else float(-(i // GRID_COLUMNS)))
        cols["frequency_khz"].append(f_khz)
        cols["estimate"].append(c["estimate"])
        cols["value"].append(c["estimate"] if estimated else f_khz)
        for key in ("readings", "missed", "no_oscillation"):
            cols[key].append(int(c[key]))
    return cols


class ChannelPlots:
    """The sensor map (``ColumnDataSource`` named ``sensor_map``) and every channel's frequency in one plot (one
    source named ``channels``), fed like :class:`fsrlab.live.page.WindowPlots`: :meth:`add` then :meth:`flush`.

    Parameters
    ----------
    session : LiveSession
        A session with a scan (:attr:`LiveSession.scan`).
    """

    def __init__(self, session) -> None:
        from bokeh.layouts import column, row
        from bokeh.models import ColumnDataSource, Div

        self.session = session
        self.estimated = session.estimator is not None
        self.channels = tuple(session.scan.channels)
        first = map_columns(session.channels(), self.estimated)
        self.placed = all(e.get("x_m") is not None for e in session.channel_map) and \
            all(e.get("y_m") is not None for e in session.channel_map)
        self.map_source = ColumnDataSource(first, name="sensor_map")
        from bokeh.palettes import Category10_10

        self.colours = {k: Category10_10[i % 10] for i, k in enumerate(self.channels)}
        self.names = [c for k in self.channels for c in (f"t{k}", f"f{k}")]
        self.source = ColumnDataSource({c: [] for c in self.names}, name="channels")
        self.scans: list[dict] = []  # complete scans not yet sent
        self.open: dict = {}  # the scan being read
        self.seen = tuple(first["readings"])
        self.scaled = False  # the colour scale is set from the first values shown
        self.health = Div(text="", name="channel_health", sizing_mode="stretch_width", height=44)
        self.layout = column(row(self._sensor_map(), self._frequencies(), sizing_mode="stretch_width"), self.health,
                             sizing_mode="stretch_width")

    def _sensor_map(self):
        from bokeh.models import ColorBar, HoverTool, LabelSet, LinearColorMapper, Range1d
        from bokeh.plotting import figure

        self.mapper = LinearColorMapper(palette=PALETTE, low=0.0, high=1.0, nan_color="#bbbbbb")
        what = "estimated force (N)" if self.estimated else "frequency (kHz)"
        xs, ys = self.map_source.data["x"], self.map_source.data["y"]
        pad = max(max(xs) - min(xs), max(ys) - min(ys), 1e-3) * 0.2 if self.placed else 0.6
        # Fixed ranges: a patch then redraws the map without laying the page out again.
        fig = figure(height=300, width=520, name="sensor_map_plot", title=f"sensors: {what}", tools="save",
                     x_axis_label="x (m)" if self.placed else "", y_axis_label="y (m)" if self.placed else "",
                     x_range=Range1d(min(xs) - pad, max(xs) + pad), y_range=Range1d(min(ys) - 1.5 * pad, max(ys) + pad))
        if not self.placed:
            fig.axis.visible = False
            fig.grid.visible = False
        dots = fig.scatter("x", "y", source=self.map_source, size=38, line_color="black",
                           fill_color={"field": "value", "transform": self.mapper})
        fig.add_layout(LabelSet(x="x", y="y", text="sensor_id", source=self.map_source, text_align="center",
                                y_offset=-34, text_font_size="10pt"))
        fig.add_tools(HoverTool(renderers=[dots], tooltips=[
            ("sensor", "@sensor_id (channel @channel)"), ("f", "@frequency_khz{0.000} kHz"),
            ("estimate", "@estimate{0.000} N"), ("readings", "@readings"), ("missed edges", "@missed"),
            ("no oscillation", "@no_oscillation")]))
        fig.add_layout(ColorBar(color_mapper=self.mapper, title=what), "right")
        return fig

    def _frequencies(self):
        from bokeh.plotting import figure

        # One plot for every channel: the page draws one canvas per redraw, not one per channel.
        fig = figure(height=300, sizing_mode="stretch_width", name="channels_plot", title="frequency by channel",
                     tools="pan,wheel_zoom,box_zoom,reset,save", x_axis_label="time (s)",
                     y_axis_label="frequency (kHz)")
        # No legend: its entries on the streamed source are drawn again at every stream (a canvas each), which
        # slowed the page's script calls to seconds. The health line names each line's colour instead.
        for k in self.channels:
            fig.line(f"t{k}", f"f{k}", source=self.source, color=self.colours[k])
        return fig

    def add(self, cols: dict) -> None:
        """Queue the session's new readings (:meth:`LiveSession.since`'s columns, with ``channel``): a row per scan,
        ``t<k>`` [s] and ``f<k>`` [kHz] for channel k; a channel read again opens the next row."""
        for t, f, k in zip(cols["time_s"], cols["frequency_hz"], cols["channel"], strict=True):
            if k not in self.channels:
                continue
            if f"t{k}" in self.open:
                self.scans.append(self.open)
                self.open = {}
            self.open[f"t{k}"] = t
            self.open[f"f{k}"] = f / 1e3 if f is not None and math.isfinite(f) else math.nan
        del self.scans[:-CHANNEL_POINTS]  # a tab held back (page.BEHIND_S) keeps no more than its plots show

    def flush(self) -> None:
        """Stream the complete scans queued (one message; a channel missing from a scan is NaN there)."""
        if self.scans:
            self.source.stream({c: [r.get(c, math.nan) for r in self.scans] for c in self.names},
                               rollover=CHANNEL_POINTS)
            self.scans.clear()

    def refresh(self) -> None:
        """Patch the map when a channel has read since the last patch (one message), and rewrite the health
        line: per channel its readings, missed edges and readings without oscillation."""
        chans = self.session.channels()
        cols = map_columns(chans, self.estimated)
        if tuple(cols["readings"]) != self.seen:
            self.seen = tuple(cols["readings"])
            n = len(cols["channel"])
            self.map_source.patch({c: [(slice(0, n), cols[c])] for c in
                                   ("frequency_khz", "estimate", "value", "readings", "missed", "no_oscillation")})
            self._rescale([v for v in cols["value"] if math.isfinite(v)])
        parts = []
        for c in chans:
            k = c["channel"]
            parts.append(f"<span id='channel-{k}'><span style='color:{self.colours[k]}'>&#9632;</span> "
                         f"{html_text(c['sensor_id'])}: "
                         f"<span id='channel-{k}-frequency'>{fmt(c['frequency_hz'], '.2f')}</span> Hz, "
                         f"{c['readings']} readings, {c['missed']} missed, {c['no_oscillation']} without oscillation"
                         "</span>")
        text = " · ".join(parts)
        if text != self.health.text:
            self.health.text = text

    def _rescale(self, values: list) -> None:
        """Widen the colour scale to hold every value shown so far, in steps of 1, 2 or 5 × a power of ten (it
        never narrows, so colours stay comparable, and it changes a few times only: each change redraws the
        colour bar)."""
        if not values:
            return
        lo, hi = min(values), max(values)
        if self.scaled and self.mapper.low <= lo and hi <= self.mapper.high:
            return
        if self.scaled:
            lo, hi = min(lo, self.mapper.low), max(hi, self.mapper.high)
        step = nice_step(max(hi - lo, abs(hi), 1e-12) / 5)
        self.mapper.update(low=math.floor(lo / step) * step, high=(math.floor(hi / step) + 1) * step)
        self.scaled = True


def nice_step(x: float) -> float:
    """The smallest of 1, 2 or 5 × a power of ten not below ``x`` (> 0)."""
    base = 10.0 ** math.floor(math.log10(x))
    return next(m * base for m in (1, 2, 5, 10) if m * base >= x * (1 - 1e-12))
