"""Words of hysteresis and calibrate about the reference: its unit, and the reference not taken as a readout.

Reference: eq. (13) of Matute et al. 2018 compares a readout's loading and unloading branches over
the reference (a stress [Pa], or here a force [N]); a reference column against itself has no
hysteresis and no calibration. The run is examples/bench.csv with its stress column renamed to a force.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from clirun import run_cli

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture
def force_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    lines = (EXAMPLES / "bench.csv").read_text().splitlines()
    header = lines[0].replace("stress_pa", "force_n")
    rows = []
    for line in lines[1:]:
        cells = line.split(",")
        j = lines[0].split(",").index("stress_pa")
        cells[j] = f"{float(cells[j]) * 71.3e-6:.6g}"  # the bench's stress on a 71.3 mm² sensor [N]
        rows.append(",".join(cells))
    (tmp_path / "force.csv").write_text("\n".join([header, *rows]) + "\n")
    return tmp_path / "force.csv"


def test_a_force_reference_is_spoken_of_in_newtons(force_run):
    code, out, err = run_cli(["hysteresis", str(force_run), "--unit", "g"])
    assert code == 0, err
    text = " ".join(out.split())
    assert "shared range" in text and " Pa" not in text, text
    assert " N" in text.split("shared range", 1)[1]


@pytest.mark.parametrize("argv, option", [
    (["hysteresis", "EX/bench.csv", "--quantity", "stress_pa"], "--quantity"),
    (["calibrate", "EX/bench.csv", "--x", "stress_pa"], "--x"),
    (["calibrate", "EX/bench.csv", "--lag", "soon"], "--lag"),
])
def test_reference_as_readout_and_negative_lag_refused(argv, option):
    code, _, err = run_cli([a.replace("EX", str(EXAMPLES)) for a in argv])
    assert code == 2 and err.count("\n") == 1 and option in err, err
