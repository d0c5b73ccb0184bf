"""``tenscell synth-population``, ``fit-population`` and ``large-study``: populations and large studies on Dask."""
from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from pathlib import Path

from ._args import (add_cluster_options, add_data_options, add_out, data_options_from_args, frequencies, integer, number,
                    number_list,
                    path)
from ._cost import Cost, announce, check, measure
from .fit import DAMPING_MODES, MODEL_GROUPS, RECOMMENDED_MODEL, TENDON_MODES
#: synthetic population generators (tenscell.population.synth.MODELS)
MODELS = ("tensegrity", "powerlaw")
#: suffix of the work directory kept beside --out while a run is under way
PARTIAL_SUFFIX = ".partial"


def register(sub) -> None:
    _register_synth(sub)
    _register_fit(sub)
    _register_study(sub)


def _register_synth(sub) -> None:
    p = sub.add_parser(
        "synth-population", help="write a synthetic population of cells (known generating parameters)",
        description="Draw cells from the tensegrity model (log-normal EA per family, c, P) or from the "
                    "structural-damping power law (log-normal G0, normal exponent x), add measurement noise, and "
                    "write one CSV per cell (<condition>/<cell>.csv) and _generating_parameters.csv into --out.")
    p.add_argument("--cells", type=integer(1, 10_000_000), required=True, help="number of cells")
    add_out(p)
    p.add_argument("--model", choices=MODELS, default="tensegrity", help="generator")
    p.add_argument("--conditions", nargs="+", default=None, metavar="NAME[:PARAM=FACTOR,...]",
                   help="conditions, e.g. control histamine:P=2 (cells split evenly; factors scale the medians)")
    p.add_argument("--noise", type=number(0.0, 1.0), default=0.02, help="relative noise of G', G'' (0.02 = 2%%)")
    p.add_argument("--spread", type=number(0.0, 10.0, "decades"), default=0.2,
                   help="standard deviation of log10 of each log-normal parameter (decades)")
    p.add_argument("--freq", type=frequencies(100_000), default=None,
                   help="frequencies: a:b:n or a comma list (Hz; default 0.01:100:13)")
    p.add_argument("--seed", type=integer(0, 2**63 - 1), default=0, help="random seed")
    p.set_defaults(func=run_synth)


def _register_fit(sub) -> None:
    p = sub.add_parser(
        "fit-population", help="fit every cell of a population (Dask), write a tidy table, figures, report",
        description="Fit the tensegrity model to each cell of INPUT (a directory of per-cell CSV files, "
                    "a glob, or one long table with a 'cell' column and optionally 'condition') on a Dask "
                    "cluster: a local one by default, an existing one with --scheduler. Each cell's record is "
                    "written as it completes into OUT.partial/; an interrupted run continues with --resume. "
                    "The output set (population.csv/.parquet, summary.csv, cells.jsonl, report.md, report.html, figures) "
                    "appears in --out only when every cell has a record. See docs/populations.md.")
    p.add_argument("input", help="directory, glob (quote it) or long table (.csv/.parquet)")
    add_out(p)
    add_cluster_options(p)
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run from its work directory, fitting only the missing cells")
    p.add_argument("--work-dir", type=path("a directory"), default=None, help=f"where cell records are kept while running "
                   f"(default: OUT{PARTIAL_SUFFIX}; removed when the output set is written)")
    p.add_argument("--seed", type=integer(0, 2**63 - 1), default=0,
                   help="run seed (each cell's seed derives from it and its id)")
    p.add_argument("--tendons", choices=TENDON_MODES, default="per-family", help="stiffness parametrization")
    p.add_argument("--damping", choices=DAMPING_MODES, default="uniform", help="damping parametrization")
    p.add_argument("--starts", type=integer(1, 10_000), default=4, help="starts per cell")
    p.add_argument("--hops", type=integer(0, 10_000), default=1, help="basin-hopping moves per start")
    p.add_argument("--tolerance", type=number(0.0, 10.0, "decades", open_lo=True), default=0.02,
                   help="RMS log10 error (decades) counted as converged")
    p.add_argument("--truth", type=path("a CSV file"), default=None,
                   help="generating parameters to check recovery against (default: INPUT/_generating_parameters.csv "
                        "when present)")
    add_data_options(p)
    _add_joint_options(p)
    p.set_defaults(func=run_fit)


#: the models a joint fit takes: every model of one cell without a gauge (not the paper's Voigt cell, whose strut
#: length is one)
JOINT_MODELS = tuple(n for group, names in MODEL_GROUPS.items() if not group.startswith("the paper") for n in names)
#: the files of a joint fit's output set
JOINT_FILES = ("fit.json", "fit.csv", "cells.csv", "report.md", "fit.png", "report.html")


def _add_joint_options(p) -> None:
    g = p.add_argument_group("joint fit: every cell at once, with shared and per-cell parameters")
    g.add_argument("--joint", action="store_true",
                   help="fit one model to every cell at once: each cell has its own value of the --per-cell "
                        "parameter(s), every other parameter is shared by the population (writes fit.json, fit.csv, "
                        "cells.csv, report.md, fit.png, report.html; see docs/populations.md)")
    g.add_argument("--model", choices=JOINT_MODELS, default=None, metavar="NAME",
                   help=f"the model of one cell in a joint fit (default {RECOMMENDED_MODEL}): a mechanism or a "
                        f"structure-free formula of `tenscell fit --model` ({', '.join(JOINT_MODELS)})")
    g.add_argument("--per-cell", type=_names, default=None, metavar="NAME[,NAME]",
                   help="the model's parameter(s) each cell has its own value of, one or two (default: P, the "
                        "prestress, for a mechanism; G0, the modulus scale, for a formula)")


def _names(text: str) -> tuple:
    import argparse

    names = tuple(t.strip() for t in str(text).split(","))
    if not all(names) or len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(f"{text!r}: expected distinct parameter names separated by commas, e.g. P "
                                         "or P,kappa")
    return names


def _register_study(sub) -> None:
    p = sub.add_parser(
        "large-study", help="Monte Carlo sensitivity or parameter sweeps on Dask, streamed to Parquet",
        description="Large studies on the population engine: chunks run as Dask tasks and each chunk's rows are "
                    "written to OUT.partial/parts/ as it completes (10^5 draws never sit in memory); --resume "
                    "continues an interrupted study. The output set (parts/, study.json, summary.json, report.md) "
                    "appears in --out when every chunk is written.")
    kinds = p.add_subparsers(dest="study", metavar="STUDY")
    kinds.required = True
    mc = kinds.add_parser("monte-carlo", help="simultaneous ±spread perturbations of every parameter")
    mc.add_argument("--draws", type=integer(1, 10**9), required=True, help="number of draws")
    mc.add_argument("--spread", type=number(0.0, 1.0, open_lo=True, open_hi=True), default=0.10,
                    help="uniform ±spread of every factor (fraction < 1)")
    mc.add_argument("--parameters", choices=("all", "material"), default="all",
                    help="perturb EA_j, c_j, P and the geometry (all) or only the material parameters")
    mc.add_argument("--chunk", type=integer(1, 10**7), default=1000, help="draws per task and per Parquet part")
    mc.add_argument("--no-factors", action="store_true", help="do not store each draw's factors")
    sw = kinds.add_parser("sweep", help="prestress × heterogeneity × frequency, several realizations each")
    sw.add_argument("--prestress", type=number_list(quantity="prestress"), required=True,
                    help="prestresses P (N), comma list")
    sw.add_argument("--heterogeneity", type=number_list(0.0, 10.0, "decades"), required=True,
                    help="standard deviations of log10 EA_j (decades), comma list")
    sw.add_argument("--freq", type=frequencies(100_000), default=None,
                    help="frequencies: a:b:n or a comma list (Hz; default 0.01:1000:51)")
    sw.add_argument("--realizations", type=integer(1, 10**6), default=20, help="cells per (P, σ)")
    for q in (mc, sw):
        add_out(q)
        add_cluster_options(q)
        q.add_argument("--resume", action="store_true", help="continue an interrupted study")
        q.add_argument("--seed", type=integer(0, 2**63 - 1), default=0, help="random seed")
        q.set_defaults(func=run_study)


def run_synth(args) -> int:
    from ..io.outputs import OutputSet
    from ..population.synth import parse_condition, synth_population

    try:
        conds = [parse_condition(c, args.model) for c in args.conditions] if args.conditions else None
    except ValueError as err:
        raise ValueError(f"--conditions: {err}") from None
    names = [c.name for c in conds or ()]
    if len(set(names)) < len(names):
        raise ValueError(f"--conditions: {', '.join(sorted({n for n in names if names.count(n) > 1}))} given twice; "
                         "names must be distinct")
    if conds and len(conds) > args.cells:
        raise ValueError(f"--cells {args.cells} cannot be split over {len(conds)} --conditions "
                         f"({', '.join(c.name for c in conds)}): give at least one cell per condition")
    out = OutputSet(args.out, command=args.command_line, flag="--out")
    announce(check(_synth_cost(args, conds), "--cells", disk_at=out.target))
    pop = synth_population(args.cells, model=args.model, conditions=conds, noise=args.noise,
                           spread_decades=args.spread, frequency_hz=args.freq, seed=args.seed)
    with out as d:
        pop.write(d)
    print(f"tenscell synth-population: {len(pop.cells)} {args.model} cells written to {out.target}/", file=sys.stderr)
    return 0


#: memory of one synthetic cell held until the population is written: about 1 KiB of record and arrays plus
#: 80 B per frequency (tracemalloc peak of 2,000 cells at 13 frequencies: 2.1 KiB per cell)
_SYNTH_CELL_BYTES, _SYNTH_BYTES_PER_FREQUENCY = 1024, 80
#: disk of one cell file: a file-system block, and about 60 characters per row (three numbers)
_CELL_FILE_BYTES, _ROW_BYTES = 4096, 60


def _synth_cost(args, conds) -> Cost:
    """Time a few cells of the same population here (after one that loads the model) and scale to --cells."""
    from ..population.synth import synth_population

    kw = dict(model=args.model, conditions=conds, noise=args.noise, spread_decades=args.spread,
              frequency_hz=args.freq, seed=args.seed)
    synth_population(len(conds or ()) or 1, **kw)  # the first call loads the model's code
    k = min(args.cells, 20)
    per = measure(lambda: synth_population(max(k, len(conds or ())), **kw), max_calls=1) / max(k, len(conds or ()))
    n_freq = len(args.freq) if args.freq is not None else 13
    return Cost("cell", args.cells, per, 1,
                memory_bytes=args.cells * (_SYNTH_CELL_BYTES + n_freq * _SYNTH_BYTES_PER_FREQUENCY),
                disk_bytes=args.cells * (_CELL_FILE_BYTES + n_freq * _ROW_BYTES))


def _fit_cost(sources, options, args, work: Path) -> Cost | None:
    """One start of the first cell fitted here, scaled to the starts and to the cells still to fit.

    An upper bound: a cell's search stops once a start reaches the tolerance. None for a run of one round.
    """
    import dataclasses

    from ..population.run import cell_seed, fit_cell

    parallel = parallel_of(args)
    todo = len(sources) - (_finished(work) if args.resume else 0)  # a resumed run fits only the rest
    if todo <= (parallel or 1):
        return None
    first, one = sources[0], dataclasses.replace(options, starts=1)
    per = options.starts * measure(lambda: fit_cell(first, cell_seed(args.seed, first.cell), one), max_calls=1)
    return Cost("cell", todo, per, parallel, detail=f"(one start timed × {options.starts} starts; fewer when a "
                                                    "start reaches the tolerance)")


def _truth(args, sources):
    """The generating parameters to check recovery against, read and checked before any fit (None if none)."""
    from ..population.synth import GENERATING_FILE

    if args.truth is not None:
        path, name = Path(args.truth), f"--truth {args.truth}"
    else:
        path = Path(args.input) / GENERATING_FILE
        if not path.is_file():
            return None
        name = f"{path} (the generating parameters found beside the input; --truth)"
    if not path.is_file():
        raise ValueError(f"{name}: {'is a directory' if path.is_dir() else 'no such file'}")
    import pandas as pd

    try:
        truth = pd.read_csv(path, keep_default_na=False, na_values=[""], dtype={"cell": "str", "condition": "str"})
    except (ValueError, OSError, UnicodeDecodeError, pd.errors.ParserError) as err:
        raise ValueError(f"{name}: not a CSV table ({' '.join(str(err).split())[:200]})") from None
    if "cell" not in truth.columns:
        raise ValueError(f"{name}: no 'cell' column (columns: {', '.join(map(str, truth.columns))[:200]})")
    cells = {s.cell for s in sources}
    if not set(truth["cell"].astype(str)) & cells:
        raise ValueError(f"{name}: none of its {len(truth)} cells is among the {len(cells)} cells of {args.input}")
    return truth.fillna({"condition": ""}) if "condition" in truth.columns else truth


def _work_dir(args, out_target: Path) -> Path:
    """The work directory of a resumable run, checked before anything is created (errors name it as typed)."""
    from ..io.outputs import OutputLocationError, check_output_file

    if getattr(args, "work_dir", None):
        work, name = Path(args.work_dir), f"--work-dir {args.work_dir}"
    else:
        work = Path(str(out_target).rstrip("/") + PARTIAL_SUFFIX)
        name = f"{work} (the work directory beside --out)"
    if work.exists() and not work.is_dir():
        raise ValueError(f"{name}: exists and is not a directory")
    probe = work / "run.json"
    try:
        check_output_file(probe, name)  # the directory exists or can be created, and is writable
    except OutputLocationError as err:
        raise ValueError(f"{name}: {str(err).removeprefix(f'{name} {probe}: ')}") from None
    if not args.resume and any((work / settings).is_file() for settings, _ in _WORK_LAYOUTS):
        # refused here, before the cost is measured; the engine refuses it too (for the Python API)
        raise ValueError(f"{name}: holds an unfinished run ({_finished(work)} finished record(s)); resume it "
                         "(--resume) or remove the directory")
    return work


#: settings file and records subdirectory of each kind of work directory (population.run, population.studies)
_WORK_LAYOUTS = (("run.json", "cells"), ("study.json", "parts"))


def _finished(work: Path) -> int:
    """Records (cells or parts) a run left in its work directory."""
    return sum(1 for _, sub in _WORK_LAYOUTS for p in (work / sub).glob("*") if p.is_file()
               and not p.name.startswith(".")) if work.is_dir() else 0


def discard_empty_work(work: Path, remove_dir: bool) -> bool:
    """Remove a work directory in which nothing finished (True if it was cleared or is absent).

    Such a directory (left by a run stopped before its first record) would only make the next run ask for
    --resume. With ``remove_dir`` False (a directory the user made) it keeps existing; only the run's files go.
    A directory holding records or anything else is left alone (False).
    """
    import shutil

    if not work.is_dir():
        return True
    ours = {name for layout in _WORK_LAYOUTS for name in layout}
    if _finished(work) or any(p.name not in ours for p in work.iterdir()):
        return False
    if remove_dir:
        shutil.rmtree(work, ignore_errors=True)
    else:
        for p in work.iterdir():
            shutil.rmtree(p, ignore_errors=True) if p.is_dir() else p.unlink(missing_ok=True)
    return True


def _run_in(work: Path, what: str, run):
    """``run()`` with its work directory.

    If the run stops before its first record, a work directory it created goes again (it would only make
    the next run ask for --resume); otherwise an interrupt says where the finished records are. A directory
    found at the start is never removed here: it may belong to a run still under way (the engine refuses
    it, naming it).
    """
    created = not work.exists()
    try:
        with _resume_hint(work, what):
            return run()
    except BaseException:
        if created and discard_empty_work(work, remove_dir=True):
            raise
        raise


@contextmanager
def _resume_hint(work: Path, what: str):
    """An interrupt inside, while the work directory holds finished records (during the run, or after its last
    record while the results are written), ends with the one line that says how to continue: --resume."""
    try:
        yield
    except KeyboardInterrupt as err:
        if not _finished(work) or "--resume" in str(err):
            raise
        # the one line the command prints for it (tenscell.cli.main prints a KeyboardInterrupt's message)
        raise KeyboardInterrupt(f"{what}: interrupted; finished results are kept in {work}/; run the same "
                                "command with --resume to continue") from None


def _failed_line(table, out_target) -> str:
    """One line for a population in which no cell was fitted."""
    counts = table["status"].value_counts()
    first = table.iloc[0]
    error = " ".join(str(first.get("error", "")).split())
    return (f"none of the {len(table)} cells was fitted ({', '.join(f'{k} {v}' for k, v in counts.items())}; "
            f"first: {first['cell']}: {error[:240]}); nothing written, {out_target}/ left as it was")


def _open_run(args, what: str):
    """The output set and work directory of a population command, checked before any work: the scheduler is
    reachable (``--scheduler``) and a ``--resume`` has an unfinished ``what`` to resume."""
    from ..io.outputs import OutputSet
    from ..population import check_scheduler
    from ..population.scheduler import reach_scheduler

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    work = _work_dir(args, out.target)
    if args.scheduler is not None:
        check_scheduler(args.scheduler)
        reach_scheduler(args.scheduler)
    if args.resume and not work.is_dir():
        raise ValueError(f"--resume: no unfinished {what} in {work}")
    return out, work


def run_fit(args) -> int:
    import shutil

    from ..population.run import PopulationFitOptions, fit_population
    from ..population.sources import read_sources

    if _check_joint(args):
        return run_joint(args)
    out, work = _open_run(args, "run")
    options = PopulationFitOptions(tendons=args.tendons, damping=args.damping, starts=args.starts, hops=args.hops,
                                   tolerance=args.tolerance)
    sources = _with_column_map(read_sources(args.input), data_options_from_args(args))
    truth = _truth(args, sources)
    cost = _fit_cost(sources, options, args, work)
    if cost is not None:
        announce(check(cost, "INPUT", hint=_CLUSTER_HINT))
    result = _run_in(work, "tenscell fit-population", lambda: fit_population(
        sources, options=options, seed=args.seed, workers=args.workers, scheduler=args.scheduler, work_dir=work,
        resume=args.resume, notify=_notifier("fit-population")))
    t = result.table
    n_ok = int((t["status"] == "ok").sum())
    if n_ok == 0:
        if not (t["status"] == "worker_lost").any():  # nothing a --resume could still fit
            shutil.rmtree(work, ignore_errors=True)
        print(f"tenscell fit-population: {_failed_line(t, out.target)}", file=sys.stderr)
        return 1
    with _resume_hint(work, "tenscell fit-population"), out as d:  # every record is kept until the set is written
        result.write(d, truth=truth)
    shutil.rmtree(work, ignore_errors=True)
    print(f"tenscell fit-population: {len(t)} cells, {n_ok} fitted ({int(t['converged'].sum())} converged), "
          f"{len(t) - n_ok} failed; {result.elapsed_s:.1f} s; wrote {out.target}/", file=sys.stderr)
    return 0


def _check_joint(args) -> bool:
    """True for a joint fit (``--joint``); an option that does not apply is refused in one line, before any work."""
    if not args.joint:
        for flag, value in (("--model", args.model), ("--per-cell", args.per_cell)):
            if value is not None:
                raise ValueError(f"{flag}: an option of the joint fit: add --joint (without it each cell is fitted on "
                                 "its own, laid out by --tendons/--damping)")
        return False
    given = (("--tendons", args.tendons != "per-family"), ("--damping", args.damping != "uniform"),
             ("--resume", args.resume), ("--work-dir", args.work_dir is not None), ("--truth", args.truth is not None),
             ("--scheduler", args.scheduler is not None))
    for flag, on in given:
        if on:
            raise ValueError(f"{flag}: not an option of the joint fit (--joint: one search over every cell, in this "
                             "machine's processes; --model and --per-cell say what is fitted, --workers N runs its "
                             "starts in N processes)")
    if args.per_cell is not None and len(args.per_cell) > 2:
        raise ValueError(f"--per-cell {','.join(args.per_cell)}: one or two parameters per cell (each cell's data "
                         "must determine them beside the shared ones)")
    return True


def _joint_data(sources):
    """Every cell's moduli, read before any fit: a cell that cannot be read is refused, naming it (one line)."""
    from ..io.data import DataError, RheologyData

    conditions = sorted({s.condition for s in sources})
    if len(conditions) > 1:
        raise ValueError(f"--joint: the input holds {len(conditions)} conditions ({', '.join(map(repr, conditions))}): "
                         "a joint fit shares its parameters between the cells of one population; fit each "
                         "condition's cells on their own (INPUT/CONDITION)")
    if len(sources) < 2:
        raise ValueError(f"--joint: the input holds {len(sources)} cell; a joint fit needs two or more")
    out = []
    for src in sources:
        try:
            data = src.load()
        except DataError as err:
            raise ValueError(f"--joint: {err} (a joint fit needs every cell; remove or mend it)") from None
        if not isinstance(data, RheologyData) or data.kind != "frequency":
            raise ValueError(f"--joint: {src.source}: not a frequency sweep of G', G''; a joint fit takes one "
                             "frequency sweep per cell")
        out.append(data)
    return out


def _joint_model(args, datasets):
    """The Population of ``--model`` and ``--per-cell`` and its problem against the cells (names checked here)."""
    from ..fitting import Population, get_model

    base = get_model(args.model or RECOMMENDED_MODEL)
    per_cell = args.per_cell
    if per_cell is None:
        names = base.problem(datasets[0]).names
        per_cell = ("G0",) if "G0" in names else ("P",) if "P" in names else ("s",)
    try:
        population = Population(base, per_cell=per_cell)
        return population, population.problem(datasets)
    except ValueError as err:
        text = str(err)
        if text.startswith("per_cell"):
            raise ValueError(f"--per-cell {','.join(per_cell)}{text.removeprefix('per_cell')}") from None
        raise


#: evaluations of every cell in one start or move of a joint fit, at most: the search's run over all cells (12-54
#: in bench/bench_popmodel.py, 59 Xie cells and 200 synthetic ones), and the cells' own fit before it (at most
#: tenscell.fitting.models.population.CELL_FIT_EVALUATIONS = 25)
_EVALUATIONS_PER_RUN = 45 + 25


def _joint_cost(problem, args, jobs: int) -> Cost:
    """One evaluation of every cell's residuals and Jacobian timed here, scaled to the search's runs."""
    import numpy as np

    from .._threads import limited

    # a realistic point at no fitting cost: the base model's own start on the reference cell, shared by every cell
    ref = problem.cells[problem.reference_cell]
    phi_ref = ref.full(ref.initial_guess(np.random.default_rng(args.seed)))
    phi = problem.fixed_log.copy()
    phi[: problem.n_shared] = phi_ref[problem.base_shared]
    phi[problem.n_shared:] = np.tile(phi_ref[problem.base_own], problem.n_cells)

    def once():
        problem._jacobian_from(problem._evaluate_constrained(phi, jac=True))

    with limited():
        per = measure(once, max_calls=3)
    runs = args.starts * (1 + args.hops)
    nnz = problem.sparsity().nnz
    # memory: the Jacobian's values and indices in COO and CSR form, a few copies (about 100 bytes per nonzero)
    return Cost("evaluation", runs * _EVALUATIONS_PER_RUN, per, min(jobs, args.starts),
                memory_bytes=100.0 * nnz, detail=f"of {problem.n_cells} cells (at most; {args.starts} start(s) × "
                                                     f"{1 + args.hops} run(s))")


def run_joint(args) -> int:
    """``fit-population --joint``: one population model over every cell, written as one output set."""
    import numpy as np

    from .. import fitting
    from .._parallel import jobs_for
    from .._progress import stage
    from ..io.outputs import OutputSet, write_bytes, write_csv_rows, write_json, write_text
    from ..io.tables import fit_table
    from ..population.sources import read_sources

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    sources = _with_column_map(read_sources(args.input), data_options_from_args(args))
    datasets = _joint_data(sources)
    population, problem = _joint_model(args, datasets)
    jobs = 1 if args.workers == 0 else jobs_for(args.starts, args.workers)  # --workers 0: in this process
    cost = check(_joint_cost(problem, args, jobs), "INPUT", hint="fewer cells, --starts or --hops")
    if cost.seconds > 10:
        announce(cost)
    stage(f"joint fit of {population.name} to {problem.n_cells} cells: {problem.n_free} free parameters "
          f"({problem.n_shared} shared), {args.starts} start(s), {jobs} process(es)")
    result = fitting.fit(datasets, model=population, starts=args.starts, hops=args.hops, seed=args.seed, jobs=jobs,
                         tolerance=args.tolerance, max_points=None)
    from ..fitting.population_scores import population_cells
    from ..reports.html_page import markdown_report_html
    from ..reports.population_fit import population_fit_markdown
    from .. import plotting
    from ..plotting.population import population_fit_figure

    title = f"Joint fit of {population.name} to {problem.n_cells} cells of {Path(str(args.input).rstrip('/')).name}"
    doc = result.to_dict()
    cells = population_cells(result)
    cells.insert(1, "cell_id", [s.cell for s in sources])
    header, rows = fit_table(result, result)
    report = population_fit_markdown(result, cells, title=title)
    png = plotting.png_bytes(population_fit_figure(result, cells, title=title))
    page = markdown_report_html(report, [("Every cell's data and the joint fit (fit.png).", png)])
    with out as d:
        write_json(d / "fit.json", doc)
        write_csv_rows(d / "fit.csv", header, rows)
        write_text(d / "cells.csv", cells.to_csv(index=False))
        write_text(d / "report.md", report)
        write_bytes(d / "fit.png", png)
        write_text(d / "report.html", page)
    shared = ", ".join(f"{p.name} = {p.value:.4g}" for p in result.parameters[: problem.n_shared])
    print(f"tenscell fit-population --joint: {population.name}, {problem.n_cells} cells: rms log10 error "
          f"{result.rms_log10_error:.4f} (worst cell {float(np.max(result.dataset_rms)):.4f}; tolerance "
          f"{result.tolerance:g}): {result.verdict}; shared {shared}; {result.elapsed_s:.1f} s; wrote {out.target}/",
          file=sys.stderr)
    return 0 if result.converged else 1


def _with_column_map(sources, options: dict):
    """With --columns/--units/--step/--temperature, each cell's file read by tenscell.io.read_data in this process
    (its own headers and units; a file that cannot be read is that cell's failure, as for tenscell's layout)."""
    units = options.pop("units", None) or {}
    if not any(v is not None and v != () for v in options.values()) and not units:
        return sources
    from ..io.data import DataError, RheologyData
    from ..io.readers import read_data
    from ..population.sources import CellSource

    out = []
    for src in sources:
        if src.text is None or src.error is not None:
            out.append(src)
            continue
        if not Path(src.source).is_file():
            raise ValueError(f"--columns/--units apply to one file per cell (a directory or a glob); {src.source} "
                             "is a cell of a long table, which is read in tenscell's own columns")
        try:
            data = read_data(src.source, **options, **units)
            if not isinstance(data, RheologyData):
                raise DataError(f"{src.source}: creep data; populations fit moduli")
            out.append(CellSource(cell=src.cell, condition=src.condition, source=src.source, data=data))
        except DataError as err:
            out.append(CellSource(cell=src.cell, condition=src.condition, source=src.source, text=src.text,
                                  error=str(err).removeprefix(f"{src.source}: ")))
    return tuple(out)


def parallel_of(args) -> int | None:
    """Tasks run at once: the local workers (0: this process), None with a --scheduler (its size is its own)."""
    if getattr(args, "scheduler", None) is not None:
        return None
    if args.workers is None:
        from .._parallel import usable_cpus

        return usable_cpus()
    return max(1, args.workers)


#: what to do about a run too long for this machine, for the commands that can use a cluster
_CLUSTER_HINT = "split it, or give a --scheduler with more workers"
#: bytes per stored value (float64 columns of the Parquet parts and of the frames read back)
_VALUE_BYTES = 8


def monte_carlo_rate(parameters: str, spread: float, seed: int, k: int = 4) -> float:
    """Seconds per Monte Carlo draw of the paper cell on one thread, from ``k`` draws timed here."""
    import numpy as np
    from threadpoolctl import threadpool_limits

    from ..model.shapes import paper_cell
    from ..sensitivity import monte_carlo_draws, monte_carlo_factors, monte_carlo_names

    n = len(monte_carlo_names(paper_cell().m, parameters))
    factors = monte_carlo_factors(np.random.default_rng(seed), k, n, spread, 0.0, parameters)
    with threadpool_limits(1):  # as the chunks run
        return measure(lambda: monte_carlo_draws(factors, parameters=parameters), max_calls=3) / k


def _study_cost(args, work: Path) -> Cost:
    """The study's cost from one unit timed here: a few Monte Carlo draws, or one cell of the sweep.

    A resumed study computes only its missing parts: the time and the disk count those, the memory of the
    summary every row.
    """
    import math

    import numpy as np
    from threadpoolctl import threadpool_limits

    from ..model.shapes import paper_cell

    cell, parallel = paper_cell(), parallel_of(args)
    if args.study == "monte-carlo":
        from ..sensitivity import monte_carlo_names

        names = monte_carlo_names(cell.m, args.parameters)
        per = monte_carlo_rate(args.parameters, args.spread, args.seed, min(args.draws, 4))
        columns = 4 + (0 if args.no_factors else len(names))
        in_flight = (parallel or 1) * min(args.chunk, args.draws) * columns * _VALUE_BYTES * 3
        todo = _still_to_do(args.draws, math.ceil(args.draws / args.chunk), work, args.resume)
        # the summary reads two columns of every draw back and works on a few copies of them
        return Cost("draw", todo, per, parallel, memory_bytes=args.draws * 8 * _VALUE_BYTES + in_flight,
                    disk_bytes=todo * columns * _VALUE_BYTES)
    from ..linear.linearize import linearize
    from ..response import moduli

    f = np.asarray(args.freq if args.freq is not None else np.logspace(-2, 3, 51))
    z = np.random.default_rng(args.seed).standard_normal(cell.m)
    EA = 10.0 ** (max(args.heterogeneity) * z)
    with threadpool_limits(1):
        per = measure(lambda: moduli(linearize(cell, P=args.prestress[0], EA=EA, c=1.0), f), max_calls=5)
    pairs = len(args.prestress) * len(args.heterogeneity)
    cells = pairs * args.realizations
    todo = _still_to_do(cells, pairs, work, args.resume)
    # medians() reads five columns of every row back and groups them (about three copies)
    return Cost("cell", todo, per, parallel, memory_bytes=cells * f.size * 5 * _VALUE_BYTES * 3,
                disk_bytes=todo * f.size * 6 * _VALUE_BYTES, detail=f"of {f.size} frequencies")


def _still_to_do(units: int, parts: int, work: Path, resume: bool) -> int:
    """Units of a study of ``parts`` equal parts still to compute (all of them unless resuming)."""
    return units if not resume else max(0, units - units * min(_finished(work), parts) // parts)


def run_study(args) -> int:
    import shutil

    from ..io.outputs import write_json, write_text
    from ..population.studies import PARTS, monte_carlo_study, sweep_study
    from ..reports.population import study_markdown

    out, work = _open_run(args, "study")
    cost = _study_cost(args, work)
    flags = ("--prestress × --heterogeneity × --realizations" if args.study == "sweep" else
             "--draws, --chunk" if args.chunk > 10**5 else "--draws")  # a large chunk is held whole by each worker
    check(cost, flags, disk_at=work, hint=_CLUSTER_HINT)
    announce(cost)
    where = dict(workers=args.workers, scheduler=args.scheduler, resume=args.resume, seed=args.seed,
                 notify=_notifier("large-study"))

    def study():
        if args.study == "monte-carlo":
            return monte_carlo_study(args.draws, work, spread=args.spread, parameters=args.parameters,
                                     chunk=args.chunk, keep_factors=not args.no_factors, **where)
        return sweep_study(args.prestress, args.heterogeneity, work, f_hz=args.freq,
                           realizations=args.realizations, **where)

    result = _run_in(work, "tenscell large-study", study)
    # everything read from the parts is read before they move into the output set
    medians = result.medians() if result.kind == "sweep" else None
    report = study_markdown(result)
    with _resume_hint(work, "tenscell large-study"), out as d:
        _link_tree(work / PARTS, d / PARTS)  # linked, not moved: an interrupt here leaves the parts to --resume
        shutil.copy2(work / "study.json", d / "study.json")
        write_json(d / "summary.json", result.summary)
        if medians is not None:
            medians.to_csv(d / "medians.csv", index=False)
        write_text(d / "report.md", report)
    shutil.rmtree(work, ignore_errors=True)
    print(f"tenscell large-study {args.study}: {result.n_rows} rows in {result.n_parts} parts; "
          f"{result.elapsed_s:.1f} s; wrote {out.target}/", file=sys.stderr)
    return 0


def _link_tree(source: Path, target: Path) -> None:
    """``target`` a copy of the directory ``source`` made of hard links (copies where the file system has none)."""
    import shutil

    def link(src, dst):
        try:
            os.link(src, dst)
        except OSError:
            shutil.copy2(src, dst)

    shutil.copytree(source, target, copy_function=link)


def _notifier(command: str):
    """One line on stderr when the engine keeps the work in this process (too small to pay for a cluster)."""
    return lambda line: print(f"tenscell {command}: {line}", file=sys.stderr, flush=True)
