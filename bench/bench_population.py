"""Benchmark of population fits on Dask (tenscell.population).

In one run, on the same synthetic population (default 200 tensegrity cells):

1. the floor: every cell fitted by ``fit_cell`` in a plain loop in this process
   (no Dask), giving the time of one fit;
2. ``fit_population`` on a local cluster of 1 worker and of 2 workers (one
   thread each; the cluster is started before the clock starts, the run
   includes listing, submitting, gathering and assembling the table):
   cells per minute, the speed-up from 1 to 2 workers (goal ≥ 1.7×) and the
   Dask overhead per cell against the loop, (t_1 worker − t_loop) / cells as a
   fraction of one fit (goal ≤ 5 %), and the share of the run's wall time the
   workers spent inside fits (Σ per-cell fit time / (workers × wall time)):
   on a machine shared with other work, where every fit is slowed alike, this
   share still shows what Dask itself costs;
3. peak resident memory of each worker process (ru_maxrss), and the CPU the
   main process (Dask's scheduler, client and nannies live there) spent per
   second of the run: what the scheduler takes from the cores the fits need;
4. recovery of the generating distribution: per parameter, the error of the
   fitted median in decades;
5. ``large-study monte-carlo``: the kernel (``monte_carlo_draws`` on the same
   draws, in this process) against ``monte_carlo_study`` with the engine's own
   choice and with 2 workers, in draws per second (goal ≥ 80 % of the kernel's
   rate per worker).

All three tables are checked to be identical (seeded per cell). Timings on a
shared machine are noisy: the load average is printed before and after.

Run: PYTHONPATH=src python bench/bench_population.py [--cells 200] [--starts 4] [--hops 1] [--draws 20000]
"""
from __future__ import annotations

import argparse
import os
import time


def _peak_rss_mb() -> float:
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: kB


def _timed_run(srcs, options, workers: int):
    from tenscell.population import _engine, fit_population
    from tenscell.population.run import _WARM

    with _engine.cluster(workers=workers, warm=_WARM) as client:
        t, cpu = time.perf_counter(), time.process_time()
        result = fit_population(list(srcs), options=options, seed=0, client=client, progress=False)
        elapsed, cpu = time.perf_counter() - t, time.process_time() - cpu
        rss = sorted(client.run(_peak_rss_mb).values())
    return result, elapsed, rss, cpu


def _large_study(draws: int) -> None:
    import shutil
    import tempfile

    import numpy as np

    from tenscell.model.shapes import paper_cell
    from tenscell.population.studies import monte_carlo_study
    from tenscell.sensitivity import _mc_spreads, monte_carlo_draws, monte_carlo_factors, monte_carlo_names

    params = "material"
    names = monte_carlo_names(paper_cell().m, params)
    spread, alpha_spread = _mc_spreads(0.1, None, params)
    factors = monte_carlo_factors(np.random.default_rng(0), draws, len(names), spread, alpha_spread, params)
    monte_carlo_draws(factors[:50], parameters=params)  # warm the kernel, and the study's own imports (pyarrow)
    with tempfile.TemporaryDirectory() as d:
        monte_carlo_study(10, f"{d}/warm", parameters=params, workers=0, progress=False)
    t = time.perf_counter()
    monte_carlo_draws(factors, parameters=params)
    kernel = draws / (time.perf_counter() - t)
    print(f"== large-study monte-carlo, {draws} draws ({params} parameters); load {os.getloadavg()[0]:.2f}")
    print(f"kernel (monte_carlo_draws, this process): {kernel:7.0f} draws/s")
    for label, workers in (("engine's choice", None), ("2 workers", 2)):
        d = tempfile.mkdtemp()
        try:
            lines: list[str] = []
            t = time.perf_counter()
            monte_carlo_study(draws, f"{d}/s", parameters=params, workers=workers, progress=False,
                              notify=lines.append)
            rate = draws / (time.perf_counter() - t)
        finally:
            shutil.rmtree(d, ignore_errors=True)
        share = f"; {rate / workers / kernel:.2f} x per worker" if workers else ""
        print(f"study, {label:15}:         {rate:7.0f} draws/s = {rate / kernel:.2f} x the kernel (goal >= 0.80)"
              f"{share}{'; ' + lines[0] if lines else ''}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=200)
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--hops", type=int, default=1)
    ap.add_argument("--draws", type=int, default=30000, help="large-study draws")
    args = ap.parse_args()
    os.environ.setdefault("TENSCELL_PROGRESS", "0")

    from threadpoolctl import threadpool_limits

    from tenscell.population import PopulationFitOptions, cell_seed, fit_cell, read_sources, recovery, synth_population

    print(f"load average before the run: {', '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    pop = synth_population(args.cells, seed=0)
    srcs = read_sources(pop)
    options = PopulationFitOptions(starts=args.starts, hops=args.hops)
    print(f"== {args.cells} synthetic tensegrity cells; per cell: tendons {options.tendons}, {options.starts} starts, "
          f"{options.hops} hop(s)")

    t = time.perf_counter()
    with threadpool_limits(1):
        loop = [fit_cell(s, cell_seed(0, s.cell), options) for s in srcs]
    t_loop = time.perf_counter() - t
    per_fit = t_loop / args.cells
    print(f"in-process loop (floor):  {t_loop:7.2f} s, {60 / per_fit:7.1f} cells/min, {1000 * per_fit:.0f} ms per fit")

    runs = {}
    for w in (1, 2):
        result, elapsed, rss, cpu = _timed_run(srcs, options, w)
        runs[w] = (result, elapsed)
        busy = result.table["time_s"].sum() / (w * elapsed)
        print(f"Dask, {w} worker(s):       {elapsed:7.2f} s, {60 * args.cells / elapsed:7.1f} cells/min; "
              f"workers busy fitting {100 * busy:.1f}% of the time (overhead {100 * (1 - busy):.1f}%, goal <= 5%); "
              f"main process (scheduler) CPU {100 * cpu / elapsed:.0f}% of a core; "
              f"peak RSS per worker {', '.join(f'{r:.0f}' for r in rss)} MB")

    (r1, t1), (r2, t2) = runs[1], runs[2]
    overhead = (t1 - t_loop) / args.cells
    print(f"speed-up 1 -> 2 workers:  {t1 / t2:.2f}x (goal >= 1.7)")
    print(f"Dask overhead per cell:   {1000 * overhead:+.1f} ms = {100 * overhead / per_fit:+.1f}% of a fit "
          "(goal <= 5%)")

    cols = [c for c in r1.table.columns if c not in ("time_s", "source")]
    same = r1.table[cols].equals(r2.table[cols]) and all(
        a.get("rms_log10_error") == b["rms_log10_error"] for a, b in zip(loop, r1.records))
    print(f"tables identical (loop, 1 worker, 2 workers): {same}")

    rec = recovery(r2.table, pop.parameters)
    print("== recovery of the generating distribution (error of the fitted median; per-cell median |error|)")
    for row in rec.itertuples(index=False):
        print(f"  {row.quantity:>28}: generating {row.generating_median:10.4g}, fitted {row.fitted_median:10.4g}, "
              f"error {row.median_error:+.3f} {row.error_unit} (per cell {row.cell_error:.3f})")
    t = r2.table
    print(f"fitted {int((t['status'] == 'ok').sum())}/{len(t)}, converged {int(t['converged'].sum())}, "
          f"prestress at its lower bound in {int(t['parameters_at_bound'].str.contains('P:lower').sum())}")
    _large_study(args.draws)
    print(f"load average after the run: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
