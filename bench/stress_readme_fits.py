"""Stress test: the README's fit lines run many times concurrently (issue 27, goal "0 internal errors in 200
concurrent runs of the README's fit lines").

The README's lines, each as a fresh ``tenscell`` process into its own output directory:

* ``tenscell fit moduli.csv --out fit/`` on the table ``tenscell moduli --EA actin=2,intermediate_filament=0.5``
  writes (made once, before the runs);
* ``tenscell fit my_cells.csv --tendons per-tendon --starts 4 --seed 0 --out fit/`` (the line that raced:
  ``dictionary changed size during iteration`` in 1 of 8 runs, a worker pickling a result whose caches the main
  thread was filling), on the same table;
* ``tenscell fit SWEEP PRESTRESS_SWEEP --model springpot-alpha-family+visc --out fit/`` on the bundled sets.

Runs go round-robin over the lines, ``--concurrent`` at a time (default 8: four times the cores, so workers and
main threads interleave). A run passes when its exit status is 0 or 1 (1: a fit that misses its tolerance, an
explained verdict), its stderr holds no traceback, its output set is complete (``fit.json``, ``report.md``,
``fit.csv``) and its fit.json's parameters equal those of every other run of the same line (same seed, same
answer). Exit 70 or a traceback is an internal error. Prints the counts per line, CPU and wall time, and the
load average at start and end. Not a test: it takes minutes (``--runs 200``: about 15 min of CPU).
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

TENSCELL = [sys.executable, "-m", "tenscell"]
OUTPUTS = ("fit.json", "report.md", "fit.csv")


def lines(table: Path) -> dict[str, list[str]]:
    """The README's fit lines, with the table standing for the user's file."""
    return {
        "fit moduli.csv": ["fit", str(table)],
        "fit --tendons per-tendon --starts 4 --seed 0": ["fit", str(table), "--tendons", "per-tendon",
                                                          "--starts", "4", "--seed", "0"],
        "fit --model springpot-alpha-family+visc": ["fit", "bundled:fabry2001", "bundled:stamenovic2002",
                                               "--model", "springpot-alpha-family+visc"],
    }


def run_one(name: str, argv: list[str], out: Path) -> dict:
    """One run of one line; its verdict and its fitted parameters."""
    r = subprocess.run(TENSCELL + argv + ["--out", str(out)], capture_output=True, text=True)
    complete = all((out / f).is_file() for f in OUTPUTS)
    params = None
    if complete:
        fit = json.loads((out / "fit.json").read_text())
        params = json.dumps(fit.get("parameters", fit.get("theta")), sort_keys=True)
    internal = r.returncode >= 70 or "Traceback" in r.stderr
    ok = r.returncode in (0, 1) and not internal and complete
    return {"line": name, "rc": r.returncode, "internal": internal, "ok": ok, "params": params,
            "err": "" if ok else r.stderr.strip().splitlines()[-1:] }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=200, help="runs in all, round-robin over the lines (default 200)")
    ap.add_argument("--concurrent", type=int, default=8, help="runs at a time (default 8)")
    args = ap.parse_args()
    load0 = os.getloadavg()[0]
    wall0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="tenscell-stress-") as tmp:
        root = Path(tmp)
        table = root / "moduli.csv"
        with table.open("w") as fh:
            subprocess.run(TENSCELL + ["moduli", "--EA", "actin=2,intermediate_filament=0.5"], stdout=fh, check=True)
        todo = list(lines(table).items())
        jobs = [(todo[i % len(todo)][0], todo[i % len(todo)][1], root / f"run{i:04d}") for i in range(args.runs)]
        with ThreadPoolExecutor(args.concurrent) as pool:
            results = list(pool.map(lambda j: run_one(*j), jobs))
    wall = time.perf_counter() - wall0
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    by_line: dict[str, list[dict]] = defaultdict(list)
    for res in results:
        by_line[res["line"]].append(res)
    failures = 0
    print(f"{args.runs} runs, {args.concurrent} at a time: {wall:.0f} s wall, {ru.ru_utime + ru.ru_stime:.0f} s CPU; "
          f"load average {load0:.1f} at start, {os.getloadavg()[0]:.1f} at end ({os.cpu_count()} CPUs)")
    for name, rs in by_line.items():
        answers = Counter(r["params"] for r in rs if r["ok"])
        bad = [r for r in rs if not r["ok"]]
        internal = sum(r["internal"] for r in rs)
        same = len(answers) <= 1
        failures += len(bad) + (0 if same else 1)
        rcs = dict(sorted(Counter(r["rc"] for r in rs).items()))
        print(f"  {name}: {len(rs)} runs, exit statuses {rcs}, internal errors {internal}, incomplete or refused "
              f"{len(bad) - internal}, {'one answer' if same else f'{len(answers)} different answers'}")
        for r in bad[:3]:
            print(f"    rc {r['rc']}: {r['err']}")
    print(f"goal (issue 27): 0 internal errors in {args.runs} concurrent runs: "
          f"{'met' if failures == 0 else f'NOT met ({failures} failures)'}")
    return 0 if failures == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
