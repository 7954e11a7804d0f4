"""``fsrlab paper``: reproduce the paper's figures and tables into a directory.

Each capability adds a builder module to :data:`SECTION_MODULES`; a builder exposes
``build(outdir: pathlib.Path) -> Section``. The report writes ``index.html`` (self-contained:
images are embedded) and ``paper.json`` (every section's ``data`` merged at the top level, plus
the errata).
"""

from __future__ import annotations

import importlib
import json
import os
import pickle
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

from fsrlab import __version__
from fsrlab.errors import ParameterError
from fsrlab.io.outputs import write_text_atomic
from fsrlab.reports.html import render_html
from fsrlab.reports.model import Section

__all__ = ["SECTION_MODULES", "SIDE_SECTIONS", "EARLY_SECTIONS", "ReportResult", "build_sections", "write_report",
           "ReportProcess", "start_report"]

#: Section builders in report order. Add yours here.
SECTION_MODULES = [
    "fsrlab.reports.sections.physics",
    "fsrlab.reports.sections.oscillator",
    "fsrlab.reports.sections.measurements",
    "fsrlab.reports.sections.experiment",
]

#: Sections built in a second process (forked) on a machine with more than one core, while this one builds
#: the others and ngspice runs: about half of the drawing and computing each (docs/performance.md).
SIDE_SECTIONS = ("fsrlab.reports.sections.physics", "fsrlab.reports.sections.measurements")

#: Sections imported before the others, so that their ``prefetch`` (ngspice) starts before the rest imports.
EARLY_SECTIONS = ("fsrlab.reports.sections.oscillator",)


@dataclass
class ReportResult:
    """Where the report went.

    Parameters
    ----------
    index : Path
        The HTML page.
    json : Path
        The machine-readable numbers.
    sections : list of Section
        The sections as built.
    """

    index: Path
    json: Path
    sections: list[Section]

    @property
    def figures(self) -> list[Path]:
        """PNG files written."""
        return [self.index.parent / f.filename for s in self.sections for f in s.figures]


class _Side:
    """Section builders run in a forked child process; their Sections come back pickled through a pipe."""

    def __init__(self, names: list[str], outdir: Path) -> None:
        self.names, self.pid, self._result = names, None, None
        if not names:
            return
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: build, send, leave without running the parent's clean-up
            os.close(read)
            code = 0
            try:
                try:
                    payload = pickle.dumps(("ok", [importlib.import_module(n).build(outdir) for n in names]))
                except BaseException as exc:  # noqa: BLE001 - the parent raises it
                    code = 1
                    try:
                        payload = pickle.dumps(("error", exc))
                    except Exception:  # noqa: BLE001 - an exception that does not pickle: its text
                        payload = pickle.dumps(("error", RuntimeError(f"{type(exc).__name__}: {exc}")))
                with os.fdopen(write, "wb") as fh:
                    fh.write(payload)
            finally:
                os._exit(code)
        os.close(write)
        self.pid, self._read = pid, read

    def result(self, name: str) -> Section:
        """The Section of ``name`` (waits for the child the first time)."""
        if self._result is None:
            with os.fdopen(self._read, "rb") as fh:
                data = fh.read()
            os.waitpid(self.pid, 0)
            if not data:
                raise RuntimeError("report: the process building " + ", ".join(self.names) + " ended without a result")
            status, value = pickle.loads(data)
            if status != "ok":
                raise value
            self._result = dict(zip(self.names, value, strict=True))
        return self._result[name]


def build_sections(outdir: Path, progress: Callable[[str], None] | None = None,
                   parallel: bool | None = None) -> list[Section]:
    """Run every section builder of :data:`SECTION_MODULES` into ``outdir``.

    Parameters
    ----------
    outdir : Path
        Directory the builders write their PNGs into.
    progress : callable, optional
        Called with each section's name before it is built (this process's sections first, those with
        a ``prefetch`` last among them, then those collected from the second process).
    parallel : bool, optional
        Build :data:`SIDE_SECTIONS` in a forked second process; default: where ``fork`` exists and
        the machine has more than one core.

    Returns
    -------
    list of Section
        In the order of :data:`SECTION_MODULES`, whichever process built them.
    """
    if parallel is None:
        parallel = hasattr(os, "fork") and (os.cpu_count() or 1) > 1
    # Slow external work (ngspice processes, no thread yet) starts first and goes on while the other
    # sections import and draw: the sections with a prefetch are imported first.
    started, modules = {}, {}
    for name in sorted(SECTION_MODULES, key=lambda n: n not in EARLY_SECTIONS):
        modules[name] = module = importlib.import_module(name)
        if hasattr(module, "prefetch"):
            started[name] = module.prefetch()
    modules = [modules[name] for name in SECTION_MODULES]
    side_names = [m.__name__ for m in modules if parallel and m.__name__ in SIDE_SECTIONS and m.__name__ not in started]
    if side_names:
        from fsrlab.reports.figures import preload

        preload()  # matplotlib, imported once for both processes
    side = _Side(side_names, outdir)  # forked before this function starts a thread
    # Each prefetch's waiting goes on in a thread of this process from here on.
    for name, wait in started.items():
        pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="fsrlab-prefetch")
        started[name] = pool.submit(wait)
        pool.shutdown(wait=False)
    built = {}
    # This process's sections first, those waiting for external work (ngspice) last, then those of the
    # second process (built meanwhile).
    for module in sorted(modules, key=lambda m: (m.__name__ in side.names, m.__name__ in started)):
        name = module.__name__
        if progress:
            progress(name.rsplit(".", 1)[-1])
        if name in side.names:
            built[name] = side.result(name)
        elif name in started:
            built[name] = module.build(outdir, prefetched=started[name])
        else:
            built[name] = module.build(outdir)
    return [built[m.__name__] for m in modules]


def write_report(outdir: str | Path, progress: Callable[[str], None] | None = None,
                 overwrite: bool = False) -> ReportResult:
    """Build the reproduction report.

    The output policy (:mod:`fsrlab.io.outputs`): ``outdir`` is refused when it holds anything unless
    ``overwrite=True``, and when empty; each file is written atomically.

    Parameters
    ----------
    outdir : str or Path
        Directory to write ``index.html``, ``paper.json`` and the PNG figures into (created).
    progress : callable, optional
        Called with each section's name before it is built.
    overwrite : bool
        Write into a directory that is not empty (its files of the same names are replaced).

    Returns
    -------
    ReportResult

    Raises
    ------
    OutputError
        ``outdir`` refused (a :class:`~fsrlab.errors.ParameterError` naming ``outdir``).
    """
    out = _checked_outdir(outdir, overwrite)
    out.mkdir(parents=True, exist_ok=True)
    sections = build_sections(out, progress)
    data: dict = {"fsrlab_version": __version__,
                  "source": "Matute et al., J. Sensors 2018, 6561901, doi:10.1155/2018/6561901"}
    for section in sections:
        clash = set(section.data) & set(data)
        if clash:
            raise RuntimeError(f"report section {section.key!r} redefines {sorted(clash)}")
        data.update(section.data)
    data["errata"] = [asdict(e) for s in sections for e in s.errata]
    # Each file under a temporary name, then renamed: an interrupted report never leaves half a file.
    json_path = write_text_atomic(out / "paper.json", json.dumps(data, indent=2, allow_nan=False) + "\n")
    index = write_text_atomic(out / "index.html", render_html(sections, out))
    return ReportResult(index=index, json=json_path, sections=sections)


class ReportProcess:
    """:func:`write_report` under way in a Python process of its own (:func:`start_report`).

    Parameters
    ----------
    outdir : str or Path
        As for :func:`write_report`.
    nice : int
        Added to the process's niceness (``os.nice``, where it exists), 0: as this process.
    overwrite : bool
        As for :func:`write_report` (checked in this process, before the other starts).
    """

    _CODE = ("import os, pickle, sys\n"
             "if int(sys.argv[2]) and hasattr(os, 'nice'):\n"
             "    os.nice(int(sys.argv[2]))\n"
             "from fsrlab.reports.paper import write_report\n"
             "pickle.dump(write_report(sys.argv[1], overwrite=True), sys.stdout.buffer)\n")

    def __init__(self, outdir: str | Path, nice: int = 0, overwrite: bool = False) -> None:
        import subprocess
        import sys

        import fsrlab

        env = dict(os.environ)
        # The same fsrlab as this process's, wherever it was imported from.
        root = str(Path(fsrlab.__file__).resolve().parents[1])
        env["PYTHONPATH"] = os.pathsep.join([root, *filter(None, [env.get("PYTHONPATH")])])
        # Checked here, before the process starts (it writes with overwrite=True).
        self.outdir = _checked_outdir(outdir, overwrite)
        if isinstance(nice, bool) or not hasattr(nice, "__index__"):
            raise ParameterError(f"must be an int >= 0, got {nice!r}", parameter="nice")
        if not int(nice) >= 0:
            raise ParameterError(f"must be >= 0 (a lower priority or the same), got {nice!r}", parameter="nice")
        self._proc = subprocess.Popen([sys.executable, "-c", self._CODE, str(self.outdir), str(int(nice))],
                                      stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)

    def result(self) -> ReportResult:
        """Wait for the report and return what :func:`write_report` returned in its process.

        Raises
        ------
        RuntimeError
            The report's process failed; the message carries the end of its error output.
        """
        out, err = self._proc.communicate()
        if self._proc.returncode != 0:
            tail = " | ".join(err.decode("utf-8", "replace").strip().splitlines()[-4:])
            raise RuntimeError(f"the reproduction report ({self.outdir}) failed (exit {self._proc.returncode}): {tail}")
        return pickle.loads(out)

    def stop(self) -> None:
        """End the report's process if it is still running (its files may be left half written)."""
        if self._proc.poll() is None:
            self._proc.kill()
        self._proc.communicate()


def start_report(outdir: str | Path, nice: int = 0, overwrite: bool = False) -> ReportProcess:
    """Start :func:`write_report` in a Python process of its own and return at once.

    Parameters
    ----------
    outdir : str or Path
        As for :func:`write_report`.
    nice : int
        Niceness added to the report's process and its own (the second process, ngspice): the demo gives 10,
        so that the recordings it draws beside keep the cores they need and the report takes what they leave.
    overwrite : bool
        As for :func:`write_report` (checked before the process starts).

    Returns
    -------
    ReportProcess
        ``.result()`` waits for it and returns its :class:`ReportResult`. A separate interpreter, not a
        thread or a fork: it competes with nothing of this process for the interpreter lock, and it
        inherits none of its open files (the demo draws the report while its last recording runs).
    """
    return ReportProcess(outdir, nice, overwrite)


def _checked_outdir(outdir, overwrite) -> Path:
    """``outdir`` through the output policy (a directory; ``overwrite`` a bool)."""
    from fsrlab.io.outputs import check_output

    if not isinstance(overwrite, bool):
        raise ParameterError(f"must be True or False, got {overwrite!r}", parameter="overwrite")
    return check_output(outdir, "outdir", overwrite=overwrite, kind="dir")
