"""Each study's estimate against its measured time (issue 35: within ×/÷ 1.5 whatever the load).

Runs ``tenscell study NAME`` for every study on the protocol (``tenscell.cli.study.STUDIES``; compactness on the
bundled Fabry sweep with two bounds and one start; mechanisms on the bundled pair; real-cells on 5 cells per line with
4 starts × 4 hops, where the measured cells are) in a new process, reads the estimate it announced before the
work and the time it took after the announcement (its last line), and prints their ratio with the load average
before and after each run. ``--burn N`` adds N busy processes of this benchmark's own for the whole run (a second
load; they are stopped at the end).

    PYTHONPATH=src python bench/bench_study_estimates.py [--burn 2] [NAMES]
"""
from __future__ import annotations

import argparse
import multiprocessing
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ARGS = {"compactness": ["bundled:fabry2001", "--decades", "3,2", "--starts", "1"],
        "mechanisms": ["bundled:stamenovic2002", "bundled:fabry2001"],
        # the measured cells (skipped where ../shared/data/real-cells is absent), 5 cells a line, a shorter search
        "real-cells": ["--cells", "5", "--starts", "4", "--hops", "4"]}
#: the studies run only where their data are
NEEDS = {"real-cells": Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "real-cells"}


def _burn() -> None:  # pragma: no cover - a busy loop, stopped by terminate()
    while True:
        pass


def _load() -> str:
    return f"{os.getloadavg()[0]:.1f}"


def run(name: str) -> tuple[float, float, str]:
    with tempfile.TemporaryDirectory() as tmp:
        before = _load()
        data = ["--data", str(NEEDS[name])] if name in NEEDS else []
        proc = subprocess.run([sys.executable, "-m", "tenscell", "study", name, *ARGS.get(name, []), *data, "--out",
                               os.path.join(tmp, "out")], capture_output=True, text=True,
                              env={**os.environ, "MPLBACKEND": "Agg", "TENSCELL_PROGRESS": "1"})
    if proc.returncode != 0:
        raise SystemExit(f"study {name}: exit {proc.returncode}: {proc.stderr[-2000:]}")
    m = re.search(r"finished in ([0-9.]+) s \(estimated ([0-9.na]+) s\)", proc.stderr)
    assert m, proc.stderr[-2000:]
    return float(m.group(1)), float(m.group(2)), f"{before} -> {_load()}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*")
    ap.add_argument("--burn", type=int, default=0, help="busy processes started for the run")
    args = ap.parse_args()
    from tenscell.cli.study import STUDIES

    burners = [multiprocessing.Process(target=_burn, daemon=True) for _ in range(args.burn)]
    for b in burners:
        b.start()
    try:
        print(f"load average {_load()} on {os.cpu_count()} CPUs; {args.burn} busy process(es) of this benchmark")
        worst = 1.0
        for name in args.names or STUDIES:
            if name in NEEDS and not NEEDS[name].is_dir():
                print(f"   {name:13s} skipped: no data at {NEEDS[name].resolve()}")
                continue
            took, estimated, load = run(name)
            ratio = max(took / estimated, estimated / took)
            worst = max(worst, ratio)
            print(f"   {name:13s} estimated {estimated:6.1f} s, took {took:6.1f} s: ratio {took / estimated:.2f} "
                  f"(goal within x/÷ 1.5) (load {load})", flush=True)
        print(f"   worst x/÷ {worst:.2f} (goal <= 1.5)")
    finally:
        for b in burners:
            b.terminate()


if __name__ == "__main__":
    main()
