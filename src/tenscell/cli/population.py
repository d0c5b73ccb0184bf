"""``tenscell synth-population``, ``fit-population`` and ``large-study``: populations and large studies on Dask."""
from __future__ import annotations

import sys
from pathlib import Path

from ._args import (add_cluster_options, add_data_options, add_out, data_options_from_args, frequencies, integer, number,
                    number_list,
                    path)
from ._cost import Cost, announce, check, measure
from .fit import DAMPING_MODES, TENDON_MODES
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
                    "The output set (population.csv/.parquet, summary.csv, cells.jsonl, report.md, figures) "
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


def reach_scheduler(address: str, timeout_s: float = 3.0, flag: str = "--scheduler") -> None:
    """ValueError unless a Dask scheduler answers at ``address`` within ``timeout_s`` (s).

    Checked before anything is created: Dask's own wait for an absent scheduler is 30 s and comes after the
    work directory exists. A Dask peer writes its handshake as soon as a connection opens (a small message:
    its size and its number of frames, each 8 bytes little-endian, lead it); a port that accepts connections but does not speak Dask
    (a proxy, another service) is refused here rather than read as a huge frame later. Only tcp:// is
    checked this way; tls:// is only connected to, other protocols are left to Dask.
    """
    import json
    import socket
    import struct

    text = str(address).strip()
    where = f"{flag} {text}"
    if Path(text).is_file():
        try:
            text = str(json.loads(Path(text).read_text())["address"])
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise ValueError(f"{where}: not a Dask scheduler file (JSON with an 'address'; {type(err).__name__})") \
                from None
        where += f" (address {text})"
    scheme, _, body = text.rpartition("://")
    if scheme not in ("", "tcp", "tls"):
        return
    host, _, port = body.rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s) as conn:
            if scheme == "tls":
                return
            head = b""
            while len(head) < 16:
                chunk = conn.recv(16 - len(head))
                if not chunk:
                    break
                head += chunk
    except (OSError, ValueError) as err:
        reason = "no answer" if isinstance(err, TimeoutError) else (getattr(err, "strerror", None) or str(err))
        raise ValueError(f"{where}: no Dask scheduler reachable within {timeout_s:g} s ({reason})") from None
    size, frames = struct.unpack("<QQ", head) if len(head) == 16 else (0, 0)
    if not (16 <= size <= 1 << 20 and 1 <= frames <= 64):
        raise ValueError(f"{where}: something answers there, but not a Dask scheduler")


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
        return run()
    except BaseException as err:
        if created and discard_empty_work(work, remove_dir=True):
            raise
        if isinstance(err, KeyboardInterrupt) and _finished(work):
            # the one line the command prints for it (tenscell.cli.main prints a KeyboardInterrupt's message)
            raise KeyboardInterrupt(f"{what}: interrupted; finished results are kept in {work}/; run the same "
                                    "command with --resume to continue") from None
        raise


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
    from ..population import _engine

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    work = _work_dir(args, out.target)
    if args.scheduler is not None:
        _engine.check_scheduler(args.scheduler)
        reach_scheduler(args.scheduler)
    if args.resume and not work.is_dir():
        raise ValueError(f"--resume: no unfinished {what} in {work}")
    return out, work


def run_fit(args) -> int:
    import shutil

    from ..population.run import PopulationFitOptions, fit_population
    from ..population.sources import read_sources

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
    with out as d:
        result.write(d, truth=truth)
    shutil.rmtree(work, ignore_errors=True)
    print(f"tenscell fit-population: {len(t)} cells, {n_ok} fitted ({int(t['converged'].sum())} converged), "
          f"{len(t) - n_ok} failed; {result.elapsed_s:.1f} s; wrote {out.target}/", file=sys.stderr)
    return 0


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
    with out as d:
        (work / PARTS).rename(d / PARTS)
        shutil.copy2(work / "study.json", d / "study.json")
        write_json(d / "summary.json", result.summary)
        if medians is not None:
            medians.to_csv(d / "medians.csv", index=False)
        write_text(d / "report.md", report)
    shutil.rmtree(work, ignore_errors=True)
    print(f"tenscell large-study {args.study}: {result.n_rows} rows in {result.n_parts} parts; "
          f"{result.elapsed_s:.1f} s; wrote {out.target}/", file=sys.stderr)
    return 0


def _notifier(command: str):
    """One line on stderr when the engine keeps the work in this process (too small to pay for a cluster)."""
    return lambda line: print(f"tenscell {command}: {line}", file=sys.stderr, flush=True)
