"""``tenscell study real-cells``: its inputs checked before any fit, its cost, and its outputs.

Registered in :mod:`tenscell.cli.study` (``STUDIES["real-cells"]``); the study is
:func:`tenscell.studies.real_cells_study.real_cells_study`, its report :mod:`tenscell.reports.real_cells`.
"""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ["check_inputs", "budgets", "real_cells_cost", "write_real_cells", "EVALUATIONS_PER_START_HOP", "FILES",
           "TIME_FILES", "POPULATION_FILES", "TIME_FIT_CPU_S", "POPULATION_CPU_S"]

#: CPU seconds one mechanism's time-domain fit takes, about the mean over the two series (measured, load 5 on
#: 2 cores: springpot-lognormal-kappa+visc 75 s on the HL60 creep with 2 starts; on the oocyte shape with 4 starts
#: springpot-alpha-family+visc 35 s, maxwell+visc 11 s): the estimate of --time-domain
TIME_FIT_CPU_S = 60.0
#: CPU seconds of one population model's scores on one line (joint fit, per-cell laws, held-out frequencies,
#: 5 folds; 2 starts × 1 hop): the estimate of --populations (measured at load 3.6 on 2 cores: the mechanism 39 s
#: and 54 s, the power law + Newtonian 4 s and 9 s, on the 25 and 57 cells of the two lines)
POPULATION_CPU_S = 30.0

#: model evaluations (residuals and Jacobian) one start of a fit on one Xie spectrum takes per basin-hopping move
#: allowed, the mean over the default models (measured: 12 starts × 30 hops took 900–8900 evaluations on a median,
#: 2 cores, load 1–2); an estimate, the command prints the measured time at its end
EVALUATIONS_PER_START_HOP = 12.0
#: what the command writes
FILES = ("real_cells.md", "real_cells_medians.csv", "real_cells_g3.csv", "real_cells_cells.csv",
         "real_cells_medians.png", "real_cells_slopes.png", "validation_tables.md", "validation_heldout.png",
         "validation_slopes.png")
#: what ``--time-domain`` adds
TIME_FILES = ("real_cells_time.csv", "real_cells_time.png")
#: what ``--populations`` adds
POPULATION_FILES = ("real_cells_populations.csv", "real_cells_exponent_stiffness.csv", "validation_population.png")


def check_inputs(args) -> None:
    """Every file the study reads, read now (RealCellsMissing: exit 2, one line naming it), and the mechanisms
    named by ``--mechanisms`` known."""
    from ..studies.real_cells import XIE_LINES, RealCellsMissing, real_cells_directory, xie_cells, xie_median

    try:
        folder = real_cells_directory(args.data_dir)
        for line in XIE_LINES:
            xie_median(line, folder)
            xie_cells(line, folder)
        if args.time_domain:
            from ..studies.real_cells import hl60_creep, oocyte_relaxation

            hl60_creep(folder)
            oocyte_relaxation(folder)
    except RealCellsMissing as err:
        flag = "--data DIR" if args.data_dir is None else f"--data {args.data_dir}"
        raise RealCellsMissing(f"{flag}: {err}") from None
    if args.mechanisms is not None:
        from ..fitting.models.catalog import mechanism_names

        names = [m.strip() for m in args.mechanisms.split(",") if m.strip()]
        bad = [m for m in names if m not in mechanism_names()]
        if not names or bad:
            raise ValueError(f"--mechanisms: {'unknown mechanism ' + repr(bad[0]) if bad else 'no mechanism named'};"
                             f" known: {', '.join(mechanism_names())}")


def budgets(args):
    """``(mechanisms, median budget, per-cell budget or None, cells per line or None)`` from the flags:
    ``--starts``/``--hops`` set the medians' budget (default :data:`~tenscell.studies.real_cells_study.MEDIAN_BUDGET`),
    ``--cells 0`` skips the per-cell fits."""
    from ..studies.real_cells_study import CELL_BUDGET, DEFAULT_MECHANISMS, MEDIAN_BUDGET, Budget

    names = DEFAULT_MECHANISMS if args.mechanisms is None else \
        tuple(m.strip() for m in args.mechanisms.split(",") if m.strip())
    med = Budget(args.starts if args.starts is not None else MEDIAN_BUDGET.starts,
                 args.hops if args.hops is not None else MEDIAN_BUDGET.hops, args.seed)
    cell = None if args.cells == 0 else Budget(CELL_BUDGET.starts, CELL_BUDGET.hops, args.seed)
    return names, med, cell, (None if args.cells in (None, 0) else args.cells)


def real_cells_cost(args, jobs: int):
    """The study's cost (:class:`tenscell.cli._cost.Cost`): the CPU time of one model evaluation of each model on
    a median, timed here (:func:`tenscell.cli._cost.cpu_per_call`), × :data:`EVALUATIONS_PER_START_HOP` × starts ×
    (hops + 1) × its fits (3 per line on the medians, one per cell), over ``jobs`` workers at the CPU share the
    machine's load leaves them (:func:`tenscell.cli._cost.cpu_share`)."""
    import numpy as np

    from .._threads import limited
    from ..studies.real_cells import XIE_LINES, real_cells_directory, xie_cells, xie_median
    from ..studies.real_cells_study import BASELINES, POPULATIONS, SPLITS, median_models
    from ._cost import Cost, cpu_per_call, cpu_share

    names, med, cell, max_cells = budgets(args)
    folder = real_cells_directory(args.data_dir)
    data = xie_median(XIE_LINES[0], folder)
    n_cells = sum(len(xie_cells(ln, folder)[:max_cells]) for ln in XIE_LINES)
    per_cell_models = {*names, BASELINES[-1]}
    cpu, evaluations = 0.0, 0
    with limited():
        for spec, _, _, label in median_models(names):
            problem = spec.problem(data, None)
            theta = problem.initial_guess(np.random.default_rng(0))
            per = cpu_per_call(lambda pb=problem, th=theta: pb.jacobian(th))
            n = EVALUATIONS_PER_START_HOP * med.starts * (med.hops + 1) * (1 + len(SPLITS)) * len(XIE_LINES)
            if cell is not None and label in per_cell_models:
                n += EVALUATIONS_PER_START_HOP * cell.starts * (cell.hops + 1) * n_cells
            if args.populations and label == names[0]:  # the populations' CPU, counted once
                n += 2 * len(POPULATIONS) * POPULATION_CPU_S / per
            if args.time_domain and spec.structural:  # two series, as many evaluations as that CPU time buys
                n += 2 * TIME_FIT_CPU_S / per
            cpu += n * per
            evaluations += int(round(n))
    workers = max(1, jobs)
    share = cpu_share(workers)
    per = cpu / max(evaluations, 1)
    cells = f", {n_cells} cells × {cell.starts} × {cell.hops}" if cell is not None else ", no per-cell fits"
    if args.populations:
        cells += (f", populations: 2 lines × {len(POPULATIONS)} models × about {POPULATION_CPU_S:.0f} s of CPU each")
    if args.time_domain:
        cells += f", 2 time series × {len(names)} mechanisms at about {TIME_FIT_CPU_S:.0f} s of CPU each"
    return Cost("model evaluation", max(evaluations, 1), per / share, workers,
                detail=f"(medians: {len(median_models(names))} models × {1 + len(SPLITS)} fits × 2 lines × "
                       f"{med.starts} starts × up to {med.hops} hops{cells}; {per * 1e3:.2g} ms of CPU each, at "
                       f"{share:.0%} of a CPU per worker: load {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)")


def write_real_cells(out: Path, log, args, jobs: int) -> None:
    """Run the study (:class:`~tenscell.studies.real_cells_study.RealCellsStudy`) and write its tables, figures and
    pages into ``out``."""
    import dataclasses
    import time

    from ..studies.protocol import execute
    from ..studies.real_cells_study import RealCellsStudy, assemble_real_cells, load_average
    from ._study_output import write_study_result

    names, med, cell, max_cells = budgets(args)
    w0, load0 = time.perf_counter(), load_average()
    study = RealCellsStudy()
    plan = study.plan({"directory": args.data_dir, "mechanisms": names, "budget": med, "cell_budget": cell,
                       "max_cells": max_cells, "time_domain": args.time_domain, "populations": args.populations})
    results, records = execute(plan, jobs=jobs, rates=study.rates, notify=lambda line: log(line))
    s = assemble_real_cells(plan, results, wall_s=time.perf_counter() - w0, load=(load0, load_average()))
    result = dataclasses.replace(study.result(s), tasks=records, elapsed_s=s.wall_s)
    written = write_study_result(out, result)
    print(s.g3.text(), flush=True)
    log(f"{', '.join(written)} ({s.cpu_s:.0f} s CPU, {s.wall_s:.0f} s wall, load {s.load[0]:.1f} -> {s.load[1]:.1f})")
