"""The command line names the option of the library parameter at fault (FsrlabError.parameter), reading no message
(issue 40), and the Python API's remaining cases of the issue.

Reference: the contract of docs/architecture.md (one line naming the option, exit 2) and
fsrlab.errors.FsrlabError (``parameter`` is the Python name; a command's own parameter of that name is the
option: ``between_runs`` → ``--between-runs``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

import fsrlab as fl
from clirun import run_cli
from fsrlab.cli import _option_of
from fsrlab.errors import ParameterError

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize("command, parameter, option", [
    ("calibrate", "between_runs", "--between-runs"), ("calibrate", "x", "--x"), ("apply", "margin", "--margin"),
    ("calibrate", "rail", "--rail"), ("import", "offset_s", None), ("acquire", "port", "--port"),
    ("firmware flash", "hex_file", "--hex"), ("nosuch", "port", "--port"),
])
def test_option_of_a_parameter(command, parameter, option):
    assert _option_of(parameter, command.split()) == option


def test_a_parameter_that_is_an_argument_is_named_by_its_metavar(tmp_path):
    """A run with too few readings: the library names ``runs``, the command's argument of that name; the line
    names it as the help shows it (its metavar), exit 2, no traceback."""
    assert _option_of("runs", ["calibrate"]) == "RUN.csv [RUN2.csv ...]"
    run = tmp_path / "few.csv"
    run.write_text("time_s,force_n,reading\n0,1,2\n1,2,3\n")
    code, _, err = run_cli(["calibrate", run, "--x", "reading", "--reference", "force_n", "-o", tmp_path / "c.json"])
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert err.startswith("fsrlab: error: Invalid value for RUN.csv [RUN2.csv ...]: ") and "fewer than 20" in err


def test_a_parameter_error_is_said_as_its_options_invalid_value(monkeypatch, tmp_path):
    """A message that happens to hold another option's words is not rewritten: the parameter decides."""
    import fsrlab.io.foreign as foreign

    def refuse(*args, **kwargs):
        raise ParameterError("mentions rate_hz and --time but is about the offset", parameter="offset_s")

    monkeypatch.setattr(foreign, "import_foreign", refuse)
    code, _, err = run_cli(["import", str(EXAMPLES / "foreign_fsr.csv"), "-o", tmp_path / "unused.csv"])
    assert code == 2 and not (tmp_path / "unused.csv").exists()
    assert err == "fsrlab: error: Invalid value for --offset-s: mentions rate_hz and --time but is about the offset\n"


def test_rate_beside_a_time_column_names_rate(tmp_path):
    src = tmp_path / "s.csv"
    src.write_text("t,fsr\n0,1\n1,2\n")
    code, _, err = run_cli(["import", src, "--time", "t", "--rate", "10", "-o", tmp_path / "o.csv"])
    assert code == 2 and err.startswith("fsrlab: error: Invalid value for --rate: ") and "has a time column" in err


def test_load_run_takes_one_column_name_as_a_string():
    """fl.load_run(require="stress_pa") asks for that column, not for the letters s, t, r, ..."""
    run = fl.load_run(EXAMPLES / "bench.csv", require="stress_pa")
    assert "stress_pa" in run.columns
    with pytest.raises(ValueError, match=r"column 'force_n' missing"):
        fl.load_run(EXAMPLES / "bench.csv", require="force_n")


def test_calibrate_on_a_derived_readout_blames_the_option_given(tmp_path, monkeypatch):
    """``calibrate A B --x c_fsr_farad`` where B cannot give it: the line names --x (the option given), never
    an option that was not."""
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(["calibrate", EXAMPLES / "bench.csv", EXAMPLES / "minimal.csv", "--x", "c_fsr_farad",
                            "-o", "c.json"])
    assert code == 2 and err.count("\n") == 1
    assert "--x" in err and "--method" not in err and "minimal.csv" in err
