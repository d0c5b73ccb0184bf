"""``tenscell fit --model NAME``: fit a mechanism (not the per-tendon cell) and write its output set."""
from __future__ import annotations

from pathlib import Path

#: the files of a mechanism fit in `tenscell fit --model NAME --out DIR`
MECHANISM_FILES = ("fit.json", "report.md", "fit.png")


def run_mechanism_fit(args, read_datasets) -> int:
    """The fit command with ``--model``: checks, fit, fit.json + report.md + fit.png; exit 1 if not converged.

    ``read_datasets(paths, prestress_options, min_points)`` is the fit command's reader (passed in: this module
    is the fit command's, not a second command).
    """
    import sys

    from .._parallel import jobs_for
    from .._progress import stage
    from ..fitting.mechanism_fit import fit_mechanism
    from ..fitting.models.mechanism_problem import make_mechanism_problem
    from ..io.outputs import OutputSet, write_json, write_text
    from ..io.thinning import bin_datasets
    from ..reports.mechanisms import mechanism_fit_markdown

    for flag, given in (("--tendons", args.tendons != "per-tendon"), ("--damping", args.damping != "uniform"),
                        ("--holdout", args.holdout is not None),
                        ("--min-prestress-share", getattr(args, "min_prestress_share", None) is not None),
                        ("--max-decades", getattr(args, "max_decades", None) is not None),
                        ("--min-prestress-elasticity", getattr(args, "min_prestress_elasticity", None) is not None)):
        if given:
            raise ValueError(f"{flag} applies to the per-tendon fit, not to --model {args.model}")
    out = OutputSet(args.out, command=args.command_line, flag="--out")
    datasets = list(bin_datasets(read_datasets(args.data, args.prestress, 2), args.max_points))
    fixed = dict(args.fix or ())
    bounds = dict(args.bound or ())
    make_mechanism_problem(datasets, args.model, bounds=bounds, fixed=fixed)  # bad input: before any fitting
    _check_ensemble(args)
    jobs = jobs_for(args.starts, args.jobs)
    stage(f"fitting mechanism {args.model} to {sum(d.n for d in datasets)} points: {args.starts} start(s), "
          f"{jobs} process(es)")
    result = fit_mechanism(datasets, args.model, starts=args.starts, seed=args.seed, jobs=jobs,
                           tolerance=args.tolerance, bounds=bounds, fixed=fixed, max_points=None)
    doc = result.to_dict()
    report = mechanism_fit_markdown(result)
    png = _figure_png(result)
    ensemble = None
    if args.ensemble:
        from ..population.ensemble import ensemble_at_data

        ensemble = ensemble_at_data(result.model(), datasets, args.ensemble,
                                    notify=lambda line: stage(f"ensemble: {line}"))
    with out as d:
        write_json(d / "fit.json", doc)
        write_text(d / "report.md", report)
        (d / "fit.png").write_bytes(png)
        if ensemble is not None:
            write_ensemble(d, ensemble, f"Ensemble of the fitted `{args.model}`")
    files = MECHANISM_FILES + (ENSEMBLE_FILES if ensemble is not None else ())
    print(f"tenscell: {result.message}; wrote {out.target}/ ({', '.join(files)})", file=sys.stderr)
    return 0 if result.converged else 1


def _check_ensemble(args) -> None:
    """``--ensemble K``: a mechanism drawn from a distribution, and K >= 2 (or 0: none), before any fitting."""
    if not args.ensemble:
        return
    from ..fitting.models.mechanism import mechanism

    if args.ensemble == 1:
        raise ValueError("--ensemble: 1 assignment has no spread between assignments; give K >= 2, or 0 for none")
    if not mechanism(args.model).heterogeneous:
        raise ValueError(f"--ensemble: mechanism {args.model} draws no tendon property from a distribution: every "
                         "assignment is the same cell, so it has no ensemble")


#: the files an ensemble adds to an output set (`fit --model ... --ensemble K`, `study mechanisms`)
ENSEMBLE_FILES = ("ensemble.csv", "ensemble.png", "ensemble.md")


def write_ensemble(out: Path, ensemble, title: str) -> None:
    """An ensemble's table, figure and Markdown into the directory ``out`` (of an open output set)."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_text
    from ..reports.ensemble import ensemble_markdown

    df = ensemble.to_dataframe()
    write_csv_rows(out / "ensemble.csv", list(df.columns), (tuple(map(float, r)) for r in df.itertuples(index=False)))
    plotting.save(ensemble.plot(), out / "ensemble.png")
    write_text(out / "ensemble.md", ensemble_markdown(ensemble, title))


def _figure_png(result) -> bytes:
    """Each data set against the fitted mechanism (PNG bytes)."""
    import numpy as np

    from .. import plotting
    from ..plotting._style import new_panels
    from ..plotting.fits import data_points

    with plotting.style():
        ax = new_panels(None, len(result.datasets), (4.8 * len(result.datasets), 3.8),
                        title=f"Mechanism {result.mechanism.name}")
        for k, (a, d) in enumerate(zip(ax, result.datasets)):
            data_points(d, a)
            if np.unique(d.frequency_hz).size > 1:
                f = np.logspace(np.log10(d.frequency_hz.min()), np.log10(d.frequency_hz.max()), 200)
                Gs, Gl = result.moduli(f, dataset=k)
                a.plot(f, Gs, "-", color="C0", label="G′ model")
                a.plot(f, Gl, "--", color="C3", label="G″ model")
                a.set_xscale("log")
                a.set_yscale("log")
                a.set_xlabel("frequency f (Hz)")
            else:
                p = np.linspace(d.prestress.min(), d.prestress.max(), 100)
                G = np.array([result.moduli([d.frequency_hz[0]], x) for x in p])[:, :, 0]
                a.plot(p, G[:, 0], "-", color="C0", label="G′ model")
                a.plot(p, G[:, 1], "--", color="C3", label="G″ model")
                a.set_xlabel("prestress (Pa)")
            a.set_ylabel("modulus (Pa)")
            a.set_title(Path(d.source).name, fontsize="small")
            a.legend(fontsize="small")
        return plotting.png_bytes(ax[0].figure)
