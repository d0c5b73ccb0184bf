"""Benchmark of populations fitted as one (tenscell.fitting.models.population; issue 27, deliver 3).

In one run:

1. **Measured cells** (when ``../shared/data/real-cells/xie2024_population`` is present): the Xie et al. cells of
   each line (59 MCF-10A, 46 MDA-MB-436, 1-200 Hz) fitted jointly by each base model (a structure-free formula
   with its modulus scale per cell, a mechanism with its prestress per cell): CPU and wall time, RMS, the shared
   parameters. With ``--scores``, each is also scored against independent per-cell power laws
   (:func:`tenscell.fitting.population_scores.score_population`: BIC, held-out frequencies, held-out cells,
   Spearman correlations).
2. **Cost per evaluation against the number of cells**: one evaluation of every cell's residuals and the sparse
   Jacobian, its nonzeros, and the floor: the base model's own problems evaluated one after the other in a plain
   loop (what any population fit must at least compute). The claim is linear growth.
3. **The goal** (issue 27): a population of 100 cells (one shared set, one parameter per cell) fits in ≤ 30 s on
   2 cores, 1,000 cells in ≤ 10× that. The cells are synthetic and Xie-like: each line's joint fit of part 1
   resampled (its shared parameters; per-cell parameters drawn with replacement from its fitted cells; Gaussian
   noise in log10 G′, G″ of the fit's own residual σ; the Xie frequencies). Without the Xie data, fixed
   generating parameters stand in (printed). Each is fitted with the command's defaults (4 starts, 1 hop) in 2
   processes: CPU time (this process and its workers) and wall time, with the load, and recovery of the
   generating parameters. Against it, in the same run: one least-squares run of the 100-cell population from the
   same start with scipy's exact (dense SVD) trust-region steps, the route a dense Jacobian would take.

Timings on a shared machine are noisy: the load average is printed before and after, CPU time beside wall time.

Run: PYTHONPATH=src python bench/bench_popmodel.py [--cells 100,1000] [--models formula,mechanism] [--scores]
(``--models mechanism-2``: the mechanism with two parameters per cell, P and kappa)
"""
from __future__ import annotations

import argparse
import math
import os
import resource
import time
from pathlib import Path

import numpy as np

from tenscell.fitting import Population, fit
from tenscell.io.data import RheologyData, read_csv

XIE = Path(__file__).resolve().parents[2] / "shared" / "data" / "real-cells" / "xie2024_population"
LINES = ("MCF-10A", "MDA-MB-436")
#: base model and its per-cell parameter, by the name the options use
MODELS = {"formula": ("structural-damping+newtonian", ("G0",)), "mechanism": ("springpot-tension+visc", ("P",)),
          "mechanism-2": ("springpot-tension+visc", ("P", "kappa"))}
F_XIE = np.array([1.0, 3.0, 10.0, 30.0, 100.0, 200.0])
#: generating parameters without the Xie data (rounded from joint fits to the MCF-10A cells); per-cell: median, sd
#: of ln
FALLBACK = {"formula": ({"alpha": 0.18, "eta": 0.31}, {"G0": (183.0, 0.45)}, 0.11),
            "mechanism": ({"EA": 134.0, "kappa": 4.65, "alpha": 0.70, "alpha_T": 0.19, "eta_cytoplasm": 1e-3},
                          {"P": (3.0, 0.6)}, 0.10),
            "mechanism-2": ({"EA": 66.5, "alpha": 0.33, "alpha_T": 0.01, "eta_cytoplasm": 0.19},
                            {"P": (3.0, 0.6), "kappa": (4.0, 0.6)}, 0.08)}


def _cpu() -> float:
    """CPU seconds of this process and of its finished children (the search's worker processes)."""
    return time.process_time() + resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime \
        + resource.getrusage(resource.RUSAGE_CHILDREN).ru_stime


def _load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def _timed(fn):
    c, t = _cpu(), time.perf_counter()
    out = fn()
    return out, _cpu() - c, time.perf_counter() - t


def _xie(line: str):
    return [read_csv(p) for p in sorted((XIE / line).glob("cell_*.csv"))]


def _generator(result, base: str, per_cell: tuple):
    """(shared values, per-cell values (n, p) to resample, residual σ in decades) of a joint fit."""
    pb = result.problem
    shared = {n: result.value(n) for n in pb.shared_names}
    own = np.array([[result.value(f"{n}[{k}]") for n in per_cell] for k in range(pb.n_cells)])
    return shared, own, float(np.sqrt(np.mean(result.residuals ** 2)))


def _fallback(kind: str, rng):
    shared, own, sigma = FALLBACK[kind]
    draws = np.exp(np.column_stack([rng.normal(math.log(m), s, 200) for m, s in own.values()]))
    return dict(shared), draws, sigma


def synthetic(base: str, per_cell: tuple, generator, n: int, seed: int):
    """``n`` Xie-like cells: the generator's shared values, per-cell values resampled with replacement, noise."""
    shared, own, sigma = generator
    rng = np.random.default_rng(seed)
    template = RheologyData(F_XIE, np.full(F_XIE.size, 100.0), np.full(F_XIE.size, 30.0), source="template")
    from tenscell.fitting import get_model

    pb = get_model(base).problem(template)
    pick = own[rng.integers(0, own.shape[0], n)]
    cells, truth = [], []
    for k in range(n):
        values = {**shared, **dict(zip(per_cell, pick[k]))}
        theta = np.log([values[name] for name in pb.names])
        P = values.get("P", 1.0)
        Gs, Gl = pb.moduli_at(theta[pb.free], F_XIE, np.full(F_XIE.size, P))
        e = 10 ** rng.normal(0.0, sigma, (2, F_XIE.size))
        cells.append(RheologyData(F_XIE, Gs * e[0], Gl * e[1], source=f"synthetic-{k:04d}"))
        truth.append(pick[k])
    return cells, shared, np.array(truth)


def per_evaluation(base: str, per_cell: tuple, generator, sizes) -> None:
    """Cost of one evaluation (residuals and sparse Jacobian) against cells, beside the plain loop over cells."""
    print(f"-- one evaluation with its Jacobian, {base} (per cell: {', '.join(per_cell)}); load {_load()}")
    print(f"{'cells':>6} {'nonzeros':>9} {'CPU ms':>8} {'ms/cell':>8} {'loop ms':>8} {'ratio':>6}")
    for n in sizes:
        cells, _, _ = synthetic(base, per_cell, generator, n, seed=1)
        pb = Population(base, per_cell=per_cell).problem(cells)
        phi = pb.full(pb.initial_guess(np.random.default_rng(0)))
        phis = pb.cell_phis(phi)
        reps = max(1, 2000 // n)

        def joint():
            out = pb._evaluate_constrained(phi, jac=True)
            pb._residuals_from(out)
            pb._jacobian_from(out)

        def loop():
            for c, p in zip(pb.cells, phis):
                out = c._evaluate_constrained(p, jac=True)
                c._residuals_from(out)
                c._jacobian_from(out)

        joint(), loop()
        c0 = time.process_time()
        for _ in range(reps):
            joint()
        t_joint = (time.process_time() - c0) / reps
        c0 = time.process_time()
        for _ in range(reps):
            loop()
        t_loop = (time.process_time() - c0) / reps
        print(f"{n:>6} {pb.sparsity().nnz:>9} {1e3 * t_joint:>8.2f} {1e3 * t_joint / n:>8.3f} {1e3 * t_loop:>8.2f} "
              f"{t_joint / t_loop:>6.2f}")


def goal(base: str, per_cell: tuple, generator, sizes, starts: int, hops: int, jobs: int) -> None:
    """The goal's fits: synthetic Xie-like populations of each size, the command's search, 2 processes."""
    print(f"-- joint fits, {base} (per cell: {', '.join(per_cell)}): {starts} starts, {hops} hop(s), {jobs} "
          f"processes; load {_load()}")
    print(f"{'cells':>6} {'CPU s':>8} {'wall s':>8} {'evals':>6} {'RMS':>7} {'noise':>7} {'worst |ln err|*':>18} "
          f"{'per-cell median |ln err|':>25}")
    first = None
    for n in sizes:
        cells, shared, truth = synthetic(base, per_cell, generator, n, seed=2)
        pop = Population(base, per_cell=per_cell)
        res, cpu, wall = _timed(lambda: fit(cells, model=pop, starts=starts, hops=hops, jobs=jobs, seed=0,
                                            progress=False, max_points=None))
        # the generating values against the fit, over the shared parameters the fit determines within ±10 %
        ident = res.identifiability()
        seen = [n for n, se in zip(ident.names, ident.standard_errors) if np.isfinite(se) and se <= 0.1]
        errs = {name: abs(math.log(res.value(name) / shared[name])) for name in seen} or {"none": math.nan}
        worst = max(errs, key=errs.get)
        own = np.array([[res.value(f"{nm}[{k}]") for nm in per_cell] for k in range(n)])
        med = float(np.median(np.abs(np.log(own / truth))))
        print(f"{n:>6} {cpu:>8.1f} {wall:>8.1f} {res.n_evaluations:>6} {res.rms_log10_error:>7.4f} "
              f"{generator[2]:>7.4f} {worst + ' ' + format(errs[worst], '.3f'):>18} {med:>25.4f}")
        first = first or (n, cpu, wall)
        if n != first[0]:
            print(f"       {n} cells / {first[0]} cells: CPU × {cpu / first[1]:.2f}, wall × {wall / first[2]:.2f}")
        if n <= 100:
            _dense_run(pop, cells)
    print("       * over the shared parameters the fit determines within ±10 % (the others: not determined by these "
          "data, e.g. a Newtonian term too small to see below 200 Hz)")


def _dense_run(pop, cells) -> None:
    """One least-squares run of the same problem from the same start: sparse LSMR steps against exact dense ones."""
    import scipy.optimize

    from tenscell.fitting.search import local_fit

    pb = pop.problem(cells)
    theta0 = pb.initial_guess(np.random.default_rng(0))
    (th, res, nfev), cpu_s, _ = _timed(lambda: local_fit(pb, theta0, 200))
    lo, hi = pb.bounds
    dense, cpu_d, _ = _timed(lambda: scipy.optimize.least_squares(
        pb.residuals, theta0, jac=pb.jacobian, bounds=(lo, hi), method="trf", x_scale="jac", max_nfev=200,
        xtol=1e-10, ftol=1e-10, gtol=1e-10))
    print(f"       one least-squares run, {pb.n_cells} cells: sparse (LSMR) {cpu_s:.2f} s CPU, {nfev} evaluations, "
          f"RMS {pb.rms(th):.5f}; dense (exact SVD steps) {cpu_d:.2f} s, {dense.nfev} evaluations, RMS "
          f"{pb.rms(dense.x):.5f}: × {cpu_d / cpu_s:.1f}")


def measured(models, scores: bool, starts: int, hops: int, jobs: int) -> dict:
    """Part 1: every line with every model; returns the generators of part 3 (per model, the first line's fit)."""
    generators: dict = {}
    if not XIE.is_dir():
        print(f"-- measured cells: skipped ({XIE} is absent: the Xie et al. data are not beside the repository)")
        return generators
    from tenscell.fitting.population_scores import comment_values, score_population

    for line in LINES:
        cells = _xie(line)
        for kind in models:
            base, per_cell = MODELS[kind]
            pop = Population(base, per_cell=per_cell)
            res, cpu, wall = _timed(lambda: fit(cells, model=pop, starts=starts, hops=hops, jobs=jobs, seed=0,
                                                progress=False, max_points=None))
            shared = ", ".join(f"{n} = {res.value(n):.4g}" for n in res.problem.shared_names)
            print(f"-- {line}, {len(cells)} cells, {pop.name}: {cpu:.1f} s CPU, {wall:.1f} s wall (load {_load()}); "
                  f"RMS {res.rms_log10_error:.4f}, {res.n_evaluations} evaluations; {shared}")
            generators.setdefault(kind, _generator(res, base, per_cell))
            if scores:
                cov = {k: [comment_values(d)[k] for d in cells] for k in ("aspect_ratio", "area", "hertz_E_Pa")}
                sc, cpu, wall = _timed(lambda: score_population(cells, pop, covariates=cov, label=line, starts=starts,
                                                                hops=hops, progress=False))
                print(f"   scores ({cpu:.0f} s CPU, {wall:.0f} s wall):")
                print("\n".join("   " + line_ for line_ in repr(sc).splitlines()[1:]))
                for n in sc.notes:
                    print(f"   - {n}")
    return generators


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", default="100,1000", help="population sizes of the goal (comma list)")
    ap.add_argument("--models", default="formula,mechanism", help="formula, mechanism, mechanism-2 (comma list)")
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--hops", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--scores", action="store_true", help="score each line's fits (many more fits)")
    ap.add_argument("--skip-measured", action="store_true")
    args = ap.parse_args()
    sizes = [int(x) for x in args.cells.split(",")]
    models = [m.strip() for m in args.models.split(",")]
    print(f"load average before the run: {_load()} on {os.cpu_count()} cores")
    gens = {} if args.skip_measured else measured(models, args.scores, args.starts, args.hops, args.jobs)
    rng = np.random.default_rng(0)
    for kind in models:
        base, per_cell = MODELS[kind]
        gen = gens.get(kind) or _fallback(kind, rng)
        where = "resampled from the MCF-10A joint fit" if kind in gens else "fixed (no Xie data)"
        print(f"== {kind}: {base}, per cell {', '.join(per_cell)}; generator {where}: "
              + ", ".join(f"{k} = {v:.4g}" for k, v in gen[0].items()) + f"; noise {gen[2]:.3f} decades")
        per_evaluation(base, per_cell, gen, [10, 100, 1000])
        goal(base, per_cell, gen, sizes, args.starts, args.hops, args.jobs)
    print(f"load average after the run: {_load()}")


if __name__ == "__main__":
    main()
