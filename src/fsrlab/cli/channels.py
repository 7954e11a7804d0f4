"""``fsrlab calibrate-channels`` and ``fsrlab crosstalk``: several FSRs on one meter (docs/multiplexing.md)."""

from __future__ import annotations

from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import emit_json, fail, pascals, plain_numbers, seconds
from fsrlab.cli.outputs import checked


@app.command("calibrate-channels")
def calibrate_channels_cmd(
    run: Path = typer.Argument(..., metavar="RUN.csv", help="A multi-channel run (acquire --channels): one row per "
            "channel reading."),
    out: Path = typer.Option(..., "--out", "-o", help="The calibrations, one JSON file keyed by sensor id."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing --out."),
    reference: str = typer.Option(None, "--reference", help="Reference column: stress_pa [Pa] or force_n [N] (default: "
            "stress_pa when the run has it)."),
    json_out: bool = typer.Option(False, "--json", help='Print {"sensors": {id: {"channel", "model", "r2"}}, "file"} '
            'as JSON.'),
) -> None:
    """Calibrate every channel of a multi-channel run from one command; one file keyed by sensor id.

    Each channel's rows are calibrated by the one calibration engine (as fsrlab calibrate does for a run);
    a channel without a reference (the load cell sits under another one) is left out.

    Examples:

    \b
      fsrlab calibrate-channels run.csv --out channels.json
    """
    from fsrlab.bench.channels import calibrate_channels
    from fsrlab.errors import FsrlabError

    if not run.is_file():
        fail(f"no such file: {run}", "RUN.csv")
    out = checked(out, "--out", overwrite=overwrite, inputs=[run])
    try:
        cals = calibrate_channels(run, **({"reference": reference} if reference else {}))
        cals.save(out, overwrite=overwrite, inputs=[run])
    except FsrlabError as err:
        fail(getattr(err, "reason", str(err)),
             {"reference": "--reference"}.get(getattr(err, "parameter", None), "RUN.csv"))
    summary = {sid: {"channel": cals.channels[sid], "model": getattr(cal, "model_name", None),
                     "r2": getattr(cal, "r2", None)} for sid, cal in cals.by_sensor.items()}
    if json_out:
        emit_json({"sensors": summary, "file": str(out)})
    else:
        for sid, row in summary.items():
            r2 = row["r2"]
            typer.echo(f"{sid} (channel {row['channel']}): {row['model']}"
                       + (f", R² {r2:.4f}" if isinstance(r2, float) else ""))
        typer.echo(f"{out}: {len(summary)} calibrations")


@app.command("crosstalk")
def crosstalk_cmd(
    twin: bool = typer.Option(False, "--twin", help="Run the check on the digital twin (the real firmware in simavr) "
            "instead of the Python virtual device."),
    channels: str = typer.Option("0-7", "--channels", metavar="LIST", help="Channels: 0-7, 0,2,5."),
    load: float = typer.Option("50k", "--load", parser=pascals, metavar="STRESS", help="Stress on the loaded channel "
            "[Pa]: 50k, 20kPa."),
    duration: float = typer.Option("0.5s", "--duration", parser=seconds, metavar="TIME", help="Simulated time per "
            "recording [s] (one unloaded, one per channel)."),
    json_out: bool = typer.Option(False, "--json",
                                  help='Print {"channels", "baseline_hz", "loaded_hz", "matrix", "worst"} as JSON.'),
) -> None:
    """Cross-talk check: load one channel at a time, read all of them; prints the channels × channels matrix.

    Row j is channel j loaded: each channel's frequency change over the loaded channel's own (the diagonal
    is 1). A virtual bench: every sensor unloaded, then each in turn under --load.

    Examples:

    \b
      fsrlab crosstalk
      fsrlab crosstalk --twin --channels 0-3 --json
    """
    from fsrlab.acquisition.protocol import parse_channels
    from fsrlab.bench.channels import crosstalk, twin_meter, virtual_meter
    from fsrlab.errors import ParameterError

    try:
        chans = parse_channels(channels)
    except ParameterError as err:
        fail(err.reason, "--channels")
    if not load > 0:
        fail(f"must be > 0 Pa, got {load:g}", "--load")
    if not duration > 0:
        fail(f"must be > 0 s, got {duration:g} s", "--duration")
    if twin:
        from fsrlab.virtual.twin import twin_available

        ok, reason = twin_available()
        if not ok:
            fail(reason, "--twin")
    try:
        result = crosstalk(twin_meter if twin else virtual_meter, chans, load, duration)
    except ValueError as err:  # the stress the virtual sensor takes (its model's range): the one left unchecked
        fail(str(getattr(err, "reason", err)), "--load")
    except RuntimeError as err:
        print(f"fsrlab: {plain_numbers(str(err))}", file=__import__("sys").stderr)
        raise typer.Exit(1) from None
    if json_out:
        emit_json(result.to_dict())
        return
    typer.echo("loaded\\read " + " ".join(f"{k:>8d}" for k in result.channels))
    for j, row in zip(result.channels, result.matrix, strict=True):
        typer.echo(f"{j:>11d} " + " ".join(f"{v:>8.5f}" for v in row))
    typer.echo(f"worst off-diagonal: {result.worst:.2e} (unloaded {result.baseline_hz.mean():.1f} Hz, "
               f"loaded {result.loaded_hz.diagonal().mean():.1f} Hz)")
