"""CSV table readers (fsrlab.io.tables): grouped repeatability readings.

Reference: the paper's printed Table 5 readings (real data, tests/data/paper.json) written as a
long CSV and read back exactly; one-line errors naming file, row and column (docs/data-format.md
style). The ISO 376 reader is tested with its computation in tests/metrics/test_iso376.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.io.tables import load_grouped_csv


def test_grouped_csv_reads_the_printed_readings_back(paper, tmp_path):
    t = paper["table5_repeatability_traditional_V"]
    lines = ["sensor,reading,load,note"]  # any column order, extra columns ignored
    expected = []
    for load in ("200g", "400g"):
        for s, row in enumerate(t[load]["readings"], start=1):
            lines += [f"{s},{v},{load},x" for v in row]
            expected += [(load, s, v) for v in row]
    p = tmp_path / "t5.csv"
    p.write_text("\n".join(lines) + "\n")
    loads, sensors, readings = load_grouped_csv(p)
    assert list(zip(loads, sensors, strict=True)) == [(e[0], e[1]) for e in expected]
    assert all(isinstance(s, int) for s in sensors)  # numeric labels become numbers
    np.testing.assert_array_equal(readings, [e[2] for e in expected])


@pytest.mark.parametrize("text, needle", [
    ("load,sensor,reading\n200g,1,0.2\n200g,1,abc\n", r"row 2 \(line 3\), column 'reading': non-numeric"),
    ("load,sensor,reading\n200g,,0.2\n", r"row 1 \(line 2\), column 'sensor': empty cell"),
    ("load,reading\n1,2\n", "column 'sensor' missing"),
    ("", "empty file"),
    ("load,sensor,reading\n", "no readings"),
])
def test_grouped_csv_errors_name_the_place(tmp_path, text, needle):
    p = tmp_path / "b.csv"
    p.write_text(text)
    with pytest.raises(ValueError, match=needle):
        load_grouped_csv(p)


@pytest.mark.parametrize("body, needle", [
    ("load,sensor,reading\n1,1,1e308\n", "row 1 (line 2), column 'reading': 1e+308 is beyond"),
    ("load,sensor,reading\n1,1,inf\n", "row 1 (line 2), column 'reading': 'inf' is not a finite number"),
])
def test_grouped_csv_rejects_absurd_readings(tmp_path, body, needle):
    # Reference: docs/data-format.md (a cell's magnitude at most 1e100 outside the known columns).
    p = tmp_path / "g.csv"
    p.write_text(body)
    with pytest.raises(ValueError) as info:
        load_grouped_csv(p)
    assert needle in str(info.value)


ISO = "series,rotation_deg,force_n,reading,direction\n1,0,0,0,1\n1,0,1,1.0,1\n1,0,2,2.0,1\n1,0,3,3.0,1\n"


@pytest.mark.parametrize("row, needle", [
    ("1,0,4,nan,1", "row 5 (line 6), column 'reading': 'nan' is not a finite number"),
    ("1,0,4,1e308,1", "row 5 (line 6), column 'reading': 1e+308 is beyond"),
    ("1,0,-4,4.0,1", "row 5 (line 6), column 'force_n': -4 is beyond what the column can hold (0 to"),
    ("1,0,inf,4.0,1", "row 5 (line 6), column 'force_n': 'inf' is not a finite number"),
    ("1,0,3,3.1,1", "row 5 (line 6), column 'force_n': series '1' already has a reading at 3 N (increasing)"),
    ("1,0,0,0.1,1", "row 5 (line 6), column 'force_n': series '1' already has its zero reading before"),
    ("1,90,4,4.0,1", "row 5 (line 6), column 'rotation_deg': series '1' was at 0°, not 90°"),
    ("1,0,4,,1", "row 5 (line 6), column 'reading': empty cell"),
])
def test_iso376_csv_rejects_bad_cells_naming_row_and_column(tmp_path, row, needle):
    # Reference: the ISO 376 reader's contract (fsrlab.io.tables.load_iso376_csv): one line, file, row, column;
    # before, nan and 1e308 readings were accepted and a repeated force silently replaced the first.
    from fsrlab.io.tables import load_iso376_csv

    p = tmp_path / "iso.csv"
    p.write_text(ISO + row + "\n")
    with pytest.raises(ValueError) as info:
        load_iso376_csv(p)
    assert needle in str(info.value) and "\n" not in str(info.value)


def test_iso376_csv_needs_two_forces(tmp_path):
    from fsrlab.io.tables import load_iso376_csv

    p = tmp_path / "iso.csv"
    p.write_text("series,rotation_deg,force_n,reading\n1,0,0,0\n1,0,1,1.0\n")
    with pytest.raises(ValueError, match="1 increasing force"):
        load_iso376_csv(p)
