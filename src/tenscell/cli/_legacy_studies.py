"""The two studies of ``tenscell study`` whose flags the table of :mod:`tenscell.cli.study` does not yet map:
``mechanisms`` and ``real-cells``.

Both studies are on the study protocol (:class:`tenscell.studies.mechanisms.MechanismsStudy`,
:class:`tenscell.studies.real_cells_study.RealCellsStudy`: their plans, tasks, assembly, tables, figures, pages and
checks); what stays here is the command line's side of them — their flags translated into the studies' options
(budgets, the ensemble's K), their estimates (a model evaluation timed per model) and the refusal of a run beyond a
day — until the studies declare those themselves.
"""
from __future__ import annotations

import os
import time
from pathlib import Path

#: assignments of the study's ensemble unless --ensemble says otherwise (tenscell.population.ensemble.DEFAULT_K)
STUDY_ENSEMBLE_K = 1000

#: the options each of these studies takes (dest -> default when not given), as the protocol's studies declare theirs
LEGACY_OPTIONS: dict[str, dict] = {
    "mechanisms": {"data": (), "seed": 0, "starts": 4, "jobs": None, "tolerance": 0.01, "mechanisms": None,
                   "hops": 10, "ensemble": None, "workers": None, "scheduler": None},
    "real-cells": {"seed": 0, "starts": None, "jobs": None, "mechanisms": None, "hops": None, "data_dir": None,
                   "cells": None, "time_domain": False, "populations": False},
}


def _study_mechanisms(out: Path, log, args=None) -> None:
    """Run the mechanisms study (:class:`~tenscell.studies.mechanisms.MechanismsStudy`: its plan, tasks and
    assembly) and write its tables, figures and page, with the ensemble when one was evaluated."""
    import dataclasses

    from .._parallel import jobs_for
    from ..studies.mechanisms import MechanismsStudy, assemble_study
    from ..studies.protocol import execute
    from ._study_output import write_study_result

    datasets = args.datasets  # read and checked before the study began (run_legacy)
    names = _study_models(args)
    K = STUDY_ENSEMBLE_K if args.ensemble is None else args.ensemble
    study = MechanismsStudy()
    plan = study.plan({"datasets": datasets, "mechanisms": names, "starts": args.starts, "hops": args.hops,
                       "seed": args.seed, "tolerance": args.tolerance, "ensemble": K or None,
                       "workers": args.workers, "scheduler": args.scheduler})
    jobs = jobs_for(len(plan.tasks), args.jobs)
    plan.options["jobs"] = jobs
    t0 = time.monotonic()
    results, records = execute(plan, jobs=jobs, rates=study.rates, notify=lambda line: log(line))
    s = assemble_study(plan, results, elapsed_s=time.monotonic() - t0)
    result = dataclasses.replace(study.result(s), tasks=records, elapsed_s=s.elapsed_s)
    written = write_study_result(out, result)
    print(result.summary, flush=True)
    if s.ensemble is not None:
        from .fit import ENSEMBLE_FILES, write_ensemble

        write_ensemble(out, s.ensemble, f"Ensemble of `{s.ensemble.mechanism}`, the distributed mechanism with the "
                                        "lowest BIC")
        written += list(ENSEMBLE_FILES)
    elif K:
        log("no ensemble: none of the mechanisms fitted draws a tendon property from a distribution")
    log(", ".join(written) + f" ({result.cpu_s:.0f} s of CPU in {len(records)} tasks)")


#: model evaluations per start and basin-hopping move, shared with `tenscell fit`'s estimate (defined in _cost)
from ._cost import EVALUATIONS_PER_START_HOP, cpu_per_call, cpu_share  # noqa: E402


def mechanisms_cost(datasets, names, starts: int, hops: int, jobs: int, validate: bool = True,
                    falsify: bool = True):
    """The mechanisms study's cost (:class:`tenscell.cli._cost.Cost`): the CPU time of one model evaluation of each
    model, timed here at a start of its fit with the BLAS threads the search uses, × the evaluations its fits are
    expected to take (:data:`EVALUATIONS_PER_START_HOP` × starts × hops for the main fit, and the same for each
    referee's refit that :func:`~tenscell.studies.mechanisms.fits_per_model` counts: refits run to the main fit's
    standard), over ``jobs`` workers at the CPU share the machine's load leaves them (:func:`cpu_share`). An upper
    bound: a model that misses the data in sample is not refereed, and a warm refit often stops sooner."""
    import numpy as np

    from .._threads import limited
    from ..fitting import get_model
    from ..fitting.entry import prepare
    from ..fitting.models.catalog import PER_TENDON_VOIGT
    from ..fitting.models.voigt import VoigtModel
    from ..studies.mechanisms import PER_TENDON_HOPS, fits_per_model
    from ._cost import Cost

    cpu, evaluations, fits = 0.0, 0, 0
    refit = starts * (hops + 1)
    with limited():
        for name in names:
            per_tendon = name == PER_TENDON_VOIGT
            spec = VoigtModel(tendons="per-tendon", damping="per-family") if per_tendon else get_model(name)
            problem = spec.problem(*prepare(datasets, None, 100, spec))
            theta = problem.initial_guess(np.random.default_rng(0))
            rate = EVALUATIONS_PER_START_HOP["voigt-per-tendon" if per_tendon else "mechanism"]
            k = fits_per_model(datasets, problem.n_free, spec.structural, validate, falsify)
            main = starts * ((max(hops, PER_TENDON_HOPS) if per_tendon else hops) + 1)
            n = int(round(rate * (main + (k - 1) * refit)))
            cpu += n * cpu_per_call(lambda pb=problem, th=theta: pb.jacobian(th))
            evaluations += n
            fits += k
    workers = min(jobs, len(names))
    share = cpu_share(workers)
    per = cpu / max(evaluations, 1)
    return Cost("model evaluation", max(evaluations, 1), per / share, workers,
                detail=f"({len(names)} model(s), {fits} fits: each model × {starts} start(s) × up to {hops} hop(s),"
                       f" its held-out, anchored and unlike refits to the same budget; {per * 1e3:.2g} ms of CPU each,"
                       f" at {share:.0%} of a CPU per worker: load "
                       f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)")


def _study_real_cells(out: Path, log, args=None) -> None:
    from .._parallel import jobs_for
    from ._real_cells import write_real_cells

    write_real_cells(out, log, args, jobs_for(len(args.real_cells_models), args.jobs))


def _check_ensemble_options(args) -> None:
    """--ensemble 1 (no spread) and --workers/--scheduler without an ensemble are refused before any fit."""
    if args.ensemble == 1:
        raise ValueError("--ensemble: 1 assignment has no spread between assignments; give K >= 2, or 0 for none")
    if args.ensemble == 0 and (args.workers is not None or args.scheduler is not None):
        raise ValueError(f"{'--workers' if args.workers is not None else '--scheduler'} applies to the study's "
                         "ensemble, and --ensemble 0 has none")
    if args.scheduler is not None:
        from .population import reach_scheduler

        reach_scheduler(args.scheduler)


def _announce_mechanisms_cost(args) -> None:
    """The mechanisms study's estimate as one line before its fits; refused beyond a day (naming the flags)."""
    from .._parallel import jobs_for
    from ._cost import announce, check

    names = _study_models(args)
    cost = mechanisms_cost(args.datasets, names, args.starts, args.hops, jobs_for(len(names), args.jobs))
    announce(check(cost, "--starts", hint="give fewer --starts or --hops, or fewer --mechanisms NAMES"))


def _study_models(args) -> tuple[str, ...]:
    """The models of the mechanisms study: ``--mechanisms NAMES`` or its default set."""
    from ..studies.mechanisms import default_models

    if args.mechanisms is None:
        return default_models(args.datasets)
    return tuple(m.strip() for m in args.mechanisms.split(",") if m.strip())


def _check_mechanisms_options(args) -> None:
    if args.mechanisms is not None:
        from ..fitting.models.catalog import mechanism_names

        if not [m for m in args.mechanisms.split(",") if m.strip()]:
            raise ValueError(f"--mechanisms {args.mechanisms!r}: no mechanism named; give a comma list of names "
                             f"({', '.join(mechanism_names())}), or leave the flag out for all of them")
        bad = [m for m in args.mechanisms.split(",") if m.strip() and m.strip() not in mechanism_names()]
        if bad:
            raise ValueError(f"--mechanisms: unknown mechanism {bad[0]!r}; known: {', '.join(mechanism_names())}")
    _check_ensemble_options(args)


def run_legacy(args, read_data) -> int:
    """``tenscell study mechanisms|real-cells`` as before the protocol (flags already checked to be the study's;
    ``read_data(args)``: the data files read and checked, for mechanisms, once its options are)."""
    import sys

    from .._parallel import jobs_for
    from .._progress import stage
    from ..io.outputs import OutputSet
    from ._cost import announce, check

    for dest, default in LEGACY_OPTIONS[args.name].items():
        if dest != "data" and getattr(args, dest) is None:
            setattr(args, dest, default)
    if args.name == "mechanisms":
        _check_mechanisms_options(args)
        args.datasets = read_data(args)
    else:
        from ._real_cells import budgets, check_inputs

        check_inputs(args)  # every file read before the output folder is made and before any fit
        args.real_cells_models = budgets(args)[0]
    out = OutputSet(args.out or f"study-{args.name}", command=args.command_line, flag="--out")
    if args.name == "mechanisms":
        _announce_mechanisms_cost(args)
    else:
        from ._real_cells import real_cells_cost

        announce(check(real_cells_cost(args, jobs_for(len(args.real_cells_models), args.jobs)), "--starts",
                       hint="give fewer --starts or --hops, --cells N, or fewer --mechanisms NAMES"))
    t = time.perf_counter()
    stage(f"study {args.name} ...")
    with out as d:
        (_study_mechanisms if args.name == "mechanisms" else _study_real_cells)(
            d, lambda msg: stage(f"    computed {msg}"), args)
    print(f"tenscell: study {args.name} finished in {time.perf_counter() - t:.1f} s; wrote {out.target}/",
          file=sys.stderr)
    return 0
