"""``fsrlab import``, :mod:`fsrlab.io.foreign` and :mod:`fsrlab.io.foreign_read`: foreign CSV files made into runs.

References: the units' definitions (1 lbf = 0.45359237 kg × 9.80665 m/s² = 4.4482216152605 N
exactly, NIST SP 811 B.8 and scipy.constants.lbf; 1 g-force = 9.80665e-3 N, the standard gravity of
the CGPM 1901); the CSV dialects users' tools write (comma, semicolon with decimal comma as a
European spreadsheet exports, tab, white space as Serial Monitor logs, # comments, UTF-16 from
"Unicode text"); a reference known in closed form (a linear force F = 2 + 3t, which linear
interpolation reproduces exactly up to float rounding, tolerance 1e-12 N); the one-line error
contract of docs/architecture.md (file, line, column; exit 2); and the run format itself
(``load_run`` reads what was written, ``fsrlab calibrate`` and ``fsrlab apply`` use it).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import scipy.constants
import typer

from clirun import run_cli
from fsrlab.cli import app
from fsrlab.errors import FileFormatError
from fsrlab.io.foreign import (
    FORCE_UNITS,
    TIME_UNITS,
    ForeignFormatError,
    import_foreign,
    interpolate_reference,
    read_table,
)
from fsrlab.io.runformat import load_run

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _write(path: Path, text: str, encoding: str = "utf-8") -> Path:
    path.write_bytes(text.encode(encoding))
    return path


def _import(tmp_path, text, *options, name="in.csv", encoding="utf-8"):
    """Import ``text`` with ``options``; (exit code, stdout, stderr, the run or None)."""
    src = _write(tmp_path / name, text, encoding)
    out = tmp_path / "run.csv"
    code, stdout, stderr = run_cli(["import", src, "-o", out, "--overwrite", *options])
    return code, stdout, stderr, (load_run(out) if code == 0 else None)


# ------------------------------------------------------------------------------------------------
# Units
# ------------------------------------------------------------------------------------------------

def test_force_units_are_their_definitions():
    assert FORCE_UNITS["lbf"] == 4.4482216152605 == scipy.constants.lbf  # exact by definition
    assert FORCE_UNITS["g"] == 9.80665e-3 and FORCE_UNITS["kg"] == 9.80665 == scipy.constants.g
    assert FORCE_UNITS["mN"] == 1e-3 and FORCE_UNITS["N"] == 1.0
    assert FORCE_UNITS["kN"] == 1e3 and FORCE_UNITS["ozf"] == 4.4482216152605 / 16 == scipy.constants.lbf / 16
    assert TIME_UNITS == {"s": 1.0, "ms": 1e-3, "us": 1e-6, "min": 60.0, "h": 3600.0}


@pytest.mark.parametrize("unit, cell, newtons", [
    ("lbf", "1", 4.4482216152605), ("lbf", "2.5", 2.5 * 4.4482216152605), ("g", "1000", 9.80665),
    ("g", "1", 9.80665e-3), ("kg", "0.5", 4.903325), ("mN", "250", 0.25), ("N", "3.5", 3.5), ("kN", "5", 5000.0),
    ("ozf", "16", 4.4482216152605), ("oz", "1", 4.4482216152605 / 16), ("kgf", "2", 2 * 9.80665),
    ("lb", "1", 4.4482216152605),
])
def test_force_column_converted_to_newtons(tmp_path, unit, cell, newtons):
    code, _, err, run = _import(tmp_path, f"time,fsr,force\n0,100,0\n1,200,{cell}\n", "--force-unit", unit)
    assert code == 0, err
    assert run["force_n"][1] == pytest.approx(newtons, rel=1e-15) and run.units["force_n"] == "N"


@pytest.mark.parametrize("unit, cells, seconds", [
    ("ms", ("0", "1500"), 1.5), ("us", ("0", "250"), 250e-6), ("s", ("0", "0.02"), 0.02), ("µs", ("0", "250"), 250e-6),
    ("min", ("0", "1.5"), 90.0), ("h", ("0", "0.25"), 900.0),
])
def test_time_column_converted_to_seconds(tmp_path, unit, cells, seconds):
    code, _, err, run = _import(tmp_path, f"t,fsr\n{cells[0]},1\n{cells[1]},2\n", "--time", "t", "--time-unit", unit)
    assert code == 0, err
    assert run["time_s"][1] == pytest.approx(seconds, rel=1e-15) and run.units["time_s"] == "s"


@pytest.mark.parametrize("unit, sidecar", [("counts", "count"), ("V", "V"), ("mV", "mV"), ("ohm", "Ω"), ("kohm", "kΩ")])
def test_reading_kept_in_its_unit(tmp_path, unit, sidecar):
    code, _, err, run = _import(tmp_path, "fsr\n1.25\n2.5\n", "--reading-unit", unit)
    assert code == 0, err
    assert run["reading"].tolist() == [1.25, 2.5] and run.units["reading"] == sidecar


def test_rate_gives_the_time(tmp_path):
    code, out, err, run = _import(tmp_path, "fsr\n1\n2\n3\n4\n", "--rate", "50")
    assert code == 0, err
    assert run["time_s"] == pytest.approx([0, 0.02, 0.04, 0.06], abs=1e-15)
    assert run.metadata["import"]["rate_hz"] == 50 and "k / 50 Hz" in out


def test_limits_are_the_run_formats():
    from fsrlab.io.foreign import _LIMITS
    from fsrlab.io.runcells import COLUMN_LIMITS, OTHER_LIMIT

    assert _LIMITS == {"time_s": COLUMN_LIMITS["time_s"][1], "force_n": COLUMN_LIMITS["force_n"][1],
                       "reading": OTHER_LIMIT}


# ------------------------------------------------------------------------------------------------
# Which column is which
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("header, time, reading, force", [
    ("time_ms,fsr,force_N", ("time_ms", "ms"), ("fsr", "counts"), ("force_N", "N")),
    ("Time (s),Analog A0,Load (g)", ("Time (s)", "s"), ("Analog A0", "counts"), ("Load (g)", "g")),
    ("millis,adc,weight_kg", ("millis", "ms"), ("adc", "counts"), ("weight_kg", "kg")),
    ("t,voltage,F (lbf)", ("t", "s"), ("voltage", "V"), ("F (lbf)", "lbf")),
    ("n,micros,FSR reading (mV),reference_mN", ("micros", "us"), ("FSR reading (mV)", "mV"), ("reference_mN", "mN")),
    ("timestamp,sensorValue,loadcell", ("timestamp", "s"), ("sensorValue", "counts"), ("loadcell", "N")),
])
def test_columns_found_from_the_header_and_said(tmp_path, header, time, reading, force):
    n = len(header.split(","))
    rows = "".join(",".join(str(k + c) for c in range(n)) + "\n" for k in range(1, 4))
    code, out, err, run = _import(tmp_path, header + "\n" + rows, "--json")
    assert code == 0, err
    mapping = json.loads(out)["mapping"]
    for role, (column, unit) in (("time", time), ("reading", reading), ("force", force)):
        assert (mapping[role]["column"], mapping[role]["unit"]) == (column, unit), role
        assert mapping[role]["how"].startswith("found")
    code, out, err, _ = _import(tmp_path, header + "\n" + rows)
    assert f"reading: {reading[0]!r}" in out and "found: the header says" in out


def test_unit_not_in_the_header_is_assumed_and_said(tmp_path):
    code, out, err, run = _import(tmp_path, "time,fsr,force\n0,1,2\n1,2,3\n")
    assert code == 0, err
    assert "taken in N (its header does not say)" in out and "taken in s" in out


def test_index_column_is_not_taken(tmp_path):
    code, out, err, run = _import(tmp_path, "n,value\n1,500\n2,600\n", "--json")
    assert code == 0, err
    assert json.loads(out)["mapping"]["reading"]["column"] == "value"
    assert list(run.columns) == ["reading"] and "force_n" not in run


def test_given_mapping_by_name_or_number(tmp_path):
    text = "a,b,c\n0,10,7\n5,20,8\n"
    code, out, err, run = _import(tmp_path, text, "--time", "1", "--time-unit", "ms", "--reading", "c", "--force", "B",
                                  "--force-unit", "g")
    assert code == 0, err
    assert run["time_s"].tolist() == [0, 0.005] and run["reading"].tolist() == [7, 8]
    assert run["force_n"] == pytest.approx([0.0980665, 0.196133], rel=1e-15)


def test_no_header_two_columns_time_then_reading(tmp_path):
    code, out, err, run = _import(tmp_path, "0 512\n10 600\n20 700\n", "--time-unit", "ms")
    assert code == 0, err
    assert run["time_s"].tolist() == [0, 0.01, 0.02] and run["reading"].tolist() == [512, 600, 700]
    assert "no header" in out


def test_ambiguous_columns_end_in_one_line_naming_them(tmp_path):
    code, out, err, _ = _import(tmp_path, "time,fsr1,fsr2\n0,1,2\n1,2,3\n")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "in.csv: line 1 (header): column 'fsr1' (2) and column 'fsr2' (3) could each be the reading" in err
    assert "--reading" in err


# ------------------------------------------------------------------------------------------------
# Dialects
# ------------------------------------------------------------------------------------------------

DIALECTS = {
    "comma": "time_ms,fsr,force_g\n0,100,0.5\n10,200,1.5\n",
    "semicolon, decimal comma": "time_ms;fsr;force_g\n0;100;0,5\n10;200;1,5\n",
    "tab, decimal comma": "time_ms\tfsr\tforce_g\n0\t100\t0,5\n10\t200\t1,5\n",
    "white space (Serial Monitor)": "time_ms  fsr   force_g\n0   100  0.5\n10  200  1.5\n",
    "comma, quoted decimal comma": 'time_ms,fsr,force_g\n0,100,"0,5"\n10,200,"1,5"\n',
    "comments, blank lines, CRLF": "# logger v2\r\n\r\n# rate 100 Hz\r\ntime_ms,fsr,force_g\r\n0,100,0.5\r\n"
                                   "# pause\r\n10,200,1.5\r\n",
    "units row": "time;fsr;force\nms;counts;g\n0;100;0,5\n10;200;1,5\n",
    "comma with spaces": "time_ms, fsr, force_g\n0, 100, 0.5\n10, 200, 1.5\n",
}


@pytest.mark.parametrize("dialect", DIALECTS)
def test_dialects_read_alike(tmp_path, dialect):
    code, _, err, run = _import(tmp_path, DIALECTS[dialect])
    assert code == 0, err
    assert run["time_s"].tolist() == [0, 0.01] and run["reading"].tolist() == [100, 200]
    assert run["force_n"] == pytest.approx([0.5 * 9.80665e-3, 1.5 * 9.80665e-3], rel=1e-15)


@pytest.mark.parametrize("encoding", ["utf-16", "latin-1", "utf-8-sig"])
def test_encodings(tmp_path, encoding):
    text = "# °C and µs from a Windows logger\ntime_ms;fsr;force_g\n0;100;0,5\n10;200;1,5\n"
    code, _, err, run = _import(tmp_path, text, encoding=encoding)
    assert code == 0, err
    assert run["reading"].tolist() == [100, 200]


def test_dialect_is_recorded(tmp_path):
    table = read_table(_write(tmp_path / "x.csv", DIALECTS["semicolon, decimal comma"]))
    assert (table.delimiter, table.decimal, table.header_line, table.lines.tolist()) == (";", ",", 1, [2, 3])
    table = read_table(_write(tmp_path / "y.csv", DIALECTS["comments, blank lines, CRLF"]))
    assert (table.delimiter, table.header_line, table.lines.tolist()) == (",", 4, [5, 7])  # the lines an editor shows


def test_skip_lines_and_date_times(tmp_path):
    text = ("Logger XY-200 export\nSerial 1234\nDate,Force (N),Sensor\n"
            "2024-05-01 12:00:00.000,0.5,100\n2024-05-01 12:00:00.250,1.0,200\n")
    code, _, err, run = _import(tmp_path, text, "--skip-lines", "2", "--time", "Date")
    assert code == 0, err
    assert np.diff(run["time_s"]).tolist() == [0.25] and run["force_n"].tolist() == [0.5, 1.0]


def test_empty_cells_are_missing(tmp_path):
    code, _, err, run = _import(tmp_path, "time,fsr,force_N\n0,100,\n1,,2\n")
    assert code == 0, err
    assert np.isnan(run["force_n"][0]) and np.isnan(run["reading"][1])


# ------------------------------------------------------------------------------------------------
# Two files
# ------------------------------------------------------------------------------------------------

def _two_files(tmp_path, shift=0.0):
    """Sensor at 10 Hz for 10 s; a reference F = 2 + 3t [N] at 4 Hz over 0.05 … 5.05 s of its own clock + shift."""
    t = np.arange(0, 100) / 10
    sensor = _write(tmp_path / "fsr.csv",
                    "time_ms,fsr\n" + "".join(f"{round(1000 * x)},{k}\n" for k, x in enumerate(t)))
    tr = 0.05 + np.arange(0, 21) * 0.25
    ref = _write(tmp_path / "cell.csv",
                 "t_s,force_N\n" + "".join(f"{float(x + shift)!r},{float(2 + 3 * x)!r}\n" for x in tr))
    return sensor, ref, t


def test_reference_interpolated_onto_the_sensor_times(tmp_path):
    sensor, ref, t = _two_files(tmp_path)
    out = tmp_path / "run.csv"
    code, stdout, err = run_cli(["import", sensor, "--reference", ref, "-o", out])
    assert code == 0, err
    run = load_run(out)
    inside = (t >= 0.05) & (t <= 5.05)
    assert run["force_n"][inside] == pytest.approx(2 + 3 * t[inside], abs=1e-12)
    assert np.isnan(run["force_n"][~inside]).all()  # no extrapolation
    assert f"aligned: {inside.sum()} of 100 rows" in stdout
    meta = run.metadata
    assert meta["import"]["matched"] == inside.sum() == 50
    assert [s["file"] for s in meta["import"]["sources"]] == [str(sensor), str(ref)]
    assert str(sensor) in meta["origin"] and str(ref) in meta["origin"]


def test_offset_moves_the_reference_clock(tmp_path):
    sensor, ref, t = _two_files(tmp_path, shift=100.0)  # another logger's clock, 100 s ahead
    out = tmp_path / "run.csv"
    code, stdout, err = run_cli(["import", sensor, "--reference", ref, "--offset-s", "-100", "-o", out, "--json"])
    assert code == 0, err
    inside = (t >= 0.05) & (t <= 5.05)
    assert load_run(out)["force_n"][inside] == pytest.approx(2 + 3 * t[inside], abs=1e-9)
    assert json.loads(stdout)["matched"] == 50
    code, _, err = run_cli(["import", sensor, "--reference", ref, "-o", out, "--overwrite"])
    assert code == 2 and "no time in common" in err and "--offset-s" in err and err.count("\n") == 1


def test_interpolation_rules():
    t_ref, f = np.array([0.0, 1.0, 2.0, 3.0]), np.array([0.0, 10.0, np.nan, 30.0])
    got = interpolate_reference(np.array([-0.1, 0.0, 0.5, 1.0, 1.5, 2.5, 3.0, 3.1]), t_ref, f)
    assert got[[1, 2, 3, 6]].tolist() == [0.0, 5.0, 10.0, 30.0]
    assert np.isnan(got[[0, 4, 5, 7]]).all()  # outside, and beside a missing sample


def test_python_api(tmp_path):
    sensor, ref, t = _two_files(tmp_path)
    imported = import_foreign(sensor, ref, force_unit="N")
    assert list(imported.columns) == ["time_s", "reading", "force_n"] and imported.matched == 50
    assert imported.rate_hz == pytest.approx(10.0)
    with pytest.raises(ValueError, match="^force_unit: 'stone' is not one of N, kN, mN, g, kg, lbf, ozf$"):
        import_foreign(sensor, force_unit="stone")
    with pytest.raises(ForeignFormatError, match="fsr.csv: line 1 \\(header\\): no column 'nope'") as info:
        import_foreign(sensor, reading="nope")
    # One of fsrlab's file errors, still a ValueError; the role names the mapping that settles it.
    assert isinstance(info.value, FileFormatError) and isinstance(info.value, ValueError)
    assert info.value.role == "reading" and info.value.parameter == "reading"  # the column the call named


# ------------------------------------------------------------------------------------------------
# Bad input: one line naming the file, the line and the column; exit 2
# ------------------------------------------------------------------------------------------------

BAD = [
    ("unknown column", "time,fsr\n0,1\n", ["--reading", "fsx"],
     r"in\.csv: line 1 \(header\): no column 'fsx' for the reading"),
    ("column number too big", "time,fsr\n0,1\n", ["--force", "3"],
     r"in\.csv: line 1 \(header\): no column '3' for the force .*1\.\.2"),
    ("non-numeric cell", "# c\ntime,fsr\n0,1\n1,abc\n", [],
     r"in\.csv: line 4, column 'fsr' \(2\): non-numeric cell 'abc'"),
    ("nan cell", "time,fsr\n0,1\n1,nan\n", [], r"in\.csv: line 3, column 'fsr' \(2\): 'nan' is not a finite number"),
    ("short row", "time,fsr,force_N\n0,1,2\n1,2\n", [], r"in\.csv: line 3, column 'force_N' \(3\): missing cell"),
    ("time not increasing", "time,fsr\n0,1\n2,1\n2,1\n", [],
     r"in\.csv: line 4, column 'time' \(1\): time does not increase \('2' after '2' on line 3\)"),
    ("time going back", "t_ms,fsr\n0,1\n20,1\n10,1\n", [],
     r"in\.csv: line 4, column 't_ms' \(1\): time does not increase"),
    ("empty time", "time,fsr\n0,1\n,1\n", [], r"in\.csv: line 3, column 'time' \(1\): empty cell, expected a time"),
    ("force beyond a run", "time,fsr,force_N\n0,1,1e300\n", [],
     r"in\.csv: line 2, column 'force_N' \(3\): 1e300 N is beyond"),
    ("empty file", "", [], r"in\.csv: empty file"),
    ("comments only", "# nothing\n\n", [], r"in\.csv: empty file"),
    ("header only", "time,fsr\n", [], r"in\.csv: no data rows \(line 1 is the header\)"),
    ("duplicate header", "time,fsr,fsr\n0,1,2\n", [],
     r"in\.csv: line 1 \(header\), column 'fsr' \(2 and 3\): the same header name twice"),
    ("force unit", "time,fsr\n0,1\n", ["--force-unit", "stone"],
     r"Invalid value for --force-unit: 'stone' is not one of N, kN, mN, g, kg, lbf, ozf"),
    ("time unit", "time,fsr\n0,1\n", ["--time-unit", "d"],
     r"Invalid value for --time-unit: 'd' is not one of s, ms, us, min, h"),
    ("reading unit", "time,fsr\n0,1\n", ["--reading-unit", "A"],
     r"Invalid value for --reading-unit: 'A' is not one of counts, V, mV, ohm, kohm"),
    ("zero rate", "fsr\n1\n", ["--rate", "0"], r"Invalid value for --rate: must be > 0 Hz, got 0"),
    ("negative rate", "fsr\n1\n", ["--rate", "-5"], r"Invalid value for --rate: must be > 0 Hz, got -5"),
    ("rate and time column", "t,fsr\n0,1\n", ["--time", "t", "--rate", "10"],
     r"Invalid value for --rate: .*in\.csv has a time column"),
    ("no readout", "time,force_N\n0,1\n", [], r"in\.csv: no readout column found .*--reading"),
    ("headless, three columns", "0,1,2\n1,2,3\n", [],
     r"in\.csv: line 1: no header and 3 columns: say which column .* reading \(--reading\)"),
    ("not text", "\x00\x01\x02", [], r"in\.csv: not a text file"),
]


@pytest.mark.parametrize("case", BAD, ids=[c[0] for c in BAD])
def test_bad_input_is_one_line_exit_2(tmp_path, case):
    _, text, options, message = case
    code, out, err, _ = _import(tmp_path, text, *options)
    assert code == 2 and out == "", err
    assert err.count("\n") == 1 and "Traceback" not in err and err.startswith("fsrlab: error: "), err
    assert re.search(message, err), err
    assert not (tmp_path / "run.csv").exists() and not (tmp_path / "run.meta.json").exists()


def test_output_never_replaces_an_input(tmp_path):
    src = _write(tmp_path / "in.csv", "time,fsr,force_N\n0,1,2\n1,2,3\n")
    before = src.read_bytes()
    for output in (src, tmp_path / "sub" / ".." / "in.csv"):
        (tmp_path / "sub").mkdir(exist_ok=True)
        code, out, err = run_cli(["import", src, "-o", output, "--overwrite"])
        assert code == 2 and "--output" in err and "is the input" in err and err.count("\n") == 1, err
    sensor, ref, _ = _two_files(tmp_path)
    code, out, err = run_cli(["import", sensor, "--reference", ref, "-o", ref, "--overwrite"])
    assert code == 2 and "is the input" in err
    meta = _write(tmp_path / "m.meta.json", "time,fsr\n0,1\n")
    code, out, err = run_cli(["import", meta, "-o", tmp_path / "m.csv"])  # its sidecar would be the input
    assert code == 2 and "m.meta.json is the input" in err
    assert src.read_bytes() == before


def test_existing_output_needs_overwrite(tmp_path):
    src = _write(tmp_path / "in.csv", "time,fsr,force_N\n0,1,2\n1,2,3\n")
    out = tmp_path / "run.csv"
    assert run_cli(["import", src, "-o", out])[0] == 0
    first = out.read_bytes()
    code, _, err = run_cli(["import", src, "-o", out, "--reading-unit", "V"])
    assert code == 2 and "exists; pass --overwrite" in err and "--output" in err
    assert out.read_bytes() == first
    assert run_cli(["import", src, "-o", out, "--reading-unit", "V", "--overwrite"])[0] == 0
    assert load_run(out).units["reading"] == "V"


# ------------------------------------------------------------------------------------------------
# The run it writes, and what calibrate and apply make of it
# ------------------------------------------------------------------------------------------------

def test_json_says_what_was_done(tmp_path):
    sensor, ref, _ = _two_files(tmp_path)
    code, out, err = run_cli(["import", sensor, "--reference", ref, "-o", tmp_path / "run.csv", "--json"])
    assert code == 0 and err == ""
    info = json.loads(out)
    assert (info["rows"], info["matched"], info["columns"]) == (100, 50, ["time_s", "reading", "force_n"])
    assert info["units"] == {"time_s": "s", "reading": "count", "force_n": "N"}
    assert info["mapping"]["time"] == {"file": str(sensor), "column": "time_ms", "index": 1, "unit": "ms",
                                       "how": "found: the header says 'time_ms'"}
    assert info["mapping"]["reference_time"]["column"] == "t_s" and info["mapping"]["force"]["unit"] == "N"
    assert [s["delimiter"] for s in info["sources"]] == ["comma", "comma"]


def test_round_trip_import_calibrate_apply(tmp_path):
    # An FSR divider (10 kΩ, 5 V, 10-bit) under triangles 0 -> 10 N -> 0, force logged in grams by
    # another logger at its own rate: the chain a user with their own sketch runs.
    rng = np.random.default_rng(5)
    t = np.arange(0, 40, 0.05)
    force = 10 * (1 - np.abs(2 * ((t % 10) / 10) - 1))
    g = 1e-5 * force ** 0.9
    counts = np.round(1023 * 10e3 * g / (1 + 10e3 * g) + rng.normal(0, 1, t.size))
    sensor = _write(tmp_path / "fsr.csv",
                    "millis,analog\n" + "".join(f"{round(1000 * a)},{c:.0f}\n"
                                                 for a, c in zip(t, counts, strict=True)))
    tr = np.arange(0, 40, 0.1)
    grams = 1000 * 10 * (1 - np.abs(2 * ((tr % 10) / 10) - 1)) / 9.80665
    ref = _write(tmp_path / "scale.csv",
                 "time (s);weight (g)\n" + "".join(f"{a:.2f};{w:.2f}\n".replace(".", ",")
                                                    for a, w in zip(tr, grams, strict=True)))
    run = tmp_path / "run.csv"
    assert run_cli(["import", sensor, "--reference", ref, "-o", run])[0] == 0
    code, out, err = run_cli(["calibrate", run, "--x", "reading", "--reference", "force_n",
                              "-o", tmp_path / "cal.json", "--json"])
    assert code == 0, err
    # The calibration's own scored error, cross-validated or held out, whichever method calibrate used.
    scored = {k: v for k, v in json.loads(out).items() if k.endswith("rmse_percent_fs") and v is not None}
    assert scored and all(v < 2.0 for v in scored.values()), scored  # 1 count of noise in ~450 counts of span
    code, out, err = run_cli(["apply", tmp_path / "cal.json", run, "-o", tmp_path / "est.csv", "--json"])
    assert code == 0, err
    est = load_run(tmp_path / "est.csv")
    ok = np.isfinite(est["force_n_estimate"]) & np.isfinite(est["force_n"]) & (est["force_n"] > 1)
    assert ok.sum() > 500
    assert np.sqrt(np.mean((est["force_n_estimate"][ok] - est["force_n"][ok]) ** 2)) < 0.2  # N, 2 % of 10 N


# ------------------------------------------------------------------------------------------------
# Help
# ------------------------------------------------------------------------------------------------

def _help() -> str:
    code, out, err = run_cli(["import", "--help"])
    assert (code, err) == (0, "")
    return out


def test_every_option_shows_its_unit():
    command = typer.main.get_command(app).commands["import"]
    for param in command.params:
        if param.param_type_name == "option" and not param.is_flag and param.name not in ("reference", "output"):
            assert re.search(r"\[[^\]]+\]", param.help or ""), f"{param.opts[0]}: no [unit]"
    assert "[N, kN, mN, g, kg, lbf or ozf; also gf, kgf, lb, oz]" in " ".join(_help().split())


def test_help_ends_with_examples_that_run(tmp_path, monkeypatch):
    description = _help().split("\nOptions:")[0].split("\nArguments:")[0].rstrip()
    examples = [ln.split()[1:] for ln in description.split("\n\n")[-1].splitlines() if ln.strip().startswith("fsrlab ")]
    assert len(examples) == 2 and all(e[0] == "import" for e in examples)
    monkeypatch.chdir(tmp_path)
    for args in examples:
        args = [str(EXAMPLES.parent / a) if a.startswith("examples/") else a for a in args]
        code, out, err = run_cli([*args, "--overwrite"])
        assert code == 0 and out, err
        assert load_run(tmp_path / "run.csv")["force_n"].size == 400


def test_a_separator_in_every_row_is_not_a_header(tmp_path):
    """A logger that writes ``526 - 101.7`` (reading, a dash, grams) on every line and no header: the
    first line is data like the others, none is dropped; a header above such rows is still one."""
    text = "526 - 101.74713\n515 - 99.85449\n516 - 94.50384\n"
    code, out, err, run = _import(tmp_path, text, "--rate", "10", "--reading", "1", "--force", "3",
                                  "--force-unit", "g")
    assert code == 0, err
    assert run["reading"].tolist() == [526, 515, 516] and "no header" in out
    assert run["force_n"] == pytest.approx(np.array([101.74713, 99.85449, 94.50384]) * 9.80665e-3, rel=1e-12)
    code, out, err, run = _import(tmp_path, "fsr sep grams\n" + text, "--rate", "10", "--force-unit", "g",
                                  "--force", "grams", name="with_header.csv")
    assert code == 0, err
    assert run["reading"].tolist() == [526, 515, 516] and "header on line 1" in out


# ------------------------------------------------------------------------------------------------
# Units stated in a header or units row: converted when known, refused otherwise (issue 40)
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("header, cell, newtons", [
    ("force (kN)", "5", 5000.0), ("force_kN", "5", 5000.0), ("load [mN]", "250", 0.25),
    ("force_oz", "16", 4.4482216152605),
    ("weight (lb)", "1", 4.4482216152605), ("force_kgf", "1", 9.80665),
])
def test_force_unit_said_by_the_header_is_converted(tmp_path, header, cell, newtons):
    code, out, err, run = _import(tmp_path, f"time,fsr,{header}\n0,100,0\n1,200,{cell}\n")
    assert code == 0, err
    assert run["force_n"][1] == pytest.approx(newtons, rel=1e-15) and "taken in N" not in out


@pytest.mark.parametrize("header, cells, seconds", [
    ("time (min)", ("0", "1.5"), 90.0), ("time_h", ("0", "0.5"), 1800.0), ("time [µs]", ("0", "250"), 250e-6),
])
def test_time_unit_said_by_the_header_is_converted(tmp_path, header, cells, seconds):
    code, _, err, run = _import(tmp_path, f"{header},fsr\n{cells[0]},1\n{cells[1]},2\n")
    assert code == 0, err
    assert run["time_s"][1] == pytest.approx(seconds, rel=1e-15)


@pytest.mark.parametrize("text, where, unit, option", [
    ("time,fsr,force_stone\n0,1,5\n1,2,6\n", "line 1 (header), column 'force_stone' (3)", "stone", "--force-unit"),
    ("time,fsr,force (MN)\n0,1,5\n1,2,6\n", "line 1 (header), column 'force (MN)' (3)", "MN", "--force-unit"),
    ("time;fsr;force\ns;counts;dyn\n0;1;5\n1;2;6\n", "column 'force' (3): the units row under it",
     "dyn", "--force-unit"),
    ("time (days),fsr\n0,1\n1,2\n", "column 'time (days)' (1)", "days", "--time-unit"),
    ("time,fsr (uA)\n0,1\n1,2\n", "column 'fsr (uA)' (2)", "uA", "--reading-unit"),
])
def test_unit_not_known_is_refused_naming_file_column_and_unit(tmp_path, text, where, unit, option):
    code, _, err, run = _import(tmp_path, text)
    assert code == 2 and run is None
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "in.csv: line 1 (header), " in err and where in err, err
    assert f"unit '{unit}' is not a" in err and f"({option})" in err


def test_header_that_says_no_unit_is_still_assumed_and_said(tmp_path):
    code, out, err, run = _import(tmp_path, "time (UTC),fsr,force\n2024-01-01T00:00:00,1,2\n2024-01-01T00:00:01,2,3\n")
    assert code == 0, err
    assert run["time_s"].tolist() == [0.0, 1.0] or run["time_s"][1] - run["time_s"][0] == 1.0
    assert "taken in N (its header does not say)" in out


def test_reference_without_a_force_column_is_refused(tmp_path):
    """The reference file's one other column (a temperature) is not taken as the force, nor is the sensor file
    itself a reference."""
    sensor = _write(tmp_path / "s.csv", "time,fsr\n0,1\n1,2\n")
    ref = _write(tmp_path / "r.csv", "time,temp\n0,21\n1,22\n")
    code, _, err = run_cli(["import", sensor, "--reference", ref, "-o", tmp_path / "o.csv"])
    assert code == 2 and "r.csv: no force column found" in err and "(--force)" in err
    code, _, err = run_cli(["import", sensor, "--reference", sensor, "-o", tmp_path / "o.csv"])
    assert code == 2 and "Invalid value for --reference: " in err and "the sensor's file itself" in err
    assert not (tmp_path / "o.csv").exists()


def test_empty_output_and_huge_offset_are_one_line(tmp_path, recwarn):
    sensor = _write(tmp_path / "s.csv", "time,fsr\n0,1\n1,2\n")
    ref = _write(tmp_path / "r.csv", "time,force_N\n0,1\n1,2\n")
    code, _, err = run_cli(["import", sensor, "-o", ""])
    assert code == 2 and err.startswith("fsrlab: error: Invalid value for --output: is empty")
    assert "PosixPath" not in err
    code, _, err = run_cli(["import", sensor, "--reference", ref, "-o", tmp_path / "o.csv", "--offset-s", "1e300"])
    assert code == 2 and "Invalid value for --offset-s: must be a time within" in err
    close = _write(tmp_path / "c.csv", "time,force_N\n0,1\n0.01,2\n")
    with pytest.raises(ValueError, match="^offset_s: .*makes two of them equal"):
        import_foreign(sensor, close, offset_s=1e15)  # floats 0.125 apart there: 1e15 + 0.01 == 1e15
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_parameters_of_the_wrong_type_name_themselves(tmp_path):
    sensor = _write(tmp_path / "s.csv", "time,fsr\n0,1\n1,2\n")
    with pytest.raises(ValueError, match="^offset_s: must be a number, got str"):
        import_foreign(sensor, offset_s="10%")
    with pytest.raises(ValueError, match="^force_unit: must be a unit's name"):
        import_foreign(sensor, force_unit=3)


def test_a_large_file_reads_as_a_small_one(tmp_path):
    """The numbers' fast path (numpy's parser) and the cell-by-cell path give the same run: the same file with
    and without a quoted cell (which sends every column cell by cell)."""
    rng = np.random.default_rng(0)
    rows = "".join(f"{k * 10},{v},{f!r}\n"
                   for k, (v, f) in enumerate(zip(rng.integers(0, 1023, 3000).tolist(),
                                                  rng.normal(500, 100, 3000).tolist(), strict=True)))
    fast = import_foreign(_write(tmp_path / "a.csv", "millis,fsr,force_g\n" + rows))
    slow = import_foreign(_write(tmp_path / "b.csv", "millis,fsr,force_g\n" + rows.replace("0,", '"0",', 1)))
    for name in fast.columns:
        assert np.array_equal(fast.columns[name], slow.columns[name]), name
