"""``fsrlab acquire`` and ``fsrlab virtual-device``: record an fsrlab meter, or emulate one on a pty.

The options the recording commands share (the sensor and its area, the load-cell calibration, the virtual
device) are :mod:`fsrlab.cli.options`.
"""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    AREA_HELP,
    C_OFF_HELP,
    CORRUPT_HELP,
    DROP_HELP,
    LOADCELL_HELP,
    NO_LOADCELL_HELP,
    PEAK_HELP,
    PERIOD_HELP,
    PROFILE_HELP,
    RATE_HELP,
    SEED_HELP,
    SENSOR_HELP,
    SPEED_HELP,
    LiveView,
    MeterCircuit,
    areas,
    check_out,
    check_rate,
    check_speed,
    check_virtual,
    emit_json,
    fail,
    farads,
    fraction,
    loadcell_option,
    make_virtual_device,
    meter_circuit_options,
    out_path,
    pascals,
    plain_numbers,
    seconds,
    sensor_area,
    sigterm_as_interrupt,
    warn,
    window_ms_option,
)

CHANNELS_HELP = ("Multiplexer channels to scan (a protocol-3 meter with a CD74HC4051, docs/multiplexing.md): 0-7, "
                 "0,2,5, 1-3,6. The run is then one row per channel reading (time_s, channel, scan, frequency_hz, "
                 "...). "
                 "With --virtual: a bench of sensors, channel k under the profile at peak x (k+1)/(highest channel+1).")
DWELL_HELP = "Counting time per channel in a scan [s], 1ms to 60s in whole milliseconds (default 3ms)."
SETTLE_HELP = "Periods discarded after the first edge that follows a switch of channel [1], 0..100 (default 2)."


def scan_options(channels: str | None, dwell: float, settle: int, channel_map: Path | None = None):
    """The ``Scan`` and channel map of ``--channels``, ``--dwell``, ``--settle``, ``--channel-map`` (None without
    channels)."""
    if channels is None:
        for given, name in ((dwell is not None, "--dwell"), (settle is not None, "--settle"),
                            (channel_map is not None, "--channel-map")):
            if given:
                fail("needs --channels (it sets how the meter scans them)", name)
        return None, None
    from fsrlab.acquisition.protocol import parse_channels
    from fsrlab.acquisition.stream import Scan
    from fsrlab.errors import ParameterError

    names = {"channels": "--channels", "dwell_ms": "--dwell", "settle": "--settle"}
    dwell_ms = 3 if dwell is None else round(dwell * 1000.0, 6)
    if dwell_ms != int(dwell_ms):
        fail(f"the meter counts whole milliseconds, got {dwell_ms:g} ms", "--dwell")
    try:
        scan = Scan(parse_channels(channels), int(dwell_ms), 2 if settle is None else settle)
    except ParameterError as err:
        fail(err.reason, names.get(err.parameter, "--channels"))
    entries = None
    if channel_map is not None:
        import json

        try:
            entries = json.loads(channel_map.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            fail(f"cannot read {channel_map}: {exc}", "--channel-map")
        from fsrlab.acquisition.recorder import channel_map as check_map

        try:
            check_map(scan.channels, entries)
        except ParameterError as err:
            fail(err.reason, "--channel-map")
    return scan, entries


def mux_source(channels: int, profile: str, peak: float, period: float, c_off: float, sensor_model=None,
               area_m2: float | None = None):
    """A virtual bench of ``channels`` sensors behind a CD74HC4051, channel k under the profile at
    peak·(k+1)/channels."""
    from fsrlab.physics.sensor import VirtualFSR
    from fsrlab.virtual.sources import VIRTUAL_CIRCUIT, MuxSource, StressProfile

    prof = StressProfile(kind=profile, peak_pa=peak, period_s=period)

    def factory(k: int):
        if sensor_model is not None:
            return sensor_model
        return VirtualFSR() if area_m2 is None else VirtualFSR(area_m2=area_m2)

    try:
        return MuxSource.scaled(channels, prof, factory, VIRTUAL_CIRCUIT.replace(c_off_farad=c_off))
    except ValueError as err:
        fail(str(err), "--peak")


@app.command("acquire")
@meter_circuit_options(virtual_c_off=True)
def acquire(
    port: str = typer.Option(None, "--port", help="Serial port (/dev/ttyACM0, COM3, a pty) or 'auto' to find an Uno by "
            "USB id."),
    virtual: bool = typer.Option(False, "--virtual", help="Record from a virtual device (pty, physics and 555 models) "
            "instead of hardware."),
    speed: str = typer.Option("realtime", "--speed", help=SPEED_HELP),
    duration: float = typer.Option("60s", "--duration", parser=seconds, metavar="TIME", help="Recording time [s]: 90, "
            "90s, 1.5min, 2h, 500ms (a bare m is refused: minutes or milliseconds?)."),
    out: Path = typer.Option(Path("run.csv"), "--out", "-o", parser=out_path, help="Run file (CSV + NAME.meta.json "
            "sidecar, docs/data-format.md)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing run file and its sidecar; without "
            "it an existing one stops the command before the device is touched."),
    window: float = typer.Option("100ms", "--window", parser=seconds, metavar="TIME", help="Measurement window [s], "
            "10ms to 60s in whole milliseconds (the meter counts ms): 20ms, 100ms, 0.25, 1s."),
    stall: float = typer.Option(None, "--stall", parser=seconds, metavar="TIME", help="No frame for this long [s] is "
            "reported as a gap (default: 5 windows, at least 2s); a device still silent at the end fails the run (exit "
            "1)."),
    range_: int = typer.Option(0, "--range", help="C_off range switch [1]: 0 (off) or 1 (C_off connected)."),
    baud: int = typer.Option(115200, "--baud", help="Line rate [bit/s]; protocol v1: 115200."),
    profile: str = typer.Option("triangle", "--profile", help=PROFILE_HELP),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS",
                               help="Virtual device: " + PEAK_HELP[0].lower() + PEAK_HELP[1:]),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME",
                                 help="Virtual device: " + PERIOD_HELP[0].lower() + PERIOD_HELP[1:]),
    seed: int = typer.Option(None, "--seed", help=SEED_HELP),
    corrupt: float = typer.Option("0", "--corrupt", parser=fraction, metavar="FRACTION",
                                  help="Virtual device (tests): " + CORRUPT_HELP[0].lower() + CORRUPT_HELP[1:]),
    drop: float = typer.Option("0", "--drop", parser=fraction, metavar="FRACTION",
                               help="Virtual device (tests): " + DROP_HELP[0].lower() + DROP_HELP[1:]),
    sensor: str = typer.Option(None, "--sensor", help=SENSOR_HELP),
    area: float = typer.Option(None, "--area", parser=areas, metavar="AREA", help=AREA_HELP),
    loadcell: Path = typer.Option(None, "--loadcell", metavar="LC.json", help=LOADCELL_HELP),
    no_loadcell: bool = typer.Option(False, "--no-loadcell", help=NO_LOADCELL_HELP),
    hx711_rate: int = typer.Option(80, "--hx711-rate", help=RATE_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No live display (notices of gaps still go to stderr)."),
    json_out: bool = typer.Option(False, "--json", help='Print {"frames", "dropped", "duration_s", "file"} as JSON, '
            '"no_reference" (windows without a load-cell conversion) for a protocol-2 device, and "run_s" (the run\'s '
            'length on the device\'s clock) with --speed max.'),
    channels: str = typer.Option(None, "--channels", metavar="LIST", help=CHANNELS_HELP),
    dwell: float = typer.Option(None, "--dwell", parser=seconds, metavar="TIME", help=DWELL_HELP),
    settle: int = typer.Option(None, "--settle", help=SETTLE_HELP),
    channel_map: Path = typer.Option(None, "--channel-map", metavar="MAP.json", help="The sensors' ids and positions "
            "for the sidecar: a JSON list of {\"channel\", \"sensor_id\", \"x_m\", \"y_m\"} [m] (default fsr<k>, no "
            "position)."),
    meter: MeterCircuit = MeterCircuit(),
) -> None:
    """Record measurement windows (frequency, duty cycle, A0 voltage) from an fsrlab meter into a run file.

    Written row by row: Ctrl-C or a kill loses at most the window in progress, and an existing run
    is replaced only with --overwrite. A protocol-2 meter adds the load cell's reference_raw and
    force_n (with --loadcell; empty, never 0, in windows without an HX711 conversion, which are
    counted); with --sensor or --area, stress_pa = force_n / area. With --port, the meter's circuit as
    built (--r, --c-off, --diode, --vcc; --r-f, --drive for the op-amp) goes into the sidecar, where
    calibrate and apply compare it with a calibration's. Exit code 1, with one line saying why and the rows so far
    kept, when the device is unplugged, fails, stays silent until the end, or no valid window
    arrives; the sidecar's "ended" says the same and "gaps" lists the silences.

    Examples:

    \b
      fsrlab acquire --virtual --duration 10s --window 20ms --out bench.csv
      fsrlab acquire --port auto --r 10k --c-off 1n --diode --channels 0-7 --duration 1.5min --out bench.csv
    """
    from fsrlab.acquisition.recorder import record, result_dict
    from fsrlab.acquisition.serial_link import SerialLink

    window_ms = _checked_options(port, virtual, speed, duration, window, stall, range_, baud, corrupt, drop,
                                 hx711_rate)
    scan, map_entries = scan_options(channels, dwell, settle, channel_map)
    circuits = meter.sidecar(range_, "--virtual" if virtual else None)
    sensor_meta, area_m2 = sensor_area(sensor, area)
    cal = loadcell_option(loadcell)
    check_out(out, overwrite, inputs=[loadcell])
    device = None
    metadata: dict = {**circuits, **({"sensor": sensor_meta} if sensor_meta else {})}
    reference = health = None
    if virtual:
        device, source = _virtual_meter(meter, profile, peak, period, seed, corrupt, drop, not no_loadcell, hx711_rate,
                                        area_m2, speed, scan)
        if cal is None and device.load_cell is not None:
            cal = device.load_cell.calibration()
        port = device.open()
        metadata = _virtual_metadata(source, sensor_meta, profile, peak, period, device.load_cell is not None)
        area_m2 = source.sensor.area_m2
        reference, health = _virtual_hooks(device)
    try:
        with SerialLink(port, baud=baud) as link, sigterm_as_interrupt(), \
                LiveView(not quiet, f"fsrlab acquire {link.port} -> {out}") as view:
            result = record(link, out, duration, window_ms=window_ms, range_=range_, metadata=metadata,
                            reference=reference, on_status=view.update, on_event=view.notice, stall_s=stall,
                            health=health, overwrite=overwrite, loadcell=cal, area_m2=area_m2,
                            clock="device" if speed == "max" else "host", scan=scan, channels_meta=map_entries)
    finally:
        if device is not None:
            device.close()
    if json_out:
        emit_json(result_dict(result))
    else:
        _print_summary(out, result, scan, cal)
        if not virtual and not result.failed and (note := meter.warning(out)):
            warn([note])
    if result.failed:
        print(f"fsrlab: {plain_numbers(result.message)}", file=sys.stderr)
        raise typer.Exit(1)


def _checked_options(port, virtual: bool, speed: str, duration: float, window: float, stall: float | None, range_: int,
                     baud: int, corrupt: float, drop: float, hx711_rate: int) -> int:
    """acquire's options checked before anything is opened; the window in whole milliseconds. [ms]"""
    if virtual == (port is not None):
        fail("give exactly one of --port PORT|auto and --virtual", "--port")
    check_speed(speed, virtual)
    if not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    window_ms = window_ms_option(window)
    if stall is not None and not stall > window_ms / 1000.0:
        fail(f"must be longer than one window ({window_ms / 1000.0:g} s), got {stall:g} s", "--stall")
    if range_ not in (0, 1):
        fail(f"must be 0 or 1, got {range_}", "--range")
    if not baud > 0:
        fail(f"must be > 0 bit/s, got {baud}", "--baud")
    for name, v in (("--corrupt", corrupt), ("--drop", drop)):
        if not 0 <= v <= 1:
            fail(f"must be in 0..1, got {v:g}", name)
    check_rate(hx711_rate)
    return window_ms


def _virtual_meter(meter: MeterCircuit, profile: str, peak: float, period: float, seed, corrupt: float, drop: float,
                   with_loadcell: bool, hx711_rate: int, area_m2: float | None, speed: str, scan):
    """acquire --virtual's device (not yet opened) and its source: one sensor, or a bench of them for --channels."""
    c_off = meter.virtual_c_off_farad
    check_virtual(profile, peak, period, c_off, corrupt, drop, seed)
    device, source = make_virtual_device(profile, peak, period, c_off, seed, corrupt, drop, with_loadcell,
                                         hx711_rate, area_m2, speed=speed)
    if scan is not None:
        from fsrlab.virtual.device import VirtualDevice

        source = mux_source(max(scan.channels) + 1, profile, peak, period, c_off, area_m2=area_m2)
        device = VirtualDevice(source, faults=device.faults, seed=seed, load_cell=device.load_cell, speed=speed)
    return device, source


def _virtual_metadata(source, sensor_meta: dict | None, profile: str, peak: float, period: float,
                      with_loadcell: bool) -> dict:
    """The sidecar's content for a virtual recording: where its numbers come from, and the sensor given."""
    virtual_meta = source.metadata()
    if sensor_meta:
        virtual_meta["sensor"] = {**sensor_meta, "virtual_model": virtual_meta["sensor"]["model"]}
    return {"origin": "fsrlab acquire --virtual (VirtualFSR -> LM555 astable and op-amp -> meter model "
                      "fsrlab.virtual.meter -> emulated firmware over a pty)",
            **virtual_meta,
            "notes": f"virtual stress profile {profile}, peak {peak:g} Pa, period {period:g} s; "
                     "stress_pa is the applied (reference) stress, force_n the emulated load cell's "
                     "reading" + ("" if with_loadcell else " (no HX711 emulated: empty)")}


def _virtual_hooks(device):
    """``record``'s ``reference`` (the stress the virtual device applied in a frame's window) and ``health``."""
    return (lambda frame: device.reference(frame.seq)), (lambda: device.failure)


def _print_summary(out: Path, result, scan, cal) -> None:
    """The recording in one line; a warning when the load cell's counts were recorded without a calibration."""
    typer.echo(f"{out}: {result.frames} {'windows' if scan is None else f'readings of {len(scan.channels)} channels'}, "
               f"{result.dropped} dropped, {result.duration_s:.1f} s "
               f"({result.stats.bad_frames} corrupt lines, {result.stats.resets} device resets, "
               f"{len(result.gaps)} gaps)"
               + (f"; {result.no_reference} windows without a load-cell reading" if result.reference else ""))
    if result.reference and cal is None and not result.failed:
        # the HX711's counts are in reference_raw, but nothing turns them into newtons (a failed recording
        # says only why it failed: one line)
        print(f"fsrlab: warning: {out}: force_n is empty in every row: no --loadcell calibration was given "
              "(the HX711's counts are in reference_raw; fsrlab loadcell tare/scale makes one)", file=sys.stderr)


@app.command("virtual-device")
def virtual_device(
    duration: float = typer.Option(None, "--duration", parser=seconds, metavar="TIME", help="Run this long [s]: 90, "
            "90s, 1.5min, 2h (default: until Ctrl-C)."),
    profile: str = typer.Option("triangle", "--profile", help=PROFILE_HELP),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS", help=PEAK_HELP),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help=PERIOD_HELP),
    c_off: float = typer.Option("1n", "--c-off", parser=farads, metavar="CAPACITANCE", help=C_OFF_HELP),
    seed: int = typer.Option(None, "--seed", help=SEED_HELP),
    corrupt: float = typer.Option("0", "--corrupt", parser=fraction, metavar="FRACTION", help=CORRUPT_HELP),
    drop: float = typer.Option("0", "--drop", parser=fraction, metavar="FRACTION", help=DROP_HELP),
    channels: int = typer.Option(None, "--channels", metavar="N", help="Sensors behind a multiplexer, 1..8 [1]: "
            "channel k under the profile at peak x (k+1)/N (scan them with acquire --channels)."),
    json_out: bool = typer.Option(False, "--json", help='Print {"port": PATH} as JSON (one line) instead of the bare '
            'path.'),
) -> None:
    """Emulate an fsrlab meter on a pseudo-terminal; prints its path (open it with --port PATH or any serial tool).

    Exit code 1, with one line saying why, if the emulated device fails.

    Examples:

    \b
      fsrlab virtual-device --duration 10min --profile sine --peak 80k --period 2s
      fsrlab virtual-device --channels 8 --corrupt 1% --drop 0.5% --seed 1
    """
    import json

    if duration is not None and not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    check_virtual(profile, peak, period, c_off, corrupt, drop, seed)
    if channels is not None and not 1 <= channels <= 8:
        fail(f"must be 1..8, got {channels}", "--channels")
    device, _ = make_virtual_device(profile, peak, period, c_off, seed, corrupt, drop)
    if channels is not None:
        from fsrlab.virtual.device import VirtualDevice

        device = VirtualDevice(mux_source(channels, profile, peak, period, c_off), faults=device.faults, seed=seed,
                               load_cell=device.load_cell)
    path = device.open(thread=False)
    typer.echo(json.dumps({"port": path}) if json_out else path)
    sys.stdout.flush()
    try:
        with sigterm_as_interrupt():
            device.serve(duration)
    except KeyboardInterrupt:
        pass
    finally:
        device.close()
    if device.error is not None:
        print(f"fsrlab: {plain_numbers(device.failure.replace('device thread failed', 'virtual device failed'))}",
              file=sys.stderr)
        raise typer.Exit(1)
