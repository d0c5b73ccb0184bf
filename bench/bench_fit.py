"""Benchmark of tenscell.fitting.

1. Time per Jacobian of the residuals: analytic (relaxation spectrum, all
   frequencies from a few matrix products) versus central finite differences
   (2 × n_free model evaluations), in the same run, for both bundled data sets.
2. Time to target from a cold start (new process state, no warm start),
   including the multi-start, for both bundled data sets and several seeds:
   - frequency data (Fabry 2001): RMS log10 error <= 0.01 and the local slope
     of G' within 0.2 ± 0.06 on 1000 frequencies from 0.01 to 100 Hz;
   - prestress data (Stamenović 2002): RMS <= 0.01 and straight-line slopes of
     the model's G', G'' over 350–1900 Pa within 10 % of 0.20 and 0.05.
   The time is read from the fit's history (best-so-far over all starts).

Run: PYTHONPATH=src python bench/bench_fit.py [--seeds 0,1,2] [--jobs 2] [--starts 4]
"""
from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import os

import numpy as np
from threadpoolctl import threadpool_limits

from tenscell import fitting
from tenscell.fitting.search import _initial_guess
from tenscell.io.data import bundled


def _time(fn, repeat):
    fn()
    t = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t) / repeat


def bench_jacobian():
    print("== Jacobian of the residuals: analytic vs central finite differences (one BLAS thread, as in the fit)")
    for name in ("fabry2001", "stamenovic2002"):
        problem = fitting.make_problem(bundled(name))
        theta = _initial_guess(problem, np.random.default_rng(0))
        with threadpool_limits(limits=1, user_api="blas"):
            t_an = _time(lambda: problem.jacobian(theta), 200)
            t_fd = _time(lambda: problem.jacobian_fd(theta), 20)
            err = np.abs(problem.jacobian(theta) - problem.jacobian_fd(theta)).max()
        print(f"{name:>15}: {problem.n_residuals} residuals x {problem.n_free} parameters: "
              f"analytic {t_an * 1e3:.3f} ms, finite differences {t_fd * 1e3:.2f} ms, "
              f"speedup {t_fd / t_an:.1f}x (max difference {err:.1e})")


def _meets(name, result):
    if result.rms_log10_error > 0.01:
        return False
    if name == "fabry2001":
        _, s1, _ = fitting.frequency_slopes(result, 0.01, 100.0, 1000)
        return bool(s1.min() >= 0.14 and s1.max() <= 0.26)
    a1, _, a2, _ = fitting.prestress_slopes(result)
    return bool(abs(a1 / 0.20 - 1) <= 0.10 and abs(a2 / 0.05 - 1) <= 0.10)


def time_to_target(name, seed, starts, jobs):
    data = bundled(name)
    t0 = time.perf_counter()
    result = fitting.fit(data, seed=seed, starts=starts, jobs=jobs, progress=False)
    wall = time.perf_counter() - t0
    hit = None
    for (t, rms), theta in zip(result.history, result.history_theta):
        if rms <= 0.01 and _meets(name, dataclasses.replace(result, theta=theta, rms_log10_error=rms)):
            hit = t
            break
    return hit, wall, result


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    print(f"load average before the run: {', '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    bench_jacobian()
    print(f"== time to target from a cold start ({args.starts} starts, {args.jobs} jobs)")
    for name in ("fabry2001", "stamenovic2002"):
        hits = []
        for seed in seeds:
            hit, wall, r = time_to_target(name, seed, args.starts, args.jobs)
            hits.append(hit)
            if name == "fabry2001":
                _, s1, _ = fitting.frequency_slopes(r, 0.01, 100.0, 1000)
                shape = f"G' slope {s1.min():.3f}..{s1.max():.3f}"
            else:
                a1, _, a2, _ = fitting.prestress_slopes(r)
                shape = f"dG'/dP {a1:.4f}, dG''/dP {a2:.4f}"
            print(f"{name:>15} seed {seed}: final rms {r.rms_log10_error:.5f}, {shape}; "
                  f"target reached after {'%.2f s' % hit if hit is not None else 'NEVER'}; whole fit {wall:.1f} s")
        ok = [h for h in hits if h is not None]
        if ok:
            print(f"{name:>15}: target reached in {len(ok)}/{len(hits)} seeds; median {statistics.median(ok):.2f} s, "
                  f"max {max(ok):.2f} s")
        else:
            print(f"{name:>15}: target never reached")


if __name__ == "__main__":
    main()
