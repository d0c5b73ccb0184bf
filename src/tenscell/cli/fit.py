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


def register(sub) -> None:
    p = sub.add_parser(
        "fit", help="fit the tensegrity model to measured G', G'' (CSV)",
        description="Fit tendon stiffnesses, damping, prestress and strut length so that the model's G', G'' "
                    "match a CSV of measured moduli (frequency sweep, prestress sweep or |G|/phase; see "
                    "docs/fitting.md). Writes fit.json, fit.csv, fit.png and report.md into --out. Exit status 0 "
                    "if the RMS of the log10 errors reached --tolerance, 1 if not, 2 for bad input.")
    p.add_argument("data", help="CSV file of measured moduli")
    p.add_argument("--tendons", choices=TENDON_MODES, default="per-tendon",
                   help="stiffness per tendon (as in the paper), per family, or one for all")
    p.add_argument("--damping", choices=DAMPING_MODES, default="uniform",
                   help="damping c: one for all (as in the paper) or per family")
    p.add_argument("--starts", type=integer(1, 10_000), default=4, help="independent starts")
    p.add_argument("--seed", type=integer(0, 2**63 - 1), default=0,
                   help="random seed; the same seed gives the same fit")
    p.add_argument("--jobs", type=integer(1, 256), default=1, help="worker processes over the starts")
    p.add_argument("--tolerance", type=number(0.0, 10.0, "decades", open_lo=True), default=0.01,
                   help="RMS of the log10 errors (decades) the fit must reach")
    p.add_argument("--baseline-starts", type=integer(1, 10_000), default=2,
                   help="starts for the homogeneous baseline fit")
    p.add_argument("--max-points", type=integer(4, 100_000), default=100,
                   help="fit at most this many points: denser data is binned in log frequency per prestress "
                        "(weighted log means; the rule is in tenscell.io.thinning and the report)")
    add_out(p)
    p.set_defaults(func=run)


def fit_outputs(result, baseline, title):
    """Everything a fit writes, computed before any file is touched: {extension: writer(path)}."""
    from .. import fitting, plotting
    from ..io.outputs import write_csv_rows, write_json, write_text
    from ..io.tables import fit_table
    from ..reports.fit import fit_markdown

    doc = result.to_dict()
    doc["baseline"] = {k: v for k, v in baseline.to_dict().items()
                       if k in ("tendons", "damping", "rms_log10_error", "converged", "time_s", "parameters")}
    header, rows = fit_table(result, baseline)
    markdown = fit_markdown(result, baseline, title=title)
    curves = [fitting.model_curve(result), fitting.model_curve(baseline, label="homogeneous baseline")]
    fig = plotting.fit_figure(result.data, curves, title=title)
    return {
        "json": lambda path: write_json(path, doc),
        "csv": lambda path: write_csv_rows(path, header, rows),
        "md": lambda path: write_text(path, markdown),
        "png": lambda path: plotting.save(fig, path),
    }


def run_fit(data, tendons, damping, starts, seed, jobs, tolerance, baseline_starts, **search):
    """The fit and its homogeneous baseline (the fit itself when it is homogeneous)."""
    from .. import fitting
    from .._progress import stage

    result = fitting.fit(data, tendons=tendons, damping=damping, starts=starts, seed=seed, jobs=jobs,
                         tolerance=tolerance, **search)
    if tendons == "uniform" and damping == "uniform":
        baseline = result
    else:
        stage(f"homogeneous baseline: {baseline_starts} start(s)")
        baseline = fitting.fit(data, tendons="uniform", starts=baseline_starts, seed=seed, jobs=1,
                               tolerance=tolerance)
    return result, baseline


def run(args) -> int:
    import sys

    from .. import fitting
    from .._progress import stage
    from ..io.data import read_csv
    from ..io.outputs import OutputSet

    out = OutputSet(args.out, command=args.command_line, flag="--out")
    data = read_csv(args.data, min_points=fitting.required_points(args.tendons, args.damping))
    if data.n > args.max_points:
        raw_n = data.n
        data = data.binned(args.max_points)
        stage(f"{raw_n:,} points binned to {data.n:,} in log frequency (--max-points {args.max_points})")
    stage(f"fitting {data.n} points: {args.starts} start(s), stiffness {args.tendons}, damping {args.damping}, "
          f"{args.jobs} process(es)")
    result, baseline = run_fit(data, args.tendons, args.damping, args.starts, args.seed, args.jobs,
                               args.tolerance, args.baseline_starts)
    outputs = fit_outputs(result, baseline, title=f"Tensegrity fit to {Path(args.data).name}")
    with out as d:
        for ext, name in FIT_FILES.items():
            outputs[ext](d / name)
    verdict = "converged" if result.converged else "NOT converged"
    print(f"tenscell fit: rms log10 error {result.rms_log10_error:.5f} (tolerance {result.tolerance:g}): {verdict}; "
          f"homogeneous baseline {baseline.rms_log10_error:.5f}; {result.elapsed_s:.1f} s; wrote {out.target}/",
          file=sys.stderr)
    return 0 if result.converged else 1
