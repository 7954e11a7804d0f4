"""CSV table readers (fsrlab.tables): grouped repeatability readings.

Reference: the paper's printed Table 5 readings (real data, tests/data/paper.json) written as a
long CSV and read back exactly; one-line errors naming file, row and column (docs/data-format.md
style). The ISO 376 reader is tested with its computation in tests/analysis/test_iso376.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from fsrlab.tables import load_grouped_csv


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
    assert list(zip(loads, sensors)) == [(e[0], e[1]) for e in expected]
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
