"""Benchmark of tenscell.fitting: Jacobians, and time to the answer against the whole command.

1. Time per Jacobian of the residuals: analytic (relaxation spectrum, all
   frequencies from a few matrix products) against finite differences on the
   same residual function, in the same run: central differences
   (2 × n_free evaluations) and scipy's default forward differences
   (``'2-point'``, n_free + 1 evaluations, what ``least_squares`` uses without
   a Jacobian), each with its largest deviation from the analytic one.
2. Time to target from a cold start, for the bundled data sets and their
   joint fit (the frequency data at 1000 Pa, per-family damping), several
   seeds. The target is the fit's own: RMS log10 error <= 0.01 on every data
   set. The shape of the final fit is printed and checked beside it:
   - frequency data (Fabry 2001): local slope of G' within 0.2 ± 0.06 on 1000
     frequencies from 0.01 to 100 Hz;
   - prestress data (Stamenović 2002): straight-line slopes of the model's
     G', G'' over 350–1900 Pa within 10 % of 0.20 and 0.05;
   - joint fit: ∂lnG'/∂lnP at 0.1 Hz (the frequency data's prestress)
     between 0.5 and 1.
   The time to target is read from the fit's history (best so far over all
   starts); the whole fit is the call to ``fit``; the whole command is
   ``python -m tenscell fit ... --jobs J`` in a new process (interpreter start,
   imports, the homogeneous baseline, report and figure included). The ratio
   whole / time to target is what the stopping rules bound (goal: <= 2):
   printed on the fit's clock (the call to ``fit``), and on the command's
   clock (launch to the moment the tolerance was first met, read from
   fit.json's "timing" plus the measured launch of python and
   ``import tenscell.cli``, against launch to exit). The command's fixed
   costs (imports ~0.5-0.7 s, baseline, report, figure) do not shrink with a
   faster search, so against the fit's own sub-second time to target the
   whole command is several times longer; that ratio is printed too.

The machine is shared: the load average is printed first, and CPU time of
this process is shown beside wall time for the in-process runs.

Run: PYTHONPATH=src python bench/bench_fit.py [--seeds 0,1,2] [--jobs 2] [--starts 4] [--skip-command]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.optimize._numdiff import approx_derivative  # what least_squares uses for jac='2-point'
from threadpoolctl import threadpool_limits

from tenscell import fitting
from tenscell.io.data import bundled

FREQUENCY_PRESTRESS_PA = 1000.0


def _time(fn, repeat):
    fn()
    t = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t) / repeat


def _cases():
    return {
        "fabry2001": ([bundled("fabry2001")], {}, ["bundled:fabry2001"]),
        "stamenovic2002": ([bundled("stamenovic2002")], {}, ["bundled:stamenovic2002"]),
        "joint": ([bundled("stamenovic2002"), bundled("fabry2001").with_prestress(FREQUENCY_PRESTRESS_PA)],
                  {"damping": "per-family"},
                  ["bundled:stamenovic2002", "bundled:fabry2001", "--prestress",
                   f"bundled:fabry2001={FREQUENCY_PRESTRESS_PA:g}", "--damping", "per-family"]),
    }


def bench_jacobian():
    print("== Jacobian of the residuals: analytic vs finite differences (one BLAS thread, as in the fit)")
    for name, (data, kw, _) in _cases().items():
        problem = fitting.make_problem(data, **kw)
        theta = problem.initial_guess(np.random.default_rng(0))
        with threadpool_limits(limits=1, user_api="blas"):
            J = problem.jacobian(theta)
            t_an = _time(lambda: problem.jacobian(theta), 200)
            t_c = _time(lambda: problem.jacobian_fd(theta), 10)
            t_f = _time(lambda: approx_derivative(problem.residuals, theta, method="2-point"), 10)
            scale = np.abs(J).max()
            e_c = np.abs(problem.jacobian_fd(theta) - J).max() / scale
            e_f = np.abs(approx_derivative(problem.residuals, theta, method="2-point") - J).max() / scale
        print(f"{name:>15}: {problem.n_residuals} residuals x {problem.n_free} parameters: analytic "
              f"{t_an * 1e3:.3f} ms; central differences {t_c * 1e3:.2f} ms ({t_c / t_an:.1f}x, max deviation "
              f"{e_c:.1e} of the largest entry); scipy '2-point' {t_f * 1e3:.2f} ms ({t_f / t_an:.1f}x, "
              f"deviation {e_f:.1e})")


def _shape_ok(name, result) -> bool:
    if name == "fabry2001":
        _, s1, _ = fitting.frequency_slopes(result, 0.01, 100.0, 1000)
        return bool(s1.min() >= 0.14 and s1.max() <= 0.26)
    if name == "stamenovic2002":
        a1, _, a2, _ = fitting.prestress_slopes(result)
        return bool(abs(a1 / 0.20 - 1) <= 0.10 and abs(a2 / 0.05 - 1) <= 0.10)
    e = fitting.prestress_activity(result).reference_storage[-1]  # the frequency data's own prestress, at 0.1 Hz
    return bool(0.5 <= e <= 1.0)


def time_to_target(name, seed, starts, jobs):
    data, kw, _ = _cases()[name]
    t0, c0 = time.perf_counter(), time.process_time()
    result = fitting.fit(data, seed=seed, starts=starts, jobs=jobs, progress=False, **kw)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return result.time_to_tolerance_s, wall, cpu, result


def launch_time(repeat: int = 5) -> float:
    """Median wall time (s) of what precedes the command's own clock: the interpreter and ``import tenscell.cli``."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import tenscell.cli"], check=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def command_time(name, seed, starts, jobs):
    """(whole command wall time in s, exit status, fit.json's "timing") of ``python -m tenscell fit`` in a new process."""
    _, _, argv = _cases()[name]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out")
        cmd = [sys.executable, "-m", "tenscell", "fit", *argv, "--seed", str(seed), "--starts", str(starts),
               "--jobs", str(jobs), "--out", out]
        t0 = time.perf_counter()
        status = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
        wall = time.perf_counter() - t0
        timing = None
        if status.returncode in (0, 1):
            with open(os.path.join(out, "fit.json")) as fh:
                timing = json.load(fh)["timing"]
        return wall, status.returncode, timing


def _shape(name, r):
    if name == "fabry2001":
        _, s1, _ = fitting.frequency_slopes(r, 0.01, 100.0, 1000)
        return f"G' slope {s1.min():.3f}..{s1.max():.3f}"
    if name == "stamenovic2002":
        a1, _, a2, _ = fitting.prestress_slopes(r)
        return f"dG'/dP {a1:.4f}, dG''/dP {a2:.4f}"
    return (f"rms per data set {', '.join(f'{f.rms_log10_error:.4f}' for f in r.fits)}; dlnG'/dlnP(0.1 Hz) "
            f"{fitting.prestress_activity(r).reference_storage[-1]:.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cases", default="fabry2001,stamenovic2002,joint")
    ap.add_argument("--skip-command", action="store_true", help="do not time the whole command")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    print(f"load average before the run: {', '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    bench_jacobian()
    launch = None if args.skip_command else launch_time()
    print(f"== time to target from a cold start ({args.starts} starts, {args.jobs} jobs)")
    if launch is not None:
        print(f"   (command clock: the command's fit.json 'timing' plus the launch, python + import tenscell.cli = "
              f"{launch:.3f} s here)")
    for name in args.cases.split(","):
        hits, ratios_fit, ratios_cmd, ratios_mixed = [], [], [], []
        for seed in seeds:
            hit, wall, cpu, r = time_to_target(name, seed, args.starts, args.jobs)
            cmd = None if args.skip_command else command_time(name, seed, args.starts, args.jobs)
            hits.append(hit)
            line = (f"{name:>15} seed {seed}: {_shape(name, r)} (shape {'ok' if _shape_ok(name, r) else 'OFF'}); "
                    f"target after "
                    f"{f'{hit:.2f} s' if hit is not None else 'NEVER'}; whole fit {wall:.1f} s (CPU here {cpu:.1f} s"
                    f"{', workers not counted' if args.jobs > 1 else ''}); stopped: {r.stop_reason}")
            if cmd is not None:
                line += f"; whole command {cmd[0]:.2f} s (exit {cmd[1]})"
            if hit:
                ratios_fit.append(wall / hit)
                line += f"; ratio fit/target {wall / hit:.2f}"
            if cmd is not None and cmd[2] is not None and cmd[2]["tolerance_met_s"] is not None:
                met = launch + cmd[2]["tolerance_met_s"]
                ratios_cmd.append(cmd[0] / met)
                ratios_mixed.append(cmd[0] / (cmd[2]["tolerance_met_s"] - cmd[2]["fit_started_s"]))
                line += (f"; command: target met {met:.2f} s after launch, ratio whole/target {cmd[0] / met:.2f} "
                         f"(fit started {launch + cmd[2]['fit_started_s']:.2f} s, outputs "
                         f"{launch + cmd[2]['outputs_started_s']:.2f} s after launch)")
            print(line, flush=True)
        ok = [h for h in hits if h is not None]
        if ok:
            text = (f"{name:>15}: target reached in {len(ok)}/{len(hits)} seeds; median {statistics.median(ok):.2f} s, "
                    f"max {max(ok):.2f} s; median ratio whole fit / target {statistics.median(ratios_fit):.2f}")
            if ratios_cmd:
                text += (f"; whole command / target on the command's clock {statistics.median(ratios_cmd):.2f} "
                         f"(against the fit's own time to target: {statistics.median(ratios_mixed):.2f})")
            print(text)
        else:
            print(f"{name:>15}: target never reached")


if __name__ == "__main__":
    main()
