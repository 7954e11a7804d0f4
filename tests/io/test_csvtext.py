"""A CSV cell over the csv module's field limit (128 KiB): one line naming the file and line, in every reader.

Reference: Python's :func:`csv.field_size_limit` (131072 by default), beyond which ``csv.reader`` raises
``_csv.Error: field larger than field limit``; the one-line error contract of docs/architecture.md
(file, line; exit 2, no traceback).
"""

from __future__ import annotations

import csv
import re

import pytest

from clirun import run_cli
from fsrlab.errors import FileFormatError
from fsrlab.io.csvtext import LongCellError, csv_cells, csv_rows
from fsrlab.io.foreign_read import read_table as read_foreign
from fsrlab.io.runformat import load_run, read_table

LONG = "1" * (csv.field_size_limit() + 10)


def test_csv_cells_and_rows_name_the_line():
    assert csv_cells("a,b") == ["a", "b"]
    with pytest.raises(LongCellError, match="longer than 131072 characters"):
        csv_cells(f'"{LONG}"')
    rows = csv_rows(["a,b", "1,2", f'3,"{LONG}"'])
    assert next(rows) == ["a", "b"] and next(rows) == ["1", "2"]
    with pytest.raises(LongCellError) as info:
        next(rows)
    assert info.value.line == 3


@pytest.mark.parametrize("text, line", [
    (f"time_s,frequency_hz\n0,\"{LONG}\"\n1,2\n", "row 1 (line 2)"),
    (f"time_s,frequency_hz{LONG}\n0,1\n", "row 0 (line 1, header)"),
])
def test_load_run_refuses_a_long_cell_in_one_line(tmp_path, text, line):
    path = tmp_path / "run.csv"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=rf"run\.csv: {re.escape(line)}: a cell longer than 131072"):
        load_run(path)


def test_table_and_foreign_readers_refuse_a_long_cell(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text(f"load,sensor,reading\n1,a,2\n1,\"{LONG}\",3\n")
    with pytest.raises(FileFormatError, match=r"t\.csv: line 3: a cell longer than 131072"):
        read_table(path, ["load"])
    with pytest.raises(FileFormatError, match=r"t\.csv: line 3: a cell longer than 131072"):
        read_foreign(path)


@pytest.mark.parametrize("command", [["import", "{f}", "-o", "{d}/o.csv"], ["hysteresis", "{f}"], ["creep", "{f}"],
                                     ["calibrate", "{f}", "-o", "{d}/c.json"], ["repeatability", "{f}"],
                                     ["iso376", "{f}"], ["report", "{f}", "-o", "{d}/rep"]])
def test_every_reader_says_one_line(tmp_path, command):
    path = tmp_path / "x.csv"
    path.write_text(f"time_s,load,sensor,reading,force_n,frequency_hz\n0,1,a,2,3,\"{LONG}\"\n")
    code, out, err = run_cli([a.format(f=path, d=tmp_path) for a in command])
    assert code == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert "longer than 131072 characters" in err and "x.csv" in err
