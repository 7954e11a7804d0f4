"""The run format (docs/data-format.md): round trips, one-line errors, crash safety.

References: the format's own specification (docs/data-format.md); round trips are exact because
cells are written in Python's shortest round-trip float form. The document's examples are checked
against what fsrlab does: its minimal run is calibrated by plain ``fsrlab calibrate`` and equals the
shipped examples/minimal.csv; each line of its error example is what ``fsrlab hysteresis run.csv``
prints for the bad file in BAD_RUNS (in the same order).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from clirun import run_cli
from fsrlab.io.runformat import RunFormatError, load_run, sidecar_path
from fsrlab.io.runwriter import RunWriter, write_run


def test_writer_roundtrip_with_sidecar(tmp_path):
    path = tmp_path / "run.csv"
    meta = {"origin": "unit test", "sensor": {"model": "FlexiForce A201-1", "area_m2": 7.13e-5},
            "circuit": {"r_ohm": 10e3, "diode": True}, "units": {"extra": "K"}, "operator": "me"}
    with RunWriter(path, ["time_s", "frequency_hz", "duty_cycle", "direction", "extra"], meta) as w:
        w.write({"time_s": 0.0, "frequency_hz": 5123.456789, "duty_cycle": 0.51, "direction": 1, "extra": 3})
        w.write({"time_s": 0.1, "frequency_hz": None, "duty_cycle": float("nan"), "direction": -1})
        w.sync()
    run = load_run(path)
    assert run.n_rows == 2
    assert run.columns["frequency_hz"][0] == 5123.456789
    assert np.isnan(run.columns["frequency_hz"][1]) and np.isnan(run.columns["duty_cycle"][1])
    assert np.isnan(run.columns["extra"][1])
    assert run.metadata["complete"] is True and run.metadata["rows"] == 2
    assert run.metadata["operator"] == "me"
    assert run.units["frequency_hz"] == "Hz" and run.units["extra"] == "K"
    assert not run.truncated
    # Force -> stress needs the area from the sidecar.
    assert sidecar_path(path).name == "run.meta.json"


def test_sidecar_written_at_open_marked_incomplete(tmp_path):
    path = tmp_path / "r.csv"
    w = RunWriter(path, ["time_s", "voltage_v"])
    meta = json.loads(sidecar_path(path).read_text())
    assert meta["format"] == "fsrlab-run" and meta["version"] == 1 and meta["complete"] is False
    w.write({"time_s": 1, "voltage_v": 0.25})
    assert load_run(path).n_rows == 1  # readable while open
    w.close()
    assert json.loads(sidecar_path(path).read_text())["complete"] is True


def test_writer_rejects_unknown_column_and_inf(tmp_path):
    with RunWriter(tmp_path / "r.csv", ["time_s"]) as w:
        with pytest.raises(ValueError, match="unknown columns"):
            w.write({"time_s": 0, "bogus": 1})
        with pytest.raises(ValueError, match="finite"):
            w.write({"time_s": float("inf")})


def test_minimal_csv_without_sidecar_loads(tmp_path):
    path = tmp_path / "min.csv"
    path.write_text("stress_pa,frequency_hz\n0,3012.5\n1000,3890.1\n2000,4630.7\n", encoding="utf-8")
    run = load_run(path, require=["stress_pa"])
    assert run.n_rows == 3
    np.testing.assert_array_equal(run.stress_pa(), [0, 1000, 2000])
    assert run.metadata["format"] == "fsrlab-run" and run.metadata["complete"] is None


def test_force_column_gives_stress_with_area(tmp_path):
    path = write_run(tmp_path / "f.csv", {"force_n": np.array([0.0, 1.0]), "voltage_v": np.array([0.1, 0.2])},
                     {"sensor": {"area_m2": 1e-4}})
    np.testing.assert_allclose(load_run(path).stress_pa(), [0.0, 1e4])
    (tmp_path / "g.csv").write_text("force_n,voltage_v\n1,2\n")
    with pytest.raises(RunFormatError, match="area_m2"):
        load_run(tmp_path / "g.csv").stress_pa()


@pytest.mark.parametrize(
    "body, message",
    [
        ("time_s,frequency_hz\n0,1\n0.1,5.1k\n", r"row 2 \(line 3\), column 'frequency_hz': non-numeric cell '5.1k'"),
        ("time_s,frequency_hz\n0,1\n0.1,nan\n", r"row 2 \(line 3\), column 'frequency_hz': 'nan' is not a finite"),
        ("time_s,frequency_hz\n0,1\n0.1,\n0.2,NaN\n",
         r"row 3 \(line 4\), column 'frequency_hz': 'NaN' is not a finite"),
        ("time_s,frequency_hz\n0,1\n0.2,2\n0.1,3\n", r"row 3 \(line 4\), column 'time_s': time goes backwards"),
        ("time_s,frequency_hz\n0,1\n,2\n", r"row 2 \(line 3\), column 'time_s': empty time cell"),
        ("time_s,frequency_hz,stress_pa\n0,1,2\n0.1,2\n", r"row 2 \(line 3\), column 'stress_pa': missing"),
        ("time_s,direction\n0,1\n0.1,2\n", r"row 2 \(line 3\), column 'direction'"),
        ("time_s,inf_col\n0,1\n1,inf\n", r"row 2 \(line 3\), column 'inf_col'"),
        # Corrupt values in a known column: beyond the column's values in docs/data-format.md.
        ("time_s,frequency_hz\n0,1\n0.1,1e308\n", r"row 2 \(line 3\), column 'frequency_hz': 1e\+308 is beyond"),
        ("time_s,frequency_hz\n0,1\n0.1,-3\n",
         r"row 2 \(line 3\), column 'frequency_hz': -3 is beyond .*0 to 1e\+09 Hz"),
        ("time_s,duty_cycle\n0,0.5\n0.1,1.5\n", r"row 2 \(line 3\), column 'duty_cycle': 1.5 is beyond .*0 to 1;"),
        ("time_s,range\n0,0\n0.1,2\n",
         r"row 2 \(line 3\), column 'range': 2 is not one of 0 \(C_off out\), 1 \(C_off in\)"),
        ("time_s,my_column\n0,1\n0.1,1e200\n", r"row 2 \(line 3\), column 'my_column': 1e\+200 is beyond"),
        # The first bad row in the file is named, whatever its kind.
        ("time_s,frequency_hz,duty_cycle\n0,1,0.5\n0.1,1,2\n0.2,x,0.5\n", r"row 2 \(line 3\), column 'duty_cycle'"),
    ],
)
def test_bad_files_fail_with_one_line_naming_file_row_column(tmp_path, body, message):
    path = tmp_path / "bad.csv"
    path.write_text(body, encoding="utf-8")
    with pytest.raises(RunFormatError, match=message) as info:
        load_run(path)
    text = str(info.value)
    assert "\n" not in text and str(path) in text


def test_missing_required_column(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("time_s,frequency_hz\n0,1\n", encoding="utf-8")
    with pytest.raises(RunFormatError, match=r"m.csv: column 'stress_pa' missing"):
        load_run(path, require=["stress_pa"])
    with pytest.raises(RunFormatError, match="column 'stress_pa' missing"):
        load_run(path).stress_pa()


def test_bad_sidecar_rejected(tmp_path):
    path = tmp_path / "s.csv"
    path.write_text("a\n1\n")
    sidecar_path(path).write_text(json.dumps({"format": "fsrlab-run", "version": 2}))
    with pytest.raises(RunFormatError, match="version 2 not supported"):
        load_run(path)


def test_incomplete_last_line_dropped_when_writer_did_not_close(tmp_path):
    # Simulates power loss mid-write: the OS kept half a line; the sidecar still says complete=false.
    path = tmp_path / "p.csv"
    w = RunWriter(path, ["time_s", "frequency_hz"])
    w.write({"time_s": 0, "frequency_hz": 1000.5})
    w._raw("0.1,10")  # half a row, no newline
    run = load_run(path)
    w._fd.close()  # the crashed writer never closes; release the descriptor without marking complete
    assert run.n_rows == 1 and run.truncated


@given(st.lists(st.tuples(st.floats(-1e12, 1e12, allow_nan=False), st.one_of(st.none(), st.floats(-1e6, 1e6))),
                min_size=1, max_size=30))
def test_roundtrip_property(tmp_path_factory, rows):
    # Property: load(write(x)) == x exactly (shortest round-trip repr), NaN/None <-> empty cell.
    path = tmp_path_factory.mktemp("rt") / "r.csv"
    t = np.cumsum(np.abs([r[0] for r in rows]))
    q = np.array([np.nan if r[1] is None else r[1] for r in rows])
    write_run(path, {"time_s": t, "q": q})
    run = load_run(path)
    np.testing.assert_array_equal(run.columns["time_s"], t)
    np.testing.assert_array_equal(run.columns["q"], q)


def test_sigkill_mid_run_leaves_readable_file(tmp_path):
    """A writer process killed with SIGKILL at an arbitrary moment leaves complete rows only."""
    path = tmp_path / "killed.csv"
    script = textwrap.dedent(f"""
        import itertools
        from fsrlab.io.runwriter import RunWriter
        w = RunWriter({str(path)!r}, ["time_s", "frequency_hz", "duty_cycle", "seq"], {{"origin": "kill test"}})
        for i in itertools.count():
            w.write({{"time_s": i * 0.001, "frequency_hz": 5000.123456789 + i, "duty_cycle": 0.5123456789, "seq": i}})
    """)
    proc = subprocess.Popen([sys.executable, "-c", script])
    try:
        # Wait (bounded) until a few thousand rows are on the OS side, then kill without warning.
        for _ in range(600):
            if path.exists() and path.stat().st_size > 200_000:
                break
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    run = load_run(path)
    assert run.n_rows > 1000
    np.testing.assert_array_equal(run.columns["seq"], np.arange(run.n_rows))
    np.testing.assert_allclose(run.columns["frequency_hz"], 5000.123456789 + np.arange(run.n_rows))
    assert run.metadata["complete"] is False


def test_to_pandas(tmp_path):
    pd = pytest.importorskip("pandas")
    path = write_run(tmp_path / "x.csv", {"stress_pa": np.array([1.0, 2.0]), "frequency_hz": np.array([3.0, 4.0])})
    df = load_run(path).to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == ["stress_pa", "frequency_hz"]


def test_readout_gives_the_sidecar_circuits(tmp_path):
    """Run.circuits(): the circuits of the sidecar as objects (fsrlab.circuits.circuit), in the
    layout written today ("circuit" and "opamp") and in the earlier one (op-amp parts under
    circuit.traditional); none without circuits; a bad part names the sidecar."""
    from fsrlab.circuits.circuit import LM555Circuit, OpAmpReadout

    lm, op = LM555Circuit(r_ohm=22e3, c_off_farad=1e-9, diode=True), OpAmpReadout(r_f_ohm=20e3, vcc_v=-5.0)
    path = write_run(tmp_path / "new.csv", {"time_s": [0.0]}, {"circuit": lm.to_dict(), "opamp": op.to_dict()})
    assert load_run(path).circuits() == (lm, op)
    earlier = {"circuit": {"topology": "lm555-astable (paper Fig. 16)", "r_ohm": 22e3, "c_off_farad": 1e-9,
                           "diode": True, "diode_drop_v": 0.0, "vcc_v": 5.0,
                           "traditional": {"r_f_ohm": 20e3, "vcc_v": -5.0}}}
    path = write_run(tmp_path / "old.csv", {"time_s": [0.0]}, earlier)
    assert load_run(path).circuits() == (lm, op)
    path = write_run(tmp_path / "none.csv", {"time_s": [0.0]})
    assert load_run(path).circuits() == (None, None)
    path = write_run(tmp_path / "bad.csv", {"time_s": [0.0]}, {"circuit": {"r_ohm": -1.0}})
    with pytest.raises(RunFormatError, match=r"bad\.meta\.json: .*r_ohm"):
        load_run(path).circuits()


def test_readout_values_decode_c_fsr_through_the_runs_circuit(tmp_path):
    """Run.readout_values, Run.circuit and Run.recorded_with. Reference: the LM555 closed forms
    (fsrlab.circuits.lm555.astable via LM555Circuit.astable) give each reading's frequency and duty
    cycle from a known C_FSR, C_off counting only where ``range`` is 1; decoding gives C_FSR back."""
    from fsrlab.circuits.circuit import PAPER_CIRCUIT, LM555Circuit
    from fsrlab.errors import ParameterError
    from fsrlab.io.recorded import RecordedWith

    circuit = LM555Circuit(r_ohm=10e3, c_off_farad=1e-9, diode=True)
    c_fsr, ranges = np.array([0.5e-9, 1.0e-9, 1.5e-9, 0.8e-9]), np.array([0.0, 1.0, 1.0, 0.0])
    timing = [circuit.on_range(g).astable(2e5, c) for c, g in zip(c_fsr, ranges, strict=True)]
    columns = {"time_s": np.arange(4.0), "frequency_hz": [float(a.frequency_hz) for a in timing],
               "duty_cycle": [float(a.duty_cycle) for a in timing], "range": ranges}
    run = load_run(write_run(tmp_path / "r.csv", columns, {"circuit": circuit.to_dict()}))
    values, used = run.readout_values("c_fsr_farad")
    np.testing.assert_allclose(values, c_fsr, rtol=1e-9)
    assert used == circuit and run.circuit() == circuit and run.circuit(PAPER_CIRCUIT) is PAPER_CIRCUIT
    values, used = run.readout_values("frequency_hz")
    assert used is None and np.array_equal(values, run["frequency_hz"])
    with pytest.raises(ParameterError) as err:
        run.readout_values("voltage_v")
    assert err.value.parameter == "x"
    assert run.recorded_with() == RecordedWith(circuit, None, (0, 1))
    assert run.recorded_with([True, False, False, True]) == RecordedWith(circuit, None, (0,))
    bare = load_run(write_run(tmp_path / "bare.csv", {"time_s": [0.0]}))
    assert bare.circuit() == PAPER_CIRCUIT and bare.recorded_with() == RecordedWith()
    bad = load_run(write_run(tmp_path / "bad.csv", {"time_s": [0.0]}, {"circuit": {"r_ohm": -1.0}}))
    with pytest.raises(RunFormatError, match=r"bad\.csv: its sidecar's circuit: .*r_ohm"):
        bad.recorded_with()
    with pytest.raises(RunFormatError, match=r"bad\.meta\.json: .*r_ohm"):  # as Run.circuits() says it
        bad.circuit()


def test_skip_bad_rows_leaves_out_and_lists_them(tmp_path):
    # Reference: docs/data-format.md, "Bad rows": each bad row left out and listed with its reason,
    # the good rows kept in order, row numbers those of the file.
    path = tmp_path / "b.csv"
    path.write_text("time_s,frequency_hz,range\n0,1,0\n0.1,1e308,1\n0.2,x,0\n0.3,5,2\n0.4,,1\n0.5,inf,0\n"
                    "0.6,3\n0.7,4,1,5\n0.8,2,0\n", encoding="utf-8")
    run = load_run(path, skip_bad_rows=True)
    np.testing.assert_array_equal(run["time_s"], [0.0, 0.4, 0.8])
    np.testing.assert_array_equal(run["frequency_hz"], [1.0, np.nan, 2.0])
    assert [(b.row, b.column) for b in run.skipped] == [(2, "frequency_hz"), (3, "frequency_hz"), (4, "range"),
                                                        (6, "frequency_hz"), (7, "range"), (8, None)]
    assert "row 3 (line 4), column 'frequency_hz': non-numeric cell 'x'" in run.skipped[1].reason
    assert load_run(tmp_path / "b.csv", skip_bad_rows=True).skipped == run.skipped


def test_skip_bad_rows_does_not_skip_time_order(tmp_path):
    # Which row is wrong when time goes backwards cannot be told: an error even when skipping.
    path = tmp_path / "t.csv"
    path.write_text("time_s,frequency_hz\n0,1\n0.1,x\n0.3,1\n0.2,1\n", encoding="utf-8")
    with pytest.raises(RunFormatError, match=r"row 4 \(line 5\), column 'time_s': time goes backwards"):
        load_run(path, skip_bad_rows=True)


def test_incomplete_run_says_so_and_names_its_last_row(tmp_path):
    # Reference: docs/data-format.md, "complete" and "Incomplete runs".
    path = tmp_path / "k.csv"
    w = RunWriter(path, ["time_s", "frequency_hz"])
    for i in range(3):
        w.write({"time_s": 0.1 * i, "frequency_hz": 1000.0 + i})
    w._raw("0.3,10")  # killed mid-line
    run = load_run(path)
    w._fd.close()
    note = run.incomplete()
    assert str(path) in note and "incomplete" in note and "row 3 (line 4, time_s 0.2 s)" in note
    assert "incomplete last line was dropped" in note
    w2 = RunWriter(tmp_path / "c.csv", ["time_s"])
    w2.close()
    assert load_run(tmp_path / "c.csv").incomplete() is None

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "data-format.md").read_text(encoding="utf-8")

# One bad run.csv per line of the doc's error example, in the doc's order.
BAD_RUNS = [
    "time_s,frequency_hz\n0,3012.5\n0.1,3890.1\n",
    "stress_pa,frequency_hz\n0,3012.5\n1000,5.1k\n",
    "stress_pa,frequency_hz,duty_cycle\n0,3012.5,0.5\n1000,3890.1,0.5\n2000,4630.7,nan\n",
    "stress_pa,frequency_hz\n0,3012.5\n1000,1e308\n",
    "time_s,stress_pa,frequency_hz\n0,0,3012.5\n0.2,1000,3890.1\n0.1,2000,4630.7\n",
    "time_s,frequency_hz,stress_pa\n0,3012.5,0\n0.1\n",
    "stress_pa,frequency_hz,direction\n0,3012.5,1\n1000,3890.1,2\n",
]


def _block(after: str, lang: str = "") -> str:
    m = re.search(re.escape(after) + r".*?```" + lang + r"\n(.*?)```", DOC, re.DOTALL)
    assert m, f"no code block after {after!r} in docs/data-format.md"
    return m.group(1)


def test_minimal_run_calibrates_with_plain_calibrate(tmp_path, monkeypatch):
    text = _block("**Minimal run**", "csv")
    assert text == (ROOT / "examples" / "minimal.csv").read_text(encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    Path("run.csv").write_text(text, encoding="utf-8")
    code, out, err = run_cli(["calibrate", "run.csv"])
    # 3 readings: the format holds, and the calibration says in one line that held-out scoring needs more
    assert code == 2 and err.count("\n") == 1 and "fewer than 20 readings" in err, err


def test_error_example_is_what_fsrlab_prints(tmp_path, monkeypatch):
    lines = _block("## Errors").strip().splitlines()
    assert len(lines) == len(BAD_RUNS)
    monkeypatch.chdir(tmp_path)
    for body, line in zip(BAD_RUNS, lines, strict=True):
        Path("run.csv").write_text(body, encoding="utf-8")
        code, out, err = run_cli(["hysteresis", "run.csv"])
        assert (code, out, err) == (2, "", line + "\n")


@pytest.mark.parametrize("name", ["bench.csv", "other.csv", "minimal.csv"])
def test_shipped_example_runs_load(name):
    from fsrlab.io.runformat import load_run

    run = load_run(ROOT / "examples" / name)
    assert run.n_rows >= 3 and "stress_pa" in run and "frequency_hz" in run


@given(st.lists(st.text(alphabet=", 0123456789.\t\r e-", max_size=12), min_size=1, max_size=8))
def test_empty_cells_are_found_in_the_joined_lines_as_line_by_line(lines):
    """The fast parser's check for an empty cell runs on the lines joined into one string; the reference is
    the check line by line (a line starting with a comma, two commas in a row, or a comma last before white
    space)."""
    from fsrlab.io.runcells import _has_empties

    by_line = any(",," in ln or ln.startswith(",") or ln.rstrip().endswith(",") for ln in lines)
    assert _has_empties("\n".join(lines)) == by_line


def test_a_row_with_an_empty_last_cell_is_read_cell_by_cell(tmp_path):
    """An empty last cell (before a carriage return) is not numpy's to read: the row keeps its other values."""
    p = tmp_path / "r.csv"
    p.write_bytes(b"time_s,frequency_hz\r\n0,1000\r\n0.1,\r\n0.2,1002\r\n")
    run = load_run(p)
    f = np.asarray(run["frequency_hz"], float)
    assert f.size == 3 and np.isnan(f[1]) and f[0] == 1000 and f[2] == 1002
