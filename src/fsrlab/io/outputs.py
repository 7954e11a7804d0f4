"""The output policy of every command that writes: what may be written where, and how.

One rule for files and report directories alike:

- an empty path is refused (``--out ""`` with an unset variable must not mean "here");
- an output that exists is refused unless the caller passes ``overwrite=True`` (``--overwrite``);
  for a directory, "exists" means it holds anything;
- an output that is one of the command's inputs, or an input's sidecar (``NAME.meta.json`` beside
  ``NAME.csv``), is refused even with ``overwrite``: symlinks, ``..`` and relative spellings are
  resolved and hard links compared, so ``-o ./b.csv`` for input ``b.csv`` is the same file;
- a directory where a file is expected (or a file where a directory is expected, or a missing
  parent directory) is refused before anything is computed;
- a file is written under a temporary name in its directory and renamed over the final name
  (:func:`atomic_path`, :func:`write_text_atomic`): an interrupted write never leaves a half file
  under the final name.

Recordings (``acquire``, ``bench``, ``weights``, ``measure``, ``live``) are checked by the same rule
but written row by row under their final name (:class:`fsrlab.io.runwriter.RunWriter`: a stopped
recording keeps every whole row).

Every refusal is an :class:`OutputError`, a ``ValueError`` that names the option.
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from fsrlab.errors import ParameterError

__all__ = ["OutputError", "OutputExistsError", "output_path", "check_output", "refuse_inputs", "protected_paths",
           "same_file", "atomic_path",
           "write_text_atomic", "write_bytes_atomic", "atomic_run", "replace_run", "run_files"]


class OutputError(ParameterError):
    """An output the policy refuses.

    Parameters
    ----------
    option : str
        The option or argument that names the output, e.g. ``"--output"``, or the library function's
        parameter, e.g. ``"path"`` (then also :attr:`~fsrlab.errors.FsrlabError.parameter`).
    message : str
        What is wrong and what is allowed.
    """

    def __init__(self, option: str, message: str):
        library = bool(option) and not option.startswith("-") and option.isidentifier()
        super().__init__(message, parameter=option if library else None)
        if not library:  # an option's name leads the message as a parameter's does
            self.args = (f"{option}: {message}" if option else message,)
        self.option = option
        self.message = message

    def __str__(self) -> str:
        return self.args[0]


class OutputExistsError(OutputError, FileExistsError):
    """An existing output that is replaced only with ``overwrite=True``; a :class:`FileExistsError` too.

    Parameters
    ----------
    option, message
        As for :class:`OutputError`.
    """


def _path_of(name: str, value) -> Path:
    """``value`` as a Path, or a TypeError (no path) or ParameterError (an empty one) naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name}: must be a path (str or path-like), got {type(value).__name__}")
    if not os.fspath(value):
        raise ParameterError("must name a file, got an empty path", parameter=name)
    return Path(value)


def _file_path(name: str, value) -> Path:
    """:func:`_path_of`, and a ParameterError naming ``name`` when it is a directory (a file is written there)."""
    p = _path_of(name, value)
    if p.is_dir():
        raise ParameterError(f"'{p}' is a directory, not a file", parameter=name)
    return p


def _iterable(name: str, value) -> list:
    """``value``'s items, or a TypeError naming ``name`` when it is not an iterable (a str is one path, not many)."""
    if isinstance(value, (str, bytes, os.PathLike)) or not isinstance(value, Iterable):
        raise TypeError(f"{name}: must be an iterable of paths, got {type(value).__name__}")
    return list(value)


def _overwrite_hint(option: str) -> str:
    """How the caller asks for a replacement: ``--overwrite`` on the command line, ``overwrite=True`` in Python."""
    return "pass --overwrite" if not option or option.startswith("-") or not option.isidentifier() else \
        "pass overwrite=True"


def output_path(text, option: str = "--out") -> Path:
    """The path an option names; an empty or blank value is refused.

    ``Path("")`` is ``Path(".")``, so the check must see the text before it becomes a path.

    Parameters
    ----------
    text : str or path-like
        The option's value as typed.
    option : str
        The option, for the message.

    Returns
    -------
    Path
    """
    if isinstance(text, bool) or not isinstance(text, (str, os.PathLike)):
        raise TypeError(f"{option}: must be a path (str or path-like), got {type(text).__name__}")
    raw = os.fspath(text) if not isinstance(text, str) else text
    if not raw.strip():
        raise OutputError(option, "is empty; give a file or directory name (an unset shell variable gives an "
                                  "empty value)")
    return Path(raw)


def _sidecar(path: Path) -> Path:
    # The run format's sidecar (fsrlab.io.schema.sidecar_path), spelled here to keep this module import-free.
    name = path.name
    return path.with_name((name[:-4] if name.lower().endswith(".csv") else name) + ".meta.json")


def run_files(path) -> tuple[Path, Path]:
    """A run's two files: ``NAME.csv`` and its sidecar ``NAME.meta.json``.

    Parameters
    ----------
    path : path-like
        The run's CSV file.

    Returns
    -------
    (Path, Path)
    """
    p = _path_of("path", path)
    return p, _sidecar(p)


def protected_paths(inputs: Iterable) -> list[tuple[Path, str]]:
    """The inputs and their sidecars: what no output may replace.

    Parameters
    ----------
    inputs : iterable of path-like or None
        The command's input files (None entries are skipped).

    Returns
    -------
    list of (Path, str)
        Each protected file and what it is ("the input X", "the sidecar of the input X").
    """
    out: list[tuple[Path, str]] = []
    for item in _iterable("inputs", inputs):
        if item is None or not os.fspath(item).strip():
            continue
        p = Path(item)
        out.append((p, f"the input {p}"))
        if p.name.lower().endswith(".csv"):
            out.append((_sidecar(p), f"the sidecar of the input {p}"))
    return out


def same_file(a, b) -> bool:
    """Whether two spellings name one file: symlinks and ``..`` resolved, hard links compared.

    Parameters
    ----------
    a, b : path-like

    Returns
    -------
    bool
    """
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist
        return False


def _input_clash(target: Path, protected: list[tuple[Path, str]]) -> str | None:
    for p, what in protected:
        if same_file(target, p):
            return what
    return None


def check_output(path, option: str, *, overwrite: bool = False, inputs: Iterable = (), kind: str = "file",
                 names: Iterable[str] = ()) -> Path:
    """Check one output against the policy (module docstring) before anything is computed or written.

    Parameters
    ----------
    path : str or path-like
        The output as the user gave it.
    option : str
        The option naming it, e.g. ``"--output"``; refusals name it.
    overwrite : bool
        Whether the user asked to replace an existing output.
    inputs : iterable of path-like
        The command's inputs; they and their sidecars are never written.
    kind : {"file", "run", "dir"}
        ``"file"``: one file; ``"run"``: ``NAME.csv`` and its sidecar ``NAME.meta.json``; ``"dir"``:
        a directory the command fills (created if missing).
    names : iterable of str
        For ``kind="dir"``: files the command writes in it, checked against the inputs too.

    Returns
    -------
    Path
        ``path`` as a ``Path``.

    Raises
    ------
    OutputError
        The output is refused; the message says why and what to do.
    """
    if kind not in ("file", "run", "dir"):
        raise ParameterError(f"must be file, run or dir, got {kind!r}", parameter="kind")
    target = output_path(path, option)
    if kind == "dir":
        _check_directory(target, option, overwrite, protected_paths(inputs), names)
    else:
        refuse_inputs(target, option, inputs, kind)
        _check_file(target, option, overwrite, kind)
    return target


def _check_directory(target: Path, option: str, overwrite: bool, protected: list[tuple[Path, str]],
                     names: Iterable[str]) -> None:
    """A directory the command fills: not a file, not an input nor holding one where the command writes, and
    empty unless ``overwrite``."""
    for parent in (target, *target.parents):
        if parent.exists() and not parent.is_dir():
            raise OutputError(option, f"{parent} is a file, not a directory")
    clash = _input_clash(target, protected)
    if clash is None:
        clash = next((c for n in names if (c := _input_clash(target / n, protected)) is not None), None)
    if clash is not None:
        raise OutputError(option, f"it would replace {clash}; choose another directory")
    if target.is_dir() and not overwrite and any(os.scandir(target)):
        raise OutputError(option, f"{target} exists and is not empty; {_overwrite_hint(option)} to replace the "
                                  "files written in it, or choose a new directory")


def _check_file(target: Path, option: str, overwrite: bool, kind: str) -> None:
    """One file, or a run's CSV and sidecar: named as such, not a directory, in a writable directory, and new
    unless ``overwrite``."""
    files = run_files(target) if kind == "run" else (target,)
    if kind == "run" and target.name.lower().endswith(".meta.json"):
        raise OutputError(option, f"{target} is named like a run's sidecar; give the run's CSV file, e.g. "
                                  f"{target.with_name(target.name[:-len('.meta.json')] + '-2.csv')}")
    if target.is_dir():
        example = target / "run.csv" if kind == "run" else f"{target / 'NAME'}"
        raise OutputError(option, f"{target} is a directory, not a file; give a file name, e.g. {example}")
    for f in files:
        if f.is_dir():
            raise OutputError(option, f"{f} is a directory; the run's sidecar would go there")
    parent = target.parent
    if not parent.is_dir():
        raise OutputError(option, f"directory {parent} does not exist" if not parent.exists()
                          else f"{parent} is not a directory")
    if not os.access(parent, os.W_OK):
        raise OutputError(option, f"cannot write in directory {parent} (permission denied)")
    if not overwrite:
        for f in files:
            if os.path.lexists(f):
                raise OutputError(option, f"{f} exists; {_overwrite_hint(option)} to replace it")


def refuse_inputs(path, option: str, inputs: Iterable, kind: str = "file") -> None:
    """Refuse an output that is one of ``inputs`` or an input's sidecar (the policy's one rule ``overwrite``
    does not lift).

    Parameters
    ----------
    path : path-like
        The output.
    option : str
        The option or parameter naming it, for the message.
    inputs : iterable of path-like
        The inputs (None entries skipped).
    kind : {"file", "run"}
        ``"run"``: the output's sidecar is checked too.

    Raises
    ------
    OutputError
    """
    target = _path_of(option, path)
    protected = protected_paths(inputs)
    for f in run_files(target) if kind == "run" else (target,):
        clash = _input_clash(f, protected)
        if clash is not None:
            flag = "--overwrite" if _overwrite_hint(option).endswith("--overwrite") else "overwrite=True"
            raise OutputError(option, f"{f} is {clash}; write the output to another file "
                                      f"({flag} never replaces an input)")


@contextmanager
def atomic_path(path) -> Iterator[Path]:
    """A temporary path beside ``path``, renamed over ``path`` when the block ends without an error.

    The temporary name keeps the suffix (a plot library chooses the format by it); it starts with a
    dot and is removed when the block raises, so the final name holds either the old file or the
    whole new one.

    Parameters
    ----------
    path : path-like
        The final file.

    Yields
    ------
    Path
        Where to write.
    """
    final = _file_path("path", path)
    # Not mkstemp: its file is 0600, and the rename would give the output those permissions.
    tmp = final.with_name(f".{final.name}.{os.getpid()}-{secrets.token_hex(4)}.partial{final.suffix}")
    try:
        yield tmp
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, final)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def write_text_atomic(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` through a temporary file and one rename.

    Parameters
    ----------
    path : path-like
    text : str

    Returns
    -------
    Path
    """
    if not isinstance(text, str):
        raise TypeError(f"text: must be a str, got {type(text).__name__}")
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_bytes_atomic(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file and one rename.

    Parameters
    ----------
    path : path-like
    data : bytes

    Returns
    -------
    Path
    """
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise TypeError(f"data: must be bytes, got {type(data).__name__}")
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


@contextmanager
def atomic_run(path) -> Iterator[Path]:
    """:func:`atomic_path` for a run: the temporary ``NAME.csv`` and its sidecar both renamed at the end.

    Each is whole under its final name at any moment; the two are renamed by :func:`replace_run`, which
    makes a stop between them detectable.

    Parameters
    ----------
    path : path-like
        The run's CSV file.

    Yields
    ------
    Path
        The temporary CSV to write the run to (its sidecar beside it).
    """
    final = _path_of("path", path)
    tmp = final.with_name(f".{final.stem}.{os.getpid()}-{secrets.token_hex(4)}.partial.csv")
    try:
        yield tmp
        replace_run(tmp, final)
    except BaseException:
        for f in run_files(tmp):
            try:
                os.unlink(f)
            except OSError:
                pass
        raise


def replace_run(src, dst) -> None:
    """Rename the complete run ``src`` (its CSV and sidecar) over ``dst``'s two files, the sidecar first.

    Two renames are not one step. The sidecar is given the SHA-256 of the CSV it was written with
    (``"csv_sha256"``) and renamed first, so a stop between the two (Ctrl-C, a kill, a full disk) leaves the
    old CSV beside a sidecar that :func:`fsrlab.io.runformat.load_run` refuses as not its own. The other order
    would leave the new CSV under the old sidecar (another run's circuit, calibration, units), which a reader
    could not tell from one run where that sidecar names no content (a recording's).

    Parameters
    ----------
    src : path-like
        The run's CSV under its temporary name, its sidecar beside it.
    dst : path-like
        The run's CSV under its final name.
    """
    from fsrlab.io.schema import CSV_SHA256

    for name, value in (("src", src), ("dst", dst)):
        _path_of(name, value)
    csv, meta = run_files(src)
    if not (csv.is_file() and meta.is_file()):
        raise ParameterError(f"'{csv}' and its sidecar '{meta.name}' must both exist (a complete run)", parameter="src")
    with open(csv, "rb") as fh:
        digest = hashlib.file_digest(fh, "sha256").hexdigest()
    doc = {**json.loads(meta.read_text(encoding="utf-8")), CSV_SHA256: digest}
    with open(meta, "w", encoding="utf-8") as fh:  # a temporary name yet: rewritten in place
        fh.write(json.dumps(doc, indent=2, allow_nan=False) + "\n")
        fh.flush()
        os.fsync(fh.fileno())
    for s, d in reversed(list(zip(run_files(src), run_files(dst), strict=True))):
        os.replace(s, d)
