"""Bad scan settings on the command line: exit 2 and one line naming the option (the library's
ParameterError mapped by its ``parameter``; the ranges of docs/protocol.md: SCAN 1..255 as channels 0..7,
DWELL 1..60000 ms, SETTLE 0..100). Nothing is opened: the settings are checked first."""

from __future__ import annotations

import pytest

from clirun import run_cli
from fsrlab.bench.channels import several_sensors
from fsrlab.errors import ParameterError


@pytest.mark.parametrize("args, option", [
    (["--channels", "8"], "--channels"), (["--channels", "0-9"], "--channels"), (["--channels", ""], "--channels"),
    (["--channels", "3-1"], "--channels"), (["--channels", "0,0"], "--channels"),
    (["--channels", "0-7", "--dwell", "0.5ms"], "--dwell"), (["--channels", "0-7", "--dwell", "61s"], "--dwell"),
    (["--channels", "0-7", "--settle", "101"], "--settle"), (["--channels", "0-7", "--settle", "-1"], "--settle"),
    (["--dwell", "3ms"], "--dwell"),
])
def test_bad_scan_options_exit_2_with_one_line_naming_the_option(tmp_path, args, option):
    code, out, err = run_cli(["acquire", "--virtual", "--duration", "1s", "--out", tmp_path / "r.csv", *args])
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and option in lines[0], err
    assert not (tmp_path / "r.csv").exists()


def test_live_refuses_bad_channels_before_serving(tmp_path):
    code, out, err = run_cli(["live", "--virtual", "--channels", "9", "--http-port", "0"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--channels" in err, err


@pytest.mark.parametrize("kwargs, parameter", [({"channels": 9}, "channels"), ({"channels": 0}, "channels"),
                                               ({"duration_s": 0.0}, "duration_s")])
def test_several_sensors_names_the_parameter(tmp_path, kwargs, parameter):
    with pytest.raises(ParameterError) as err:
        several_sensors(tmp_path, **kwargs)
    assert err.value.parameter == parameter


def test_live_refuses_one_sensors_calibration_for_channels(tmp_path):
    cal = tmp_path / "cal.json"
    cal.write_text("{}")
    code, out, err = run_cli(["live", "--virtual", "--channels", "0-3", "--cal", cal, "--http-port", "0"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--cal" in err, err
