"""``fsrlab live``: the meter's front panel in a browser (time series, hysteresis loop, status, controls)."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    AREA_HELP,
    LOADCELL_HELP,
    SENSOR_HELP,
    MeterCircuit,
    areas,
    check_virtual,
    fail,
    load_frame_calibration,
    loadcell_option,
    make_virtual_device,
    mass_list,
    meter_circuit_options,
    meter_differences,
    out_path,
    pascals,
    refuse_other_meter,
    seconds,
    sensor_area,
    virtual_bench,
    warn,
    window_ms_option,
)
from fsrlab.errors import FsrlabError, ParameterError
from fsrlab.io.jsonable import to_jsonable
from fsrlab.units import STANDARD_GRAVITY


def _estimator(cal, area_m2: float | None, ranges: tuple[int, ...]):
    """``row -> (estimate [N], uncertainty [N])`` by the calibration's causal estimator (compensation included),
    NaN on a range not in ``ranges`` (those where the meter reads as the calibration's run did)."""
    import math

    est = cal.estimator()
    scale = 1.0 if est.reference == "force_n" else (area_m2 or math.nan)  # stress → force

    def step(row):
        if row.get("range") not in ranges:  # switched to a range where the readout means another force
            return math.nan, math.nan
        x = row.get(est.x)
        t = row.get("time_s")  # the memory's creep ages by the row's time, not by the calibration's row step
        e, u, _inside = est.step(x if x is not None and math.isfinite(x) else None,
                                 t if t is not None and math.isfinite(t) else None)
        return (math.nan if e is None else e * scale), (math.nan if u is None else u * scale)
    return step


def _json_line(obj) -> None:
    """One JSON object on one line (a reader can act on the URL before the command ends)."""
    import json

    typer.echo(json.dumps(to_jsonable(obj)))


@app.command()
@meter_circuit_options(virtual_c_off=True)
def live(
    port: str = typer.Option(None, "--port", help="Serial port of the meter (/dev/ttyACM0, COM3, a pty) or 'auto'."),
    virtual: bool = typer.Option(False, "--virtual", help="Show a virtual device (pty, physics and 555 models) instead "
            "of hardware."),
    out: Path = typer.Option(None, "--out", "-o", parser=out_path, help="Run file for the page's 'Start recording' "
            "(CSV + sidecar); later recordings get -2, -3, ...; never replaced. Without it recording is off."),
    cal: Path = typer.Option(None, "--cal", help="Calibration JSON (fsrlab calibrate -o): the page also shows the "
            "estimate and its uncertainty."),
    host: str = typer.Option("127.0.0.1", "--host", help="Interface to serve on: 127.0.0.1 (this computer only) or "
            "e.g. 0.0.0.0; any other than 127.0.0.1 needs the random token printed with the URL."),
    http_port: int = typer.Option(5006, "--http-port", help="TCP port of the page [1], 1..65535, or 0 for any free "
            "one."),
    open_browser: bool = typer.Option(False, "--open", help="Open the page in the default browser."),
    window: float = typer.Option("100ms", "--window", parser=seconds, metavar="TIME", help="Measurement window at the "
            "start [s], 10ms to 60s: 20ms, 100ms, 1s."),
    range_: int = typer.Option(0, "--range", help="C_off range switch at the start: 0 (off) or 1 (C_off connected)."),
    duration: float = typer.Option(None, "--duration", parser=seconds, metavar="TIME", help="Serve this long [s], then "
            "stop (default: until Ctrl-C): 10s, 2min."),
    profile: str = typer.Option("triangle", "--profile", help="Virtual device: stress profile (triangle, sine, ...)."),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS", help="Virtual device: peak stress "
            "[Pa], e.g. 50k."),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help="Virtual device: period of the "
            "profile [s], e.g. 4s."),
    seed: int = typer.Option(None, "--seed", help="Virtual device: random seed [1] (default: a fresh one)."),
    loadcell: Path = typer.Option(None, "--loadcell", help=LOADCELL_HELP),
    sensor: str = typer.Option(None, "--sensor", help=SENSOR_HELP),
    area: float = typer.Option(None, "--area", parser=areas, metavar="AREA", help=AREA_HELP),
    masses: str = typer.Option(None, "--masses", metavar="MASSES", help="Offer the guided known-weight calibration on "
            "the page with these masses, increasing, comma-separated [kg]: 0,100g,200g,400g (g, kg or mg; 0 needs no "
            "unit). With --virtual a virtual bench places each mass when the page says Placed."),
    repeat: int = typer.Option(1, "--repeat", help="Guided calibration: cycles of placements [1], e.g. 3."),
    unload: bool = typer.Option(False, "--unload", help="Guided calibration: also unload in reverse (for hysteresis)."),
    channels: str = typer.Option(None, "--channels", metavar="LIST", help="Scan these multiplexer channels (a "
            "protocol-3 meter, docs/multiplexing.md): 0-7, 0,2,5; the page shows a sensor map, every channel's "
            "frequency and its link health. With --virtual: channel k under the profile at peak x (k+1)/(highest "
            "channel+1)."),
    refresh_s: float = typer.Option("40ms", "--refresh", parser=seconds, metavar="TIME", help="Shortest time "
            "between two updates of the page's numbers [s], 40ms to 10s, e.g. 250ms on a small computer; its plots "
            "redraw every 100 ms or this, if longer. The browser's work grows with the rate (docs/live.md: headless "
            "Chromium on a 2-core machine took about 1.15 cores at 40 ms, 0.47 at 250 ms)."),
    unplug_after: int = typer.Option(None, "--unplug-after", help="Virtual device (tests): pull the cable after this "
            "many windows [1]."),
    json_out: bool = typer.Option(False, "--json", help='Print JSON lines: {"url", "token"} when the page is up, '
            '{"frames", "recorded", "state"} at the end.'),
    meter: MeterCircuit = MeterCircuit(),
) -> None:
    """Serve the meter's front panel: frequency, duty cycle, op-amp voltage and the reference live, the
    loading/unloading loop, the link's health, and controls (recording, range, window).

    The page shows the latest window's numbers every 40 ms and redraws the plots every 100 ms
    (--refresh for slower; docs/live.md), and works offline (BokehJS comes with the bokeh package). It is
    served on 127.0.0.1 only unless --host names another interface; then every request needs the
    token printed with the URL. One browser tab controls the meter; more tabs watch. With --port, the
    meter's circuit as built (--r with --c-off, --diode, --vcc; --r-f, --drive for the op-amp) goes into
    the recordings' sidecars, and a --cal recorded with another circuit or range is refused (exit 2);
    on a range switched to where it does not fit, the estimate is left blank.

    Examples:

    \b
      fsrlab live --virtual --out bench.csv --open
      fsrlab live --port auto --r 10k --c-off 1n --diode --cal cal.json --out run.csv
      fsrlab live --virtual --host 0.0.0.0 --http-port 8080
    """

    window_ms, host = _checked_options(port, virtual, window, range_, http_port, duration, host)
    from fsrlab.cli.acquisition import scan_options
    from fsrlab.live.page import check_refresh

    check_refresh(refresh_s)  # before the meter or the page starts

    scan, _ = scan_options(channels, None, None)
    if scan is not None and masses is not None:
        fail("the guided calibration reads one sensor: leave out --channels or --masses", "--channels")
    if scan is not None and cal is not None:
        fail("a calibration file holds one sensor's calibration; the page shows the channels' frequencies "
             "(apply per-channel calibrations to the run: fsrlab calibrate-channels)", "--cal")
    if out is not None:
        _check_new_run(out, [cal, loadcell])
    circuits = meter.sidecar(None, "--virtual" if virtual else None)  # the page may switch to either range
    sensor_meta, area_m2 = sensor_area(sensor, area)
    lc = loadcell_option(loadcell)
    calibration = load_frame_calibration(cal, "live") if cal is not None else None
    from fsrlab.live.page import Controller, make_document
    from fsrlab.live.session import LiveSession

    device, reference, health = None, None, None
    metadata: dict = {**circuits, **({"sensor": sensor_meta} if sensor_meta else {})}
    steps = None if masses is None else _guided_steps(masses, repeat, unload, out)
    place = None
    if virtual:
        device, source, place = _virtual_meter(profile, peak, period, meter, seed, steps, area_m2, unplug_after)
        if scan is not None:
            device, source = _virtual_bench_of_sensors(device, scan, profile, peak, period, meter, seed, area_m2)
        if lc is None:
            lc = device.load_cell.calibration()
        area_m2 = source.sensor.area_m2
        metadata = {"origin": "fsrlab live --virtual", **source.metadata(), **metadata}
        reference, health = _virtual_hooks(device, steps is None)
    weights = None if steps is None else _weights_plan(steps, place, repeat, unload)
    estimator = None
    if calibration is not None:
        refuse_other_meter(calibration, metadata, range_)  # before the device is opened
        usable = tuple(r for r in (0, 1) if not meter_differences(calibration, metadata, r))
        estimator = _estimator(calibration, area_m2, usable)
    if virtual:
        port = device.open()
    elif (cal is not None or out is not None) and (note := meter.warning(out, cal)):
        warn([note])
    link = _open_link(port, device)
    session = LiveSession(link, window_ms=window_ms, range_=range_, reference=reference, loadcell=lc, area_m2=area_m2,
                          estimator=estimator, health=health, metadata=metadata, weights=weights, scan=scan)
    session.start()
    controller = Controller(out)
    srv = _start_server(lambda doc: make_document(doc, session, controller, "force", "N", 1.0, refresh_s=refresh_s),
                        host, http_port,
                        (session, link, device))
    _serve(srv, session, link, device, json_out, open_browser, duration)
    if json_out:
        _json_line({"frames": session.status.frames, "recorded": session.status.recorded,
                    "state": session.status.state})
    else:
        typer.echo(f"fsrlab live: {session.status.frames} windows shown; {session.status.state}: "
                f"{session.status.message}")


def _checked_options(port, virtual: bool, window: float, range_: int, http_port: int, duration: float | None,
                     host: str) -> tuple[int, str]:
    """live's options checked before anything is opened: the window in whole milliseconds and the interface."""
    from fsrlab.live.hosts import check_bind_host

    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    window_ms = window_ms_option(window)
    if range_ not in (0, 1):
        fail(f"must be 0 or 1, got {range_}", "--range")
    if not 0 <= http_port <= 65535:
        fail(f"must be 0..65535, got {http_port}", "--http-port")
    if duration is not None and not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    try:
        host = check_bind_host(host)
    except ParameterError as exc:
        fail(exc.reason, "--host")
    return window_ms, host


def _virtual_hooks(device, applied_stress: bool):
    """The session's ``reference`` (the stress the virtual device applied in a frame's window; None for a bench
    that places masses, whose reference is the load cell's) and ``health``."""
    reference = (lambda frame: device.reference(frame.seq)) if applied_stress else None
    return reference, (lambda: device.failure)


def _weights_plan(steps, place, repeat: int, unload: bool) -> dict:
    """The session's guided known-weight calibration: the placements, who places them and the sidecar's plan."""
    return {"steps": steps, "place": place, "x": "frequency_hz", "gravity_m_s2": STANDARD_GRAVITY,
            "metadata": {"weights": {"masses_kg": [s.mass_kg for s in steps], "repeat": repeat, "unload": unload}}}


def _open_link(port: str, device):
    """The serial link to the meter, or one line naming --port (the virtual device closed again)."""
    from fsrlab.acquisition.serial_link import SerialLink

    try:
        return SerialLink(port)
    except Exception as exc:  # noqa: BLE001 - one line: the port could not be opened
        if device is not None:
            device.close()
        if isinstance(exc,
                      FsrlabError) and exc.parameter == "port":  # e.g. --port auto and no board: as acquire says it
            fail(exc.reason, "--port")
        fail(f"cannot open {port}: {exc}", "--port")


def _start_server(make_doc, host: str, http_port: int, opened: tuple):
    """The page's server on ``host``:``http_port``; if it cannot start, what is open (session, link, device) is
    closed and one line names the option at fault."""
    from fsrlab.live.server import start_server

    try:
        return start_server(make_doc, host=host, port=http_port)
    except OSError as exc:
        for thing in opened:
            if thing is not None:
                thing.close()
        fail(f"cannot serve on {host}:{http_port}: "
             f"{exc.strerror or exc}", "--host" if host != "127.0.0.1" else "--http-port")


def _guided_steps(masses: str, repeat: int, unload: bool, out: Path | None):
    """The placements of ``--masses`` (the guided known-weight calibration on the page), or one line naming the
    option at fault."""
    from fsrlab.bench.weights import plan_steps

    try:
        masses_kg = mass_list(masses)
    except typer.BadParameter as exc:
        fail(exc.message, "--masses")
    if len(masses_kg) < 2:
        fail(f"give at least two masses, e.g. 0,100g; got {masses!r}", "--masses")
    if not 1 <= repeat <= 1000:
        fail(f"must be 1 to 1000 cycles, got {repeat}", "--repeat")
    if out is None:
        fail("the guided calibration writes a run: give --out RUN.csv", "--masses")
    return plan_steps(masses_kg, repeat, unload)


def _virtual_meter(profile: str, peak: float, period: float, meter: MeterCircuit, seed, steps, area_m2,
                   unplug_after: int | None):
    """``--virtual``: the virtual device (a bench that places the plan's masses with ``--masses``), its source,
    and the placing callback (None without masses)."""
    check_virtual(profile, peak, period, meter.virtual_c_off_farad, 0.0, 0.0, seed)
    place = None
    if steps is not None:  # a virtual bench that places the masses of the plan
        device, source, place = virtual_bench(steps, seed, area_m2, STANDARD_GRAVITY)
    else:
        device, source = make_virtual_device(profile, peak, period, meter.virtual_c_off_farad, seed, 0.0, 0.0, True,
                                             80, area_m2)
    if unplug_after is not None:
        if unplug_after < 1:
            fail(f"must be >= 1 window, got {unplug_after}", "--unplug-after")
        from fsrlab.virtual.device import Faults

        device.faults = Faults(unplug_after=unplug_after)
    return device, source, place


def _virtual_bench_of_sensors(device, scan, profile: str, peak: float, period: float, meter: MeterCircuit, seed,
                              area_m2):
    """``--virtual --channels``: the device with a sensor per channel behind the multiplexer, as acquire's."""
    from fsrlab.cli.acquisition import mux_source
    from fsrlab.virtual.device import VirtualDevice

    source = mux_source(max(scan.channels) + 1, profile, peak, period, meter.virtual_c_off_farad, area_m2=area_m2)
    return VirtualDevice(source, faults=device.faults, seed=seed, load_cell=device.load_cell), source


def _serve(srv, session, link, device, json_out: bool, open_browser: bool, duration: float | None) -> None:
    """Say where the page is, open it when asked, and serve until Ctrl-C or ``duration`` [s]; then close all."""
    if json_out:
        _json_line({"url": srv.url, "token": srv.token})
    else:
        typer.echo(f"fsrlab live: {srv.url}  (Ctrl-C to stop)")
    sys.stdout.flush()
    if open_browser:
        import webbrowser

        webbrowser.open(srv.url)
    loop = srv.server.io_loop
    if duration is not None:
        loop.call_later(duration, loop.stop)
    try:
        loop.start()
    except KeyboardInterrupt:
        pass
    finally:
        srv.server.stop()
        session.close()
        link.close()
        if device is not None:
            device.close()


def _check_new_run(out: Path, inputs: list) -> None:
    """``--out``: a run that does not exist yet (live has no --overwrite: it never replaces a run)."""
    from fsrlab.io.outputs import OutputError, check_output

    try:
        check_output(out, "--out", inputs=inputs, kind="run")
    except OutputError as exc:
        fail(exc.message.replace("pass --overwrite to replace it", "live never replaces a run: give a new name"),
             "--out")
