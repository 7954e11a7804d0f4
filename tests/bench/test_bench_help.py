"""Help of ``fsrlab bench``: the units of its loads (the [unit] and examples of every recording command,
bench, report, demo and twin included, are checked in tests/cli/test_recording_commands_help.py).

Reference: the help conventions of docs/architecture.md (Extension points, CLI).
"""

from __future__ import annotations

from clirun import run_cli


def test_masses_option_states_its_unit():
    code, out, _ = run_cli(["bench", "--help"])
    assert "[kg]" in out and "[Pa]" in out and "[s]" in out


def test_report_examples_run(tmp_path, monkeypatch):
    # Reference: the files under examples/ (examples/README.md says where each came from).
    import shutil
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    code, out, _ = run_cli(["report", "--help"])
    last = out.split("\nOptions:")[0].split("\nArguments:")[0].rstrip().split("\n\n")[-1]
    examples = [line.split()[1:] for line in last.splitlines() if line.strip().startswith("fsrlab ")]
    shutil.copytree(root / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    for args in examples:
        code, out, err = run_cli(args)
        assert code == 0, f"{args}: {err}"
        assert "Traceback" not in err and "Warning" not in err
    assert (tmp_path / "report-run" / "index.html").is_file()
