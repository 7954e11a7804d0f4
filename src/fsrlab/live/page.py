"""The live page: a Bokeh document per browser tab, fed from a :class:`~fsrlab.live.session.LiveSession`.

Time series of frequency, duty cycle, op-amp voltage and the reference (with the calibrated estimate
and its band when a calibration is given), the loading/unloading loop (readout against reference),
a status line, the latest window in numbers, and the controls. Each tab shows the latest window in numbers every
:data:`UPDATE_S` and streams the windows it has not plotted yet every :data:`PLOT_S`
(``ColumnDataSource.stream`` with a rollover, so memory stays bounded); one tab at a time controls the device and the recording, the others watch.
"""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path

__all__ = ["UPDATE_S", "PLOT_S", "STATUS_S", "POINTS", "Controller", "make_document"]

UPDATE_S = 0.04
"""Period of a page's update callback. [s]"""
PLOT_S = 0.1
"""Shortest time between two redraws of the plots (the numbers update every :data:`UPDATE_S`). [s]"""
STATUS_S = 0.25
"""Period of the status line's refresh. [s]"""
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


def _fmt(v, spec: str) -> str:
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def _html(text) -> str:
    """A text the page shows inside its HTML (messages, file names, the device, the event log): control
    characters as their escapes (:func:`fsrlab.io.shown.printable`, the one rendering boundary), then ``&``,
    ``<`` and ``>`` as entities, so that neither a terminal escape nor markup in a file name acts on the page."""
    import html

    from fsrlab.io.shown import printable

    return html.escape(printable(str(text)), quote=False)


def make_document(doc, session, controller: Controller, reference_label: str = "reference",
                  reference_unit: str = "", reference_scale: float = 1.0, title: str = "fsrlab live") -> None:
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
    """
    from bokeh.layouts import column, row
    from bokeh.models import Band, Button, ColumnDataSource, Div, RadioButtonGroup, Select
    from bokeh.plotting import figure

    empty = {c: [] for c in ("time_s", "seq", "frequency_khz", "duty_pct", "voltage_v", "reference", "estimate",
                             "lower", "upper")}
    src = ColumnDataSource(dict(empty), name="windows")
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
    if session.estimator is not None:
        r_fig.add_layout(Band(base="time_s", lower="lower", upper="upper", source=src, fill_alpha=0.25,
                              fill_color="#d62728"))
        r_fig.line("time_s", "estimate", source=src, color="#d62728", legend_label="estimate ± u")
    r_fig.legend.location = "top_left"
    loop = figure(height=360, width=420, x_axis_label=f"{reference_label}{unit}", name="loop_plot",
                  y_axis_label="estimate" + unit if session.estimator is not None else "frequency (kHz)",
                  title="loading / unloading loop")
    loop.scatter("reference", "estimate" if session.estimator is not None else "frequency_khz", source=src,
                 size=3, alpha=0.6)

    # Fixed heights: a new text then repaints the line without laying the page out again.
    status = Div(text="connecting…", name="status", sizing_mode="stretch_width", height=22)
    latest = Div(text="", name="latest", sizing_mode="stretch_width", height=22)
    events = Div(text="", name="events", sizing_mode="stretch_width", height=100)
    controls = controller.claim(doc)
    record = Button(label="Start recording", button_type="success", name="record",
                    disabled=not controls or controller.out is None)
    tare = Button(label="Tare load cell", name="tare", disabled=not controls or session.loadcell is None)
    tare.on_click(lambda: session.command("tare"))
    guided = session.weights is not None and controller.out is not None
    start_w = Button(label="Start guided calibration", name="weights", disabled=not (controls and guided))
    placed = Button(label="Placed", button_type="primary", name="placed", disabled=not (controls and guided))
    skip = Button(label="Skip step", name="skip", disabled=not (controls and guided))
    prompt = Div(text="" if guided else "guided known weights: start fsrlab live with --masses and --out",
                 name="prompt", sizing_mode="stretch_width", height=22)

    def on_weights():
        path = controller.next_path("-weights")
        if path is not None:
            session.command("weights", str(path))

    start_w.on_click(on_weights)
    placed.on_click(lambda: session.command("answer", "ok"))
    skip.on_click(lambda: session.command("answer", "skip"))
    rng = RadioButtonGroup(labels=["range 0 (C_off out)", "range 1 (C_off in)"], active=session.status.range,
                           name="range", disabled=not controls)
    window = Select(title="window (ms)", value=str(session.status.window_ms), options=list(WINDOWS_MS),
                    name="window", disabled=not controls)
    role = Div(text=("view only: another tab controls the meter" if not controls else
                     "this tab controls the meter" + ("" if controller.out is not None else
                                                      " (recording off: start fsrlab live with --out RUN.csv)")),
               name="role")

    def on_record():
        if session.status.recording:
            session.command("stop_recording")
        else:
            path = controller.next_path()
            if path is not None:
                session.command("record", str(path))

    record.on_click(on_record)
    rng.on_change("active", lambda attr, old, new: session.command("range", int(new)))
    window.on_change("value", lambda attr, old, new: session.command("window", int(new)))

    state = {"cursor": 0, "status_at": 0.0, "plot_at": 0.0}
    pending = {c: [] for c in empty}

    def update():
        cursor, cols = session.since(state["cursor"])
        state["cursor"] = cursor
        n = len(cols["seq"])
        if n:
            k = reference_scale
            est, unc = [k * e for e in cols["estimate"]], [k * u for u in cols["uncertainty"]]
            ref = [k * r for r in cols["reference"]]
            new = {"time_s": cols["time_s"], "seq": cols["seq"],
                   "frequency_khz": [f / 1e3 for f in cols["frequency_hz"]],
                   "duty_pct": [100 * d for d in cols["duty_cycle"]], "voltage_v": cols["voltage_v"],
                   "reference": ref, "estimate": est,
                   "lower": [e - u for e, u in zip(est, unc, strict=True)], "upper": [e + u for e, u in zip(est, unc, strict=True)]}
            for key, values in new.items():
                pending[key].extend(values)
            i = n - 1
            latest.text = (f"<span id='latest-seq'>{cols['seq'][i]}</span> · f = "
                           f"<span id='latest-frequency'>{_fmt(cols['frequency_hz'][i], '.2f')}</span> Hz · duty = "
                           f"<span id='latest-duty'>{_fmt(cols['duty_cycle'][i], '.6f')}</span> · V0 = "
                           f"<span id='latest-voltage'>{_fmt(cols['voltage_v'][i], '.4f')}</span> V · "
                           f"{reference_label} = <span id='latest-reference'>{_fmt(ref[i], '.6g')}</span> {reference_unit}"
                           + (f" · estimate = <span id='latest-estimate'>{_fmt(est[i], '.6g')}</span> ± {_fmt(unc[i], '.2g')}"
                              if session.estimator is not None else ""))
        now = time.monotonic()
        if pending["seq"] and now - state["plot_at"] >= PLOT_S:  # the plots redraw at most every PLOT_S
            state["plot_at"] = now
            src.stream({c: list(v) for c, v in pending.items()}, rollover=POINTS)
            for v in pending.values():
                v.clear()
        if now - state["status_at"] < STATUS_S:
            return
        state["status_at"] = now
        st = session.status
        text = (f"<b>{_html(st.state)}</b> {_html(st.message)} · {_html(st.device)} · "
                       f"<span id='fps'>{st.frames_per_s:.1f}</span> frames/s · frames {st.frames} · "
                       f"dropped <span id='dropped'>{st.dropped}</span> · corrupt {st.corrupt} · missed edges "
                       f"{st.missed} · stalls {st.stalls} · range {st.range} · window {st.window_ms} ms"
                       + (f" · <b>recording</b> <span id='recording'>{_html(st.recording)}</span> ({st.recorded} rows)"
                          if st.recording else ""))
        if text != status.text:
            status.text = text
        said = (f"<b>{_html(st.weights)}</b>: " if st.weights else "") + f"<span id='prompt'>{_html(st.prompt)}</span>" \
            if (st.prompt or st.weights) else prompt.text
        if said != prompt.text:
            prompt.text = said
        label = "Stop recording" if st.recording else "Start recording"
        if label != record.label:
            record.label = label
            record.button_type = "danger" if st.recording else "success"
        log = "<br>".join(_html(e) for e in st.events[-5:])
        if log != events.text:
            events.text = log

    doc.add_periodic_callback(update, int(UPDATE_S * 1000))
    doc.on_session_destroyed(lambda ctx: controller.release(doc))
    doc.title = title
    doc.add_root(column(Div(text=f"<h2 style='margin:4px 0'>{_html(title)}</h2>"), status, latest,
                        row(record, tare, rng, window, role), row(start_w, placed, skip, prompt, sizing_mode="stretch_width"), row(column(f_fig, d_fig, v_fig, r_fig, sizing_mode="stretch_width"),
                                                              loop, sizing_mode="stretch_width"),
                        events, sizing_mode="stretch_width"))
