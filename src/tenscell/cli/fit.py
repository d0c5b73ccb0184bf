"""``tenscell fit``: fit the tensegrity model to measured G', G'' (CSV) and write the fit's output set."""
from __future__ import annotations

from pathlib import Path

from ._args import add_out, integer, number

#: the fit's parametrizations (the same tuples as tenscell.fitting.TENDON_MODES / DAMPING_MODES,
#: written out so that building the parser does not import the fitting code; a test checks they agree)
TENDON_MODES = ("per-tendon", "per-family", "uniform")
DAMPING_MODES = ("uniform", "per-family")

#: the files of one fit: extension -> name in `tenscell fit --out`
FIT_FILES = {"json": "fit.json", "csv": "fit.csv", "md": "report.md", "png": "fit.png"}


#: the prestress (Pa) at which the bundled frequency data (fabry2001) were measured, for joint fits: the
#: baseline prestress of airway smooth muscle cells, where the bundled prestress data (stamenovic2002)
#: give G'(0.1 Hz) close to the frequency data's 280 Pa
BUNDLED_FREQUENCY_PRESTRESS_PA = 1000.0


def register(sub) -> None:
    p = sub.add_parser(
        "fit", help="fit the tensegrity model to measured G', G'' (CSV; several files: one joint fit)",
        description="Fit tendon stiffnesses, damping, prestress and strut length so that the model's G', G'' "
                    "match CSV files of measured moduli (frequency sweep, prestress sweep or |G|/phase; see "
                    "docs/fitting.md). Several files are fitted jointly by one parameter set: a frequency sweep "
                    "that states its prestress (a prestress_Pa column, or --prestress FILE=PA) is linked to the "
                    "others by one prestress scale; otherwise its prestress is a fitted, reported parameter. "
                    "bundled:NAME reads a data set shipped with tenscell (fabry2001, stamenovic2002). "
                    "Writes fit.json, fit.csv, fit.png and report.md into --out. Exit status 0 if every data "
                    "set's RMS of the log10 errors reached --tolerance, 1 if not, 2 for bad input.")
    p.add_argument("data", nargs="+", help="CSV file(s) of measured moduli, or bundled:NAME")
    p.add_argument("--prestress", action="append", metavar="FILE=PA",
                   help="the prestress (Pa) at which the data in FILE were measured (repeatable)")
    p.add_argument("--tendons", choices=TENDON_MODES, default="per-tendon",
                   help="stiffness per tendon (as in the paper), per family, or one for all")
    p.add_argument("--damping", choices=DAMPING_MODES, default="uniform",
                   help="damping c: one for all (as in the paper) or per family")
    add_constraints(p)
    p.add_argument("--starts", type=integer(1, 10_000), default=4, help="independent starts")
    p.add_argument("--seed", type=integer(0, 2**63 - 1), default=0,
                   help="random seed; the same seed gives the same fit")
    p.add_argument("--jobs", type=integer(1, 256), default=1, help="worker processes over the starts")
    p.add_argument("--tolerance", type=number(0.0, 10.0, "decades", open_lo=True), default=0.01,
                   help="RMS of the log10 errors (decades) every data set must reach")
    p.add_argument("--baseline-starts", type=integer(1, 10_000), default=2,
                   help="starts for the homogeneous baseline fit")
    p.add_argument("--max-points", type=integer(4, 100_000), default=100,
                   help="fit at most this many points: denser data is binned in log frequency per prestress "
                        "(weighted log means; the rule is in tenscell.io.thinning and the report)")
    add_out(p)
    p.set_defaults(func=run)


def add_constraints(p) -> None:
    """The search-space constraints: ``--min-prestress-share``, ``--min-prestress-elasticity``, ``--max-decades``."""
    p.add_argument("--min-prestress-share", type=number(0.0, 1.0, open_lo=True), default=None, metavar="S",
                   help="keep the prestress mechanically active: P·Kp must carry at least this share (0-1) of "
                        "the static stiffness at every prestress of the data")
    p.add_argument("--min-prestress-elasticity", type=number(0.0, 10.0, open_lo=True), default=None, metavar="E",
                   help="keep the prestress mechanically active: dlnG'/dlnP at 0.1 Hz must be at least E at every "
                        "prestress of the data (adherent cells: about 0.7)")
    p.add_argument("--max-decades", type=number(0.0, 100.0, "decades", open_lo=True), default=None, metavar="D",
                   help="bound the spread log10(max EA / min EA) of the tendon stiffnesses to D decades")


def read_data_arg(text: str, min_points: int):
    """A data file, or ``bundled:NAME`` for a data set shipped with tenscell."""
    from ..io.data import bundled, read_csv

    if text.lower().startswith("bundled:"):
        return bundled(text.split(":", 1)[1])
    return read_csv(text, min_points=min_points)


def read_datasets(paths, prestress_options, min_points: int):
    """Read the data files and attach the prestresses stated by ``--prestress FILE=PA``."""
    stated = {}
    for opt in prestress_options or ():
        name, sep, value = opt.rpartition("=")
        if not sep or not name:
            raise ValueError(f"--prestress: expected FILE=PA (e.g. freq.csv=1000), got {opt!r}")
        match = [k for k, p in enumerate(paths) if name in (p, Path(p).name)]
        if len(match) != 1:
            raise ValueError(f"--prestress {opt}: {name!r} matches {len(match)} of the data files given "
                             f"({', '.join(paths)})")
        try:
            stated[match[0]] = float(value)
        except ValueError:
            raise ValueError(f"--prestress {opt}: {value!r} is not a number (Pa)") from None
    datasets = []
    for k, p in enumerate(paths):
        d = read_data_arg(p, min_points if len(paths) == 1 else 1)
        if k in stated:
            try:
                d = d.with_prestress(stated[k])
            except ValueError as err:
                raise ValueError(f"--prestress: {err}") from None
        datasets.append(d)
    return datasets


def fit_outputs(result, baseline, title):
    """Everything a fit writes, computed before any file is touched: {extension: writer(path)}."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_json, write_text
    from ..io.tables import fit_table
    from ..plotting.fits import fit_panels
    from ..reports.fit import fit_markdown

    doc = result.to_dict()
    doc["baseline"] = {k: v for k, v in baseline.to_dict().items()
                       if k in ("tendons", "damping", "rms_log10_error", "converged", "time_s", "parameters")}
    header, rows = fit_table(result, baseline)
    markdown = fit_markdown(result, baseline, title=title)
    fig = fit_panels(result, baseline=baseline, title=title)
    return {
        "json": lambda path: write_json(path, doc),
        "csv": lambda path: write_csv_rows(path, header, rows),
        "md": lambda path: write_text(path, markdown),
        "png": lambda path: plotting.save(fig, path),
    }


def run_fit(data, tendons, damping, starts, seed, jobs, tolerance, baseline_starts, **search):
    """The fit and its homogeneous baseline (the fit itself when it is homogeneous and unconstrained)."""
    from .. import fitting

    result = fitting.fit(data, tendons=tendons, damping=damping, starts=starts, seed=seed, jobs=jobs,
                         tolerance=tolerance, **search)
    constrained = search.get("min_prestress_share") or search.get("min_prestress_elasticity") or search.get(
        "max_decades")
    if tendons == "uniform" and damping == "uniform" and not constrained:
        baseline = result
    else:
        # the baseline only shows what a homogeneous cell cannot do: a short search suffices
        baseline = fitting.fit(data, tendons="uniform", starts=baseline_starts, seed=seed, jobs=1,
                               tolerance=tolerance, hops=10, patience=3)
    return result, baseline


def run(args) -> int:
    import sys

    from .. import fitting
    from .._progress import stage
    from ..io.outputs import OutputSet

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    datasets = read_datasets(args.data, args.prestress, fitting.required_points(args.tendons, args.damping))
    for k, data in enumerate(datasets):
        if data.n > args.max_points:
            datasets[k] = data.binned(args.max_points)
            stage(f"{data.source}: {data.n:,} points binned to {datasets[k].n:,} in log frequency "
                  f"(--max-points {args.max_points})")
    constraints = {"min_prestress_share": args.min_prestress_share, "max_decades": args.max_decades,
                   "min_prestress_elasticity": args.min_prestress_elasticity}
    fitting.make_problem(datasets, tendons=args.tendons, damping=args.damping, **constraints)  # bad input: before
    result, baseline = run_fit(datasets, args.tendons, args.damping, args.starts, args.seed, args.jobs,
                               args.tolerance, args.baseline_starts, **constraints)
    names = " and ".join(Path(p).name for p in args.data)
    outputs = fit_outputs(result, baseline, title=f"Tensegrity fit to {names}")
    with out as d:
        for ext, name in FIT_FILES.items():
            outputs[ext](d / name)
    verdict = "converged" if result.converged else "NOT converged"
    each = "; ".join(f"{Path(f.data.source).name} {f.rms_log10_error:.5f}" for f in result.fits)
    print(f"tenscell fit: rms log10 error {each} (tolerance {result.tolerance:g}): {verdict}; "
          f"homogeneous baseline {baseline.rms_log10_error:.5f}; {result.elapsed_s:.1f} s; wrote {out.target}/",
          file=sys.stderr)
    return 0 if result.converged else 1
