"""Pieces of the command-line fuzzer (tests/cli/test_fuzz.py): option values, input files and their
corruptions, and running one command line in a directory of its own.

Reference: the value spellings of fsrlab.units and cli/options.py (valid ones), and the run, table
and calibration formats of docs/data-format.md (the small valid files written here).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import signal
import time
import traceback
import warnings
from pathlib import Path

from hypothesis import strategies as st

from clirun import run_cli

# ------------------------------------------------------------------------------------------------
# Option values
# ------------------------------------------------------------------------------------------------

# Values each quantity parser (cli/options.py) reads, chosen to work together in the commands.
VALID = {
    "ohms": ["10k", "4k7", "200k", "1M", "1meg", "10kΩ", "100kohm", "2.2e5"],
    "farads": ["1n", "470p", "4.7nF", "1.5n", "0", "4n7"],
    "volts": ["5", "3.3V", "600mV", "0.6", "2", "1"],
    "hertz": ["1k", "20k", "6478.5", "6.4785kHz", "5k", "40k"],
    "pascals": ["322k", "50kPa", "4.73MPa", "200k"],
    "metres": ["4.418n", "4nm", "5n"],
    "electronvolts": ["0.223", "223meV", "0.3"],
    "seconds": ["0.1", "100ms", "2s", "0.5"],
    "fraction": ["0.05", "5%", "0.5", "0.10189", "25%"],
    "number": ["2", "7", "1.5", "1"],
    "eng": ["1", "0.5", "50k", "1n", "4"],
    "areas": ["71.3mm2", "1cm2", "7.13e-5m2"],
    "masses": ["500g", "0.2kg", "5kg", "0"],
    "gravity_value": ["9.80665", "9.81", "9.81m/s2"],
    "int": ["0", "1", "2", "3", "5", "100"],
    "float": ["0.5", "1", "2", "0.1"],
}
GARBAGE = ["", " ", "0", "-0", "-1", "1e308", "-1e308", "1e-320", "1e999", "nan", "NaN", "inf", "-inf", "1m",
           "1M", "1meg", "10kF", "5V", "1kHz", "10%", "150%", "-5%", "1k5", "4k7", "2R2", "0x1F", "1_000", "1,5",
           "1.2.3", "--", "-", "+", "e3", "k", "µ", "10µF", "１０", "٣", "1e", "1e+", "10 k", "1\t2", "None",
           "True", "'5'", "5;x", "%s", "{0}", "a" * 300, "1m5", "5min", "2h", "500ms", "1ks", "kΩ"]
NUMBER_TEXT = st.one_of(
    st.integers(-10**6, 10**6).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.floats(min_value=1e-15, max_value=1e9).map(lambda x: f"{x:g}"),
)
PREFIX = st.sampled_from(["", "f", "p", "n", "u", "µ", "m", "k", "K", "M", "meg", "G", "T", "x", "kk", "mm"])
UNIT = st.sampled_from(["", "Ω", "ohm", "F", "V", "Hz", "s", "ms", "min", "h", "Pa", "eV", "m", "%", "N", "A", "°"])
ENG = st.builds(lambda n, sp, p, u: f"{n}{sp}{p}{u}", NUMBER_TEXT, st.sampled_from(["", " "]), PREFIX, UNIT)
RKM = st.builds(lambda a, letter, b, u: f"{a}{letter}{b}{u}", st.integers(0, 999), st.sampled_from(list("pnumkMRG")),
                st.integers(0, 99), UNIT)
TEXT = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=12)

OTHER_UNITS = [v for pool in VALID.values() for v in pool]

# ------------------------------------------------------------------------------------------------
# Input files
# ------------------------------------------------------------------------------------------------


INPUTS = ["run.csv", "other.csv", "min.csv", "table.csv", "iso.csv", "cal.json", "empty.csv", "notes.txt"]
ELSEWHERE = ["missing.csv", ".", "sub", "sub/new.csv", "run.csv/x", "new.csv", "out.json", "run.meta.json",
             "nodir/new.csv", "new\x1b[2J.csv", "missing\x1b]0;title\x07.csv", "a\u202eb.csv"]
CORRUPTIBLE = ["run.csv", "run.meta.json", "other.csv", "other.meta.json", "min.csv", "table.csv", "iso.csv",
               "cal.json"]
BAD_CELLS = ["nan", "NaN", "1e308", "-1e308", "inf", "", "abc", "1,5", "0", "-0", "1e-320", "  ", "1e999", '"',
             "10k", "١", "200g\x1b[2J", "\x1b]0;title\x07", "a\u202eb", "\x9b31m"]
#: Terminal control characters (ECMA-48 C0 and C1, DEL) and Unicode's bidirectional overrides: never printed raw
#: (fsrlab.io.shown.printable, the one rendering boundary); line feed and tab are text.
RAW_CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")
BAD_JSON = [None, "abc", 1e308, -1, [], {}, True, float("nan"), float("inf"), 0, "", [1, "a"], {"a": None}]


def write_corpus(root: Path) -> None:
    """Small valid inputs of every kind the commands read."""
    from fsrlab.virtual.synthetic import synthetic_run

    synthetic_run(cycles=2, points_per_ramp=20, seed=1).write(root / "run.csv")
    synthetic_run(cycles=2, points_per_ramp=15, seed=7).write(root / "other.csv")
    c = synthetic_run(cycles=2, points_per_ramp=20, seed=2).columns
    (root / "min.csv").write_text("stress_pa,frequency_hz\n" + "".join(
        f"{float(s)!r},{float(f)!r}\n" for s, f in zip(c["stress_pa"], c["frequency_hz"], strict=True)))
    (root / "table.csv").write_text("load,sensor,reading\n" + "".join(
        f"{load},{s},{1.0 + 0.1 * load / 200 + 0.01 * s + 0.003 * k}\n"
        for load in (200, 400) for s in (1, 2) for k in range(3)))
    forces = [1000.0, 2000.0, 3000.0, 4000.0]
    lines = ["series,rotation_deg,force_n,reading,direction"]
    for label, rot, scale, back in (("1", 0, 1.0, False), ("2", 0, 1.0004, False), ("3", 120, 1.0006, True),
                                    ("5", 240, 0.9994, True)):
        lines.append(f"{label},{rot},0,0.0,1")
        lines += [f"{label},{rot},{f!r},{2e-4 * scale * f!r},1" for f in forces]
        if back:
            lines += [f"{label},{rot},{f!r},{2e-4 * scale * 1.001 * f!r},-1" for f in forces]
        lines.append(f"{label},{rot},0,0.0,-1")
    (root / "iso.csv").write_text("\n".join(lines) + "\n")
    (root / "empty.csv").write_text("")
    (root / "notes.txt").write_text("not a table\n")
    (root / "sub").mkdir()
    cwd = os.getcwd()
    try:
        os.chdir(root)
        code, _, err = run_cli(["calibrate", "run.csv", "--compensate", "-o", "cal.json"])
    finally:
        os.chdir(cwd)
    assert code == 0, err


def corrupt_csv(text: str, op: str, a: int, b: int, cell: str) -> str:
    lines = text.splitlines()
    if not lines:
        return text
    rows = [line.split(",") for line in lines]
    i, j = a % len(rows), b % max(1, len(rows[a % len(rows)]))
    if op == "truncate":
        return text[: a % (len(text) + 1)]
    if op == "cell":
        rows[i][j % len(rows[i])] = cell
    elif op == "swap":
        k = b % len(rows)
        jj = a % len(rows[k])
        rows[i][j % len(rows[i])], rows[k][jj] = rows[k][jj], rows[i][j % len(rows[i])]
    elif op == "drop_cell":
        del rows[i][j % len(rows[i])]
    elif op == "extra_cell":
        rows[i].insert(j % (len(rows[i]) + 1), cell)
    elif op == "drop_line":
        del rows[i]
    elif op == "dup_line":
        rows.insert(i, list(rows[i]))
    elif op == "reverse":
        rows[1:] = rows[1:][::-1]
    elif op == "header":
        rows[0][j % len(rows[0])] = cell if b % 2 else rows[0][(j + 1) % len(rows[0])]
    elif op == "crlf":
        return "\r\n".join(",".join(r) for r in rows) + "\r\n"
    elif op == "bom":
        return "\ufeff" + text
    elif op == "binary":
        return text[: a % (len(text) + 1)] + "\x00\xff\ufffd" + text[a % (len(text) + 1):]
    return "\n".join(",".join(r) for r in rows) + ("\n" if b % 3 else "")


def json_paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from json_paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for k, v in enumerate(obj):
            yield from json_paths(v, prefix + (k,))


def corrupt_json(text: str, op: str, a: int, value) -> str:
    if op == "truncate":
        return text[: a % (len(text) + 1)]
    if op == "not_json":
        return "not json\n"
    try:
        obj = json.loads(text)
    except ValueError:
        return text
    paths = [p for p in json_paths(obj) if p]
    if not paths:
        return text
    path = paths[a % len(paths)]
    parent = obj
    for k in path[:-1]:
        parent = parent[k]
    if op == "delete":
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return json.dumps(obj)


CORPUS_NAMES = {"run.csv", "run.meta.json", "other.csv", "other.meta.json", "min.csv", "table.csv", "iso.csv",
                "cal.json", "empty.csv", "notes.txt", "sub"}
CSV_OPS = ["truncate", "cell", "cell", "cell", "swap", "drop_cell", "extra_cell", "drop_line", "dup_line",
           "reverse", "header", "crlf", "bom", "binary"]
JSON_OPS = ["truncate", "not_json", "delete", "set", "set", "delete_file"]

corruption = st.tuples(st.sampled_from(CORRUPTIBLE), st.integers(0, 10**6), st.integers(0, 10**6),
                       st.sampled_from(CSV_OPS), st.sampled_from(JSON_OPS), st.sampled_from(BAD_CELLS),
                       st.sampled_from(BAD_JSON))


def apply_corruptions(root: Path, corruptions) -> None:
    for name, a, b, csv_op, json_op, cell, value in corruptions:
        p = root / name
        if not p.exists():
            continue
        if name.endswith(".json"):
            if json_op == "delete_file":
                p.unlink()
                continue
            p.write_text(corrupt_json(p.read_text(encoding="utf-8"), json_op, a, value), encoding="utf-8")
        else:
            p.write_text(corrupt_csv(p.read_text(encoding="utf-8"), csv_op, a, b, cell), encoding="utf-8")


# ------------------------------------------------------------------------------------------------
# Running a case
# ------------------------------------------------------------------------------------------------

def copy_named(corpus: Path, root: Path, args: list[str]) -> None:
    """The corpus files a command line names, with their sidecars, and the default run.csv."""
    named = {"run.csv"} | {a.split("/")[0] for a in args}
    named |= {n[: -len(".csv")] + ".meta.json" for n in named if n.endswith(".csv")}
    for name in named & CORPUS_NAMES:
        src = corpus / name
        if src.is_file():
            shutil.copyfile(src, root / name)
        elif src.is_dir():
            (root / name).mkdir()


def hashes(root: Path) -> dict[str, str]:
    out = {}
    for p in sorted(root.rglob("*")):
        if p.is_file():
            out[str(p.relative_to(root))] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


SKIP_DIRS = {".venv", ".git", ".hypothesis", ".pytest_cache", ".ruff_cache", "__pycache__", "build", "report"}


def listing(root: Path) -> dict[str, tuple[int, int]]:
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = [d for d in dirnames if d not in SKIP_DIRS and not d.endswith(".egg-info")]
        for f in filenames:
            st_ = os.stat(os.path.join(dirpath, f))
            out[os.path.join(dirpath, f)] = (st_.st_size, st_.st_mtime_ns)
    return out


# "nan", "inf", "-inf" as a value (not inside a word such as "info" or "infinite").
NON_FINITE = re.compile(r"(?<![\w.])[-+]?(?:nan|inf|infinity)(?![\w])", re.IGNORECASE)
FILE_NAME = re.compile(r"[\w./-]+\.(?:csv|json|txt)\b")


def columns_of(root: Path, args: list[str]) -> set[str]:
    """Header cells of the CSV files a command line names (a message may name one as its column)."""
    out = set()
    for a in set(args) & CORPUS_NAMES:
        p = root / a
        if a.endswith(".csv") and p.is_file():
            with open(p, encoding="utf-8", errors="replace") as f:
                out |= {c.strip() for c in f.readline().split(",") if len(c.strip()) > 2}
    return out


CASE_TIMEOUT_S = 30  # a case still running then fails (a command that needs options to end, see FORCED)


class CaseTimeout(Exception):
    """A case ran longer than CASE_TIMEOUT_S."""


def _on_alarm(signum, frame):  # noqa: ARG001
    raise CaseTimeout(f"the case ran longer than {CASE_TIMEOUT_S} s")


SHOWN_BY_DEFAULT = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)



def execute(root: Path, args: list[str]):
    """Run ``fsrlab ARGS`` with cwd ``root``: (code, stdout, stderr, warnings shown, seconds)."""
    cwd = os.getcwd()
    previous = signal.signal(signal.SIGALRM, _on_alarm)
    signal.alarm(CASE_TIMEOUT_S)
    started = time.perf_counter()
    try:
        os.chdir(root)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                code, out, err = run_cli(args)
            except CaseTimeout as exc:
                code, out, err = None, "", str(exc)
            except Exception as exc:  # noqa: BLE001 -- what `fsrlab` would print as a traceback, exit 1
                code, out, err = 1, "", "Traceback (most recent call last):\n" + "".join(
                    traceback.format_exception_only(type(exc), exc))
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
        os.chdir(cwd)
    shown = [w for w in caught if not issubclass(w.category, SHOWN_BY_DEFAULT)]
    return code, out, err, shown, time.perf_counter() - started


# ------------------------------------------------------------------------------------------------
# Outputs: every command that writes, against the output policy (fsrlab.io.outputs)
# ------------------------------------------------------------------------------------------------

#: Each writing command: (argv with OUT where the output goes, the output's kind, the input whose path
#: and sidecar it must never replace, or None). Recording commands are virtual and short: every case
#: below is refused before a device starts.
WRITERS = {
    "calibrate -o": (["calibrate", "bench.csv", "-o", "OUT"], "file", "bench.csv"),
    "apply -o": (["apply", "calibration.json", "bench.csv", "-o", "OUT"], "run", "bench.csv"),
    "creep --plot": (["creep", "creep.csv", "--plot", "OUT"], "plot", "creep.csv"),
    "report --out": (["report", "bench.csv", "--out", "OUT"], "dir", None),
    "paper --out": (["paper", "--out", "OUT"], "dir", None),
    "demo --out": (["demo", "--out", "OUT", "--cycles", "1", "--repeat", "2"], "dir", None),
    "bench --report": (["bench", "spring", "--virtual", "--quiet", "--out", "new.csv", "--report", "OUT"], "dir", None),
    "acquire --out": (["acquire", "--virtual", "--quiet", "--duration", "0.2", "--out", "OUT"], "run", None),
    "measure --out": (["measure", "--virtual", "--quiet", "--duration", "0.2", "--cal", "bench.csv.json", "--out",
                       "OUT"], "run", "bench.csv.json"),
    "weights --out": (["weights", "--virtual", "--quiet", "--out", "OUT"], "run", None),
    "bench --out": (["bench", "spring", "--virtual", "--quiet", "--out", "OUT"], "run", None),
    "live --out": (["live", "--virtual", "--http-port", "0", "--duration", "0.2", "--out", "OUT"], "run", None),
    "loadcell tare -o": (["loadcell", "tare", "--virtual", "-o", "OUT"], "file", None),
    "loadcell scale -o": (["loadcell", "scale", "--virtual", "--mass", "500g", "--cal", "lc.json", "-o", "OUT"], "file",
                          "lc.json"),
}
OUTPUT_CASES = ("exists", "is an input", "is a sidecar", "is empty", "is a directory")


def output_case(writer: str, case: str, root: Path) -> list[str] | None:
    """The command line of one case in ``root`` (which holds the corpus files), or None when it does not apply.

    The files it needs are made in ``root``: an existing output, a non-empty directory, a directory.
    """
    argv, kind, source = WRITERS[writer]
    overwrite = ["--overwrite"] if "--overwrite" in _options_of(argv[0]) else []
    if case == "exists":
        if kind == "dir":
            (root / "full").mkdir(exist_ok=True)
            (root / "full" / "index.html").write_text("mine\n")
            out = "full"
        else:
            out = "exists.png" if kind == "plot" else "exists.csv" if kind == "run" else "exists.json"
            (root / out).write_text("mine\n")
        overwrite = []
    elif case == "is an input":
        if source is None:
            return None
        out = "./" + source if kind != "plot" else None
        if kind == "plot":  # a plot must end in .png: the input is a copy named so, given as the run
            shutil.copy(root / "creep.csv", root / "creep-in.png")
            argv = [a if a != "creep.csv" else "creep-in.png" for a in argv]
            out = "sub/../creep-in.png"
            (root / "sub").mkdir(exist_ok=True)
    elif case == "is a sidecar":
        if source is None or not source.endswith(".csv"):
            return None
        sidecar = source[:-4] + ".meta.json"
        if kind == "plot":
            return None  # a sidecar never ends in .png
        out = sidecar
    elif case == "is empty":
        out = ""
    else:  # "is a directory": a directory where a file goes, a file where a directory goes
        if kind == "dir":
            (root / "afile").write_text("mine\n")
            out = "afile"
        else:
            (root / "adir.csv").mkdir(exist_ok=True)
            (root / "adir.csv" / "keep").write_text("mine\n")
            out = "adir.csv"
    return [a if a != "OUT" else out for a in argv] + overwrite


def _options_of(command: str) -> set[str]:
    import typer

    from fsrlab.cli import app

    group = typer.main.get_command(app)
    return {opt for p in group.commands[command].params for opt in p.opts}


def tree_hashes(root: Path) -> dict[str, str]:
    """sha256 of every file under ``root`` (relative path → digest), directories as entries too."""
    out = {}
    for p in sorted(root.rglob("*")):
        rel = str(p.relative_to(root))
        out[rel] = "dir" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out
