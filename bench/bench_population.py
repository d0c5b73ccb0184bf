"""Benchmark of the population engine: what Dask costs, and where the default runs the work, at low and high load.

Every run is a fresh interpreter (byte-code cached, as an installed package has it); its CPU is counted from
this process's ``RUSAGE_CHILDREN``, so a run's CPU includes its Dask workers' (reaped before it exits) and
excludes only what it did before the run (imports, the synthetic data). In one run, on the same synthetic
population (default 200 tensegrity cells, 4 starts and 1 hop each):

1. ``fit_population`` in this process (``workers=0``: the plain loop), on a local cluster of 1 worker and of
   2 workers (started inside the run, as a user's run does): CPU and wall. Goals (issue 29): Dask's CPU
   overhead with one worker at most 5 % over the plain loop; 1 -> 2 workers at least 1.7x in wall on a quiet
   2-core machine (the load is printed: "quiet" may not be reachable on a shared machine);
2. what a local cluster costs, measured: one worker's CPU to be ready, and the CPU an idle cluster takes
   per second in this process (scheduler, nannies) and in its worker;
3. the default (no ``workers``): the engine's decision line and its run, against the run in this process, at
   the machine's own load and at a high load made here (two busy-loop processes, printed), for the 200-cell
   fit and for an ensemble of 1,000 assignments of a distributed mechanism (3 prestresses x 61 frequencies;
   goal: it stays in this process). Goal: the default never makes a run slower than in this process;
4. ``large-study monte-carlo``: the kernel (``monte_carlo_draws``, in this process) against
   ``monte_carlo_study`` with the engine's choice and on 2 workers, in draws per second and CPU;
5. the tables of every fit run are identical (seeded per cell), and the recovery of the generating medians.

Run: python bench/bench_population.py [--cells 200] [--starts 4] [--hops 1] [--draws 20000] [--repeat 2] [--quick]
(``--quick``: 40 cells, 5000 draws, one repeat, no high-load runs.) About 10 minutes of CPU in all.
"""
from __future__ import annotations

import argparse
import contextlib
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

HERE = os.path.abspath(__file__)
ENSEMBLE = {"K": 1000, "prestress": [500.0, 1000.0, 1500.0], "freq": (-2.0, 3.0, 61)}


def _load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def child_env(cache: str) -> dict[str, str]:
    """Byte-code cached in ``cache`` for the child and its Dask workers, one BLAS thread in the main process too."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(PYTHONPYCACHEPREFIX=cache, TENSCELL_PROGRESS="0")
    return env


def run_child(env: dict[str, str], *args: str) -> dict:
    """Run this file as a child with ``args``; its JSON answer plus ``cpu_s``: its CPU (and its workers') in the run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([sys.executable, HERE, "--child", *args], capture_output=True, text=True, env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(f"child {args} failed:\n{out.stderr[-3000:]}")
    answer = json.loads(out.stdout.strip().splitlines()[-1])
    total = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    answer["cpu_s"] = total - answer.pop("cpu_before_run_s")
    return answer


# ---- the children ------------------------------------------------------------------------------------------
def _child_fit(cells: int, starts: int, hops: int, workers: str) -> dict:
    import hashlib

    from tenscell.population import PopulationFitOptions, fit_population, read_sources, synth_population

    pop = synth_population(cells, seed=0)
    srcs = list(read_sources(pop))
    options = PopulationFitOptions(starts=starts, hops=hops)
    lines: list[str] = []
    w = None if workers == "default" else int(workers)
    c0, t0 = time.process_time(), time.perf_counter()
    r = fit_population(srcs, options=options, seed=0, workers=w, progress=False, notify=lines.append)
    wall = time.perf_counter() - t0
    cols = [c for c in r.table.columns if c not in ("time_s", "source")]
    digest = hashlib.sha256(r.table[cols].sort_values("cell").to_csv(index=False).encode()).hexdigest()[:16]
    answer = {"cpu_before_run_s": c0, "main_cpu_s": time.process_time() - c0, "wall_s": wall, "workers": r.n_workers,
              "notify": lines,
              "fit_cpu_s": float(r.table["time_s"].sum()), "digest": digest}
    if workers == "2":  # the recovery of the generating distribution, from one of the runs
        from tenscell.population import recovery

        rec = recovery(r.table, pop.parameters)
        answer["recovery"] = [[row.quantity, row.generating_median, row.fitted_median, row.median_error,
                               row.error_unit, row.cell_error] for row in rec.itertuples(index=False)]
        t = r.table
        answer["fitted"] = [int((t["status"] == "ok").sum()), len(t), int(t["converged"].sum()),
                            int(t["parameters_at_bound"].str.contains("P:lower").sum())]
    return answer


def _child_ensemble(workers: str) -> dict:
    import numpy as np

    from tenscell import paper_cell
    from tenscell.fitting.fitted import FittedMechanism
    from tenscell.fitting.models.catalog import MECHANISMS
    from tenscell.population import mechanism_ensemble

    model = FittedMechanism(MECHANISMS["voigt-lognormal-damping"], paper_cell(),
                            {"EA_actin": 1.0, "EA_intermediate_filament": 0.2, "c": 0.3, "c_decades": 1.0},
                            s=1e-3, prestress_pa=tuple(ENSEMBLE["prestress"]))
    f = np.logspace(*ENSEMBLE["freq"])
    lines: list[str] = []
    w = None if workers == "default" else int(workers)
    c0, t0 = time.process_time(), time.perf_counter()
    r = mechanism_ensemble(model, f, ENSEMBLE["prestress"], K=ENSEMBLE["K"], workers=w, progress=False,
                           notify=lines.append)
    return {"cpu_before_run_s": c0, "wall_s": time.perf_counter() - t0, "workers": r.workers, "notify": lines,
            "mean": float(np.abs(r.mean).sum())}


def _child_cluster_costs() -> dict:
    """One worker's CPU to be ready; an idle 1-worker cluster's CPU per second here and in the worker."""
    import tenscell.population.run  # noqa: F401 - what this process has imported when the engine starts a cluster
    from tenscell.population import _engine
    from tenscell.population.run import _WARM

    def own_cpu() -> float:
        import resource as r
        u = r.getrusage(r.RUSAGE_SELF)
        return u.ru_utime + u.ru_stime

    c0 = time.process_time()
    import distributed  # noqa: F401

    imported = time.process_time() - c0
    c0, t0 = time.process_time(), time.perf_counter()
    with _engine.cluster(workers=1, warm=_WARM) as client:
        ready_wall, ready_main = time.perf_counter() - t0, time.process_time() - c0
        start = sum(client.run(own_cpu).values())
        c1 = time.process_time()
        time.sleep(10.0)
        idle_main = (time.process_time() - c1) / 10.0
        idle_worker = (sum(client.run(own_cpu).values()) - start) / 10.0
    return {"cpu_before_run_s": 0.0, "import_distributed_s": imported, "ready_wall_s": ready_wall,
            "ready_main_s": ready_main, "worker_start_s": start, "idle_main": idle_main, "idle_worker": idle_worker}


def _child_study(draws: int, workers: str) -> dict:
    import numpy as np

    from tenscell.model.shapes import paper_cell
    from tenscell.population.studies import monte_carlo_study
    from tenscell.sensitivity import _mc_spreads, monte_carlo_draws, monte_carlo_factors, monte_carlo_names

    params = "material"
    if workers == "kernel":
        names = monte_carlo_names(paper_cell().m, params)
        spread, alpha_spread = _mc_spreads(0.1, None, params)
        factors = monte_carlo_factors(np.random.default_rng(0), draws, len(names), spread, alpha_spread, params)
        monte_carlo_draws(factors[:50], parameters=params)  # first-use costs out of the clock
        c0, t0 = time.process_time(), time.perf_counter()
        monte_carlo_draws(factors, parameters=params)
        return {"cpu_before_run_s": c0, "wall_s": time.perf_counter() - t0, "notify": [], "workers": 0}
    lines: list[str] = []
    with tempfile.TemporaryDirectory() as d:
        c0, t0 = time.process_time(), time.perf_counter()
        monte_carlo_study(draws, f"{d}/s", parameters=params, workers=None if workers == "default" else int(workers),
                          progress=False, notify=lines.append)
        wall = time.perf_counter() - t0
    return {"cpu_before_run_s": c0, "wall_s": wall, "notify": lines}


def _child_warm() -> dict:
    """Import what the runs and their workers import, writing the byte-code cache (as an installation has it)."""
    import importlib

    for name in ("distributed", "distributed.worker", "distributed.nanny", "tenscell.population.run",
                 "tenscell.population.ensemble", "tenscell.population.studies", "tenscell.fitting",
                 "tenscell.sensitivity", "scipy.optimize", "pandas", "pyarrow.parquet"):
        importlib.import_module(name)
    return {"cpu_before_run_s": 0.0}


def child(argv: list[str]) -> None:
    kind, *rest = argv
    answer = {"warm": _child_warm,
              "fit": lambda: _child_fit(int(rest[0]), int(rest[1]), int(rest[2]), rest[3]),
              "ensemble": lambda: _child_ensemble(rest[0]),
              "costs": _child_cluster_costs,
              "study": lambda: _child_study(int(rest[0]), rest[1])}[kind]()
    print(json.dumps(answer))


# ---- the parent --------------------------------------------------------------------------------------------
@contextlib.contextmanager
def busy_loops(n: int):
    """``n`` processes spinning on a CPU each (another user's work), for the block."""
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]
    try:
        time.sleep(2.0)  # running, and seen by the load average's next samples
        yield
    finally:
        for p in procs:
            p.kill()
        for p in procs:
            p.wait()


def _verdict(ok: bool) -> str:
    return "met" if ok else "NOT met"


def _decision(run: dict) -> str:
    return run["notify"][0] if run.get("notify") else "(no decision line)"


def fits(env, args) -> dict:
    """The 200-cell fit in this process, on 1 and on 2 workers, interleaved ``args.repeat`` times; the best of each."""
    fit = ("fit", str(args.cells), str(args.starts), str(args.hops))
    print(f"== fit-population of {args.cells} synthetic tensegrity cells ({args.starts} starts, {args.hops} hop(s) "
          f"each), each run {args.repeat} times interleaved (best CPU and best wall kept: contention only adds); "
          f"load before: {_load()}", flush=True)
    labels = {"0": "in this process (workers=0)", "1": "1 Dask worker", "2": "2 Dask workers"}
    tries: dict[str, list[dict]] = {w: [] for w in labels}
    for _ in range(args.repeat):
        for w, label in labels.items():
            r = run_child(env, *fit, w)
            tries[w].append(r)
            print(f"  {label:28s} CPU {r['cpu_s']:7.2f} s (this process {r['main_cpu_s']:6.2f}, workers "
                  f"{r['cpu_s'] - r['main_cpu_s']:6.2f})   wall {r['wall_s']:7.2f} s   (load {_load()})", flush=True)
    runs = {w: {**t[0], "cpu_s": min(r["cpu_s"] for r in t), "wall_s": min(r["wall_s"] for r in t)}
            for w, t in tries.items()}
    loop, one, two = runs["0"], runs["1"], runs["2"]
    overhead = one["cpu_s"] / loop["cpu_s"] - 1.0
    print(f"  Dask CPU overhead, 1 worker, against the plain loop: {100 * overhead:+.1f} % (best {one['cpu_s']:.2f} s "
          f"against {loop['cpu_s']:.2f} s; goal <= 5 %): {_verdict(overhead <= 0.05)}")
    print(f"  Dask CPU overhead, 2 workers: {100 * (two['cpu_s'] / loop['cpu_s'] - 1):+.1f} %")
    speed = one["wall_s"] / two["wall_s"]
    print(f"  1 -> 2 workers: {speed:.2f}x wall (goal >= 1.7 on a quiet 2-core machine): {_verdict(speed >= 1.7)}; "
          f"load {_load()} on {os.cpu_count()} cores")
    same = len({r["digest"] for t in tries.values() for r in t}) == 1
    print(f"  tables identical (every run: in process, 1 worker, 2 workers): {same}")
    return runs


def costs(env) -> None:
    c = run_child(env, "costs")
    print(f"== what a local cluster costs (load {_load()})")
    print(f"  importing distributed here: {c['import_distributed_s']:.2f} s CPU; a 1-worker cluster ready in "
          f"{c['ready_wall_s']:.2f} s wall, {c['ready_main_s']:.2f} s CPU here and {c['worker_start_s']:.2f} s CPU "
          f"in the worker (the engine charges {_engine_constant('WORKER_START_CPU_S'):g} s per worker)")
    print(f"  idle cluster: {100 * c['idle_main']:.2f} % of a CPU here (scheduler, nanny), "
          f"{100 * c['idle_worker']:.2f} % in the worker")


def _engine_constant(name: str) -> float:
    from tenscell.population import _engine

    return float(getattr(_engine, name))


def _quiet_plan(tasks: int, task_cpu_s: float) -> str:
    """What :func:`tenscell.population._engine.plan` decides for this work with no CPU busy elsewhere."""
    from tenscell._parallel import CpuUse, usable_cpus
    from tenscell.population import _engine

    use = CpuUse(wall_s=0.0, cpu_s=0.0, cpus=usable_cpus(), busy_elsewhere=0.0, source="assumed")
    return _engine.plan(tasks, task_cpu_s, use).describe()


def defaults(env, args, loop_fit: dict) -> None:
    fit = ("fit", str(args.cells), str(args.starts), str(args.hops))
    loads = [("the machine's own load", 0)] + ([] if args.quick else [("high load: 2 busy loops started here", 2)])
    for label, spinners in loads:
        with busy_loops(spinners) if spinners else contextlib.nullcontext():
            print(f"== the default (no workers) at {label}; load {_load()}", flush=True)
            here = loop_fit if not spinners else run_child(env, *fit, "0")
            d = run_child(env, *fit, "default")
            print(f"  fit-population, {args.cells} cells: {_decision(d)}")
            if not spinners:
                print(f"    the same work on this machine with no other load (the engine's model, not a run): "
                      f"{_quiet_plan(args.cells - 1, here['cpu_s'] / args.cells)}")
            ratio = d["wall_s"] / here["wall_s"]
            verdict = ("met: the same path as in this process (the walls differ by the machine's load)"
                       if d["workers"] == 0 else _verdict(ratio <= 1.0))
            print(f"    default: {d['workers']} worker(s), wall {d['wall_s']:.2f} s, CPU {d['cpu_s']:.2f} s; in this "
                  f"process: wall {here['wall_s']:.2f} s, CPU {here['cpu_s']:.2f} s -> default/here {ratio:.2f}x wall "
                  f"(goal: never slower): {verdict}")
            e_here, e_def = run_child(env, "ensemble", "0"), run_child(env, "ensemble", "default")
            print(f"  ensemble of {ENSEMBLE['K']} assignments: {_decision(e_def)}")
            print(f"    default: {e_def['workers']} worker(s), wall {e_def['wall_s']:.2f} s, CPU {e_def['cpu_s']:.2f} s; "
                  f"in this process: wall {e_here['wall_s']:.2f} s, CPU {e_here['cpu_s']:.2f} s; stays in this "
                  f"process (goal): {_verdict(e_def['workers'] == 0)}")
            if not spinners:
                chunks = ENSEMBLE["K"] // 50
                print(f"    with no other load (the engine's model): {_quiet_plan(chunks - 1, e_here['cpu_s'] / chunks)}")
                e_two = run_child(env, "ensemble", "2")
                print(f"    on 2 workers (what the default avoids): wall {e_two['wall_s']:.2f} s, CPU "
                      f"{e_two['cpu_s']:.2f} s = {e_two['cpu_s'] / e_here['cpu_s']:.2f}x the CPU, "
                      f"{e_two['wall_s'] / e_here['wall_s']:.2f}x the wall of this process")
            print(f"  load after: {_load()}", flush=True)


def study(env, draws: int) -> None:
    print(f"== large-study monte-carlo, {draws} draws (material parameters); load {_load()}", flush=True)
    kernel = run_child(env, "study", str(draws), "kernel")
    rate = draws / kernel["wall_s"]
    print(f"  kernel (monte_carlo_draws, this process): {rate:7.0f} draws/s, CPU {kernel['cpu_s']:.2f} s")
    for label, w in (("engine's choice", "default"), ("2 workers", "2")):
        r = run_child(env, "study", str(draws), w)
        per = draws / r["wall_s"]
        share = f"; {per / 2 / rate:.2f}x per worker" if w == "2" else ""
        print(f"  study, {label:15s}: {per:7.0f} draws/s = {per / rate:.2f}x the kernel{share}; CPU {r['cpu_s']:.2f} s "
              f"= {r['cpu_s'] / kernel['cpu_s']:.2f}x the kernel's{'; ' + r['notify'][0] if r['notify'] else ''}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=200)
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--hops", type=int, default=1)
    ap.add_argument("--draws", type=int, default=20000, help="large-study draws")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each fit configuration, interleaved")
    ap.add_argument("--quick", action="store_true", help="40 cells, 5000 draws, no high-load runs, one repeat")
    ap.add_argument("--parts", default="fits,costs,defaults,study",
                    help="comma list of the parts to run (fits, costs, defaults, study; defaults needs fits)")
    ap.add_argument("--child", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child)
        return
    if args.quick:
        args.cells, args.draws, args.repeat = 40, 5000, 1
    print(f"bench_population: {os.cpu_count()} cores, load average {_load()} at start; CPU = user + system of the "
          "run's processes (its Dask workers included)", flush=True)
    with tempfile.TemporaryDirectory() as cache:
        env = child_env(cache)
        run_child(env, "warm")  # writes the byte-code cache
        parts = set(args.parts.split(","))
        runs = fits(env, args) if parts & {"fits", "defaults"} else {}
        if "costs" in parts:
            costs(env)
        if "defaults" in parts:
            defaults(env, args, runs["0"])
        if "study" in parts:
            study(env, args.draws)
    two = runs.get("2", {})
    if "recovery" in two:
        print("== recovery of the generating distribution (error of the fitted median; per-cell median |error|)")
        for q, gen, fitted, err, unit, per_cell in two["recovery"]:
            print(f"  {q:>28}: generating {gen:10.4g}, fitted {fitted:10.4g}, error {err:+.3f} {unit} "
                  f"(per cell {per_cell:.3f})")
        ok, n, conv, low = two["fitted"]
        print(f"  fitted {ok}/{n}, converged {conv}, prestress at its lower bound in {low}")
    print(f"load average after the run: {_load()}")


if __name__ == "__main__":
    main()
