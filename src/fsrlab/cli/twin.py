"""``fsrlab twin``: the real firmware in simavr, driven by the sensor and 555 models, on a pty."""

from __future__ import annotations

import sys

import typer

from fsrlab.cli import app
from fsrlab.cli.options import (
    C_OFF_HELP,
    PEAK_HELP,
    PERIOD_HELP,
    PROFILE_HELP,
    RATE_HELP,
    SENSOR_HELP,
    check_rate,
    check_virtual,
    fail,
    farads,
    make_virtual_device,
    pascals,
    plain_numbers,
    seconds,
    sensor_area,
    sigterm_as_interrupt,
    virtual_sensor_option,
)


@app.command("twin")
def twin(
    profile: str = typer.Option("triangle", "--profile", help=PROFILE_HELP),
    peak: float = typer.Option("50k", "--peak", parser=pascals, metavar="STRESS", help=PEAK_HELP),
    period: float = typer.Option("4s", "--period", parser=seconds, metavar="TIME", help=PERIOD_HELP),
    sensor: str = typer.Option(None, "--sensor", help=SENSOR_HELP[:-1] + "; the model stays VirtualFSR, with that "
            "area. Or a virtual sensor: virtual-fsr (default), paper-a201-1 .. paper-a201-4 (fitted to the paper's §6, "
            "valid to about 10 kPa: use --peak 10k)."),
    c_off: float = typer.Option("1n", "--c-off", parser=farads, metavar="CAPACITANCE", help=C_OFF_HELP),
    speed: str = typer.Option("realtime", "--speed", help="Pacing of simulated time: realtime (the wall clock) or max "
            "(as fast as simavr goes)."),
    duration: float = typer.Option(None, "--duration", parser=seconds, metavar="TIME", help="Run this long [s] of wall "
            "time: 90, 90s, 1.5min, 2h (default: until Ctrl-C)."),
    seed: int = typer.Option(0, "--seed", help="Random seed of the load cell's noise (an integer)."),
    no_loadcell: bool = typer.Option(False, "--no-loadcell", help="No HX711 on D2/D3 (ref_ok 0: reference columns "
            "empty)."),
    hx711_rate: int = typer.Option(80, "--hx711-rate", help=RATE_HELP.replace("Virtual device: t", "T")),
    channels: int = typer.Option(None, "--channels", metavar="N", help="Sensors behind a CD74HC4051 multiplexer on the "
            "timing node, 1..8 [1]: channel k under the profile at peak x (k+1)/N; the firmware's select lines D5..D7 "
            "pick the one the 555 sees (scan them with acquire --channels)."),
    json_out: bool = typer.Option(False, "--json", help='Print {"port": PATH} as JSON (one line) instead of the bare '
            'path.'),
) -> None:
    """Run the digital twin: the meter's real firmware in simavr on a pty; prints its path first.

    D8 carries the edges of the exact LM555 transient of the virtual sensor under the stress
    profile (with the C_off the firmware switches on D4), A0 the op-amp readout (eq. 38), the HX711
    on D2/D3 the load cell's reading of the applied force. Open the printed port with
    `fsrlab acquire --port PATH`, `fsrlab live --port PATH` or any serial monitor. Notices (a profile
    that drives the sensor out of oscillation) go to stderr. Needs simavr and the built firmware
    (`make sysdeps`, `make firmware`), or, from an installed package, a C compiler and simavr's
    headers (the harness is built on first use; `fsrlab doctor` says). Exit code 1, with one line
    saying why, if the twin fails.

    Examples:

    \b
      fsrlab twin --profile triangle --peak 50k --period 4s
      fsrlab twin --channels 8 --profile triangle --speed max --duration 5s
    """
    import json

    if duration is not None and not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    if speed not in ("realtime", "max"):
        fail(f"must be realtime or max, got {speed!r}", "--speed")
    if seed < 0:
        fail(f"must be an integer >= 0, got {seed}", "--seed")
    check_rate(hx711_rate)
    if channels is not None and not 1 <= channels <= 8:
        fail(f"must be 1..8, got {channels}", "--channels")
    check_virtual(profile, peak, period, c_off, 0.0, 0.0, None)
    model, _ = virtual_sensor_option(sensor)
    area_m2 = None if model is not None else sensor_area(sensor, None)[1]

    from fsrlab.virtual.twin import Twin, twin_available

    ok, reason = twin_available()
    if not ok:
        fail(reason)
    _, source = make_virtual_device(profile, peak, period, c_off, None, 0.0, 0.0, load_cell=False, area_m2=area_m2,
                                sensor_model=model)
    if channels is not None:
        from fsrlab.cli.acquisition import mux_source

        source = mux_source(channels, profile, peak, period, c_off, model, area_m2)
    from fsrlab.acquisition.loadcell import LoadCellModel

    cell = None if no_loadcell else LoadCellModel(rate_sps=hx711_rate)
    device = Twin(source, speed=speed, seed=seed, loadcell=cell)
    device.on_notice = lambda text: print(f"fsrlab twin: {text}", file=sys.stderr, flush=True)
    try:
        path = device.open()
    except RuntimeError as err:
        fail(str(err))
    import time

    try:
        typer.echo(json.dumps({"port": path}) if json_out else path)
        sys.stdout.flush()
        end = None if duration is None else time.monotonic() + duration
        with sigterm_as_interrupt():
            while device.failure is None and (end is None or time.monotonic() < end):
                time.sleep(0.1 if end is None else max(0.0, min(0.1, end - time.monotonic())))
    except KeyboardInterrupt:
        pass
    finally:
        failure = device.failure
        device.close()
    if failure is not None:
        print(f"fsrlab: twin failed: {plain_numbers(failure)}", file=sys.stderr)
        raise typer.Exit(1)
