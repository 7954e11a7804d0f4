"""``--port auto`` with no board connected: the same one line and exit code 2 from every command that opens a
meter (issue 40).

Reference: the one-line error contract of docs/architecture.md ("fsrlab: error: Invalid value for
--port: ...", exit 2), and :func:`fsrlab.acquisition.serial_link.find_uno`'s message for a machine whose
serial ports hold no Uno (pyserial's port list replaced by an empty one: no USB search of this machine).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from clirun import run_cli

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
NO_BOARD = "fsrlab: error: Invalid value for --port: auto found no Arduino Uno (USB ids "


@pytest.fixture
def no_ports(monkeypatch):
    from serial.tools import list_ports

    monkeypatch.setattr(list_ports, "comports", lambda *a, **k: [])


@pytest.mark.parametrize("command", [
    ["acquire", "--port", "auto", "-o", "{d}/a.csv", "--duration", "1"],
    ["bench", "spring", "--port", "auto", "-o", "{d}/b.csv"],
    ["weights", "--port", "auto", "-o", "{d}/w.csv", "--masses", "0,50g"],
    ["measure", "--port", "auto", "--cal", str(EXAMPLES / "calibration.json"), "-o", "{d}/m.csv"],
    ["firmware", "flash", "--port", "auto"],
    ["loadcell", "tare", "--port", "auto", "-o", "{d}/lc.json"],
    ["live", "--port", "auto", "-o", "{d}/l.csv"],
])
def test_no_board_is_one_line_exit_2(tmp_path, no_ports, command):
    code, _, err = run_cli([a.format(d=tmp_path) for a in command])
    lines = [ln for ln in err.splitlines() if not ln.startswith("fsrlab: warning:")]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith(NO_BOARD), err
    assert lines[0].endswith("serial ports present: none")
    assert list(tmp_path.iterdir()) == []  # nothing written
