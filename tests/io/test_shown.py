"""Text from files in messages (fsrlab.io.shown), number cells, and wide headers.

References: Python's float() grammar, which also reads "5_000" (PEP 515) and non-ASCII decimal digits
(str.isdecimal), neither of which a CSV data cell should mean; ECMA-48 for the control sequences a
terminal would act on (ESC [ ... m); the scaling of a linear algorithm (4× the columns → about 4×
the work; the former duplicate check, cols.count per column, was quadratic: 16×).
"""

from __future__ import annotations

import time

import pytest

from clirun import run_cli
from fsrlab.io.schema import check_columns
from fsrlab.io.shown import number_cell, shown, shown_list


def test_shown_escapes_control_characters_and_caps_the_length():
    assert shown("\x1b[31mred\x07") == "'\\x1b[31mred\\x07'"
    assert shown("a\u202eb") == "'a\\u202eb'"  # right-to-left override, a format character
    long = shown("x" * 100_000)
    assert len(long) < 100 and long.endswith("(100000 characters)")
    listed = shown_list([f"c{i}" for i in range(100_000)])
    assert len(listed) < 260 and listed.endswith("and 99964 more") or listed.endswith("more")


@pytest.mark.parametrize("cell", ["5_000", "1_0.5", "１０", "٣", "1e", "", "0x10", "1,5", " 1"])
def test_number_cells_are_plain_ascii_numbers(cell):
    with pytest.raises(ValueError):
        number_cell(cell)


@pytest.mark.parametrize("cell, value", [("5000", 5000.0), ("-1.5e3", -1500.0), (".5", 0.5), ("+2.", 2.0)])
def test_number_cells_read(cell, value):
    assert number_cell(cell) == value


def test_cells_with_separators_or_other_digits_are_not_numbers(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for cell in ("5_000", "１０"):
        (tmp_path / "r.csv").write_text(f"time_s,stress_pa,frequency_hz\n0,0,4000\n1,1,{cell}\n2,0,4000\n",
                                        encoding="utf-8")
        code, _, err = run_cli(["hysteresis", "r.csv"])
        assert code == 2 and "non-numeric cell" in err and "frequency_hz" in err, err
        (tmp_path / "t.csv").write_text(f"load,sensor,reading\n1,a,{cell}\n1,a,3\n", encoding="utf-8")
        code, _, err = run_cli(["repeatability", "t.csv"])
        assert code == 2 and "non-numeric cell" in err, err


def test_a_header_with_escape_sequences_and_100k_columns_gives_one_short_safe_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    names = ["time_s", "stress_pa", "\x1b[2J\x1b[31mred"] + [f"c{i}" for i in range(100_000)]
    (tmp_path / "wide.csv").write_text(",".join(names) + "\n" + ",".join("0" for _ in names) + "\n")
    code, _, err = run_cli(["hysteresis", "wide.csv"])
    assert code == 2 and err.count("\n") == 1
    assert "\x1b" not in err and "\\x1b[2J" in err
    assert len(err) < 600, len(err)


def test_repeatability_names_the_file_and_group_of_a_zero_mean(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "z.csv").write_text("load,sensor,reading\n1,a,2\n1,a,3\n2,b,0\n2,b,0\n")
    code, _, err = run_cli(["repeatability", "z.csv"])
    assert code == 2 and "z.csv" in err and "load=2" in err and "'b'" in err and "zero mean" in err, err


def _seconds(n: int) -> float:
    cols = [f"c{i}" for i in range(n)]
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        check_columns(cols)
        best = min(best, time.perf_counter() - t0)
    return best


def test_header_check_is_linear():
    _seconds(1000)  # warm up
    ratio = _seconds(40_000) / _seconds(10_000)
    assert ratio < 9, f"4× the columns took {ratio:.1f}× the time (linear: ~4, quadratic: ~16)"
