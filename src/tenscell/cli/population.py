"""``tenscell synth-population``, ``fit-population`` and ``large-study``: populations and large studies on Dask."""
from __future__ import annotations

import sys
from pathlib import Path

from ._args import add_out, frequencies, integer, number, number_list
from .fit import DAMPING_MODES, TENDON_MODES
#: synthetic population generators (tenscell.population.synth.MODELS)
MODELS = ("tensegrity", "powerlaw")
#: suffix of the work directory kept beside --out while a run is under way
PARTIAL_SUFFIX = ".partial"


def add_cluster_options(p) -> None:
    """``--workers N | --scheduler ADDRESS``: where the tasks run (shared by every Dask command)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=integer(0, 4096), default=None,
                   help="local Dask workers started for this run (default: one per CPU when the work pays for starting "
                        "them, judged from the first task's time, else in this process; 0: no Dask)")
    g.add_argument("--scheduler", default=None,
                   help="an existing Dask scheduler: tcp://HOST:PORT or a scheduler file (dask scheduler "
                        "--scheduler-file F)")


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
                    "The output set (population.csv/.parquet, summary.csv, cells.jsonl, report.md, figures) "
                    "appears in --out only when every cell has a record. See docs/populations.md.")
    p.add_argument("input", help="directory, glob (quote it) or long table (.csv/.parquet)")
    add_out(p)
    add_cluster_options(p)
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run from its work directory, fitting only the missing cells")
    p.add_argument("--work-dir", default=None, help=f"where cell records are kept while running "
                   f"(default: OUT{PARTIAL_SUFFIX}; removed when the output set is written)")
    p.add_argument("--seed", type=integer(0, 2**63 - 1), default=0,
                   help="run seed (each cell's seed derives from it and its id)")
    p.add_argument("--tendons", choices=TENDON_MODES, default="per-family", help="stiffness parametrization")
    p.add_argument("--damping", choices=DAMPING_MODES, default="uniform", help="damping parametrization")
    p.add_argument("--starts", type=integer(1, 10_000), default=4, help="starts per cell")
    p.add_argument("--hops", type=integer(0, 10_000), default=1, help="basin-hopping moves per start")
    p.add_argument("--tolerance", type=number(0.0, 10.0, "decades", open_lo=True), default=0.02,
                   help="RMS log10 error (decades) counted as converged")
    p.add_argument("--truth", default=None,
                   help="generating parameters to check recovery against (default: INPUT/_generating_parameters.csv "
                        "when present)")
    p.set_defaults(func=run_fit)


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
    mc.add_argument("--spread", type=number(0.0, 1.0, open_lo=True), default=0.10,
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

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    conds = [parse_condition(c, args.model) for c in args.conditions] if args.conditions else None
    pop = synth_population(args.cells, model=args.model, conditions=conds, noise=args.noise,
                           spread_decades=args.spread, frequency_hz=args.freq, seed=args.seed)
    with out as d:
        pop.write(d)
    print(f"tenscell synth-population: {len(pop.cells)} {args.model} cells written to {out.target}/", file=sys.stderr)
    return 0


def _truth(args):
    from ..population.synth import GENERATING_FILE

    if args.truth is not None:
        if not Path(args.truth).is_file():
            raise ValueError(f"--truth {args.truth}: no such file")
        return args.truth
    guess = Path(args.input) / GENERATING_FILE
    return str(guess) if guess.is_file() else None


def run_fit(args) -> int:
    import shutil

    from ..io.outputs import OutputSet
    from ..population import _engine
    from ..population.run import PopulationFitOptions, fit_population
    from ..population.sources import read_sources

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    work = Path(args.work_dir) if args.work_dir else Path(str(out.target).rstrip("/") + PARTIAL_SUFFIX)
    if args.scheduler is not None:
        _engine.check_scheduler(args.scheduler)
    if args.resume and not work.is_dir():
        raise ValueError(f"--resume: no unfinished run in {work}")
    truth = _truth(args)
    options = PopulationFitOptions(tendons=args.tendons, damping=args.damping, starts=args.starts, hops=args.hops,
                                   tolerance=args.tolerance)
    sources = read_sources(args.input)
    try:
        result = fit_population(sources, options=options, seed=args.seed, workers=args.workers,
                                scheduler=args.scheduler, work_dir=work, resume=args.resume,
                                notify=_notifier("fit-population"))
    except KeyboardInterrupt:
        raise KeyboardInterrupt(f"tenscell fit-population: interrupted; finished cells are kept in {work}/; "
                                "run the same command with --resume to continue") from None
    with out as d:
        result.write(d, truth=truth)
    shutil.rmtree(work, ignore_errors=True)
    t = result.table
    n_ok = int((t["status"] == "ok").sum())
    print(f"tenscell fit-population: {len(t)} cells, {n_ok} fitted ({int(t['converged'].sum())} converged), "
          f"{len(t) - n_ok} failed; {result.elapsed_s:.1f} s; wrote {out.target}/", file=sys.stderr)
    return 0


def run_study(args) -> int:
    import shutil

    from ..io.outputs import OutputSet, write_json, write_text
    from ..population import _engine
    from ..population.studies import PARTS, monte_carlo_study, sweep_study
    from ..reports.population import study_markdown

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    work = Path(str(out.target).rstrip("/") + PARTIAL_SUFFIX)
    if args.scheduler is not None:
        _engine.check_scheduler(args.scheduler)
    if args.resume and not work.is_dir():
        raise ValueError(f"--resume: no unfinished study in {work}")
    where = dict(workers=args.workers, scheduler=args.scheduler, resume=args.resume, seed=args.seed,
                 notify=_notifier("large-study"))
    try:
        if args.study == "monte-carlo":
            result = monte_carlo_study(args.draws, work, spread=args.spread, parameters=args.parameters,
                                       chunk=args.chunk, keep_factors=not args.no_factors, **where)
        else:
            result = sweep_study(args.prestress, args.heterogeneity, work, f_hz=args.freq,
                                 realizations=args.realizations, **where)
    except KeyboardInterrupt:
        raise KeyboardInterrupt(f"tenscell large-study: interrupted; finished parts are kept in {work}/; "
                                "run the same command with --resume to continue") from None
    with out as d:
        (work / PARTS).rename(d / PARTS)
        shutil.copy2(work / "study.json", d / "study.json")
        write_json(d / "summary.json", result.summary)
        if result.kind == "sweep":
            med = result.medians()
            med.to_csv(d / "medians.csv", index=False)
        write_text(d / "report.md", study_markdown(result))
    shutil.rmtree(work, ignore_errors=True)
    print(f"tenscell large-study {args.study}: {result.n_rows} rows in {result.n_parts} parts; "
          f"{result.elapsed_s:.1f} s; wrote {out.target}/", file=sys.stderr)
    return 0


def _notifier(command: str):
    """One line on stderr when the engine keeps the work in this process (too small to pay for a cluster)."""
    return lambda line: print(f"tenscell {command}: {line}", file=sys.stderr, flush=True)
