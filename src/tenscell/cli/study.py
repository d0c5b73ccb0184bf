"""``tenscell study NAME``: a table of studies (name → where its study object lives) and one writer for all.

Each study follows the study protocol (:mod:`tenscell.studies.protocol`): the flags the user typed go to its
``plan(options)``, which checks them (one line naming the flag, before any work) and lists its tasks; the
estimate comes from the plan (its calibration, measured here, and the CPU share the machine gives now) and is
announced before the work and revised as tasks finish; every table becomes ``{name}.csv`` with its named columns,
every figure is drawn through its plotter and saved, every page written — as one output set, complete or not at
all. Adding a study is one line of :data:`STUDIES` (its flags, when new, go into :func:`register`).

Building the parser imports only the standard library: a study's module is imported when it runs.
"""
from __future__ import annotations

import importlib
import sys
import time

from ._args import (add_cluster_options, add_data_options, add_out, data_options_from_args, ensemble_size, integer,
                    number, number_list, path)
from .fit import stated_prestress

#: the studies of `tenscell study NAME`: name -> "module:attribute" of its study object (tenscell.studies.protocol)
STUDIES = {
    "no-if": "tenscell.studies.no_if:STUDY",
    "sensitivity": "tenscell.studies.sensitivity:STUDY",
    "references": "tenscell.studies.references:STUDY",
    "semiflexible": "tenscell.studies.semiflexible:STUDY",
    "stiffening": "tenscell.studies.stiffening:STUDY",
    "compactness": "tenscell.studies.compactness:STUDY",
    "powerlaw": "tenscell.studies.powerlaw:STUDY",
    "structures": "tenscell.studies.structures:STUDY",
    "mechanisms": "tenscell.studies.mechanisms:STUDY",
    "real-cells": "tenscell.studies.real_cells_study:STUDY",
}
#: assignments of the mechanisms study's ensemble unless --ensemble says otherwise
#: (tenscell.population.ensemble.DEFAULT_K; the parser imports only the standard library)
STUDY_ENSEMBLE_K = 1000
#: the paper's variant studies, which `tenscell reproduce` runs (the others fit data)
VARIANTS = ("no-if", "sensitivity", "references", "semiflexible", "stiffening")
#: the default of --decades (compactness)
_DECADES = tuple(float(d) for d in range(1, 15))
#: the flags of the studies (dests): what `run` passes to a study when typed (their defaults filled by register())
STUDY_FLAGS = ("draws", "seed", "from_fit", "decades", "damping", "starts", "jobs", "tolerance", "mechanisms", "hops",
               "ensemble", "workers", "scheduler", "data_dir", "cells", "time_domain", "populations", "prestress",
               "scale")
_DEFAULTS: dict[str, object] = {}


def load_study(name: str):
    """The study object of ``tenscell study NAME`` (its module imported now)."""
    module, attribute = STUDIES[name].split(":")
    return getattr(importlib.import_module(module), attribute)


def register(sub) -> None:
    p = sub.add_parser("study", help="run one of the discussion's variant studies (figures, CSV, markdown)",
                       description="Studies of the paper's discussion and future work: no-if (no intermediate "
                                   "filaments, the G'' peak), sensitivity (elasticities, ±10% table, Monte Carlo), "
                                   "references (valid q0(α, δ), regular and cylindrical cells), semiflexible (elastic "
                                   "struts), stiffening (strain-stiffening IFs); compactness DATA... (how narrow the "
                                   "distribution of tendon stiffnesses can be and still fit the data: best RMS for "
                                   "each bound on its spread); mechanisms DATA... (every mechanism — per-tendon and "
                                   "compact Voigt, Maxwell, SLS, springpot, cytoplasm, distributions — fitted to the "
                                   "same data: parameters, RMS, AIC/BIC, identifiability, G' slope ripple, held-out "
                                   "error; it prints its estimated time first and refuses a run beyond a day); "
                                   "real-cells (the mechanisms and their structure-free baselines on measured cells "
                                   "— the Xie et al. 2024 AFM spectra, read from --data — in sample and held out, "
                                   "with goal G3 and the per-cell G' slopes); powerlaw (whether structures of plain "
                                   "members — diluted networks near their rigidity threshold, hierarchical nets, "
                                   "damping set by length or force — make a weak power law: the map of "
                                   "d ln G'/d ln f, several minutes); structures (each mechanism on each structure — "
                                   "6-, 12-, 30-strut spheres, nucleus, elastic struts, a lattice — fitted to the "
                                   "bundled pair free and with σ anchored: a ranking of structures; about 15 min of "
                                   "CPU).")
    p.add_argument("name", choices=sorted(STUDIES), help="which study")
    p.add_argument("data", nargs="*", help="compactness, mechanisms: file(s) of measured moduli (as for `tenscell "
                                           "fit`), or bundled:NAME")
    add_out(p, derived="study-NAME")
    p.add_argument("--draws", type=integer(1, 100_000), default=200, help="Monte Carlo draws per set (sensitivity)")
    p.add_argument("--seed", type=integer(0, 2**63 - 1), default=0, help="random seed (sensitivity, compactness, mechanisms)")
    p.add_argument("--from-fit", metavar="FIT_JSON", type=path("a fit.json file"), default=None,
                   help="sensitivity: of the fitted paper cell of a `tenscell fit` run (its fit.json: strut length, "
                        "EA, c and prestress; a fit to data that state their prestress at their median)")
    g = p.add_argument_group("compactness (fits with the stiffness spread bounded to each of --decades)")
    g.add_argument("--decades", type=number_list(0.0, 100.0, "decades", open_lo=True),
                   default=_DECADES, help="bounds on the spread (comma list)")
    g.add_argument("--prestress", action="append", type=stated_prestress, metavar="FILE=PA",
                   help="the prestress (Pa) at which the data in FILE were measured (repeatable)")
    g.add_argument("--damping", choices=("uniform", "per-family"), default="uniform", help="damping c")
    g.add_argument("--starts", type=integer(1, 10_000), default=None,
                   help="starts per bound (default 4; mechanisms: per fit; real-cells: per fit of a median, default 12)")
    g.add_argument("--jobs", type=integer(1, 256), default=None,
                   help="worker processes over the starts (mechanisms: over the mechanisms) (default: one per CPU, at most --starts;"
                        " the result does not depend on it)")
    g.add_argument("--tolerance", type=number(0.0, 10.0, "decades", open_lo=True), default=0.01,
                   help="RMS of the log10 errors (decades) a fit must reach")
    m = p.add_argument_group("mechanisms (every mechanism fitted to the same data: one table, one figure)")
    m.add_argument("--mechanisms", metavar="NAMES", default=None,
                   help="comma list of mechanisms (default all; see `tenscell fit --model`)")
    m.add_argument("--hops", type=integer(0, 10_000), default=None,
                   help="basin-hopping moves per start (default 10; real-cells: per fit of a median, default 30)")
    m.add_argument("--ensemble", type=ensemble_size, default=None, metavar="K",
                   help=f"evaluate the distributed mechanism with the lowest BIC over K assignments of its tendon "
                        f"values at the data's prestresses and frequencies (ensemble.csv, .png, .md; default "
                        f"{STUDY_ENSEMBLE_K}; 0: none; 1 is refused: one assignment has no spread)")
    add_cluster_options(m)
    r = p.add_argument_group("real-cells (the mechanisms and their baselines on the measured Xie et al. 2024 cells, "
                             "held out; docs/validation.md)")
    r.add_argument("--data", dest="data_dir", type=path("a directory"), default=None, metavar="DIR",
                   help="the real-cell data folder (default ../shared/data/real-cells; never shipped with tenscell)")
    r.add_argument("--cells", type=integer(0, 10_000), default=None, metavar="N",
                   help="fit only the first N cells of each line one by one (default all; 0: no per-cell fits)")
    r.add_argument("--time-domain", action="store_true",
                   help="also fit the HL60 creep curve and the oocyte relaxation's shape in the time domain (each "
                        "mechanism about a minute of CPU per series)")
    r.add_argument("--populations", action="store_true",
                   help="also score population models on each line (springpot-alpha-family+visc with its prestress "
                        "per cell, the power law + Newtonian with its modulus per cell) against independent per-cell "
                        "power laws, with goal G4 (a few minutes of CPU)")
    w = p.add_argument_group("powerlaw (the map of structures of plain members)")
    w.add_argument("--scale", choices=("full", "quick", "tiny"), default="full",
                   help="how much of the map: full (the docs' map, several minutes), quick (a coarser map, about a "
                        "minute), tiny (a few structures, seconds)")
    add_data_options(p)
    p.set_defaults(func=run)
    _DEFAULTS.update({dest: p.get_default(dest) for dest in STUDY_FLAGS})


def _given(args) -> dict:
    """The study flags the user typed (those whose value differs from the parser's default), by dest."""
    return {dest: getattr(args, dest) for dest in STUDY_FLAGS if getattr(args, dest) != _DEFAULTS[dest]}


def _options_of(name: str):
    return load_study(name).options


def _refuse_foreign(name: str, own, given: dict, data) -> None:
    """A flag the study does not take, or data files it does not fit (or the lack of them), is refused naming it."""
    from ..studies.protocol import flag

    if ("data" in own) != bool(data):
        raise ValueError(f"study {name} needs data files (e.g. bundled:fabry2001)" if "data" in own
                         else f"study {name} takes no data files, got {' '.join(data)}")
    for dest in given:
        if dest not in own and not (dest == "prestress" and "data" in own):  # --prestress: how to read data files
            takes = [n for n in sorted(STUDIES)
                     if dest in _options_of(n) or (dest == "prestress" and "data" in _options_of(n))]
            raise ValueError(f"{flag(dest)} applies to study {' and '.join(takes)}, not to study {name}")


def _read_data(args) -> tuple:
    """The data files read and checked (before the output folder and any work)."""
    from .fit import read_datasets

    return tuple(read_datasets(args.data, args.prestress, 1, data_options_from_args(args)))


def run(args) -> int:
    from .._progress import stage
    from ..io.outputs import OutputSet
    from ..studies.protocol import run_study
    from ._cost import estimate_plan
    from ._study_output import write_study_result

    given = _given(args)
    _refuse_foreign(args.name, _options_of(args.name), given, args.data)
    given.pop("prestress", None)  # applied as the data files are read
    data = _read_data(args) if args.data else None
    study = load_study(args.name)
    plan = study.plan({**given, "data": data} if data else given)  # the study checks its options: no work yet
    for d in data or ():  # what was read (layout, step, temperature, conversions), once the options are accepted
        stage(d.provenance.line())
    out = OutputSet(args.out or f"study-{args.name}", command=args.command_line, flag="--out")
    rates, estimate = estimate_plan(plan)
    t = time.perf_counter()
    stage(f"study {args.name} ...")
    with out as d:
        result = run_study(study, plan, rates=rates, notify=lambda line: stage(f"    {line}"))
        write_study_result(d, result, lambda line: stage(f"    {line}"))
        stage(f"    wrote {', '.join(result.files())} ({result.cpu_s:.0f} s of CPU in {len(result.tasks)} tasks)")
    if result.summary:
        print(result.summary, flush=True)
    print(f"tenscell: study {args.name} finished in {time.perf_counter() - t:.1f} s (estimated "
          f"{estimate:.1f} s); wrote {out.target}/", file=sys.stderr)
    return 0
