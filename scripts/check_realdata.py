"""The team's check on held-back real recordings, through the command line exactly as a user runs it.

For each train → test pair of ``benchmarks/bench_realdata.py`` (``PAIRS``; a pair with a part uses the
first or second half of one run), every run is written into a temporary folder as a plain CSV with the
columns ``time_s,force_n,reading`` (no sidecar, no units: the way most users' files arrive). Then, with
the ``fsrlab`` command given by ``--fsrlab`` (default: the one beside this Python)::

    fsrlab calibrate TRAIN.csv [TRAIN2.csv ...] --x reading --reference force_n -o plain.json
    fsrlab calibrate TRAIN.csv [TRAIN2.csv ...] --x reading --reference force_n --compensate -o comp.json
    fsrlab apply plain.json TEST.csv -o est.csv --json      (and comp.json; each test run)

and the estimate written by ``apply`` is scored over the loaded rows (reference above 5 % of the test
runs' largest): RMSE [% of the test's reference span]; compensated / plain; each against a polynomial
(degree 1–5) whose degree is chosen on the training runs alone (leave one recording out with two or more,
else the first 70 % of the run fitted and the rest scored, as ``bench_realdata._fair_polynomial``) and
fitted **in the readout variable the physics names**: the conductance 1/reading when the training
reading looks like a resistance (every reading above zero, spanning more than a decade, falling as the
force rises: Spearman's rank correlation below zero), the raw reading otherwise; the share of loaded rows
whose error lies within ±2u; the share of loaded rows without an estimate.

The summary is issue 37's "done when", each line for the first ``DEVELOPED_ON`` pairs (the calibration
was developed on them), for the pairs added later, and for all:

- the compensated calibration at most ×1.05 the plain one on every pair;
- against the physics-variable polynomial, the compensated calibration's geometric mean at most ×0.80
  and its worst pair at most ×1.25;
- ±2u (compensated) covers at least 90 % on every pair recorded in the same session (``SAME_SESSION``);
- at most 2 % of the loaded rows without an estimate, on every pair (compensated and plain).

Usage (``FSRLAB_REALDATA`` or ``--data``: the folder ``scripts/prepare_realdata.py`` writes)::

    python scripts/check_realdata.py --data /work/realdata
    python scripts/check_realdata.py --data /work/realdata --src /tmp/old/src      # another source tree
    python scripts/check_realdata.py --fsrlab "fsrlab" --pairs 0-5,20 --json
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import os
import shlex
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_realdata import DEVELOPED_ON, PAIRS  # noqa: E402 (found on the sys.path set above); the one list of pairs

#: Indices of PAIRS whose training and test rows come from one session: halves of one run, a repeat
#: recorded minutes later on the same mounting (the robot's Velostat series, 25 Nov 2021, 13:58-15:19,
#: one mounting per indenter), hand and servo runs of one numbered FSR session. Not: another FSR
#: session, another cover on the taxel (bare vs silicone), another force-plate experiment (the phantom
#: placed again), the insole's runs after a restart of its logger (another clock base) or another day.
SAME_SESSION = {0, 1, 2, 3, 4, 6, 7, 8, 9, 13, 14, 15, 16, 18, 20, 22, 23, 24, 26, 27, 28, 29, 30, 31, 33}

CRITERIA = {"comp_vs_plain": 1.05, "geomean_vs_poly": 0.80, "worst_vs_poly": 1.25, "coverage": 0.90,
            "missing": 0.02}


# --- runs ----------------------------------------------------------------------------------------------
def read_run(path: Path) -> dict:
    """The columns of a ``time_s,reading,force_n`` file (any order) as float arrays (NaN for empty cells)."""
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    head = rows[0]
    data = np.array([[float(c) if c.strip() else np.nan for c in r] for r in rows[1:] if r], float)
    return {h: data[:, i] for i, h in enumerate(head)}


def plain_copy(root: Path, spec, tmp: Path, tag: str) -> tuple[Path, dict]:
    """The run ``spec`` (name or (name, part)) written as ``time_s,force_n,reading`` into ``tmp``."""
    name, part = (spec, None) if isinstance(spec, str) else spec
    src = root / f"{name}.csv"
    if not src.exists():
        raise FileNotFoundError(src)
    run = read_run(src)
    if part is not None:
        n = run["time_s"].size // 2
        sl = slice(None, n) if part == 0 else slice(n, None)
        run = {k: v[sl] for k, v in run.items()}
        run["time_s"] = run["time_s"] - run["time_s"][0]
    out = tmp / f"{tag}.csv"
    with out.open("w") as fh:
        fh.write("time_s,force_n,reading\n")
        for t, y, x in zip(run["time_s"], run["force_n"], run["reading"], strict=True):
            fh.write(",".join("" if not np.isfinite(v) else f"{v:.10g}" for v in (t, y, x)) + "\n")
    return out, run


# --- the polynomial a user can fit -------------------------------------------------------------------
def physics_variable(train: list[dict]) -> str:
    """``conductance`` (1/reading) when the training reading looks like a resistance, else ``reading``."""
    x = np.concatenate([r["reading"] for r in train])
    y = np.concatenate([r["force_n"] for r in train])
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < 3 or x.min() <= 0 or x.max() / x.min() <= 10:
        return "reading"
    def rank(v):
        return np.argsort(np.argsort(v, kind="stable"), kind="stable").astype(float)

    rho = np.corrcoef(rank(x), rank(y))[0, 1]
    return "conductance" if rho < 0 else "reading"


def _var(x: np.ndarray, variable: str) -> np.ndarray:
    if variable == "reading":
        return x
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(x > 0, 1.0 / x, np.nan)


def fair_polynomial(train: list[dict], test: list[dict], variables: tuple[str, ...]) -> dict:
    """RMSE [% of the test's span] over the loaded test rows of the polynomial whose degree 1–5 (and variable,
    when more than one is given) is chosen on the training runs alone: mean squared error with one recording
    left out at a time when there are two or more, else fitted on the first 70 % of the run and scored on
    the rest (as ``bench_realdata._fair_polynomial``)."""
    ys_runs = [r["force_n"] for r in train]

    def cols(variable: str) -> list[tuple[np.ndarray, np.ndarray]]:
        out = []
        for r, y in zip(train, ys_runs, strict=True):
            x = _var(r["reading"], variable)
            ok = np.isfinite(x) & np.isfinite(y)
            out.append((x[ok], y[ok]))
        return out

    def heldout(c, d: int) -> float:
        if len(c) > 1:
            errs = []
            for k, (xk, yk) in enumerate(c):
                xs = np.concatenate([v[0] for j, v in enumerate(c) if j != k])
                ys = np.concatenate([v[1] for j, v in enumerate(c) if j != k])
                errs.append(np.mean((np.polynomial.Polynomial.fit(xs, ys, d)(xk) - yk) ** 2))
            return float(np.mean(errs))
        x, y = c[0]
        n = int(0.7 * x.size)
        return float(np.mean((np.polynomial.Polynomial.fit(x[:n], y[:n], d)(x[n:]) - y[n:]) ** 2))

    by_var = {v: cols(v) for v in variables}
    _, variable, degree = min((heldout(by_var[v], d), v, d) for v in variables for d in range(1, 6))
    xs, ys = (np.concatenate(v) for v in zip(*by_var[variable], strict=True))
    p = np.polynomial.Polynomial.fit(xs, ys, degree)
    x = _var(np.concatenate([r["reading"] for r in test]), variable)
    y = np.concatenate([r["force_n"] for r in test])
    loaded = y > 0.05 * np.nanmax(y)
    e = p(x[loaded]) - y[loaded]
    got = np.isfinite(e)
    return {"rmse_pct": 100 * float(np.sqrt(np.mean(e[got] ** 2))) / float(np.nanmax(y) - np.nanmin(y)),
            "degree": degree, "variable": variable, "missing": float(np.mean(~got))}


# --- the command line ---------------------------------------------------------------------------------
def run_cmd(prefix: list[str], args: list[str], cwd: Path, timeout: float) -> subprocess.CompletedProcess:
    return subprocess.run(prefix + args, cwd=cwd, capture_output=True, text=True, timeout=timeout, check=False)


def _why(p: subprocess.CompletedProcess) -> str:
    lines = [ln for ln in (p.stderr or p.stdout).strip().splitlines() if ln.strip()]
    return (lines[-1] if lines else f"exit {p.returncode}")[:300]


def calibrated(prefix, train_files, test_files, tests, tmp: Path, compensate: bool, timeout: float) -> dict:
    """calibrate on the training files, apply to each test file; the scores over the loaded rows."""
    tag = "comp" if compensate else "plain"
    cal = tmp / f"{tag}.json"
    args = ["calibrate", *[p.name for p in train_files], "--x", "reading", "--reference", "force_n",
            *(["--compensate"] if compensate else []), "-o", cal.name]
    t0 = time.perf_counter()
    p = run_cmd(prefix, args, tmp, timeout)
    if p.returncode != 0 or not cal.exists():
        return {"error": f"calibrate: {_why(p)}", "command": shlex.join(["fsrlab", *args])}
    est, unc, ys, model = [], [], [], None
    for i, f in enumerate(test_files):
        out = tmp / f"{tag}-est{i}.csv"
        a = ["apply", cal.name, f.name, "-o", out.name, "--json"]
        q = run_cmd(prefix, a, tmp, timeout)
        if q.returncode != 0 or not out.exists():
            return {"error": f"apply: {_why(q)}", "command": shlex.join(["fsrlab", *a])}
        try:
            model = json.loads(q.stdout).get("model", model)
        except ValueError:
            pass
        r = read_run(out)
        if r["force_n"].size != tests[i]["force_n"].size:
            return {"error": f"apply wrote {r['force_n'].size} rows of {tests[i]['force_n'].size}"}
        ys.append(tests[i]["force_n"])
        est.append(r.get("force_n_estimate", np.full(r["force_n"].size, np.nan)))
        unc.append(r.get("force_n_uncertainty", np.full(r["force_n"].size, np.nan)))
    y, e, u = np.concatenate(ys), np.concatenate(est), np.concatenate(unc)
    err = e - y
    loaded = y > 0.05 * np.nanmax(y)
    got = loaded & np.isfinite(err)
    rmse = float(np.sqrt(np.mean(err[got] ** 2))) if got.any() else math.nan
    span = float(np.nanmax(y) - np.nanmin(y))
    return {"rmse_n": rmse, "rmse_pct": 100 * rmse / span, "model": model,
            "coverage": float(np.mean(np.abs(err[got]) <= 2 * u[got])) if got.any() else math.nan,
            "missing": float(np.mean(~np.isfinite(err[loaded]))), "loaded_rows": int(loaded.sum()),
            "seconds": round(time.perf_counter() - t0, 1)}


def score_pair(i: int, prefix: list[str], root: Path, timeout: float) -> dict:
    name, tr, te = PAIRS[i]
    out = {"index": i, "name": name, "developed_on": i < DEVELOPED_ON, "same_session": i in SAME_SESSION,
           "train": [s if isinstance(s, str) else f"{s[0]} ({'first' if s[1] == 0 else 'second'} half)" for s in tr],
           "test": [s if isinstance(s, str) else f"{s[0]} ({'first' if s[1] == 0 else 'second'} half)" for s in te]}
    with tempfile.TemporaryDirectory(prefix=f"check-realdata-{i}-") as d:
        tmp = Path(d)
        try:
            train = [plain_copy(root, s, tmp, f"train{k}") for k, s in enumerate(tr)]
            test = [plain_copy(root, s, tmp, f"test{k}") for k, s in enumerate(te)]
        except FileNotFoundError as exc:
            out["error"] = f"not found: {exc}"
            return out
        trains, tests = [r for _, r in train], [r for _, r in test]
        var = physics_variable(trains)
        out["poly"] = fair_polynomial(trains, tests, (var,))
        out["poly_raw"] = fair_polynomial(trains, tests, ("reading",))
        positive = all(np.nanmin(r["reading"]) > 0 for r in trains)
        out["poly_chosen"] = fair_polynomial(trains, tests, ("reading", "conductance") if positive else ("reading",))
        for comp in (False, True):
            out["comp" if comp else "plain"] = calibrated(prefix, [p for p, _ in train], [p for p, _ in test], tests,
                                                          tmp, comp, timeout)
    p, c, poly = out["plain"], out["comp"], out["poly"]["rmse_pct"]
    if "error" not in p and "error" not in c:
        out["comp_vs_plain"] = c["rmse_pct"] / p["rmse_pct"]
    for k in ("plain", "comp"):
        if "error" not in out[k]:
            out[k]["vs_poly"] = out[k]["rmse_pct"] / poly
            out[k]["vs_poly_raw"] = out[k]["rmse_pct"] / out["poly_raw"]["rmse_pct"]
            out[k]["vs_poly_chosen"] = out[k]["rmse_pct"] / out["poly_chosen"]["rmse_pct"]
    return out


# --- summary ------------------------------------------------------------------------------------------
def summary(results: list[dict]) -> dict:
    groups = {f"first {DEVELOPED_ON} (developed on)": [r for r in results if r["developed_on"]],
              "added later (measured only)": [r for r in results if not r["developed_on"]], "all": results}
    out = {}
    for g, rs in groups.items():
        if not rs:
            continue
        ok = [r for r in rs if "error" not in r and "error" not in r["plain"] and "error" not in r["comp"]]
        good = {r["index"] for r in ok}
        failed = [r["index"] for r in rs if r["index"] not in good]
        s = {"pairs": len(rs), "failed_pairs": failed}
        cvp = np.array([r["comp_vs_plain"] for r in ok])
        vs = np.array([r["comp"]["vs_poly"] for r in ok])
        vs_plain = np.array([r["plain"]["vs_poly"] for r in ok])
        same = [r for r in ok if r["same_session"]]
        cov = np.array([r["comp"]["coverage"] for r in same])
        miss = np.array([max(r["comp"]["missing"], r["plain"]["missing"]) for r in ok])
        if ok:
            s["comp_vs_plain"] = {"worst": float(cvp.max()),
                                  "over": [r["index"] for r in ok if r["comp_vs_plain"] > CRITERIA["comp_vs_plain"]],
                                  "pass": bool(cvp.max() <= CRITERIA["comp_vs_plain"] and not failed)}
            s["vs_poly"] = {"geomean": float(np.exp(np.mean(np.log(vs)))), "worst": float(vs.max()),
                            "worst_pair": ok[int(vs.argmax())]["index"], "at_most_1": int((vs <= 1).sum()),
                            "plain_geomean": float(np.exp(np.mean(np.log(vs_plain)))),
                            "plain_worst": float(vs_plain.max()),
                            **{f"{ref}_geomean": float(np.exp(np.mean(np.log([r["comp"][f"vs_{ref}"] for r in ok]))))
                               for ref in ("poly_raw", "poly_chosen")},
                            **{f"{ref}_worst": float(max(r["comp"][f"vs_{ref}"] for r in ok))
                               for ref in ("poly_raw", "poly_chosen")},
                            "pass": bool(np.exp(np.mean(np.log(vs))) <= CRITERIA["geomean_vs_poly"]
                                         and vs.max() <= CRITERIA["worst_vs_poly"] and not failed)}
            s["coverage_same_session"] = {"pairs": len(same), "at_least_90": int((cov >= CRITERIA["coverage"]).sum()),
                                          "below": [r["index"] for r in same
                                                    if r["comp"]["coverage"] < CRITERIA["coverage"]],
                                          "lowest": float(cov.min()) if cov.size else None,
                                          "pass": bool(cov.size == 0 or cov.min() >= CRITERIA["coverage"])}
            s["missing"] = {"worst": float(miss.max()), "over": [r["index"] for r, m in zip(ok, miss, strict=True)
                                                                   if m > CRITERIA["missing"]],
                            "pass": bool(miss.max() <= CRITERIA["missing"] and not failed)}
        out[g] = s
    return out


def yes(ok: bool) -> str:
    return "PASS" if ok else "FAIL"


def _f(v, fmt):
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, fmt)


def table(results: list[dict], summ: dict, prefix: list[str]) -> str:
    lines = [f"fsrlab command: {shlex.join(prefix)}", "",
             ("| # | pair | S | polynomial (training-chosen degree, variable) "
              "| plain: RMSE % span, ×poly, ±2u, missing | "
              "compensated: RMSE % span, ×poly, ±2u, missing | comp/plain | model (compensated) |"),
             "|---:|---|:-:|---:|---:|---:|---:|---|"]
    for r in results:
        if r.get("error"):
            lines.append(f"| {r['index']} | {r['name']} | | {r['error']} | | | | |")
            continue
        cells = []
        for k in ("plain", "comp"):
            s = r[k]
            cells.append(s["error"] if "error" in s else
                         f"{s['rmse_pct']:.2f} %, ×{s['vs_poly']:.2f}, {100 * s['coverage']:.0f} %, "
                         f"{100 * s['missing']:.1f} %")
        p = r["poly"]
        var = "1/reading" if p["variable"] == "conductance" else "reading"
        alt = (f"; raw {r['poly_raw']['rmse_pct']:.2f} % ({r['poly_raw']['degree']})"
               if p["variable"] != "reading" else "")
        lines.append(f"| {r['index']} | {r['name']} | {'S' if r['same_session'] else ''} "
                     f"| {p['rmse_pct']:.2f} % ({p['degree']}, {var}){alt} | "
                     f"{cells[0]} | {cells[1]} | {_f(r.get('comp_vs_plain'), '.3f')} "
                     f"| {r['comp'].get('model') or ''} |")
    lines += ["", "S: training and test rows from one session (±2u criterion applies).", "",
              "Issue 37, done when (on the compensated calibration; plain in brackets where it applies):"]
    for g, s in summ.items():
        lines.append(f"\n{g}: {s['pairs']} pairs"
                     + (f"; FAILED to run: {s['failed_pairs']}" if s["failed_pairs"] else ""))
        if "comp_vs_plain" not in s:
            continue
        c, v, cv, m = s["comp_vs_plain"], s["vs_poly"], s["coverage_same_session"], s["missing"]
        lines.append(f"  compensated ≤ ×1.05 plain on every pair: worst ×{c['worst']:.3f}; over: {c['over'] or 'none'} "
                     f"-> {yes(c['pass'])}")
        lines.append(f"  vs polynomial (degree chosen on training, physics variable): "
                     f"geometric mean ×{v['geomean']:.3f} "
                     f"(≤ ×0.80), worst ×{v['worst']:.3f} on #{v['worst_pair']} (≤ ×1.25), "
                     f"{v['at_most_1']} at most ×1.00; "
                     f"[plain ×{v['plain_geomean']:.3f}, worst ×{v['plain_worst']:.3f}] -> {yes(v['pass'])}")
        lines.append(f"    for reference, compensated vs the polynomial in the raw reading: "
                     f"×{v['poly_raw_geomean']:.3f}, worst "
                     f"×{v['poly_raw_worst']:.3f}; vs the polynomial whose variable too (reading or 1/reading) "
                     "is chosen "
                     f"on training: ×{v['poly_chosen_geomean']:.3f}, worst ×{v['poly_chosen_worst']:.3f}")
        lines.append(f"  ±2u ≥ 90 % on every same-session pair: {cv['at_least_90']} of {cv['pairs']}; below: "
                     f"{cv['below'] or 'none'}; lowest {_f(cv['lowest'] and 100 * cv['lowest'], '.0f')} % "
                     f"-> {yes(cv['pass'])}")
        lines.append(f"  ≤ 2 % loaded rows without estimate (plain and compensated): "
                     f"worst {100 * m['worst']:.1f} %; over: "
                     f"{m['over'] or 'none'} -> {yes(m['pass'])}")
    return "\n".join(lines) + "\n"


def tree_state(src: Path) -> dict:
    """The git commit of the source tree fsrlab runs from and a hash of its uncommitted changes (other people
    may be editing it while the check runs: compare the state before and after)."""
    def git(*args: str) -> str:
        p = subprocess.run(["git", "-C", str(src), *args], capture_output=True, text=True, check=False)
        return p.stdout.strip() if p.returncode == 0 else ""

    diff = git("diff", "HEAD", "--", ".")
    untracked = git("ls-files", "--others", "--exclude-standard", "--", ".")
    return {"tree": str(src), "commit": git("rev-parse", "--short", "HEAD"),
            "uncommitted": hashlib.sha1((diff + untracked).encode()).hexdigest()[:10] if diff or untracked else None}


def parse_pairs(spec: str | None) -> list[int]:
    if not spec:
        return list(range(len(PAIRS)))
    out = []
    for part in spec.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b) + 1)) if b else [int(a)]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog="See the module docstring for what is scored.")
    ap.add_argument("--data", default=os.environ.get("FSRLAB_REALDATA"),
                    help="folder of time_s,reading,force_n CSV files (default: $FSRLAB_REALDATA)")
    ap.add_argument("--fsrlab", help="command prefix that runs fsrlab, e.g. 'fsrlab' or "
                                     "\"python -c 'import sys; from fsrlab.cli import main; sys.exit(main())'\"")
    ap.add_argument("--src", help="run fsrlab from this source tree (its src/ folder): PYTHONPATH=SRC with this Python")
    ap.add_argument("--pairs", help="indices of PAIRS, e.g. 0-5,20 (default: all)")
    ap.add_argument("--jobs", type=int, default=1, help="pairs scored at once (default 1)")
    ap.add_argument("--timeout", type=float, default=900, help="seconds per fsrlab command (default 900)")
    ap.add_argument("--json", action="store_true", help="print JSON (pairs and summary) instead of the table")
    ap.add_argument("--json-out", metavar="PATH", help="also write that JSON to PATH")
    a = ap.parse_args(argv)
    if not a.data or not Path(a.data).is_dir():
        ap.error("give --data or set FSRLAB_REALDATA to the folder scripts/prepare_realdata.py writes")
    if a.src:
        src = str(Path(a.src).resolve())
        prefix = ["env", f"PYTHONPATH={src}", sys.executable, "-c",
                  "import sys; from fsrlab.cli import main; sys.argv[0] = 'fsrlab'; sys.exit(main())"]
    elif a.fsrlab:
        prefix = shlex.split(a.fsrlab)
    else:
        prefix = [str(Path(sys.executable).with_name("fsrlab"))]
    idx = parse_pairs(a.pairs)
    tree = Path(a.src).resolve() if a.src else ROOT / "src"
    before = tree_state(tree)
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        results = list(pool.map(lambda i: score_pair(i, prefix, Path(a.data), a.timeout), idx))
    summ = summary(results)
    after = tree_state(tree)
    state = f"source {tree}: commit {before['commit'] or '?'}" + (
        f", uncommitted changes {before['uncommitted']}" if before["uncommitted"] else ", clean")
    if after != before:
        state += f"; CHANGED while the check ran (after: {after['commit']}, {after['uncommitted']})"
    doc = {"fsrlab": prefix, "source_before": before, "source_after": after, "data": str(a.data),
           "criteria": CRITERIA, "developed_on": DEVELOPED_ON,
           "same_session": sorted(SAME_SESSION), "seconds": round(time.perf_counter() - t0, 1), "pairs": results,
           "summary": summ}
    if a.json_out:
        Path(a.json_out).write_text(json.dumps(doc, indent=1, default=float) + "\n")
    if a.json:
        json.dump(doc, sys.stdout, indent=1, default=float)
        print()
    else:
        sys.stdout.write(state + "\n" + table(results, summ, prefix))
        print(f"\n{len(results)} pairs in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
