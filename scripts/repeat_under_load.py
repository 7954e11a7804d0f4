#!/usr/bin/env python3
"""Run tests again and again with every core kept busy: the check for a test that fails one run in ten.

A test that depends on timing or threads must pass 20 runs in a row on a busy machine (CI runs on one).
This script starts one busy process per core (``python -c "while True: pass"``), runs pytest on the given
test paths or node ids ``--runs`` times, stops at the first failure (or goes on with ``--keep-going``) and
prints which runs failed and the first lines of each failure. Exit 0 when every run passed.

Examples
--------
::

    .venv/bin/python scripts/repeat_under_load.py tests/virtual/test_device.py
    .venv/bin/python scripts/repeat_under_load.py --runs 20 tests/acquisition tests/live -k "not browser"
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tests", nargs="+", help="test paths or node ids, as pytest takes them")
    ap.add_argument("--runs", type=int, default=20, help="how many runs in a row (default 20)")
    ap.add_argument("--busy", type=int, default=os.cpu_count() or 2,
                    help="busy processes beside the tests (default: one per core)")
    ap.add_argument("-k", dest="keyword", default=None, help="pytest's -k expression")
    ap.add_argument("--keep-going", action="store_true", help="run every run even after a failure")
    args = ap.parse_args(argv)
    if args.runs < 1 or args.busy < 0:
        ap.error("--runs must be >= 1 and --busy >= 0")
    cmd = [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", *args.tests]
    if args.keyword:
        cmd += ["-k", args.keyword]
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(args.busy)]
    failed = []
    try:
        for i in range(1, args.runs + 1):
            t0 = time.monotonic()
            proc = subprocess.run(cmd, capture_output=True, text=True)
            last = (proc.stdout.strip().splitlines() or [""])[-1]
            print(f"run {i:2d}/{args.runs}: {'ok  ' if proc.returncode == 0 else 'FAIL'} "
                  f"{time.monotonic() - t0:6.1f} s  {last}", flush=True)
            if proc.returncode != 0:
                failed.append(i)
                lines = [ln for ln in proc.stdout.splitlines() if ln.startswith(("E ", "FAILED", "ERROR"))]
                print("    " + "\n    ".join(lines[:8]), flush=True)
                if not args.keep_going:
                    break
    finally:
        for p in busy:
            p.kill()
    print(f"{args.runs if args.keep_going or not failed else failed[-1]} runs, {len(failed)} failed"
          + (f" (runs {', '.join(map(str, failed))})" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
