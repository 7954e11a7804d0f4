"""The command line's contract: one-line errors with exit code 2, --version."""

import pytest

from fsrlab.cli import main


def run(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    out, err = capsys.readouterr()
    return exc.value.code, out, err


def test_unknown_command_is_one_line_exit_2(capsys):
    code, out, err = run(["no-such-command"], capsys)
    assert code == 2
    assert err.count("\n") == 1 and "no-such-command" in err


def test_unknown_option_is_one_line_exit_2(capsys):
    code, _, err = run(["paper", "--bogus"], capsys)
    assert code == 2 and err.strip().count("\n") == 0 and "--bogus" in err


def test_version(capsys):
    code, out, _ = run(["--version"], capsys)
    assert code == 0 and out.startswith("fsrlab ")
