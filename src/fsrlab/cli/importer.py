"""``fsrlab import``: a foreign CSV (a user's own sketch, data logger, spreadsheet) made into a run.

Thin: the options go to :func:`fsrlab.io.foreign.import_foreign`, the run is written by
:func:`fsrlab.io.foreign.write_imported`; this module checks the output path and renders.
"""

from __future__ import annotations

from pathlib import Path

import typer

from fsrlab.cli import app
from fsrlab.cli.options import check_out, emit_json, fail, hertz, option_names, out_path, seconds

# The option a user gives to settle a question about a column (ForeignFormatError.role).
_ROLE_OPTIONS = {"time": "--time (or --rate)", "reading": "--reading", "force": "--force",
                 "reference_time": "--reference-time (or --reference-rate)", "offset": "--offset-s",
                 "time_unit": "--time-unit", "reading_unit": "--reading-unit", "force_unit": "--force-unit",
                 "reference_time_unit": "--reference-time-unit"}
_PARAMETERS = {"time_unit": "--time-unit", "reference_time_unit": "--reference-time-unit",
               "reading_unit": "--reading-unit", "force_unit": "--force-unit", "rate_hz": "--rate",
               "reference_rate_hz": "--reference-rate", "reference_time": "--reference-time",
               "offset_s": "--offset-s", "skip_lines": "--skip-lines", "output": "--output",
               "reference": "--reference", "path": "--output"}


@app.command("import")
def import_cmd(
    sensor: Path = typer.Argument(..., metavar="SENSOR.csv", help="The foreign CSV with the sensor's readout (and the "
            "force, without --reference)."),
    reference: Path = typer.Option(None, "--reference", metavar="REF.csv", help="A second foreign CSV with the "
            "reference force (another logger), aligned on the time stamps."),
    output: Path = typer.Option(..., "--output", "-o", metavar="RUN.csv", parser=out_path, help="The run to write: "
            "time_s [s], reading [its unit], force_n [N], and its sidecar RUN.meta.json."),
    time: str = typer.Option(None, "--time", metavar="COL", help="Time column of SENSOR.csv [header name or 1-based "
            "number], e.g. time_ms or 1 (default: found from the header)."),
    time_unit: str = typer.Option(None, "--time-unit", help="Unit of the time column [s, ms, us, min or h] (default: "
            "what its header says, else s; a unit it says that is none of these is refused)."),
    rate: float = typer.Option(None, "--rate", parser=hertz, help="Sample rate of SENSOR.csv when it has no time "
            "column [Hz], e.g. 100 or 1k: row k at k/rate."),
    reading: str = typer.Option(None, "--reading", metavar="COL", help="Readout column [header name or 1-based number] "
            "(default: found from the header: fsr, analog, adc, reading, ...); kept as 'reading'."),
    reading_unit: str = typer.Option(None, "--reading-unit", help="Unit of the readout, kept as it is [counts, V, mV, "
            "ohm or kohm] (default: what its header says, else counts)."),
    force: str = typer.Option(None, "--force", metavar="COL", help="Force column [header name or 1-based number], in "
            "REF.csv when given (default: found from the header: force, load, N, g, ...)."),
    force_unit: str = typer.Option(None, "--force-unit", help="Unit of the force column [N, kN, mN, g, kg, lbf or ozf; "
            "also gf, kgf, lb, oz], converted to force_n [N] with g0 = 9.80665 m/s² (default: what its header says, "
            "else N; a unit it says that is none of these is refused)."),
    reference_time: str = typer.Option(None, "--reference-time", metavar="COL", help="Time column of REF.csv [header "
            "name or 1-based number] (default: found from the header)."),
    reference_time_unit: str = typer.Option(None, "--reference-time-unit", help="Unit of REF.csv's time column [s, ms, "
            "us, min or h] (default: what its header says, else s)."),
    reference_rate: float = typer.Option(None, "--reference-rate", parser=hertz, help="Sample rate of REF.csv when it "
            "has no time column [Hz]."),
    offset: float = typer.Option(0.0, "--offset-s", parser=seconds, help="Added to REF.csv's times before the "
            "alignment [s], e.g. -0.25 or 250ms."),
    header: bool = typer.Option(None, "--header/--no-header", help="Whether the first line (after comments) is a "
            "header (default: when a cell of it is not a number)."),
    skip_lines: int = typer.Option(0, "--skip-lines", help="Lines to leave out at the top of each file, e.g. a "
            "logger's preamble [lines]."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing output run and its sidecar (never "
            "an input file)."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON: rows, matched, columns, units, the mapping "
            "chosen, how each file was read."),
) -> None:
    """Import a foreign CSV (your own sketch, a data logger, a spreadsheet) as a run.

    Columns are given by header name or number, or found from the header (time, ms, millis; fsr,
    analog, adc, reading; force, load, N, g), and the command says which it took. The delimiter
    (comma, semicolon, tab, white space), a decimal comma, # comment lines and a header row are
    recognised. With --reference, the reference's force is interpolated linearly onto the sensor's
    times inside the reference's span (rows outside get an empty force_n). The run then goes to
    fsrlab calibrate RUN.csv --x reading --reference force_n and fsrlab apply. See
    docs/data-format.md.

    Examples (files under examples/ in the fsrlab source tree):

    \b
      fsrlab import examples/foreign_fsr.csv -o run.csv
      fsrlab import examples/foreign_fsr.csv --reference examples/foreign_loadcell.csv --time time_ms -o run.csv --json
    """
    from fsrlab.errors import FileFormatError, ParameterError
    from fsrlab.io.foreign import ForeignFormatError, import_foreign, write_imported

    inputs = [sensor] + ([reference] if reference is not None else [])
    check_out(output, overwrite, inputs=inputs, option="--output")
    if rate is not None and not rate > 0:
        fail(f"must be > 0 Hz, got {rate:g}", "--rate")
    if reference_rate is not None and not reference_rate > 0:
        fail(f"must be > 0 Hz, got {reference_rate:g}", "--reference-rate")
    if skip_lines < 0:
        fail(f"must be >= 0 lines, got {skip_lines}", "--skip-lines")
    for path, option in zip(inputs, ("SENSOR.csv", "--reference"), strict=False):
        if path.is_dir():
            fail(f"{path} is a directory, not a file", option)
        if not path.exists():
            fail(f"{path} does not exist", option)
    try:
        imported = import_foreign(sensor, reference, time=time, time_unit=time_unit, rate_hz=rate, reading=reading,
                                  reading_unit=reading_unit, force=force, force_unit=force_unit,
                                  reference_time=reference_time, reference_time_unit=reference_time_unit,
                                  reference_rate_hz=reference_rate, offset_s=offset, header=header,
                                  skip_lines=skip_lines)
    except ForeignFormatError as exc:  # a file's problem: file, line, column, and the option that settles it
        hint = f" ({_ROLE_OPTIONS[exc.role]})" if exc.role in _ROLE_OPTIONS else ""
        raise FileFormatError(f"{exc.reason}{hint}") from None
    except ValueError as exc:  # a parameter's problem: its option's name
        with option_names(_PARAMETERS):
            raise exc from None
    except OSError as exc:
        raise ParameterError(f"cannot read '{exc.filename or sensor}': {exc.strerror or exc}") from None
    with option_names(_PARAMETERS):
        write_imported(imported, output, overwrite=overwrite)  # an OSError names the run or its sidecar
    summary = {"output": str(output), "rows": imported.rows, "matched": imported.matched,
               "columns": list(imported.columns), "units": imported.units, "mapping": imported.mapping,
               "rate_hz": imported.rate_hz, "offset_s": imported.offset_s, "sources": imported.sources,
               "notes": imported.notes}
    if json_out:
        emit_json(summary)
        return
    typer.echo("\n".join(_lines(imported, output)))


def _lines(imported, output: Path) -> list[str]:
    lines = []
    for source in imported.sources:
        head = f"header on line {source['header_line']}" if source["header_line"] else "no header"
        lines.append(f"{source['file']}: {source['rows']} rows, {source['delimiter']}-separated, decimal "
                     f"{'comma' if source['decimal'] == ',' else 'point'}, {head}")
        for role, entry in imported.mapping.items():
            if entry["file"] != source["file"]:
                continue
            if "rate_hz" in entry:
                lines.append(f"  {role.replace('_', ' ')}: row k at k / {entry['rate_hz']:g} Hz (--rate)")
                continue
            name = f"{entry['column']!r} (column {entry['index']})" if entry["column"] else f"column {entry['index']}"
            to = " -> force_n [N]" if role == "force" else " -> time_s [s]" if role.endswith("time") else ""
            lines.append(f"  {role.replace('_', ' ')}: {name} in {entry['unit']}{to}; {entry['how']}")
    for note in imported.notes:
        lines.append(f"  note: {note}")
    if imported.matched is not None:
        lines.append(f"aligned: {imported.matched} of {imported.rows} rows have a reference force (linear between "
                     f"the reference's samples, none outside its span; offset {imported.offset_s:g} s)")
    elif "time_s" not in imported.columns:
        lines.append("no time column and no --rate: the run has no time_s (row order only)")
    cols = ", ".join(f"{c} [{imported.units[c]}]" for c in imported.columns)
    lines.append(f"wrote {output} ({imported.rows} rows: {cols})")
    return lines
