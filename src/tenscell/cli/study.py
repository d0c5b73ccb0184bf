"""``tenscell study NAME``: the discussion's variant studies (figures, CSV, Markdown)."""
from __future__ import annotations

import math
import os
import time
from pathlib import Path

from ._args import add_data_options, add_out, data_options_from_args, ensemble_size, integer, number, number_list, path
from .fit import stated_prestress
from ._args import add_cluster_options

#: assignments of the study's ensemble unless --ensemble says otherwise (tenscell.population.ensemble.DEFAULT_K)
STUDY_ENSEMBLE_K = 1000


def _study_no_if(out: Path, log, args=None) -> None:
    from .. import plotting
    from ..studies.no_if import no_if_study
    from ..reports.studies import no_if_markdown
    from ..io.outputs import write_csv_rows, write_text

    s = no_if_study()
    rows = ((P, f, a, b, c, d) for (P, f, a, b), (_, _, c, d) in zip(s.without.rows(), s.with_ifs.rows()))
    write_csv_rows(out / "no_if_moduli.csv",
                   ["prestress", "frequency_Hz", "G_storage_noIF", "G_loss_noIF", "G_storage_IF", "G_loss_IF"], rows)
    write_csv_rows(out / "no_if_peaks.csv", ["prestress", "peak_frequency_Hz", "peak_G_loss", "G_storage_at_peak"],
                   ((float(P), p.frequency_hz, p.height, p.storage) for P, p in zip(s.without.prestress, s.peaks)))
    plotting.save(plotting.no_if_figure(s), out / "no_if_moduli.png")
    plotting.save(plotting.no_if_peaks_figure(s), out / "no_if_peaks.png")
    write_text(out / "no_if.md", no_if_markdown(s))
    log("no_if_moduli.csv, no_if_peaks.csv, no_if_moduli.png, no_if_peaks.png, no_if.md")


def _study_sensitivity(out: Path, log, args=None) -> None:
    from .. import plotting, studies
    from ..io.outputs import write_csv_rows, write_text

    from ..reports.sensitivity import sensitivity_markdown

    draws = getattr(args, "draws", 200)
    seed = getattr(args, "seed", 0)
    study = studies.sensitivity_study(draws, seed=seed, **getattr(args, "fitted_cell", {}))
    el, table, summary, mcs = study.elasticities, study.table, study.summary, list(study.monte_carlo)
    f = el.frequency_hz
    write_csv_rows(out / "elasticities.csv", ["parameter", "group", "value", "method", "frequency_Hz",
                                              "dlnGstorage_dlnp", "dlnGloss_dlnp"],
                   ((n, g, float(v), m, float(f[k]), float(el.storage[i, k]), float(el.loss[i, k]))
                    for i, (n, g, v, m) in enumerate(zip(el.names, el.groups, el.values, el.methods)) for k in range(f.size)))
    write_csv_rows(out / "perturbations.csv", ["parameter", "group", "dGstorage_minus", "dGstorage_plus",
                                               "dGloss_minus", "dGloss_plus", "note"],
                   ((r.name, r.group, *r.storage, *r.loss, r.note) for r in table))
    write_csv_rows(out / "sensitivity_table.csv", ["group", "n", "max_abs_elasticity_storage", "max_abs_elasticity_loss",
                                                   "max_change_storage", "max_change_loss", "holds_8pct", "note"],
                   ((x.group, x.n, x.max_elasticity_storage, x.max_elasticity_loss, x.max_change_storage,
                     x.max_change_loss, x.holds, x.note) for x in summary))
    write_csv_rows(out / "monte_carlo.csv", ["set", "draw", "valid", "max_change_storage", "max_change_loss", "reason"],
                   ((mc.label, i, bool(mc.valid[i]), float(mc.change_storage[i]), float(mc.change_loss[i]), mc.reasons[i])
                    for mc in mcs for i in range(mc.factors.shape[0])))
    plotting.save(plotting.elasticities_figure(el), out / "elasticities.png")
    plotting.save(plotting.monte_carlo_figure(mcs), out / "monte_carlo.png")
    write_text(out / "sensitivity.md", sensitivity_markdown(study))
    log("elasticities.csv, perturbations.csv, sensitivity_table.csv, monte_carlo.csv, elasticities.png, "
        "monte_carlo.png, sensitivity.md")


def _study_references(out: Path, log, args=None) -> None:
    from .. import plotting
    from ..studies.references import references_study
    from ..reports.studies import references_markdown
    from ..io.outputs import write_csv_rows, write_text

    s = references_study()
    mp = s.map
    write_csv_rows(out / "reference_map.csv", ["alpha_deg", "delta_deg", "status", "min_tension", "if_tension"],
                   ((math.degrees(a), math.degrees(d), ("valid", "not prestressable", "K0 not positive definite")[mp.status[i, k]],
                     float(mp.min_tension[i, k]), float(mp.if_tension[i, k]))
                    for i, d in enumerate(mp.delta) for k, a in enumerate(mp.alpha)))
    write_csv_rows(out / "references_moduli.csv", ["reference", "prestress", "frequency_Hz", "G_storage", "G_loss"],
                   ((name, *row) for name, r in s.responses.items() for row in r.rows()))
    plotting.save(plotting.reference_map_figure(mp, s.if_free_curve), out / "reference_map.png")
    P = float(next(iter(s.responses.values())).prestress[len(next(iter(s.responses.values())).prestress) // 2])
    plotting.save(plotting.references_figure(s.responses, P), out / "references.png")
    write_text(out / "references.md", references_markdown(s))
    log("reference_map.csv, references_moduli.csv, reference_map.png, references.png, references.md")


def _study_semiflexible(out: Path, log, args=None) -> None:
    from .. import plotting
    from ..studies.semiflexible import semiflexible_study
    from ..reports.studies import semiflexible_markdown
    from ..io.outputs import write_csv_rows, write_text

    s = semiflexible_study()
    f = s.frequency_hz
    write_csv_rows(out / "semiflexible.csv", ["EA_strut", "frequency_Hz", "G_storage", "G_loss", "G_storage_rigid", "G_loss_rigid"],
                   ((float(e), float(f[k]), float(s.G[i, k].real), float(s.G[i, k].imag), float(s.G_rigid[k].real),
                     float(s.G_rigid[k].imag)) for i, e in enumerate(s.EA_strut) for k in range(f.size)))
    write_csv_rows(out / "semiflexible_convergence.csv", ["EA_strut", "max_rel_diff_storage", "max_rel_diff_loss"],
                   zip(map(float, s.EA_strut), map(float, s.error_storage), map(float, s.error_loss)))
    plotting.save(plotting.semiflexible_figure(s), out / "semiflexible.png")
    write_text(out / "semiflexible.md", semiflexible_markdown(s))
    log("semiflexible.csv, semiflexible_convergence.csv, semiflexible.png, semiflexible.md")


def _study_stiffening(out: Path, log, args=None) -> None:
    from .. import plotting
    from ..studies.stiffening import stiffening_study
    from ..reports.studies import stiffening_markdown
    from ..io.outputs import write_csv_rows, write_text

    s = stiffening_study()
    write_csv_rows(out / "stiffening.csv", ["b", "prestress", "frequency_Hz", "G_storage", "G_loss", "G_static", "IF_tangent_N_per_m"],
                   ((float(b), float(P), float(f), float(s.G[i, k, j].real), float(s.G[i, k, j].imag), float(s.static[i, k]),
                     float(s.if_tangent[i, k]))
                    for i, b in enumerate(s.b) for k, P in enumerate(s.prestress) for j, f in enumerate(s.frequency_hz)))
    plotting.save(plotting.stiffening_figure(s), out / "stiffening.png")
    write_text(out / "stiffening.md", stiffening_markdown(s))
    log("stiffening.csv, stiffening.png, stiffening.md")


def _study_compactness(out: Path, log, args=None) -> None:
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_text
    from ..plotting.fits import stiffness_histogram
    from ..reports.compactness import compactness_markdown
    from ..studies.compactness import compactness_study
    from .._parallel import jobs_for
    s = compactness_study(args.datasets, args.decades, damping=args.damping, starts=args.starts, seed=args.seed,
                          jobs=jobs_for(args.starts, args.jobs), tolerance=args.tolerance)
    write_csv_rows(out / "compactness.csv", s.HEADER, s.rows())
    plotting.save(s.plot(title="Best fit against the bound on the stiffness spread"), out / "compactness_front.png")
    written = "compactness.csv, compactness_front.png, compactness.md"
    knee = s.knee_fit
    if knee is not None:
        plotting.save(stiffness_histogram(knee.EA, families=knee.cell.structure.families,
                                          title=f"Stiffnesses at the narrowest bound within tolerance ({s.knee:g} "
                                                "decades)"), out / "compactness_histogram.png")
        write_csv_rows(out / "compactness_knee_stiffness.csv", ["tendon", "family", "EA_N"],
                       ((j, fam, float(e)) for j, (fam, e) in enumerate(zip(knee.cell.structure.families, knee.EA))))
        written += ", compactness_histogram.png, compactness_knee_stiffness.csv"
    write_text(out / "compactness.md", compactness_markdown(s))
    log(written)


def _study_mechanisms(out: Path, log, args=None) -> None:
    from .. import plotting
    from .._parallel import jobs_for
    from ..io.outputs import write_csv_rows, write_text
    from ..plotting.mechanisms import mechanisms_figure
    from ..reports.mechanisms import STUDY_COLUMNS, mechanisms_markdown, study_table_rows
    from ..studies.mechanisms import mechanisms_study

    datasets = args.datasets  # read and checked before the study began (run)
    names = _study_models(args)
    K = STUDY_ENSEMBLE_K if args.ensemble is None else args.ensemble
    s = mechanisms_study(datasets, mechanisms=names, starts=args.starts, hops=args.hops, seed=args.seed,
                         tolerance=args.tolerance, jobs=jobs_for(len(names), args.jobs), ensemble=K or None,
                         workers=args.workers, scheduler=args.scheduler, notify=lambda line: log(f"ensemble: {line}"))
    write_csv_rows(out / "mechanisms.csv", list(STUDY_COLUMNS), study_table_rows(s))
    plotting.save(mechanisms_figure(s, datasets), out / "mechanisms.png")
    report = mechanisms_markdown(s)
    write_text(out / "mechanisms.md", report)
    print(report.split("## The goals")[0].split("\n\n", 2)[-1], flush=True)
    written = "mechanisms.csv, mechanisms.png, mechanisms.md"
    if s.ensemble is not None:
        from .fit import ENSEMBLE_FILES, write_ensemble

        write_ensemble(out, s.ensemble, f"Ensemble of `{s.ensemble.mechanism}`, the distributed mechanism with the "
                                        "lowest BIC")
        written += ", " + ", ".join(ENSEMBLE_FILES)
    elif K:
        log("no ensemble: none of the mechanisms fitted draws a tendon property from a distribution")
    log(written)


#: model evaluations (residuals and Jacobian: one unit of a fit's work) per start and basin-hopping move, shared with
#: `tenscell fit`'s estimate (defined in _cost)
from ._cost import EVALUATIONS_PER_START_HOP  # noqa: E402


def _cpu_per_call(fn, calls: int = 5) -> float:
    """CPU seconds of one call of ``fn`` (the mean of ``calls`` after one warm-up): what the work costs, whatever
    share of the CPUs the machine gives it now."""
    fn()
    t0 = time.process_time()
    for _ in range(calls):
        fn()
    return max(time.process_time() - t0, 1e-9) / calls


def cpu_share(workers: int) -> float:
    """The share of one CPU each of ``workers`` new processes can expect now: the CPUs over everything runnable
    (the load average plus them), at most 1. On a shared machine a short timed call is served at once while a
    long run waits its turn, so wall time is estimated from CPU time and this share."""
    try:
        load = os.getloadavg()[0]
    except (OSError, AttributeError):  # pragma: no cover - no load average on this platform
        return 1.0
    return min(1.0, (os.cpu_count() or 1) / max(load + workers, 1.0))


def mechanisms_cost(datasets, names, starts: int, hops: int, jobs: int, validate: bool = True,
                    falsify: bool = True):
    """The mechanisms study's cost (:class:`tenscell.cli._cost.Cost`): the CPU time of one model evaluation of each
    model, timed here at a start of its fit with the BLAS threads the search uses, × the evaluations its fits are
    expected to take (:data:`EVALUATIONS_PER_START_HOP` × starts × hops for the main fit; the same at the refits'
    budget, :data:`tenscell.studies.mechanisms.REFIT`, for each of the others that
    :func:`~tenscell.studies.mechanisms.fits_per_model` counts), over ``jobs`` workers at the CPU share the
    machine's load leaves them (:func:`cpu_share`)."""
    import numpy as np

    from .._threads import limited
    from ..fitting import get_model
    from ..fitting.entry import prepare
    from ..fitting.models.catalog import PER_TENDON_VOIGT
    from ..fitting.models.voigt import VoigtModel
    from ..studies.mechanisms import PER_TENDON_HOPS, REFIT, fits_per_model
    from ._cost import Cost

    cpu, evaluations, fits = 0.0, 0, 0
    refit = REFIT["starts"] * (REFIT["hops"] + 1)
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
            cpu += n * _cpu_per_call(lambda pb=problem, th=theta: pb.jacobian(th))
            evaluations += n
            fits += k
    workers = min(jobs, len(names))
    share = cpu_share(workers)
    per = cpu / max(evaluations, 1)
    return Cost("model evaluation", max(evaluations, 1), per / share, workers,
                detail=f"({len(names)} model(s), {fits} fits: each model × {starts} start(s) × up to {hops} hop(s),"
                       f" its anchored, structure-free, held-out and unlike refits × {REFIT['starts']} × "
                       f"{REFIT['hops']}; {per * 1e3:.2g} ms of CPU each, at {share:.0%} of a CPU per worker: load "
                       f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)")


def _study_real_cells(out: Path, log, args=None) -> None:
    from .._parallel import jobs_for
    from ._real_cells import write_real_cells

    write_real_cells(out, log, args, jobs_for(len(args.real_cells_models), args.jobs))


def _study_powerlaw(out: Path, log, args=None) -> None:
    """The power-law study on the study protocol (a minimal writer until the table of protocol studies lands)."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_text
    from ..studies.powerlaw import STUDY
    from ..studies.protocol import run_study

    result = run_study(STUDY, {"scale": "full"}, rates=STUDY.calibration, notify=log)
    for table in result.tables:
        write_csv_rows(out / f"{table.name}.csv", list(table.columns), table.rows)
    for figure in result.figures:
        plotting.save(figure.draw(), out / figure.name)
    for name, text in result.pages:
        write_text(out / name, text)
    log(", ".join(result.files()))


#: studies that fit data files given on the command line (not part of `reproduce`'s variants stage)
DATA_STUDIES = ("compactness", "mechanisms")
#: studies that are not among the paper's variants (`reproduce` leaves them out): those fitting data, and the
#: power-law study of issue 34 (several minutes)
NOT_VARIANTS = (*DATA_STUDIES, "real-cells", "powerlaw")
#: --starts and --hops where a study does not set its own default
_DEFAULT_SEARCH = {"starts": 4, "hops": 10}
#: the per-study defaults of --starts and --hops (None: the study's own budget)
_SEARCH_DEFAULTS = {"starts": {"real-cells": None}, "hops": {"real-cells": None}}

#: the studies of `tenscell study NAME`: name -> writer(out_dir, log, args)
STUDIES = {
    "compactness": _study_compactness,
    "mechanisms": _study_mechanisms,
    "real-cells": _study_real_cells,
    "no-if": _study_no_if,
    "sensitivity": _study_sensitivity,
    "references": _study_references,
    "semiflexible": _study_semiflexible,
    "stiffening": _study_stiffening,
    "powerlaw": _study_powerlaw,
}


#: Monte Carlo draws of the sensitivity study run without an estimate (200, the default, take about 2 s)
_QUICK_DRAWS = 1000

#: options that apply to some studies only: dest -> (default, flag, studies); any other value elsewhere is refused
_STUDY_OPTIONS = {
    "draws": (200, "--draws", ("sensitivity",)),
    "seed": (0, "--seed", ("sensitivity", "compactness", "mechanisms", "real-cells")),
    "decades": (tuple(float(d) for d in range(1, 15)), "--decades", ("compactness",)),
    "prestress": (None, "--prestress", ("compactness", "mechanisms")),
    "damping": ("uniform", "--damping", ("compactness",)),
    "starts": (None, "--starts", ("compactness", "mechanisms", "real-cells")),
    "jobs": (None, "--jobs", ("compactness", "mechanisms", "real-cells")),
    "tolerance": (0.01, "--tolerance", ("compactness", "mechanisms")),
    "mechanisms": (None, "--mechanisms", ("mechanisms", "real-cells")),
    "hops": (None, "--hops", ("mechanisms", "real-cells")),
    "data_dir": (None, "--data", ("real-cells",)),
    "cells": (None, "--cells", ("real-cells",)),
    "time_domain": (False, "--time-domain", ("real-cells",)),
    "populations": (False, "--populations", ("real-cells",)),
    "ensemble": (None, "--ensemble", ("mechanisms",)),
    "workers": (None, "--workers", ("mechanisms",)),
    "scheduler": (None, "--scheduler", ("mechanisms",)),
}


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
                                   "with goal G3 and the per-cell G' slopes); powerlaw (whether structures of plain members — diluted "
                                   "networks near their rigidity threshold, hierarchical nets, damping set by length "
                                   "or force — make a weak power law: the map of d ln G'/d ln f, several minutes).")
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
                   default=_STUDY_OPTIONS["decades"][0], help="bounds on the spread (comma list)")
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
    add_data_options(p)
    p.set_defaults(func=run)


def _fitted_paper_cell(path) -> dict:
    """The sensitivity study's keyword arguments for the fitted paper cell in ``path`` (ValueError otherwise)."""
    from ..fitting.fitted import load_fit

    from ..fitting.fitted import FittedCell

    model = load_fit(path)
    if not isinstance(model, FittedCell):
        raise ValueError(f"--from-fit {path}: the sensitivity study varies the paper cell's α, δ, L, EA and c; this "
                         f"fit is {model.describe()}, not a fit of the Voigt cell (tenscell fit without --model)")
    p = model.cell.parameters
    if not {"alpha", "delta"} <= set(p) or not p.get("intermediate_filaments", False):
        raise ValueError(f"--from-fit {path}: the sensitivity study varies the paper cell's α, δ and L; this fit's "
                         f"cell is {model.cell.describe()}")
    return {"alpha": float(p["alpha"]), "delta": float(p["delta"]), "L": model.L, "P": model.prestress(),
            "EA": model.EA, "c": model.c}


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


def run(args) -> int:
    import sys
    import time

    from ..io.outputs import OutputSet

    if (args.name in DATA_STUDIES) != bool(args.data):
        raise ValueError(f"study {args.name} needs data files (e.g. bundled:fabry2001)" if args.name in DATA_STUDIES
                         else f"study {args.name} takes no data files, got {' '.join(args.data)}")
    for dest, (default, flag, names) in _STUDY_OPTIONS.items():
        if args.name not in names and getattr(args, dest) != default:
            raise ValueError(f"{flag} applies to study {' and '.join(names)}, not to study {args.name}")
    if args.name == "mechanisms" and args.mechanisms is not None:
        from ..fitting.models.catalog import mechanism_names

        if not [m for m in args.mechanisms.split(",") if m.strip()]:
            raise ValueError(f"--mechanisms {args.mechanisms!r}: no mechanism named; give a comma list of names "
                             f"({', '.join(mechanism_names())}), or leave the flag out for all of them")
        bad = [m for m in args.mechanisms.split(",") if m.strip() and m.strip() not in mechanism_names()]
        if bad:
            raise ValueError(f"--mechanisms: unknown mechanism {bad[0]!r}; known: {', '.join(mechanism_names())}")
    if args.name == "mechanisms":
        _check_ensemble_options(args)
    for dest, defaults in _SEARCH_DEFAULTS.items():  # each study's own default budget
        if getattr(args, dest) is None:
            setattr(args, dest, defaults.get(args.name, _DEFAULT_SEARCH[dest]))
    if args.name == "real-cells":
        from ._real_cells import budgets, check_inputs

        check_inputs(args)  # every file read before the output folder is made and before any fit
        args.real_cells_models = budgets(args)[0]
    if args.from_fit is not None:
        if args.name != "sensitivity":
            raise ValueError(f"--from-fit applies to study sensitivity, not to study {args.name}")
        args.fitted_cell = _fitted_paper_cell(args.from_fit)
    from .._progress import stage

    out = OutputSet(args.out or f"study-{args.name}", command=args.command_line, flag="--out")
    if args.name in DATA_STUDIES:  # read and check the data files before the study's stage line and any fit
        from .fit import read_datasets

        args.datasets = read_datasets(args.data, args.prestress, 1, data_options_from_args(args))
        for data in args.datasets:  # what was read: layout, step, temperature, conversions
            stage(data.provenance.line())
    if args.name == "sensitivity" and args.draws > _QUICK_DRAWS:
        from ._cost import Cost, announce, check
        from .population import monte_carlo_rate

        per = monte_carlo_rate("all", 0.1, args.seed)
        announce(check(Cost("draw", 2 * args.draws, per, 1, detail="(two Monte Carlo sets of --draws)"), "--draws"))
    if args.name == "mechanisms":
        _announce_mechanisms_cost(args)
    if args.name == "real-cells":
        from .._parallel import jobs_for
        from ._cost import announce, check
        from ._real_cells import real_cells_cost

        announce(check(real_cells_cost(args, jobs_for(len(args.real_cells_models), args.jobs), _cpu_per_call,
                                       cpu_share), "--starts",
                       hint="give fewer --starts or --hops, --cells N, or fewer --mechanisms NAMES"))
    t = time.perf_counter()
    stage(f"study {args.name} ...")
    with out as d:
        STUDIES[args.name](d, lambda msg: stage(f"    computed {msg}"), args)
    print(f"tenscell: study {args.name} finished in {time.perf_counter() - t:.1f} s; wrote {out.target}/",
          file=sys.stderr)
    return 0
