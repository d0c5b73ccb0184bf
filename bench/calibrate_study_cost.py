"""The constants of the studies' cost estimates: ``tenscell.fitting.search.EVALUATIONS_PER_START_HOP`` (the weight of
a fit task of `tenscell study mechanisms`) and, with ``--populations``,
``tenscell.studies.real_cells_study.POPULATION_EVALUATIONS`` (the weight of a population's scores in `tenscell study
real-cells --populations`, in evaluations of its base model on a median spectrum).

Fits every mechanism of the study to the bundled data with the study's search (4 starts, 10 hops, seed 0, one
process), counts its model evaluations (residuals and Jacobian) per start and per allowed hop, and times one
evaluation as the estimate does; prints the median over the mechanisms, the per-tendon fit's own rate, and how
far the estimate of each fit lands from its measured wall time (CPU time too: the machine may be shared).

    .venv/bin/python bench/calibrate_study_cost.py [--populations]

``--populations`` scores each population model of the study on the first 10 and on all cells of the first measured
line (its default budget; the real-cell data under ../shared/data/real-cells), times one evaluation of its base
model on that line's median as the probe does, and prints ``(fixed, per cell)`` in evaluations.
"""
from __future__ import annotations

import os
import statistics
import sys
import time

import numpy as np


def main() -> None:
    from tenscell._threads import limited
    from tenscell.cli._cost import measure
    from tenscell.fitting import get_model
    from tenscell.fitting.entry import prepare
    from tenscell.fitting.models.catalog import MECHANISMS, PER_TENDON_VOIGT
    from tenscell.fitting.models.voigt import VoigtModel
    from tenscell.io.data import bundled
    from tenscell.studies.mechanisms import PER_TENDON_HOPS, _fit

    data = (bundled("stamenovic2002"), bundled("fabry2001"))
    opts = {"starts": 4, "hops": 10, "seed": 0, "tolerance": 0.01}
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    rates = {}
    for name in (PER_TENDON_VOIGT, *MECHANISMS):
        spec = VoigtModel(tendons="per-tendon", damping="per-family") if name == PER_TENDON_VOIGT else get_model(name)
        problem = spec.problem(*prepare(data, None, 100, spec))
        theta = problem.initial_guess(np.random.default_rng(0))
        with limited():
            per = measure(lambda: problem.jacobian(theta), min_time_s=0.02, max_calls=5)
        c0, w0 = time.process_time(), time.perf_counter()
        r = _fit(data, name, opts)
        cpu, wall = time.process_time() - c0, time.perf_counter() - w0
        hops = max(opts["hops"], PER_TENDON_HOPS) if name == PER_TENDON_VOIGT else opts["hops"]
        rates[name] = r.n_evaluations / (opts["starts"] * (hops + 1))
        print(f"{name:28s} {r.n_evaluations:6d} evaluations = {rates[name]:5.1f} per start-hop; one timed "
              f"{1e3 * per:6.2f} ms; fit {wall:6.1f} s wall, {cpu:6.1f} s CPU; estimate/wall "
              f"{r.n_evaluations * per / wall:5.2f}", flush=True)
    mech = [v for k, v in rates.items() if k != PER_TENDON_VOIGT]
    print(f"EVALUATIONS_PER_START_HOP = {{'mechanism': {statistics.median(mech):.1f}, "
          f"'voigt-per-tendon': {rates[PER_TENDON_VOIGT]:.1f}}}; load average {os.getloadavg()[0]:.1f}")


def populations() -> None:
    from tenscell.fitting import get_model
    from tenscell.studies import real_cells_study as rc
    from tenscell.studies._common import PROBE_EVALUATIONS, evaluation_probe
    from tenscell.studies.real_cells import XIE_LINES, xie_cells, xie_median

    line = XIE_LINES[0]
    cells, median = xie_cells(line, None), xie_median(line, None)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs; {line}, {len(cells)} cells")
    for base, per in rc.POPULATIONS:
        evaluation_probe(get_model(base), median)
        c0 = time.process_time()
        for _ in range(5):
            evaluation_probe(get_model(base), median)
        one = (time.process_time() - c0) / (5 * PROBE_EVALUATIONS)
        cpu = []
        for n in (10, len(cells)):
            c0 = time.process_time()
            rc.population_scores(rc.population_cells(cells[:n]), line, base, per, budget=rc.POPULATION_BUDGET)
            cpu.append(time.process_time() - c0)
        slope = (cpu[1] - cpu[0]) / (len(cells) - 10) / one
        fixed = cpu[0] / one - 10 * slope
        print(f"{base:30s} 10 cells {cpu[0]:6.1f} s, {len(cells)} cells {cpu[1]:6.1f} s of CPU; one evaluation "
              f"{1e3 * one:.2f} ms: ({fixed:.0f}, {slope:.0f}) evaluations; load average {os.getloadavg()[0]:.1f}",
              flush=True)


if __name__ == "__main__":
    populations() if "--populations" in sys.argv[1:] else main()
