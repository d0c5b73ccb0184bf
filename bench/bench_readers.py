"""Benchmark of the readers: a dense creep table fitted through log-time binning, and reading itself.

Issue 28's goal: the 7,199-point creep table ``../shared/data/instrument-exports/creep_ps145_data.csv`` (polystyrene,
sampled every 0.1 s from 0.2 to 720 s) fits in <= 10 s on 2 cores; it took 291 s unbinned, and 83 log-spaced points
of it 2.4 s. In one run, with the load average printed and CPU time beside wall time:

1. reading: ``read_data`` of the table (7,199 rows, units given), against the physical floor of parsing its
   numbers (``numpy.loadtxt`` of the same file);
2. binning: ``CreepData.binned(100)`` (the fit's default ``--max-points``);
3. the fit the command runs (per-tendon, 4 starts, seed 0, one process): on the binned table (what ``tenscell
   fit`` does), against the competent baseline, the same fit on 83 log-spaced points picked from the table, and
   the whole command (``python -m tenscell fit FILE --units time=s --units compliance=1/Pa``) in a new process,
   CPU time of the process and its children included.

The unbinned fit (7,199 points; 291 s) is not run: its cost is one residual evaluation's ratio, printed.
Skips, saying why, where ../shared/data is absent.

Run: PYTHONPATH=src python bench/bench_readers.py [--starts 4] [--skip-command]
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

FILE = Path(__file__).resolve().parents[2] / "shared" / "data" / "instrument-exports" / "creep_ps145_data.csv"


def _clock(fn):
    """(result, wall s, CPU s of this process)."""
    c, w = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--skip-command", action="store_true")
    opts = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} CPUs")
    if not FILE.is_file():
        print(f"skipped: {FILE} is absent (../shared/data is read at run time, never copied)")
        return 0
    from tenscell import fitting
    from tenscell.io.creep_data import CreepData
    from tenscell.io.readers import read_data

    data, w, c = _clock(lambda: read_data(FILE, time_unit="s", compliance_unit="1/Pa"))
    _, w0, c0 = _clock(lambda: np.loadtxt(FILE, skiprows=1, delimiter="\t"))
    print(f"== reading {data.n:,} rows: {w * 1e3:.0f} ms wall, {c * 1e3:.0f} ms CPU; numpy.loadtxt of the same "
          f"numbers {c0 * 1e3:.0f} ms CPU: ratio {c / c0:.1f}")
    binned, w, c = _clock(lambda: data.binned(100))
    print(f"== binning to {binned.n} points: {w * 1e3:.1f} ms")
    idx = np.unique(np.searchsorted(data.time_s, np.logspace(np.log10(data.time_s[0]), np.log10(data.time_s[-1]),
                                                            90)).clip(0, data.n - 1))
    spaced = CreepData(time_s=data.time_s[idx], compliance=data.compliance[idx], source="log-spaced")
    kw = dict(starts=opts.starts, seed=0, jobs=1, progress=False, max_points=None)
    rows = []
    for name, d in (("binned (what the command fits)", binned), (f"{spaced.n} log-spaced points (baseline)", spaced)):
        r, w, c = _clock(lambda d=d: fitting.fit(d, **kw))
        rows.append((name, d.n, r.rms_log10_error, r.converged, w, c))
        print(f"== fit, {name}: {d.n} points, rms {r.rms_log10_error:.4f} ({'converged' if r.converged else 'not'}),"
              f" {w:.1f} s wall, {c:.1f} s CPU")
    print(f"   ratio binned / baseline (CPU): {rows[0][5] / rows[1][5]:.2f}")
    prob_full = fitting.make_problem([data])
    prob_bin = fitting.make_problem([binned])
    from tenscell.fitting.search import _initial_guess

    theta = _initial_guess(prob_bin, np.random.default_rng(0))
    if theta is not None:
        _, _, c_full = _clock(lambda: [prob_full.residuals(theta) for _ in range(3)])
        _, _, c_bin = _clock(lambda: [prob_bin.residuals(theta) for _ in range(3)])
        print(f"== one residual evaluation: {data.n:,} points {c_full / 3 * 1e3:.1f} ms, {binned.n} binned "
              f"{c_bin / 3 * 1e3:.1f} ms CPU: the unbinned fit costs about {c_full / c_bin:.0f}x per evaluation")
    if not opts.skip_command:
        with tempfile.TemporaryDirectory() as tmp:
            before = _children_cpu()
            t = time.perf_counter()
            run = subprocess.run([sys.executable, "-m", "tenscell", "fit", str(FILE), "--units", "time=s", "--units",
                                  "compliance=1/Pa", "--out", f"{tmp}/fit"], capture_output=True, text=True,
                                 env={**os.environ, "TENSCELL_PROGRESS": "0"})
            wall, cpu = time.perf_counter() - t, _children_cpu() - before
        print(f"== the command (exit {run.returncode}): {wall:.1f} s wall, {cpu:.1f} s CPU (process and children); "
              f"goal <= 10 s on 2 cores: {'met' if wall <= 10 else 'NOT met'} at this load")
        print("   " + run.stderr.strip().splitlines()[-1][:200])
    return 0


if __name__ == "__main__":
    sys.exit(main())
