"""Benchmark of a mechanism fit against a direct numpy model and scipy's least squares, in one run.

The model is ``springpot-tension+visc`` on both bundled data sets jointly (Stamenović 2002's prestress sweep at
0.1 Hz, 8 points; Fabry 2001's frequency sweep, 16 points, its prestress fitted): seven parameters (EA, kappa,
alpha, alpha_T, eta, the prestress scale s and the frequency sweep's prestress), beta held at 1000. The baseline
is that model written directly in numpy (:func:`direct_model`, 25 lines: k* of every tendon at every point,
K = P·H + A diag(k*) Aᵀ for all points in one batched product, one batched solve) and fitted by
``scipy.optimize.least_squares`` (trf, the problem's bounds, its own 2-point finite-difference Jacobian) from the
middle of the bounds; the benchmark checks that it reaches the optimum tenscell's fit reports.

1. **One residual vector**: tenscell's ``problem.residuals`` against the direct code (goal: ≤ 1.5×), and the
   exact Jacobian against what the baseline pays for one (n_free + 1 residuals of the direct code). One BLAS
   thread for both, as in a fit.
2. **The fit**: ``tenscell.fitting.fit(..., model="springpot-tension+visc")`` (default options: 4 starts) against
   the baseline's least squares, CPU time of this process (goal: ≤ 2×); the evaluations, the stop reason.
3. **The study** (``--study``): ``tenscell study mechanisms bundled:stamenovic2002 bundled:fabry2001`` in a new
   process, its CPU time (user + system, the worker processes included; goal ≤ 40 s), and how often each
   stopping rule of the search ends the study's fits (every mechanism on all the data and on the training
   window, the study's options).

The machine is shared: the load average is printed before and after; every time is CPU time.

Run: PYTHONPATH=src python bench/bench_mechanism_fit.py [--seeds 0,1,2] [--study] [--rules]
"""
from __future__ import annotations

import argparse
import collections
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy.optimize
from threadpoolctl import threadpool_limits

from tenscell import fitting
from tenscell.fitting.models import get_model
from tenscell.io.data import bundled
from tenscell.model.shapes import paper_cell

MODEL = "springpot-tension+visc"
#: the held active modulus per unit tension of the model (tenscell.fitting.models.catalog.ACTIVE_BETA)
BETA = 1000.0


def direct_model(cell, sta, fab, beta=BETA):
    """The model's residuals ``log10 G_model − log10 G_data`` (G' block, G'' block) as a function of the
    natural logs of (EA, kappa, alpha, alpha_T, eta, s, P_fab), written directly in numpy."""
    A, H, b, l, T0 = cell.A, cell.prestress_hessian, cell.load, cell.lengths, cell.T0
    w = 2 * np.pi * np.concatenate([sta.frequency_hz, fab.frequency_hz])[:, None]
    y = np.log10(np.concatenate([sta.G_storage, fab.G_storage, sta.G_loss, fab.G_loss]))
    rhs = np.broadcast_to(b.astype(complex), (w.size, b.size))[..., None]

    def residuals(theta):
        EA, kappa, alpha, alpha_T, eta, s, P_fab = np.exp(theta)
        P = s * np.concatenate([sta.prestress, np.full(fab.n, P_fab)])[:, None]
        T = P * T0
        k = (EA + T) / l + (kappa / l) * (1j * w) ** alpha + (beta * T / l) * (1j * w) ** alpha_T
        K = P[:, :, None] * H + (A[None] * k[:, None, :]) @ A.T
        J = np.linalg.solve(K, rhs)[..., 0] @ b
        G = 0.5 / cell.strut_length / J + 1j * w[:, 0] * eta
        return np.concatenate([np.log10(G.real), np.log10(G.imag)]) - y

    return residuals


def _cpu(fn, repeat):
    fn()
    c = time.process_time()
    for _ in range(repeat):
        fn()
    return (time.process_time() - c) / repeat


def _paired(fns, repeat, blocks=7):
    """Median CPU per call of each function, timed in alternating blocks (a shared machine's load drifts)."""
    times = [[] for _ in fns]
    for _ in range(blocks):
        for k, fn in enumerate(fns):
            times[k].append(_cpu(fn, max(1, repeat // blocks)))
    return [float(np.median(t)) for t in times]


def _load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg()) + f" on {os.cpu_count()} cores"


def bench_residual(problem, direct, theta, repeat):
    print("== one evaluation at the optimum (CPU per call, one BLAS thread; medians of 7 alternating blocks)")
    with threadpool_limits(limits=1, user_api="blas"):
        dev = float(np.max(np.abs(problem.residuals(theta) - direct(theta))))
        t_dir, t_res, t_jac = _paired([lambda: direct(theta), lambda: problem.residuals(theta),
                                       lambda: problem.jacobian(theta)], repeat)
    n = problem.n_free
    print(f"   residuals: direct numpy {t_dir * 1e3:.3f} ms, tenscell {t_res * 1e3:.3f} ms: ratio "
          f"{t_res / t_dir:.2f} (goal <= 1.5); largest difference {dev:.1e} decades")
    print(f"   Jacobian: tenscell exact (residuals included) {t_jac * 1e3:.3f} ms = {t_jac / t_dir:.2f} direct "
          f"residuals; the baseline's 2-point differences cost {n + 1} ({(n + 1) * t_dir * 1e3:.2f} ms)")


def baseline_fit(problem, direct):
    """scipy least_squares on the direct model from the middle of the bounds: (CPU s, result)."""
    lo, hi = problem.bounds
    with threadpool_limits(limits=1, user_api="blas"):
        c = time.process_time()
        res = scipy.optimize.least_squares(direct, 0.5 * (lo + hi), bounds=(lo, hi), method="trf")
        return time.process_time() - c, res


def bench_fit(data, problem, direct, seeds):
    print(f"== the fit: tenscell.fitting.fit(model={MODEL!r}) against least_squares on the direct model (CPU)")
    t_base, base = baseline_fit(problem, direct)
    rms_base = float(np.sqrt(np.mean(base.fun**2)))
    print(f"   baseline: {t_base:.3f} s, {base.nfev} residuals + {base.njev} Jacobians of {problem.n_free + 1} "
          f"residuals each; rms {rms_base:.6f}")
    ratios = []
    for seed in seeds:
        c = time.process_time()
        r = fitting.fit(data, model=MODEL, seed=seed, progress=False)
        t = time.process_time() - c
        same = (abs(r.rms_log10_error / rms_base - 1) <= 1e-6 and float(np.max(np.abs(r.theta - base.x))) <= 1e-3)
        ratios.append(t / t_base)
        print(f"   seed {seed}: {t:.3f} s = {t / t_base:.1f}x the baseline (goal <= 2); {r.n_evaluations} "
              f"evaluations; rms {r.rms_log10_error:.6f}; the baseline reached "
              f"{'the same optimum' if same else 'ANOTHER point'} (largest log-parameter difference "
              f"{float(np.max(np.abs(r.theta - base.x))):.1e}); stopped: {r.stop_reason}")
    print(f"   median ratio {float(np.median(ratios)):.1f}x")


def bench_study():
    print("== tenscell study mechanisms bundled:stamenovic2002 bundled:fabry2001 (a new process, CPU of it and its "
          "workers)")
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "tenscell", "study", "mechanisms", "bundled:stamenovic2002",
                               "bundled:fabry2001", "--out", os.path.join(tmp, "out")], capture_output=True,
                              text=True, env={**os.environ, "MPLBACKEND": "Agg"})
        wall = time.perf_counter() - t
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    print(f"   exit {proc.returncode}; CPU {cpu:.1f} s (goal <= 40), wall {wall:.1f} s")


def bench_rules(data):
    """How the search ends each of the study's fits (its options: 4 starts, 10 hops, seed 0)."""
    from tenscell.fitting.models.catalog import MECHANISMS
    from tenscell.fitting.scores import split_holdout

    print("== how the study's fits stop (every mechanism, all the data and the training window; 4 starts, 10 hops)")
    fmax = float(data[1].frequency_hz.max())
    train = [data[0], split_holdout(data[1], fmax / 100 * 1.0001, fmax)[0]]
    reasons: collections.Counter = collections.Counter()
    for name in MECHANISMS:
        for label, d in (("all", data), ("train", train)):
            c = time.process_time()
            r = fitting.fit(d, model=name, seed=0, starts=4, hops=10, progress=False)
            kind = r.stop_reason.split(":")[0].split(" (")[0]
            kind = "starts agree" if "agree" in kind else kind
            reasons[kind] += 1
            print(f"   {name:26s} {label:5s} {time.process_time() - c:5.2f} s, {r.n_evaluations:4d} evaluations, "
                  f"rms {r.rms_log10_error:.5f}: {r.stop_reason}", flush=True)
    print("   " + "; ".join(f"{k}: {v}" for k, v in reasons.most_common()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--repeat", type=int, default=700, help="evaluations timed per kind")
    ap.add_argument("--study", action="store_true", help="time the whole mechanisms study (minutes)")
    ap.add_argument("--rules", action="store_true", help="count the stopping rules over the study's fits")
    args = ap.parse_args()
    print(f"load average before the run: {_load()}")
    data = [bundled("stamenovic2002"), bundled("fabry2001")]
    problem = get_model(MODEL).problem(data)
    direct = direct_model(paper_cell(), *data)
    _, base = baseline_fit(problem, direct)
    bench_residual(problem, direct, base.x, args.repeat)
    bench_fit(data, problem, direct, [int(s) for s in args.seeds.split(",")])
    if args.rules:
        bench_rules(data)
    if args.study:
        bench_study()
    print(f"load average after the run: {_load()}")


if __name__ == "__main__":
    main()
