"""``make demo`` / ``fsrlab demo``: the whole measurement chain on a virtual bench, then the reproduction report.

:func:`run_demo` does what a user of fsrlab does with a sensor, with no hardware:

1. chooses the bench: the digital twin (the firmware in simavr) when
   :func:`~fsrlab.acquisition.protocols.twin_status` says it can run, else the Python virtual
   device, and says which;
2. records two spring runs (``fsrlab bench spring``: a calibration run and a test run) and a
   dead-weight run (``fsrlab bench weights``: 200 g and 400 g placed again and again);
3. calibrates on the calibration run against the load cell's force when the meter has one (the
   virtual meter emulates an HX711; else the stress the bench applied), with the causal hysteresis
   compensation and the lag searched automatically (it finds 0 within a row: the reference is taken
   in the readout's own window), and fits a
   known-weight calibration (m·g; a polynomial of degree ≤ 2 through 0 and the masses) on the
   dead-weight run;
4. applies the calibration to the test run (the compensated estimate);
5. writes the measurement report of the test run (:func:`fsrlab.report.run_report.write_run_report`)
   with the dead-weight run's placements;
6. writes the reproduction report (:func:`fsrlab.report.paper.write_report`);
7. writes ``index.html`` linking both.

The sensor is chosen in one place, :func:`demo_sensor`.
"""

from __future__ import annotations

import html
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

__all__ = ["DEMO_SENSOR", "demo_sensor", "DemoSettings", "DemoResult", "run_demo"]

DEMO_SENSOR = "paper-a201-1"
"""The sensor the demo runs on (:func:`demo_sensor`): ``paper-a201-1`` (the first of the four sensors
fitted to the paper's §6, :func:`fsrlab.physics.paper_sensor.paper_sensor`; its dead weights load a
22 mm puck, :data:`~fsrlab.physics.paper_sensor.DEAD_WEIGHT_AREA_M2`), another of ``paper-a201-2`` ..
``-4``, or ``virtual-fsr`` (:class:`~fsrlab.physics.sensor.VirtualFSR`, FlexiForce A201-like)."""


def demo_sensor(name=None):
    """The virtual sensor of the demo: the one place where it is chosen.

    Parameters
    ----------
    name : str or object, optional
        A name for :func:`fsrlab.acquisition.protocols.virtual_sensor` (default :data:`DEMO_SENSOR`),
        or a sensor object, returned as is.

    Returns
    -------
    (object, str)
        The sensor (with ``respond`` and ``area_m2``) and its description.

    Raises
    ------
    ValueError
        An unknown name (see :func:`fsrlab.acquisition.protocols.virtual_sensor`).
    """
    from fsrlab.acquisition.protocols import virtual_sensor

    return virtual_sensor(DEMO_SENSOR if name is None else name)


@dataclass(frozen=True)
class DemoSettings:
    """How long the demo's recordings are (the virtual bench runs in real time).

    Parameters
    ----------
    cycles : int
        Spring cycles per run.
    period_s : float
        Duration of one spring cycle. [s]
    peak_pa : float
        Peak stress of the spring cycles (the paper's bench: 10 kPa). [Pa]
    masses_kg : tuple of float
        Dead weights (the paper: 200 g and 400 g). [kg]
    repeat : int
        Placements of each dead weight (the paper: 5).
    settle_hold_s : float
        Steady time recorded per placement. [s]
    window_ms : int
        Measurement window. [ms]
    seed : int
        Noise seed of the first run (the others use the next ones).
    """

    cycles: int = 4
    period_s: float = 4.0
    peak_pa: float = 10e3
    masses_kg: tuple = (0.2, 0.4)
    repeat: int = 5
    settle_hold_s: float = 0.5
    window_ms: int = 20
    seed: int = 1


@dataclass
class DemoResult:
    """What :func:`run_demo` did.

    Attributes
    ----------
    index : Path
        The demo's ``index.html``.
    device : str
        ``twin`` or ``virtual``.
    files : dict
        Name → path of every file written (runs, calibration, reports).
    steps : list of (str, float)
        Each step and its duration. [s]
    numbers : dict
        The headline numbers (HE of f, V0 and the estimate, RE, calibration).
    """

    index: Path
    device: str
    files: dict = field(default_factory=dict)
    steps: list = field(default_factory=list)
    numbers: dict = field(default_factory=dict)

    @property
    def total_s(self) -> float:
        """Total duration. [s]"""
        return float(sum(t for _, t in self.steps))


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
    from fsrlab.acquisition.protocols import SpringPlan, WeightsPlan, run_protocol, twin_status

    say = progress or (lambda line: None)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    s = settings
    sensor_obj, sensor_text = demo_sensor(sensor)
    if device not in ("auto", "twin", "virtual"):
        raise ValueError(f"device: must be auto, twin or virtual, got {device!r}")
    ok, reason = twin_status()
    if device == "twin" and not ok:
        raise ValueError(f"device: the digital twin is not available: {reason}")
    bench = "twin" if (device == "twin" or (device == "auto" and ok)) else "virtual"
    result = DemoResult(index=out / "index.html", device=bench)
    total = 7 if paper else 6
    t_all = time.monotonic()
    k = [0]

    def step(title: str):
        k[0] += 1
        say(f"[{k[0]}/{total}] {title}")
        return time.monotonic()

    def done(title: str, t0: float, text: str = "") -> None:
        dt = time.monotonic() - t0
        result.steps.append((title, dt))
        say(f"      {text + '; ' if text else ''}{dt:.1f} s (total {time.monotonic() - t_all:.1f} s)")

    def recorder(label: str, total_s: float | None):
        last = [time.monotonic()]

        def on_status(st) -> None:
            now = time.monotonic()
            if now - last[0] >= 3.0:
                last[0] = now
                say(f"      {label}: {st.elapsed_s:.0f} s" + (f" of {total_s:.0f} s" if total_s else "")
                    + f", {st.frames} windows")
        return on_status

    def record(plan, name: str, seed: int, label: str, total_s: float | None, settle=None):
        nonlocal bench
        path = out / name
        try:
            run = run_protocol(plan, path, device=bench, sensor=sensor_obj, seed=seed, window_ms=s.window_ms,
                               overwrite=True, on_status=recorder(label, total_s), settle=settle)
        except Exception as exc:  # noqa: BLE001 - the twin failing: say so and use the Python device
            if bench != "twin" or device == "twin":
                raise
            say(f"      the digital twin failed ({type(exc).__name__}: {exc}); using the Python virtual device")
            bench = result.device = "virtual"
            run = run_protocol(plan, path, device=bench, sensor=sensor_obj, seed=seed, window_ms=s.window_ms,
                               overwrite=True, on_status=recorder(label, total_s), settle=settle)
        if run.result.failed or not run.result.frames:
            raise RuntimeError(f"{path}: the recording failed: {run.result.message}")
        result.files[name] = path
        return run

    # 1. The bench and the spring runs.
    spring = SpringPlan(peak_pa=s.peak_pa, cycles=s.cycles, period_s=s.period_s)
    t0 = step(f"spring cycles on the {'digital twin (firmware in simavr)' if bench == 'twin' else 'Python virtual device'}"
              f"{'' if bench == 'twin' else ' (the twin is not available: ' + reason + ')'}: sensor {sensor_text}; "
              f"{s.cycles} cycles 0 → {s.peak_pa / 1e3:g} kPa → 0 of {s.period_s:g} s, twice (calibration run, test run)")
    r1 = record(spring, "calibration-run.csv", s.seed, "calibration run", spring.duration_s)
    r2 = record(spring, "test-run.csv", s.seed + 1, "test run", spring.duration_s)
    done("spring runs", t0, f"{r1.result.frames} + {r2.result.frames} windows on the {bench} bench")

    # 2. Dead weights.
    weights = WeightsPlan(masses_kg=tuple(s.masses_kg), repeat=s.repeat)
    t0 = step(f"dead weights: {', '.join(format(m * 1e3, 'g') + ' g' for m in weights.masses_kg)}, "
              f"each placed {s.repeat} times from below, unloaded in between ({len(weights.steps())} placements)")
    rw = record(weights, "weights-run.csv", s.seed + 2, "dead weights", None,
                settle={"hold_s": s.settle_hold_s})
    result.files["placements"] = rw.placements
    done("dead weights", t0, f"{rw.summary['recorded']} of {len(weights.steps())} placements recorded")

    # 3. Calibration.
    from fsrlab.analysis.calibration_io import save_calibration
    from fsrlab.analysis.pipeline import apply_calibration, calibrate_run

    import numpy as np

    from fsrlab.runformat import load_run

    calrun = load_run(out / "calibration-run.csv")
    # The load cell when the meter has one (the virtual meter emulates an HX711): the reference a bench
    # with hardware has; else the stress the bench applied.
    reference = "force_n" if "force_n" in calrun and np.isfinite(calrun["force_n"]).mean() > 0.5 else "stress_pa"
    what = "the load cell's force (HX711)" if reference == "force_n" else "the applied stress"
    t0 = step(f"calibration: the calibration run against {what}, model chosen by grouped cross-validation, with the "
              "causal hysteresis compensation; and a known-weight calibration on the dead weights (m·g)")
    # The lag is searched as on any recording; the virtual bench takes the reference in the readout's own
    # window, so the search finds 0 within a row (docs/calibration.md, "Lag").
    try:
        cal = calibrate_run(calrun, compensate=True, reference=reference)
    except ValueError as exc:  # a run too short for the compensation: the plain calibration, said
        say(f"      no compensation: {str(exc).split(': ', 1)[-1]}")
        cal = calibrate_run(calrun, reference=reference)
    result.files["calibration"] = save_calibration(cal, out / "calibration.json")
    known = None
    try:
        # Three load levels (0 and two masses): a polynomial of degree 2 at most.
        known = calibrate_run(out / "weights-run.csv", degree=min(2, len(weights.masses_kg)), reference="force_n")
        result.files["known-weight calibration"] = save_calibration(known, out / "known-weight-calibration.json")
    except ValueError as exc:
        say(f"      known-weight calibration not possible: {exc}")
    result.numbers["calibration"] = {"model": cal.model_name, "reference": cal.y_name, "cv_rmse": cal.cv_rmse,
                                     "unit": cal.y_unit, "lag_s": cal.lag_s}
    if known is not None:
        result.numbers["known_weight_calibration"] = {"model": known.model_name, "reference": known.y_name,
                                                      "cv_rmse": known.cv_rmse, "unit": known.y_unit}
    done("calibration", t0, f"{cal.model_name}, CV RMSE {cal.cv_rmse:.3g} {cal.y_unit}"
         + (f"; known weights: {known.model_name}, CV RMSE {known.cv_rmse:.3g} {known.y_unit}"
            if known is not None else ""))

    # 4. Compensation on the test run.
    from fsrlab.runwriter import write_run

    t0 = step("compensation: the calibration applied to the test run (causal estimate, row by row)")
    est = apply_calibration(cal, out / "test-run.csv")
    result.files["estimate"] = write_run(out / "test-estimate.csv", est.columns, est.metadata, overwrite=True)
    done("compensation", t0, f"{out / 'test-estimate.csv'}")

    # 5. Measurement report.
    from fsrlab.report.run_report import write_run_report

    t0 = step("measurement report of the test run: HE of f and V0 (Table 3), RE1/RE2 (eq. 39), ISO 376, calibration")
    rep = write_run_report(out / "test-run.csv", out / "measurement", weights_run=out / "weights-run.csv",
                           calibration=cal)
    result.files["measurement report"] = rep.index
    hs = {h.quantity: h.percent for h in rep.report.hysteresis}
    result.numbers.update({"he_frequency_percent": hs.get("frequency_hz"), "he_voltage_percent": hs.get("voltage_v"),
                           "he_estimate_percent": None if rep.report.estimate is None else rep.report.estimate.percent,
                           "repeatability": [p.to_dict() for p in rep.report.repeatability],
                           "iso376_class": None if rep.report.iso376 is None else rep.report.iso376.instrument_class})
    fmt = lambda v: "—" if v is None else f"{v:.2f} %"  # noqa: E731
    done("measurement report", t0, f"HE f {fmt(hs.get('frequency_hz'))}, V0 {fmt(hs.get('voltage_v'))}, "
         f"estimate {fmt(result.numbers['he_estimate_percent'])}")

    # 6. The reproduction report.
    if paper:
        from fsrlab.report.paper import write_report

        t0 = step("reproduction report of the paper (fsrlab paper)")
        pr = write_report(out / "paper", progress=None)
        result.files["reproduction report"] = pr.index
        done("reproduction report", t0, f"{len(pr.sections)} sections")

    # 7. The index.
    t0 = step("index")
    _write_index(result, sensor_text, s)
    done("index", t0, str(result.index))
    return result


def _num(v) -> str:
    """A number for the index page ("—" when missing)."""
    return "—" if v is None else f"{v:.3g}"


def _cal_text(title: str, c: dict | None) -> str:
    """One calibration's line on the index page."""
    if not c:
        return f"{title}: none"
    return html.escape(f"{title}: {c['model']} against {c['reference']}, cross-validated RMSE "
                       f"{_num(c['cv_rmse'])} {c['unit']}")


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
<h2>Steps</h2><ol>{steps}</ol><h2>Files</h2><ul>{files}</ul></body></html>
"""
    result.index.write_text(page, encoding="utf-8")
