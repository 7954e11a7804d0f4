"""The live page: a Bokeh document per browser tab, fed from a :class:`~fsrlab.live.session.LiveSession`.

Time series of frequency, duty cycle, op-amp voltage and the reference (with the calibrated estimate
and its band when a calibration is given), the loading/unloading loop (readout against reference),
a status line, the latest window in numbers, and the controls. With a scan of several sensors the time
series are small multiples, one per channel, under a sensor map coloured by each channel's latest
frequency (or estimated force) with its link health (:mod:`fsrlab.live.page_channels`). Each tab shows
the latest window in numbers every :data:`UPDATE_S` and streams the windows it has not plotted yet every
:data:`PLOT_S` (``ColumnDataSource.stream`` with a rollover, so memory stays bounded; the sensor map is one
``patch`` at that rate at most); one tab at a time controls the device and the recording, the others watch.
"""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path

from fsrlab.live.page_text import fmt as _fmt
from fsrlab.live.page_text import html_text as _html

__all__ = ["UPDATE_S", "REFRESH_MAX_S", "PLOT_S", "STATUS_S", "BEHIND_S", "POINTS", "Controller", "check_refresh",
           "make_document"]

UPDATE_S = 0.04
"""Period of a page's update callback by default, and the shortest allowed (:func:`check_refresh`). [s]"""
REFRESH_MAX_S = 10.0
"""Longest period of a page's update callback. [s]"""
PLOT_S = 0.1
"""Shortest time between two redraws of the plots (the numbers update every :data:`UPDATE_S`). [s]"""
STATUS_S = 0.25
"""Period of the status line's refresh. [s]"""
BEHIND_S = 1.0
"""Updates a tab's browser may have been sent and not yet applied, in seconds of refresh: the next numbers, plots
and status lines wait until it has applied the earlier ones (back-pressure: a starved browser gets fewer updates
instead of falling behind). At least two. [s]"""
POINTS = 10_000
"""Windows a page keeps per plot (the oldest roll over). [1]"""
WINDOWS_MS = ("20", "50", "100", "200", "500", "1000")
"""Window lengths offered on the page. [ms]"""


class Controller:
    """Which tab controls the device, and where recordings go.

    Parameters
    ----------
    out : Path or None
        Run file for the first recording; later ones get ``-2``, ``-3``, ... (an existing file is never
        replaced). None: recording is off.
    """

    def __init__(self, out: Path | None) -> None:
        self.out = out
        self.owner = None
        self._lock = threading.Lock()
        self._count = 0

    def claim(self, doc) -> bool:
        """Make ``doc`` the controlling tab if none is; True when it controls."""
        with self._lock:
            if self.owner is None:
                self.owner = doc
            return self.owner is doc

    def release(self, doc) -> None:
        """A tab closed: the next tab that asks may take control."""
        with self._lock:
            if self.owner is doc:
                self.owner = None

    def next_path(self, suffix: str = "") -> Path | None:
        """The next unused run file name (``suffix`` after the stem: ``-weights`` for a guided calibration)."""
        if self.out is None:
            return None
        from fsrlab.io.runformat import sidecar_path

        while True:
            self._count += 1
            stem = self.out.stem + suffix + ("" if self._count == 1 else f"-{self._count}")
            path = self.out.with_name(stem + self.out.suffix)
            if not path.exists() and not sidecar_path(path).exists():
                return path



def check_refresh(refresh_s) -> float:
    """``refresh_s`` as the period of a page's update callback, from :data:`UPDATE_S` to :data:`REFRESH_MAX_S`.

    Parameters
    ----------
    refresh_s : float
        Shortest time between two updates of the page's numbers; its plots redraw at most every
        ``max(refresh_s, PLOT_S)``. [s]

    Raises
    ------
    ParameterError
        Not in that range (a TypeError when not a number).
    """
    from fsrlab.physics.params import check_between

    check_between("refresh_s", refresh_s, UPDATE_S, REFRESH_MAX_S, "s", scalar=True)
    return float(refresh_s)


def make_document(doc, session, controller: Controller, reference_label: str = "reference",
                  reference_unit: str = "", reference_scale: float = 1.0, title: str = "fsrlab live",
                  refresh_s: float = UPDATE_S) -> None:
    """Fill a Bokeh document (one browser tab) with the live view of ``session``.

    Parameters
    ----------
    doc : bokeh.document.Document
        The tab's document (Bokeh calls this with it).
    session : LiveSession
        The device session.
    controller : Controller
        Shared among tabs: who controls, where recordings go.
    reference_label, reference_unit : str
        How the reference is named on the page (``stress``/``kPa`` or ``force``/``N``).
    reference_scale : float
        Reference and estimate as shown = value in SI units × this (1e-3 for kPa). [1]
    title : str
        Page title.
    refresh_s : float
        Shortest time between two updates of the numbers (:func:`check_refresh`); the plots redraw at most
        every ``max(refresh_s, PLOT_S)``: the browser's work grows with the rate (docs/live.md). [s]
    """
    from bokeh.layouts import column
    from bokeh.models import Div

    if session.scan is None:
        plots = WindowPlots(session, reference_label, reference_unit, reference_scale)
    else:
        from fsrlab.live.page_channels import ChannelPlots

        plots = ChannelPlots(session)
    panel = ControlPanel(doc, session, controller)
    update = Updater(session, plots, panel, reference_label, reference_unit, reference_scale, refresh_s)
    doc.add_periodic_callback(update, round(update.refresh_s * 1000))
    doc.on_session_destroyed(lambda ctx: controller.release(doc))
    doc.title = title
    doc.add_root(column(Div(text=f"<h2 style='margin:4px 0'>{_html(title)}</h2>"), panel.status, update.latest,
                        *panel.rows, plots.layout, panel.events, update.ack, sizing_mode="stretch_width"))


class WindowPlots:
    """One sensor's time series (frequency, duty cycle, op-amp voltage, reference with the estimate and its band)
    and the loading/unloading loop, on one ``ColumnDataSource`` named ``windows``.

    Parameters
    ----------
    session : LiveSession
    reference_label, reference_unit : str
        How the reference is named.
    reference_scale : float
        Shown = SI value × this. [1]
    """

    COLUMNS = ("time_s", "seq", "frequency_khz", "duty_pct", "voltage_v", "reference", "estimate", "lower", "upper")

    def __init__(self, session, reference_label: str, reference_unit: str, reference_scale: float) -> None:
        from bokeh.layouts import column, row
        from bokeh.models import Band, ColumnDataSource
        from bokeh.plotting import figure

        self.scale = reference_scale
        self.source = src = ColumnDataSource({c: [] for c in self.COLUMNS}, name="windows")
        self.pending = {c: [] for c in self.COLUMNS}
        ts = dict(height=170, sizing_mode="stretch_width", tools="pan,wheel_zoom,box_zoom,reset,save",
                  x_axis_label="time (s)")
        f_fig = figure(y_axis_label="frequency (kHz)", name="frequency_plot", **ts)
        f_fig.line("time_s", "frequency_khz", source=src, color="#1f77b4")
        d_fig = figure(y_axis_label="duty cycle (%)", x_range=f_fig.x_range, **ts)
        d_fig.line("time_s", "duty_pct", source=src, color="#ff7f0e")
        v_fig = figure(y_axis_label="op-amp V0 (V)", x_range=f_fig.x_range, **ts)
        v_fig.line("time_s", "voltage_v", source=src, color="#2ca02c")
        unit = f" ({reference_unit})" if reference_unit else ""
        r_fig = figure(y_axis_label=f"{reference_label}{unit}", x_range=f_fig.x_range, **ts)
        r_fig.line("time_s", "reference", source=src, color="black", legend_label="reference")
        estimated = session.estimator is not None
        if estimated:
            r_fig.add_layout(Band(base="time_s", lower="lower", upper="upper", source=src, fill_alpha=0.25,
                                  fill_color="#d62728"))
            r_fig.line("time_s", "estimate", source=src, color="#d62728", legend_label="estimate ± u")
        r_fig.legend.location = "top_left"
        loop = figure(height=360, width=420, x_axis_label=f"{reference_label}{unit}", name="loop_plot",
                      y_axis_label="estimate" + unit if estimated else "frequency (kHz)",
                      title="loading / unloading loop")
        loop.scatter("reference", "estimate" if estimated else "frequency_khz", source=src, size=3, alpha=0.6)
        self.layout = row(column(f_fig, d_fig, v_fig, r_fig, sizing_mode="stretch_width"), loop,
                          sizing_mode="stretch_width")

    def add(self, cols: dict) -> None:
        """Queue the session's new windows (:meth:`LiveSession.since`'s columns) for the next :meth:`flush`."""
        k = self.scale
        est, unc = [k * e for e in cols["estimate"]], [k * u for u in cols["uncertainty"]]
        new = {"time_s": cols["time_s"], "seq": cols["seq"],
               "frequency_khz": [f / 1e3 for f in cols["frequency_hz"]],
               "duty_pct": [100 * d for d in cols["duty_cycle"]], "voltage_v": cols["voltage_v"],
               "reference": [k * r for r in cols["reference"]], "estimate": est,
               "lower": [e - u for e, u in zip(est, unc, strict=True)],
               "upper": [e + u for e, u in zip(est, unc, strict=True)]}
        for key, values in new.items():
            self.pending[key].extend(values)
            del self.pending[key][:-POINTS]  # a tab held back (BEHIND_S) keeps no more than its plots show

    def refresh(self) -> None:
        """Nothing beside the plots to refresh (the status line says the link's health)."""

    def flush(self) -> None:
        """Stream the queued windows to the page (one message), the oldest rolling over past :data:`POINTS`."""
        if self.pending["seq"]:
            self.source.stream({c: list(v) for c, v in self.pending.items()}, rollover=POINTS)
            for v in self.pending.values():
                v.clear()


class ControlPanel:
    """The status, prompt and event lines and the controls (recording, tare, range, window, guided weights).

    Parameters
    ----------
    doc : bokeh.document.Document
        The tab (it asks the controller whether it controls).
    session : LiveSession
    controller : Controller
    """

    def __init__(self, doc, session, controller: Controller) -> None:
        from bokeh.layouts import row
        from bokeh.models import Button, Div, RadioButtonGroup, Select

        self.session, self.controller = session, controller
        # Fixed heights: a new text then repaints the line without laying the page out again.
        self.status = Div(text="connecting…", name="status", sizing_mode="stretch_width", height=22)
        self.events = Div(text="", name="events", sizing_mode="stretch_width", height=100)
        controls = controller.claim(doc)
        self.record = Button(label="Start recording", button_type="success", name="record",
                             disabled=not controls or controller.out is None)
        self.record.on_click(self._on_record)
        tare = Button(label="Tare load cell", name="tare", disabled=not controls or session.loadcell is None)
        tare.on_click(lambda: session.command("tare"))
        guided = session.weights is not None and controller.out is not None
        start_w = Button(label="Start guided calibration", name="weights", disabled=not (controls and guided))
        placed = Button(label="Placed", button_type="primary", name="placed", disabled=not (controls and guided))
        skip = Button(label="Skip step", name="skip", disabled=not (controls and guided))
        self.prompt = Div(text="" if guided else "guided known weights: start fsrlab live with --masses and --out",
                          name="prompt", sizing_mode="stretch_width", height=22)
        start_w.on_click(self._on_weights)
        placed.on_click(lambda: session.command("answer", "ok"))
        skip.on_click(lambda: session.command("answer", "skip"))
        rng = RadioButtonGroup(labels=["range 0 (C_off out)", "range 1 (C_off in)"], active=session.status.range,
                               name="range", disabled=not controls)
        window = Select(title="window (ms)", value=str(session.status.window_ms), options=list(WINDOWS_MS),
                        name="window", disabled=not controls)
        rng.on_change("active", lambda attr, old, new: session.command("range", int(new)))
        window.on_change("value", lambda attr, old, new: session.command("window", int(new)))
        recording_off = "" if controller.out is not None else " (recording off: start fsrlab live with --out RUN.csv)"
        role = Div(text=("view only: another tab controls the meter" if not controls else
                         "this tab controls the meter" + recording_off), name="role")
        self.rows = [row(self.record, tare, rng, window, role),
                     row(start_w, placed, skip, self.prompt, sizing_mode="stretch_width")]

    def _on_record(self) -> None:
        if self.session.status.recording:
            self.session.command("stop_recording")
        elif (path := self.controller.next_path()) is not None:
            self.session.command("record", str(path))

    def _on_weights(self) -> None:
        path = self.controller.next_path("-weights")
        if path is not None:
            self.session.command("weights", str(path))

    def refresh(self) -> None:
        """Show the session's status, prompt, recording state and last events (only what changed is sent)."""
        st = self.session.status
        text = (f"<b>{_html(st.state)}</b> {_html(st.message)} · {_html(st.device)} · "
                f"<span id='fps'>{st.frames_per_s:.1f}</span> frames/s · frames {st.frames} · "
                f"dropped <span id='dropped'>{st.dropped}</span> · corrupt {st.corrupt} · missed edges "
                f"{st.missed} · stalls {st.stalls} · range {st.range} · window {st.window_ms} ms"
                + (f" · <b>recording</b> <span id='recording'>{_html(st.recording)}</span> ({st.recorded} rows)"
                   if st.recording else ""))
        if text != self.status.text:
            self.status.text = text
        said = self.prompt.text
        if st.prompt or st.weights:
            lead = f"<b>{_html(st.weights)}</b>: " if st.weights else ""
            said = lead + f"<span id='prompt'>{_html(st.prompt)}</span>"
        if said != self.prompt.text:
            self.prompt.text = said
        label = "Stop recording" if st.recording else "Start recording"
        if label != self.record.label:
            self.record.label = label
            self.record.button_type = "danger" if st.recording else "success"
        log = "<br>".join(_html(e) for e in st.events[-5:])
        if log != self.events.text:
            self.events.text = log


class Updater:
    """The page's periodic callback: the latest window in numbers every call (every ``refresh_s``), the plots at
    most every ``max(refresh_s, PLOT_S)``, the status lines at most every ``max(refresh_s, STATUS_S)``.

    Parameters
    ----------
    session : LiveSession
    plots : WindowPlots or ChannelPlots
        What :meth:`add` and :meth:`flush` feed.
    panel : ControlPanel
    reference_label, reference_unit : str
    reference_scale : float
        Shown = SI value × this. [1]
    refresh_s : float
        Period of the callback (:func:`check_refresh`). [s]

    Each update of the numbers is counted in ``latest.tags``; the browser copies the count it has applied into
    the hidden ``ack`` model's tags, which comes back to the server. Once a count has come back, no more than
    :data:`BEHIND_S` of updates go out ahead of the browser: the windows read meanwhile wait for the plots and
    only the latest is shown in numbers. A browser that never answers is updated as if it kept up.
    """

    def __init__(self, session, plots, panel: ControlPanel, reference_label: str, reference_unit: str,
                 reference_scale: float, refresh_s: float = UPDATE_S) -> None:
        from bokeh.models import CustomJS, Div

        # the plots (the status lines) every call when the calls are PLOT_S (STATUS_S) or more apart: no call is
        # missed to a clock's jitter
        self.refresh_s = refresh_s = check_refresh(refresh_s)
        self.plot_s = PLOT_S if refresh_s < PLOT_S else 0.0
        self.status_s = STATUS_S if refresh_s < STATUS_S else 0.0
        self.session, self.plots, self.panel = session, plots, panel
        self.label, self.unit, self.scale = reference_label, reference_unit, reference_scale
        self.latest = Div(text="", name="latest", sizing_mode="stretch_width", height=22, tags=[0])
        self.ack = Div(text="", name="ack", visible=False)
        self.latest.js_on_change("tags", CustomJS(args={"ack": self.ack}, code="ack.tags = [cb_obj.tags[0]]"))
        self.ack.on_change("tags", self._acknowledged)
        self.ahead = max(2, math.ceil(BEHIND_S / refresh_s))  # updates that may be out unapplied
        self.sent, self.acked, self.unsent = 0, None, None
        self.cursor, self.plot_at, self.status_at = 0, 0.0, 0.0

    def _acknowledged(self, attr, old, new) -> None:
        """The browser has applied the update counted ``new[0]`` (anything else from it is ignored)."""
        if isinstance(new, list) and new and type(new[0]) is int and 0 <= new[0] <= self.sent:
            self.acked = new[0]

    def behind(self) -> bool:
        """Whether this tab's browser has not applied the last ``ahead`` updates it was sent (:data:`BEHIND_S` of
        refresh, at least two): then no more go out until it has."""
        return self.acked is not None and self.sent - self.acked >= self.ahead

    def __call__(self) -> None:
        self.cursor, cols = self.session.since(self.cursor)
        if cols["seq"]:
            self.plots.add(cols)
            self.unsent = self.latest_text(cols, len(cols["seq"]) - 1)
        if self.behind():  # the windows wait in the plots' queue, the latest line in self.unsent
            return
        if self.unsent is not None:
            self.latest.text, self.unsent = self.unsent, None
            self.sent += 1
            self.latest.tags = [self.sent]
        now = time.monotonic()
        if now - self.plot_at >= self.plot_s:  # the plots redraw at most every max(refresh_s, PLOT_S)
            self.plot_at = now
            self.plots.flush()
        if now - self.status_at >= self.status_s:
            self.status_at = now
            self.panel.refresh()
            self.plots.refresh()

    def latest_text(self, cols: dict, i: int) -> str:
        """The line that shows window ``i`` of ``cols`` in numbers (each number in a span with an id)."""
        k = self.scale
        channel = (f"channel <span id='latest-channel'>{cols['channel'][i]}</span> · "
                   if "channel" in cols else "")
        text = (f"<span id='latest-seq'>{cols['seq'][i]}</span> · {channel}f = "
                f"<span id='latest-frequency'>{_fmt(cols['frequency_hz'][i], '.2f')}</span> Hz · duty = "
                f"<span id='latest-duty'>{_fmt(cols['duty_cycle'][i], '.6f')}</span> · V0 = "
                f"<span id='latest-voltage'>{_fmt(cols['voltage_v'][i], '.4f')}</span> V · "
                f"{self.label} = <span id='latest-reference'>{_fmt(k * cols['reference'][i], '.6g')}</span> "
                f"{self.unit}")
        if self.session.estimator is not None:
            text += (f" · estimate = <span id='latest-estimate'>{_fmt(k * cols['estimate'][i], '.6g')}</span> ± "
                     f"{_fmt(k * cols['uncertainty'][i], '.2g')}")
        return text
