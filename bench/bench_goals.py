"""Issue 35's speed goals, each as a ratio or a CPU time, with the load average beside it (``make bench``).

1. **A unimodal mechanism fit** (``springpot-tension+visc`` on the bundled pair, ``fit``'s defaults) against one
   local fit: ``scipy.optimize.least_squares`` on the model written directly in numpy, from the middle of the bounds
   (``bench_mechanism_fit.baseline_fit``). Goal ≤ 3.
2. **The recommended multimodal mechanism** (``springpot-alpha-family+visc``) against its multi-start floor: the CPU
   of the fewest starts and hops per start (a fixed budget, every start run to it, no stopping rule) that reach the
   default search's optimum for every seed measured — the cheapest search that does not stop by a rule but is told
   in advance how much to spend. The default search's mean CPU over the seeds over the floor's mean. Goal ≤ 1.6.
   The ratio of each seed's search to the point where it first held its optimum is printed too.
3. **The fit command** ``tenscell fit bundled:stamenovic2002 bundled:fabry2001 --model springpot-alpha-family+visc``
   (a new process, with its workers: CPU of the whole command) against the CPU of its fit (``fit`` in this
   process, the same options). Goal ≤ 1.5.
4. **Populations**: 100 and 1,000 synthetic Xie-like cells of ``springpot-tension+visc`` with P per cell
   (``bench_popmodel.synthetic``), the command's search (4 starts, 1 hop), one process: CPU. Goals ≤ 5 s, ≤ 45 s.
5. **make check**: its wall time (goal ≤ 60 s at a load ≤ 2).
6. With ``--all``: ``tenscell study mechanisms`` on the bundled pair (CPU, goal ≤ 40 s), ``make validate`` (CPU,
   goal ≤ 300 s; where the measured-cell data are present) and ``make test`` (CPU, goal ≤ 240 s).

The studies' estimates against their measured times are ``bench/bench_study_estimates.py``. Every time is CPU time
(``time.process_time`` in this process, ``RUSAGE_CHILDREN`` for a command and its workers) unless said; the load
average is printed with each goal: on a shared machine CPU times grow with the load (the cores' caches and
hyper-threads are shared), so compare ratios measured at one load.

    PYTHONPATH=src python bench/bench_goals.py [--all] [--seeds 0,1,2]
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))


def _load() -> str:
    return "load " + ", ".join(f"{x:.1f}" for x in os.getloadavg()) + f" on {os.cpu_count()} CPUs"


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _command(argv, env=None, **kw) -> tuple[float, float, subprocess.CompletedProcess]:
    """(CPU s of the command and its workers, wall s, the process); ``env``: its environment (default: this one's)."""
    before, t = _children_cpu(), time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, env={**(os.environ if env is None else env),
                                                                      "MPLBACKEND": "Agg", "TENSCELL_PROGRESS": "1"},
                          **kw)
    return _children_cpu() - before, time.perf_counter() - t, proc


def _data():
    from tenscell.io.data import bundled

    return [bundled("stamenovic2002"), bundled("fabry2001")]


def _fit_cpu(data, model, seed, **kw):
    from tenscell import fitting

    c = time.process_time()
    r = fitting.fit(data, model=model, seed=seed, progress=False, **kw)
    return time.process_time() - c, r


def unimodal(seeds) -> None:
    from bench_mechanism_fit import MODEL, baseline_fit, direct_model

    from tenscell.fitting.models import get_model
    from tenscell.model.shapes import paper_cell

    data = _data()
    problem = get_model(MODEL).problem(data)
    direct = direct_model(paper_cell(), *data)
    base = [baseline_fit(problem, direct)[0] for _ in range(3)]
    t_base = float(np.median(base))
    print(f"1. unimodal fit ({MODEL}) / one local fit ({t_base:.3f} s CPU, median of 3); goal <= 3; {_load()}")
    ratios = []
    for seed in seeds:
        cpu, r = _fit_cpu(data, MODEL, seed)
        ratios.append(cpu / t_base)
        print(f"   seed {seed}: {cpu:.3f} s CPU, {r.n_evaluations} evaluations, rms {r.rms_log10_error:.6f}: "
              f"ratio {cpu / t_base:.2f}; stopped: {r.stop_reason}")
    print(f"   worst ratio {max(ratios):.2f} (goal <= 3)")


def _steps(problem, seed, starts, hops):
    """Per start, each step's (CPU s, RMS) of a fixed budget: every start runs ``hops`` moves, no stopping rule."""
    import tenscell.fitting.search as search

    log: dict[int, list] = {k: [] for k in range(starts)}
    step = search._step

    def timed(pb, chain, settings, max_nfev):
        c = time.process_time()
        out = step(pb, chain, settings, max_nfev)
        log[out.start].append((time.process_time() - c, out.rms))
        return out

    search._step = timed
    try:  # a tolerance no fit reaches and an endless patience: no rule stops it before the budget
        search.run_search(problem, starts=starts, hops=hops, patience=10**6, tolerance=1e-9, seed=seed,
                          progress=False, multimodal=True)
    finally:
        search._step = step
    return log


def multimodal(seeds, starts=4, hops=6) -> None:
    from tenscell.fitting.models import get_model

    model = "springpot-alpha-family+visc"
    data = _data()
    problem = get_model(model).problem(data)
    print(f"2. multimodal fit ({model}) / its multi-start floor; goal <= 1.6; {_load()}")
    runs = {}
    for seed in seeds:
        cpu, r = _fit_cpu(data, model, seed)
        runs[seed] = (cpu, r.rms_log10_error)
        print(f"   seed {seed}: default search {cpu:.2f} s CPU, {r.n_evaluations} evaluations, rms "
              f"{r.rms_log10_error:.6f}; stopped: {r.stop_reason}")
    logs = {seed: _steps(problem, seed, starts, hops) for seed in seeds}

    def reached(seed, s, h):  # (CPU of s starts × h hops, whether one of them holds the seed's optimum)
        target = runs[seed][1] * (1 + 1e-3)
        steps = [logs[seed][k][: h + 1] for k in range(s)]
        return sum(c for st in steps for c, _ in st), any(rms <= target for st in steps for _, rms in st)

    budgets = sorted(((s, h) for s in range(1, starts + 1) for h in range(hops + 1)),
                     key=lambda b: np.mean([reached(seed, *b)[0] for seed in seeds]))
    floor = next((b for b in budgets if all(reached(seed, *b)[1] for seed in seeds)), None)
    if floor is None:
        print(f"   no budget up to {starts} starts x {hops} hops reaches every seed's optimum: no floor")
        return
    cpu_floor = float(np.mean([reached(seed, *floor)[0] for seed in seeds]))
    cpu_default = float(np.mean([runs[seed][0] for seed in seeds]))
    first = []
    for seed in seeds:  # this seed's search up to the step where it first held its optimum, in round order
        target, spent = runs[seed][1] * (1 + 1e-3), 0.0
        for h in range(hops + 1):
            done = False
            for k in range(starts):
                if h < len(logs[seed][k]):
                    spent += logs[seed][k][h][0]
                    done = logs[seed][k][h][1] <= target
                if done:
                    break
            if done:
                break
        first.append(runs[seed][0] / spent)
    print(f"   floor: {floor[0]} start(s) x {floor[1]} hop(s) reach every seed's optimum: {cpu_floor:.2f} s CPU "
          f"(mean over seeds); default search {cpu_default:.2f} s: ratio {cpu_default / cpu_floor:.2f} (goal <= 1.6)")
    print("   each seed's search over its CPU up to first holding its optimum (round order): "
          + ", ".join(f"{x:.2f}" for x in first))


def _fit_command(model, seed, env=None):
    with tempfile.TemporaryDirectory() as tmp:
        return _command([sys.executable, "-m", "tenscell", "fit", "bundled:stamenovic2002", "bundled:fabry2001",
                         "--model", model, "--seed", str(seed), "--out", os.path.join(tmp, "out")], env=env)


def command(seed=0) -> None:
    model = "springpot-alpha-family+visc"
    cpu, wall, proc = _fit_command(model, seed)
    if proc.returncode not in (0, 1):
        print(f"3. fit command: exit {proc.returncode}: {proc.stderr[-1000:]}")
        return
    fit_cpu, _ = _fit_cpu(_data(), model, seed)
    skipped = [line.split("tenscell: ", 1)[1] for line in proc.stderr.splitlines() if "not run by default" in line]
    print(f"3. tenscell fit --model {model} (whole command, its workers included) / its fit; goal <= 1.5; {_load()}")
    print(f"   command {cpu:.2f} s CPU ({wall:.1f} s wall), fit {fit_cpu:.2f} s CPU: ratio {cpu / fit_cpu:.2f}")
    for line in skipped:
        print(f"   ({line})")
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        # every process then compiles tenscell's sources as it imports them, which an installed package does not
        with tempfile.TemporaryDirectory() as cache:
            env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
            env["PYTHONPYCACHEPREFIX"] = cache
            _fit_command(model, seed, env)  # writes the bytecode
            cached, _, _ = _fit_command(model, seed, env)
        print(f"   (PYTHONDONTWRITEBYTECODE is set: each process compiles tenscell's sources; with the bytecode "
              f"cached, as installed: {cached:.2f} s CPU, ratio {cached / fit_cpu:.2f})")
    _command_breakdown(model, seed)


def _command_breakdown(model, seed) -> None:
    """Where the command's CPU goes beyond its fit: each part of it run once more in this process (the interpreter
    and the imports in a new one), in the order the command runs them. The command runs the fit in 2 worker
    processes and the baseline, the plotting import and the figures in a third; all of it with one BLAS thread."""
    from tenscell._threads import limited
    from tenscell.cli import fit as cli_fit
    from tenscell.fitting.models import baseline_of, get_model
    from tenscell.fitting.scores import compare_models

    importing, _, _ = _command([sys.executable, "-c", "import tenscell.cli.fit, tenscell.fitting"])
    parts = [("interpreter and imports (a new process)", importing)]
    spec, data = get_model(model), _data()

    def timed(label, fn):
        c = time.process_time()
        with limited():
            out = fn()
        parts.append((label, time.process_time() - c))
        return out

    result = timed("the fit (in this process)", lambda: _fit_cpu(data, spec, seed)[1])
    baseline = timed("its baseline (worker)", lambda: cli_fit._baseline_fit(data, baseline_of(spec), 2, seed, 0.01))
    timed("profile plan and estimate", lambda: cli_fit.profile_cost(result, ["EA"], 3.0))
    timed("report quantities (compute_derived)", result.compute_derived)
    timed("plotting import (worker)", cli_fit._warm_plotting)
    pngs = timed("figures: fit and residuals (worker)", lambda: cli_fit.fit_figures(result, baseline, "fit"))

    class Done:
        def result(self):
            return pngs

    timed("report.md, report.html, fit.json, fit.csv", lambda: cli_fit.fit_outputs(
        result, baseline, "fit", comparison=compare_models(result, homogeneous=baseline), figure=Done()))
    print("   breakdown (CPU s, each part again in this process): "
          + "; ".join(f"{label} {cpu:.2f}" for label, cpu in parts) + f"; {_load()}")


def populations(sizes=(100, 1000)) -> None:
    import bench_popmodel as pm

    from tenscell.fitting import Population, fit

    base, per = pm.MODELS["mechanism"]
    gen = pm._fallback("mechanism", np.random.default_rng(0))
    print(f"4. population of {base} (per cell: {', '.join(per)}), 4 starts, 1 hop, one process; goals <= 5 s (100 "
          f"cells), <= 45 s (1,000); {_load()}")
    for n in sizes:
        cells, _, _ = pm.synthetic(base, per, gen, n, seed=2)
        c = time.process_time()
        r = fit(cells, model=Population(base, per_cell=per), starts=4, hops=1, jobs=1, seed=0, progress=False,
                max_points=None)
        print(f"   {n} cells: {time.process_time() - c:.1f} s CPU, {r.n_evaluations} evaluations, rms "
              f"{r.rms_log10_error:.4f}; stopped: {r.stop_reason}")


def make_check() -> None:
    _, wall, proc = _command(["make", "-s", "check", f"PY={sys.executable}", "STAMP="], cwd=ROOT)
    print(f"5. make check: exit {proc.returncode}, {wall:.1f} s wall (goal <= 60 s at a load <= 2); {_load()}")


def heavy() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        cpu, wall, proc = _command([sys.executable, "-m", "tenscell", "study", "mechanisms", "bundled:stamenovic2002",
                                    "bundled:fabry2001", "--out", os.path.join(tmp, "m")])
    print(f"6. study mechanisms: exit {proc.returncode}, {cpu:.1f} s CPU, {wall:.0f} s wall (goal <= 40 s); {_load()}")
    if (ROOT.parent / "shared" / "data" / "real-cells").is_dir():
        cpu, wall, proc = _command(["make", "-s", "validate", f"PY={sys.executable}", "STAMP=",
                                    f"VENV={Path(sys.executable).parents[1]}"], cwd=ROOT)
        print(f"   make validate: exit {proc.returncode}, {cpu:.0f} s CPU, {wall:.0f} s wall (goal <= 300 s); "
              f"{_load()}")
    cpu, wall, proc = _command([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider"], cwd=ROOT)
    print(f"   make test: exit {proc.returncode}, {cpu:.0f} s CPU, {wall:.0f} s wall (goal <= 240 s CPU); {_load()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--all", action="store_true", help="also the study, make validate and make test (many minutes)")
    args = ap.parse_args()
    from threadpoolctl import threadpool_limits

    seeds = [int(s) for s in args.seeds.split(",")]
    with threadpool_limits(1, user_api="blas"):  # as the fits run
        unimodal(seeds)
        multimodal(seeds)
    command()
    with threadpool_limits(1, user_api="blas"):
        populations()
    make_check()
    if args.all:
        heavy()


if __name__ == "__main__":
    main()
