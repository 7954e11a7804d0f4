"""``make demo`` / ``fsrlab demo``: the whole measurement chain on a virtual bench, then both reports.

:func:`run_demo` runs the chain of :func:`fsrlab.bench.demo.run_chain` (the bench, the spring and
dead-weight runs, the calibrations, the compensated estimate of the test run), then

5. writes the measurement report of the test run (:func:`fsrlab.reports.run_report.write_run_report`)
   with the dead-weight run's placements;
6. writes the reproduction report (:func:`fsrlab.reports.paper.write_report`), in a process of its own
   started as soon as the spring runs are in: it draws while the dead weights are recorded;
7. runs several sensors on one meter (:func:`fsrlab.bench.channels.several_sensors`): 8 channels scanned
   on the Python virtual device, calibrated per channel from the one run, and the cross-talk matrix;
8. writes ``index.html`` linking both reports, with the multi-sensor numbers.
"""

from __future__ import annotations

import html
import time
from collections.abc import Callable
from pathlib import Path

from fsrlab.bench.demo import DemoResult, DemoSettings, run_chain

__all__ = ["run_demo"]


def run_demo(out="demo", settings: DemoSettings = DemoSettings(), sensor=None, device: str = "auto",
             paper: bool = True, progress: Callable[[str], None] | None = None) -> DemoResult:
    """Run the measurement chain on a virtual bench and write the reports (see the module's docstring).

    Parameters
    ----------
    out : path-like
        Output directory (created; files in it are replaced).
    settings : DemoSettings
        Durations and loads.
    sensor : str or object, optional
        :func:`demo_sensor`'s name or a sensor object (default :data:`DEMO_SENSOR`).
    device : {"auto", "twin", "virtual"}
        ``auto``: the twin when available, else the Python virtual device.
    paper : bool
        Also write the reproduction report (``out/paper``).
    progress : callable, optional
        ``progress(line)``: what the demo does, step by step.

    Returns
    -------
    DemoResult

    Raises
    ------
    ValueError
        A bad setting or sensor, ``device="twin"`` without the twin.
    RuntimeError
        A recording that failed (the message says which and why).
    """
    say = progress or (lambda line: None)
    started = []

    def start_paper() -> None:
        # The reproduction report needs nothing the chain records: its own process draws it while the last
        # recording (the dead weights) runs and the calibration is fitted, at a lower priority: the twin's
        # simulation and its feeder keep the cores they need (their latency sets the recording's pace), the
        # report takes what they leave.
        from fsrlab.reports.paper import start_report

        # The demo's directory was checked by its caller; its files are replaced (run_chain).
        started.append((start_report(Path(out) / "paper", nice=10, overwrite=True), time.monotonic()))

    try:
        return _run_demo(run_chain(out, settings, sensor, device, 8 if paper else 7, say,
                                   start_paper if paper else None), settings, paper, started)
    except BaseException:
        for report, _ in started:  # a failed chain: no report left running on its own
            report.stop()
        raise


def _run_demo(chain, s: DemoSettings, paper: bool, started: list) -> DemoResult:
    """Steps 5 to 8 of :func:`run_demo` after the chain."""
    result, cal, sensor_text = chain.result, chain.calibration, chain.sensor_text
    step, done = chain.steps.step, chain.steps.done
    out = result.index.parent

    # 5. Measurement report.
    from fsrlab.reports.run_report import write_run_report

    t0 = step("measurement report of the test run: HE of f and V0 (Table 3), RE1/RE2 (eq. 39), ISO 376, calibration")
    rep = write_run_report(out / "test-run.csv", out / "measurement", weights_run=out / "weights-run.csv",
                           calibration=cal, overwrite=True)
    result.files["measurement report"] = rep.index
    hs = {h.quantity: h.percent for h in rep.report.hysteresis}
    result.numbers.update({"he_frequency_percent": hs.get("frequency_hz"), "he_voltage_percent": hs.get("voltage_v"),
                           "he_estimate_percent": None if rep.report.estimate is None else rep.report.estimate.percent,
                           "repeatability": [p.to_dict() for p in rep.report.repeatability],
                           "iso376_class": None if rep.report.iso376 is None else rep.report.iso376.instrument_class})
    fmt = lambda v: "—" if v is None else f"{v:.2f} %"  # noqa: E731
    done("measurement report", t0, f"HE f {fmt(hs.get('frequency_hz'))}, V0 {fmt(hs.get('voltage_v'))}, "
         f"estimate {fmt(result.numbers['he_estimate_percent'])}")

    # 6. The reproduction report (started with the dead weights, in its own process).
    if paper:
        t0 = step("reproduction report of the paper (fsrlab paper), drawn while the dead weights were recorded")
        report, since = started[0]
        pr = report.result()
        result.files["reproduction report"] = pr.index
        done("reproduction report", t0, f"{len(pr.sections)} sections, {time.monotonic() - since:.1f} s since it "
                "started")

    # 7. Several sensors on one meter.
    _several_sensors(out, result, step, done)

    # 8. The index.
    t0 = step("index")
    _write_index(result, sensor_text, s)
    done("index", t0, str(result.index))
    return result


def _several_sensors(out: Path, result: DemoResult, step, done) -> None:
    """The multi-sensor step: 8 sensors behind the multiplexer, recorded, calibrated per channel, cross-talk."""
    from fsrlab.bench.channels import several_sensors

    t0 = step("several sensors on one meter: 8 channels scanned (Python virtual device, CD74HC4051), "
              "each calibrated from the one run, then the cross-talk check")
    ss = several_sensors(out / "channels", overwrite=True)
    result.files["multi-channel run"] = ss.run
    result.files["per-channel calibration"] = ss.calibration
    cals = ss.calibrations
    result.numbers["channels"] = {
        "sensors": [{"sensor_id": sid, "channel": cals.channels[sid], "readings_per_s": float(rate),
                     "peak_hz": float(peak), "model": c.model_name, "heldout_rmse": c.selection.heldout_rmse,
                     "unit": c.y_unit}
                    for (sid, c), rate, peak in zip(cals.by_sensor.items(), ss.readings_per_s, ss.peak_hz,
                                                    strict=True)],
        "crosstalk": ss.crosstalk.to_dict()}
    done("several sensors", t0, f"{len(cals.by_sensor)} channels, {ss.readings_per_s.min():.0f} readings/s each or "
         f"more, peaks {ss.peak_hz[0]:.0f}–{ss.peak_hz[-1]:.0f} Hz; cross-talk worst {ss.crosstalk.worst:.1e}")


def _channels_html(ch: dict | None) -> str:
    """The index page's multi-sensor section: each channel's rate, peak and calibration, the cross-talk matrix."""
    if not ch:
        return ""
    rows = "".join(f"<tr><td>{html.escape(c['sensor_id'])}</td><td>{c['channel']}</td>"
                   f"<td>{c['readings_per_s']:.1f}</td><td>{c['peak_hz']:.0f}</td><td>{html.escape(c['model'])}</td>"
                   f"<td>{_num(c['heldout_rmse'])} "
                   f"{html.escape(c['unit'])}</td></tr>" for c in ch["sensors"])
    ct = ch["crosstalk"]
    head = "".join(f"<th>{k}</th>" for k in ct["channels"])
    matrix = "".join(f"<tr><th>{j}</th>" + "".join(f"<td>{v:.1e}</td>" for v in row) + "</tr>"
                     for j, row in zip(ct["channels"], ct["matrix"], strict=True))
    return f"""<h2>Several sensors on one meter</h2>
<p>Eight sensors behind a CD74HC4051 on the one 555 (docs/multiplexing.md), channel k under a triangle to
50 kPa · (k + 1)/8, scanned for 2 s of the device's clock; each channel calibrated from that one run
(fsrlab calibrate-channels), all in one file keyed by sensor id.</p>
<table><tr><th>sensor</th><th>channel</th><th>readings/s</th><th>peak f [Hz]</th><th>calibration</th>
<th>held-out RMSE</th></tr>{rows}</table>
<p>Cross-talk (fsrlab crosstalk): row j is channel j under 50 kPa, the others unloaded; each entry is a
channel's frequency change over channel j's own. Worst off-diagonal: {ct['worst']:.1e}.</p>
<table><tr><th>loaded ↓ read →</th>{head}</tr>{matrix}</table>
"""


def _num(v) -> str:
    """A number for the index page ("—" when missing)."""
    return "—" if v is None else f"{v:.3g}"


def _cal_text(title: str, c: dict | None) -> str:
    """One calibration's line on the index page."""
    if not c:
        return f"{title}: none"
    return html.escape(f"{title}: {c['model']} against {c['reference']}, held-out RMSE ({c['scheme']}) "
                       f"{_num(c['heldout_rmse'])} {c['unit']}")


def _write_index(result: DemoResult, sensor_text: str, s: DemoSettings) -> None:
    """The demo's ``index.html``: what was done, the headline numbers, links to both reports and the files."""
    from fsrlab import __version__

    out = result.index.parent
    n = result.numbers

    def rel(p) -> str:
        return html.escape(str(Path(p).relative_to(out)) if Path(p).is_relative_to(out) else str(p))

    def pct(v) -> str:
        return "—" if v is None else f"{v:.2f} %"
    links = []
    for name in ("measurement report", "reproduction report"):
        if name in result.files:
            links.append(f"<li><a href='{rel(result.files[name])}'>{name.capitalize()}</a></li>")
    files = "".join(f"<li>{html.escape(k)}: <a href='{rel(v)}'>{rel(v)}</a></li>" for k, v in result.files.items())
    steps = "".join(f"<li>{html.escape(t)}: {d:.1f} s</li>" for t, d in result.steps)
    re_rows = "".join(
        f"<tr><td>{'f' if p['quantity'] == 'frequency_hz' else 'V0'}</td><td>{p['load_g']:g} g</td>"
        f"<td>{p['re1_percent']:.3f}</td><td>{p['re2_percent']:.3f}</td></tr>" for p in n.get("repeatability", []))
    page = f"""<!doctype html><html lang='en'><head><meta charset='utf-8'><title>fsrlab demo</title>
<style>body{{font-family:system-ui,sans-serif;max-width:900px;margin:2em auto;padding:0 1em;line-height:1.45}}
table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:.2em .6em}}</style></head><body>
<h1>fsrlab demo: the measurement chain on a virtual bench</h1>
<p>fsrlab {html.escape(__version__)}. Bench: {'the digital twin (the firmware in simavr)' if result.device == 'twin'
    else 'the Python virtual device (a model of the meter on a pty)'}; sensor: {html.escape(sensor_text)};
spring cycles 0 → {s.peak_pa / 1e3:g} kPa → 0 ({s.cycles} × {s.period_s:g} s per run), dead weights
{', '.join(format(m * 1e3, 'g') + ' g' for m in s.masses_kg)} × {s.repeat}.</p>
<ul>{''.join(links)}</ul>
<h2>Headline numbers (test run)</h2>
<table><tr><th>hysteresis error (eq. 13)</th><th>value</th></tr>
<tr><td>resistive readout (op-amp V0)</td><td>{pct(n.get('he_voltage_percent'))}</td></tr>
<tr><td>capacitive readout (555 frequency)</td><td>{pct(n.get('he_frequency_percent'))}</td></tr>
<tr><td>calibrated, compensated estimate</td><td>{pct(n.get('he_estimate_percent'))}</td></tr></table>
<p></p><table><tr><th>readout</th><th>load</th><th>RE1 [%] (eq. 39)</th><th>RE2 [%]</th></tr>{re_rows}</table>
<p>{_cal_text('Calibration (spring run)', n.get('calibration'))}; {_cal_text('known-weight calibration',
n.get('known_weight_calibration'))}.</p>
<p>ISO 376 class: {html.escape(str(n.get('iso376_class')))} (the measurement report says what is missing).</p>
{_channels_html(n.get('channels'))}
<h2>Steps</h2><ol>{steps}</ol><h2>Files</h2><ul>{files}</ul></body></html>
"""
    from fsrlab.io.outputs import write_text_atomic

    write_text_atomic(result.index, page)
