"""``tenscell fit``: fit any model to measured G', G'' or creep (files) and write the fit's output set.

One path for every model (the paper's Voigt cell, a mechanism, a structure-free formula): the same reading of the
data files (``--columns``, ``--units``, ``--step``...), the same checks of ``--bound``/``--fix`` against the model's
parameters before any fitting, the same hold-out, search, report, figure and fit.json.
"""
from __future__ import annotations

import argparse
import contextlib
import time
from pathlib import Path

from ._args import (RANGES, add_cluster_options, add_data_options, add_out, data_options_from_args, ensemble_size,
                    integer, number)
from ._cost import Cost

#: the fit's parametrizations (the same tuples as tenscell.fitting.TENDON_MODES / DAMPING_MODES,
#: written out so that building the parser does not import the fitting code; a test checks they agree)
TENDON_MODES = ("per-tendon", "per-family", "uniform")
DAMPING_MODES = ("uniform", "per-family")
#: the models of `--model` by group (tenscell.fitting.models.GROUPS, written out for a quick parser; a test checks
#: they agree), and the one recommended for a first fit (tenscell.fitting.models.RECOMMENDED)
MODEL_GROUPS = {
    "the paper's Voigt cell": ("voigt-per-tendon", "voigt-per-family", "voigt-uniform"),
    "mechanisms: Voigt tendons": ("voigt-compact", "voigt-compact+visc", "voigt-lognormal-damping",
                                  "voigt-lognormal-stiffness", "voigt-trap-damping+visc"),
    "mechanisms: filament turnover (Maxwell)": ("maxwell", "maxwell+visc"),
    "mechanisms: standard linear solid": ("sls", "sls-trap+visc"),
    "mechanisms: fractional tendons": ("springpot", "springpot+visc", "springpot-tension+visc",
                                       "springpot-alpha-family+visc", "springpot-lognormal-kappa+visc"),
    "structure-free formulas (baselines)": ("structural-damping", "structural-damping+newtonian",
                                            "structural-damping-prestress", "structural-damping-prestress+newtonian",
                                            "modified-power-law+constant"),
}
RECOMMENDED_MODEL = "springpot-alpha-family+visc"
MODEL_NAMES = tuple(n for names in MODEL_GROUPS.values() for n in names)
#: the name of tenscell 0.2 (every name --model takes)
MECHANISM_NAMES = MODEL_NAMES

#: the files of one fit: extension -> name in `tenscell fit --out` (report.html: report.md with its figures, one
#: self-contained page)
FIT_FILES = {"json": "fit.json", "csv": "fit.csv", "md": "report.md", "png": "fit.png", "html": "report.html"}
#: the profile-likelihood figure, written beside them when the fit profiled a parameter (`--profile`)
PROFILE_FILE = "profile.png"
#: the files an ensemble adds to an output set (`fit --model ... --ensemble K`, `study mechanisms`)
ENSEMBLE_FILES = ("ensemble.csv", "ensemble.png", "ensemble.md")


def _model_help() -> str:
    groups = "; ".join(f"{g}: {', '.join(names)}" for g, names in MODEL_GROUPS.items())
    return (f"what to fit (default: the paper's Voigt cell laid out by --tendons/--damping). For a first fit of "
            f"your own cells try {RECOMMENDED_MODEL} (few parameters; the tensegrity's geometric prestress "
            f"stiffness carries the prestress dependence; scored against its own structure-free formula in the report). Groups: {groups}. --fix/--bound take the model's parameter names or kinds")


#: the prestress (Pa) at which the bundled frequency data (fabry2001) were measured, for joint fits: the
#: baseline prestress of airway smooth muscle cells, where the bundled prestress data (stamenovic2002)
#: give G'(0.1 Hz) close to the frequency data's 280 Pa
BUNDLED_FREQUENCY_PRESTRESS_PA = 1000.0


def register(sub) -> None:
    p = sub.add_parser(
        "fit", help="fit the tensegrity model to measured G', G'', creep J(t) or relaxation G(t) (CSV; several files: "
                    "one joint fit)",
        description="Fit tendon stiffnesses, damping, prestress and strut length so that the model's G', G'' "
                    "match files of measured moduli (frequency sweep, prestress sweep or |G|/phase) or creep "
                    "compliance: tenscell's CSV, TA TRIOS and Anton Paar RheoCompass text exports, or CSV/TSV/Excel "
                    "tables whose headers say what they hold (else --columns/--units; see docs/importing-data.md "
                    "and docs/fitting.md). Several files are fitted jointly by one parameter set: a frequency sweep "
                    "that states its prestress (a prestress_Pa column, or --prestress FILE=PA) is linked to the "
                    "others by one prestress scale; otherwise its prestress is a fitted, reported parameter. "
                    "bundled:NAME reads a data set shipped with tenscell (fabry2001, stamenovic2002). "
                    "Writes fit.json, fit.csv, fit.png, report.md and report.html (the report with its figures: the "
                    "fit, the residuals, the profiles) into --out, and profile.png when a parameter was profiled. "
                    "Exit status 0 if every data "
                    "set's RMS of the log10 errors reached --tolerance or lies inside the data's own noise (their "
                    "sd columns), 1 if not, 2 for bad input.")
    p.add_argument("data", nargs="+", help="file(s) of measured moduli, creep compliance or stress relaxation, or "
                                           "bundled:NAME")
    p.add_argument("--prestress", action="append", type=stated_prestress, metavar="FILE=PA",
                   help="the prestress (Pa) at which the data in FILE were measured (repeatable)")
    p.add_argument("--tendons", choices=TENDON_MODES, default="per-tendon",
                   help="stiffness per tendon (as in the paper), per family, or one for all")
    p.add_argument("--damping", choices=DAMPING_MODES, default="uniform",
                   help="damping c: one for all (as in the paper) or per family")
    p.add_argument("--model", choices=MODEL_NAMES, default=None, metavar="NAME", help=_model_help())
    e = p.add_argument_group("ensemble (with --model of a mechanism whose tendon values are drawn from a "
                             "distribution)")
    e.add_argument("--ensemble", type=ensemble_size, default=0, metavar="K",
                   help="evaluate the fitted mechanism over K assignments at the data's prestresses and frequencies "
                        "(ensemble.csv, .png, .md: mean, spread between assignments, the fit's own average; "
                        "0: none), on the population engine")
    add_cluster_options(e)
    add_constraints(p)
    add_data_options(p)
    p.add_argument("--bound", action="append", type=_bound, metavar="KIND=LO:HI", default=None,
                   help="bounds of every parameter of a kind, in SI units (repeatable): EA (N), c (N·s/m), P (N), "
                        "s (m²), P_data (Pa), L (m); e.g. --bound EA=1e-3:1e3")
    p.add_argument("--anchored", nargs="?", const="", default=None, metavar="FACTOR|exact",
                   help="hold the model's physical prestress σ (the tendons' virial stress, Σ T·l/(3V) over the hull "
                        "of the nodes; docs/conventions.md) within ×/÷FACTOR of the measured prestress (default 1.5), "
                        "or equal to it (exact); needs a data set that states its prestress in Pa. Written "
                        "--anchored=exact or --anchored 2 before another flag")
    p.add_argument("--gauge-window", action="store_true",
                   help="hold the prestress scale s in [0.01, 100] m² (strut lengths 0.1-10 m in the paper's "
                        "convention; the same as --bound s=0.01:100): a window on the gauge, not an anchor (it never "
                        "binds on the bundled data; --anchored is the physical anchor)")
    p.add_argument("--fix", action="append", type=_fixed, metavar="NAME=VALUE", default=None,
                   help="hold a parameter fixed, by its name in fit.json, in SI units (repeatable): e.g. --fix L=1, "
                        "--fix c=0.5, --fix P=20, --fix c_actin=2, --fix EA_intermediate_filament=0.3")
    p.add_argument("--validate", choices=("auto", "yes", "no"), default="auto",
                   help="refit the model and its structure-free baselines (its own formula, the structural-damping "
                        "law with and without a Newtonian term) on held-out splits of the data (frequency sweeps cut "
                        "at 1, 10, 30 Hz; prestress sweeps without some prestresses) and rank them in the report by "
                        "their held-out error; auto: when it costs at most a quarter of the fit's own CPU, else the "
                        "line says what it would cost")
    p.add_argument("--profile", choices=("auto", "yes", "no"), default="auto",
                   help="profile-likelihood intervals of the parameters the local analysis cannot bound (at a bound, "
                        "undetermined, one-sided) and of a mechanism's held fields: each held at 9 values over its "
                        "bounds while the others are refitted (about 15-20 refits per parameter), in the report and "
                        "fit.json; auto: for models with at most 12 free parameters, when it costs at most a quarter of "
                        "the fit's own CPU, else the line says what it would cost")
    p.add_argument("--holdout", type=_holdout, metavar="FMIN:FMAX", default=None,
                   help="train on the points outside FMIN..FMAX Hz and report every model's error on the held-out "
                        "points (one frequency sweep)")
    p.add_argument("--starts", type=integer(1, 10_000), default=4, help="independent starts")
    p.add_argument("--seed", type=integer(0, 2**63 - 1), default=0,
                   help="random seed; the same seed gives the same fit")
    p.add_argument("--jobs", type=integer(1, 256), default=None,
                   help="worker processes over the starts (default: one per CPU, at most --starts;"
                        " the result does not depend on it)")
    p.add_argument("--tolerance", type=number(0.0, 10.0, "decades", open_lo=True), default=0.01,
                   help="RMS of the log10 errors (decades) every data set must reach")
    p.add_argument("--baseline-starts", type=integer(1, 10_000), default=2,
                   help="starts for the homogeneous baseline fit")
    p.add_argument("--max-points", type=integer(4, 100_000), default=100,
                   help="fit at most this many points: denser data is binned in log frequency (moduli) or log time "
                        "(creep) per prestress (weighted log means; the rule and the weights are in "
                        "tenscell.io.thinning and the report)")
    add_out(p)
    p.set_defaults(func=run)


#: parameter kinds that --bound takes, with their units
BOUND_UNITS = {"EA": "N", "c": "N·s/m", "P": "N", "s": "m²", "P_data": "Pa", "L": "m"}
#: allowed bounds of each kind: the ranges of the matching flags (s = P / P_data spans their ratio)
BOUND_RANGES = {"EA": RANGES["EA"][:2], "c": RANGES["c"][:2], "P": RANGES["prestress"][:2],
                "P_data": RANGES["prestress"][:2], "L": RANGES["L"][:2],
                "s": (RANGES["prestress"][0] / RANGES["prestress"][1], RANGES["prestress"][1] / RANGES["prestress"][0])}


def _pair(text: str, flag: str, example: str) -> tuple[str, str]:
    name, sep, value = str(text).partition("=")
    if not sep or not name.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"expected {example}, got {str(text)[:40]!r}")
    return name.strip(), value.strip()


def _bound(text):
    kind, value = _pair(text, "--bound", "KIND=LO:HI (e.g. EA=1e-3:1e3)")
    if kind not in BOUND_UNITS and not kind.isidentifier():
        raise argparse.ArgumentTypeError(f"unknown parameter kind {kind!r}; kinds: {', '.join(BOUND_UNITS)} "
                                         "(or, with --model, a parameter name of the mechanism)")
    # a mechanism's parameter names (--model) are checked against the mechanism before any fitting
    unit = BOUND_UNITS.get(kind, "")
    u = f" {unit}" if unit else ""
    parts = value.split(":")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"{kind}: expected LO:HI in {unit or 'SI units'}, got {value[:40]!r}")
    try:
        lo, hi = (number()(x) for x in parts)  # numbers first: a reversed interval is named as such
        if not lo < hi:
            raise argparse.ArgumentTypeError(f"{kind}={value}: reversed or empty interval; the lower bound {lo:g}{u} "
                                             f"must be below the upper bound {hi:g}{u} (LO:HI)")
        check = number(*BOUND_RANGES[kind], unit) if kind in BOUND_RANGES else number(0.0, None, "", open_lo=True)
        lo, hi = (check(x) for x in parts)
    except argparse.ArgumentTypeError as err:
        raise argparse.ArgumentTypeError(str(err) if str(err).startswith(f"{kind}=") else f"{kind}: {err}") from None
    return kind, (lo, hi)


_bound.__name__ = "bound"


def _fixed(text):
    name, value = _pair(text, "--fix", "NAME=VALUE (e.g. L=1)")
    return name, number(0.0, None, "", open_lo=True)(value)


_fixed.__name__ = "fixed value"


def _holdout(text):
    parts = str(text).split(":")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"expected FMIN:FMAX in Hz, got {str(text)[:40]!r}")
    lo, hi = (number(quantity="frequency")(x) for x in parts)
    if not lo < hi:
        raise argparse.ArgumentTypeError(f"FMIN {lo:g} Hz must be below FMAX {hi:g} Hz")
    return lo, hi


_holdout.__name__ = "holdout window"


def spec_from_args(args):
    """The model to fit: ``--model NAME``, or the Voigt cell of ``--tendons``, ``--damping`` and the constraints.

    ValueError naming the flag for a Voigt flag given with another model.
    """
    from ..fitting.models import get_model

    voigt = {"tendons": (args.tendons, "per-tendon", "--tendons"), "damping": (args.damping, "uniform", "--damping"),
             "min_prestress_share": (getattr(args, "min_prestress_share", None), None, "--min-prestress-share"),
             "max_decades": (getattr(args, "max_decades", None), None, "--max-decades"),
             "min_prestress_elasticity": (getattr(args, "min_prestress_elasticity", None), None,
                                          "--min-prestress-elasticity")}
    given = {k: v for k, (v, default, _) in voigt.items() if v != default}
    spec = get_model("voigt-per-tendon" if args.model is None else args.model)
    if spec.capabilities.voigt_options:  # --model voigt-per-family: --tendons may only agree with it
        if args.model is not None and "tendons" in given and given["tendons"] != spec.tendons:
            raise ValueError(f"--tendons {given['tendons']} contradicts --model {args.model}")
        options = {k: v for k, (v, _, _) in voigt.items() if args.model is None or k != "tendons"}
        return spec.with_options(**options)
    if given:
        flag = voigt[next(iter(given))][2]
        raise ValueError(f"{flag} applies to the Voigt cell (no --model, or --model voigt-*), not to --model "
                         f"{args.model}")
    return spec


def anchor_from_args(args):
    """The anchor of ``--anchored [FACTOR|exact]`` (None without the flag); ValueError in one line naming the flag
    and its syntax, before any file is read."""
    text = getattr(args, "anchored", None)
    if text is None:
        return None
    if getattr(args, "gauge_window", False):
        raise ValueError("--anchored holds σ to the measured prestress and --gauge-window holds s in 0.01-100 m²: "
                         "give one of them")
    from ..fitting.anchor import parse_anchor

    return parse_anchor(text)


def _no_scale(flag: str, plain) -> None:
    if "s" not in plain.names:
        raise ValueError(f"{flag}: this fit has no prestress scale s (no data set states its prestress in Pa: "
                         "give a prestress sweep, or --prestress FILE=PA)")


def _anchored(bounds: dict, fixed: dict, plain, anchor, cell) -> tuple[dict, dict]:
    """``bounds`` and ``fixed`` with σ held to the measured prestress (``--anchored``)."""
    flag = f"--anchored{'=exact' if anchor.is_exact else ''}"
    if "s" in bounds or "s" in fixed:
        how = "--bound s=LO:HI" if "s" in bounds else "--fix s=VALUE"
        raise ValueError(f"{flag} sets the prestress scale s itself (σ held {anchor.label} of the measured "
                         f"prestress); give it or {how}, not both")
    if cell is None:
        raise ValueError(f"{flag}: model {plain.spec.name} is a structure-free formula: it has no structure, so no "
                         "σ to hold to the measured prestress")
    _no_scale("--anchored", plain)
    opts = anchor.fit_options(cell, plain.names, fixed)
    return {**bounds, **opts["bounds"]}, opts["fixed"]


def _gauge_window(bounds: dict, plain) -> dict:
    """``bounds`` with the prestress scale in the gauge window (``--gauge-window``)."""
    from ..fitting.shares import GAUGE_WINDOW_S

    if "s" in bounds:
        raise ValueError("--gauge-window sets the prestress scale's bounds itself (s in 0.01-100 m²); give it or "
                         "--bound s=LO:HI, not both")
    _no_scale("--gauge-window", plain)
    return {**bounds, "s": GAUGE_WINDOW_S}


def search_space(args, datasets, spec) -> dict:
    """``bounds`` and ``fixed`` as keyword arguments of :func:`tenscell.fitting.fit`, checked against ``spec``'s
    parameters for these data (each --bound kind or name and --fix name named with the flag, in the units typed)
    before any fitting."""
    import math

    plain = spec.problem(datasets)
    bounds = dict(args.bound or ())
    user_fixed = dict(args.fix or ())
    anchor = anchor_from_args(args)
    if getattr(args, "gauge_window", False):
        bounds = _gauge_window(bounds, plain)
    if anchor is not None:
        bounds, user_fixed = _anchored(bounds, user_fixed, plain, anchor, plain.cell)
    for key, (lo, hi) in bounds.items():
        if key not in plain.kinds and key not in plain.names:
            raise ValueError(f"--bound {key}={lo:g}:{hi:g}: no parameter or parameter kind {key!r} in this fit "
                             f"(kinds here: {', '.join(dict.fromkeys(plain.kinds))}; parameters: "
                             f"{_names_text(plain.names)})")
    try:
        bounded = spec.problem(datasets, bounds=bounds)
    except ValueError as err:
        raise ValueError(f"--bound: {err}") from None
    fixed = user_fixed
    lower, upper = [math.exp(x) for x in bounded.lower], [math.exp(x) for x in bounded.upper]
    for name, v in fixed.items():
        if name not in plain.names:
            raise ValueError(f"--fix {name}={v:g}: no parameter named {name!r} in this fit (parameters: "
                             f"{_names_text(plain.names)})")
        i = plain.names.index(name)
        unit = plain.units[i]
        if not lower[i] <= v <= upper[i]:
            raise ValueError(f"--fix {name}={v:g}: outside its bounds [{lower[i]:.6g}, {upper[i]:.6g}] {unit} "
                             f"(widen them with --bound {plain.kinds[i]}=LO:HI)")
    space = {"bounds": bounds or None, "fixed": fixed or None}
    spec.problem(datasets, **space)
    return space


def check_contradictions(args) -> None:
    """Refuse flags that contradict each other (before any file is read)."""
    if getattr(args, "max_decades", None) is not None and args.tendons == "uniform":
        raise ValueError(f"--max-decades {args.max_decades:g} bounds the spread of the tendon stiffnesses; with "
                         "--tendons uniform there is one stiffness and no spread (use per-family or per-tendon)")


def _names_text(names) -> str:
    per_tendon = [n for n in names if n.startswith("EA[")]
    rest = [n for n in names if not n.startswith("EA[")]
    return ", ".join(([f"EA[0]..EA[{len(per_tendon) - 1}]"] if per_tendon else []) + rest)


def add_constraints(p) -> None:
    """The search-space constraints: ``--min-prestress-share``, ``--min-prestress-elasticity``, ``--max-decades``."""
    p.add_argument("--min-prestress-share", type=number(0.0, 1.0, open_lo=True), default=None, metavar="S",
                   help="keep the prestress mechanically active: P·Kp must carry at least this share (0-1) of "
                        "the static stiffness at every prestress of the data")
    # at most 1: with K0 = Ke + P·Kp, Ke positive semi-definite, the static elasticity is the prestress share
    # (<= 1, 1 when P·Kp carries all the stiffness); at 0.1 Hz, 300 random paper cells (EA, c, P over eight
    # decades) gave at most 0.95. A bound above 1 is one no cell meets
    p.add_argument("--min-prestress-elasticity", type=number(0.0, 1.0, open_lo=True), default=None, metavar="E",
                   help="keep the prestress mechanically active: dlnG'/dlnP at 0.1 Hz must be at least E at every "
                        "prestress of the data (0 < E <= 1, 1 meaning G' proportional to P; adherent cells: about "
                        "0.7)")
    p.add_argument("--max-decades", type=number(0.0, 100.0, "decades", open_lo=True), default=None, metavar="D",
                   help="bound the spread log10(max EA / min EA) of the tendon stiffnesses to D decades")


def read_data_arg(text: str, min_points: int, options: dict | None = None):
    """A data file (moduli or creep compliance; tenscell's CSV, an instrument export or a table with recognised
    headers, see :func:`tenscell.io.readers.read_data`), or ``bundled:NAME`` for a data set shipped with
    tenscell. ``options``: :func:`~tenscell.cli._args.data_options_from_args` (column map, units, step, checks
    accepted)."""
    from ..io.readers import read_data

    options = dict(options or {})
    units = options.pop("units", None) or {}
    return read_data(text, min_points=min_points, **options, **units)


def stated_prestress(text):
    """An argparse ``type``: ``FILE=PA``, the prestress (Pa, in the range of --prestress) of a data file."""
    name, sep, value = str(text).rpartition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"expected FILE=PA (e.g. freq.csv=1000), got {str(text)[:40]!r}")
    lo, hi, _ = RANGES["prestress"]
    return name.strip(), number(lo, hi, "Pa")(value)


stated_prestress.__name__ = "stated prestress"


def read_datasets(paths, prestress_options, min_points: int, options: dict | None = None):
    """Read the data files (with the column map, units and step of ``options``, see
    :func:`~tenscell.cli._args.data_options_from_args`) and attach the prestresses stated by ``--prestress FILE=PA``
    ((file, Pa) pairs)."""
    seen: dict = {}
    for p in paths:
        key = p.lower() if p.lower().startswith("bundled:") else Path(p).resolve()
        if key in seen:
            raise ValueError(f"{p} is given twice (as {seen[key]} too): a joint fit would count its points twice")
        seen[key] = p
    stated: dict[int, float] = {}
    for name, value in prestress_options or ():
        match = [k for k, p in enumerate(paths) if name in (p, Path(p).name)]
        if len(match) != 1:
            raise ValueError(f"--prestress {name}={value:g}: {name!r} matches {len(match)} of the data files given "
                             f"({', '.join(paths)})")
        if match[0] in stated:
            raise ValueError(f"--prestress {name}={value:g}: {name} already has --prestress "
                             f"{name}={stated[match[0]]:g}; one prestress per file")
        stated[match[0]] = value
    datasets = []
    for k, p in enumerate(paths):
        d = read_data_arg(p, min_points if len(paths) == 1 else 1, options)
        if k in stated:
            try:
                d = d.with_prestress(stated[k])
            except ValueError as err:
                raise ValueError(f"--prestress: {err}") from None
        datasets.append(d)
    return datasets


def read_inputs(args, min_points: int) -> tuple[list, list[str]]:
    """The fit command's data and what to say about them: every file read with the data flags, the stated
    prestresses attached, data denser than ``--max-points`` binned; with one line per file saying what was read
    (layout, step, temperature, conversions: :meth:`~tenscell.io.provenance.Provenance.line`) and how it was
    binned, for the command to print once every check has passed (a refusal stays one line)."""
    from ..io.thinning import bin_datasets

    datasets = read_datasets(args.data, args.prestress, min_points, data_options_from_args(args))
    binned = bin_datasets(datasets, args.max_points)
    lines = []
    for path, data, thin in zip(args.data, datasets, binned):
        lines.append(data.provenance.line())
        if thin is not data:
            axis = "time" if data.kind == "creep" else "frequency"
            weights = "each bin weighing as one point" if thin.counts is None and not thin.has_sd else \
                "each bin weighing √(its points)" if not thin.has_sd else "weighted by the stated SDs"
            lines.append(f"{data.n:,} points of {Path(path).name} binned to {thin.n:,} in log {axis} (--max-points "
                         f"{args.max_points}; {weights})")
    return list(binned), lines


def fit_outputs(result, baseline, title, comparison=None, timing=None, figure=None, validation=None):
    """Everything a fit writes, computed before any file is touched: {extension: writer(path)}.

    ``validation`` (optional): the model and its baselines out of sample
    (:func:`tenscell.fitting.validation.compare_out_of_sample`), in fit.json and the report.

    ``timing`` (optional): the command's own clock, stored in fit.json as is.
    ``figure`` (optional): a future of the figures' PNG bytes (:func:`fit_figures`,
    drawn in a worker process meanwhile); without it the figures are drawn here.

    The keys are those of :data:`FIT_FILES`, and ``"profile"`` (:data:`PROFILE_FILE`) when the result holds
    profiles (:meth:`~tenscell.fitting.FitResult.compute_profile`).
    """
    from ..io.outputs import write_bytes, write_csv_rows, write_json, write_text
    from ..io.tables import fit_table
    from ..reports.fit import fit_markdown
    from ..reports.html_page import fit_report_html

    doc = result.to_dict()
    own = baseline is result  # a fit that is its own baseline (a homogeneous Voigt cell, a formula)
    doc["baseline"] = None if own else {k: v for k, v in baseline.to_dict().items()
                                        if k in ("model_name", "tendons", "damping", "rms_log10_error", "converged",
                                                 "time_s", "parameters", "AIC", "BIC")}
    if comparison is None:
        from ..fitting.scores import compare_models

        comparison = compare_models(result, homogeneous=baseline)
    doc["model_comparison"] = comparison.to_dict()
    doc["out_of_sample"] = None if validation is None else validation.to_dict()
    if timing is not None:
        doc["timing"] = timing
    header, rows = fit_table(result, baseline)
    report_baseline = None if own else baseline
    markdown = fit_markdown(result, report_baseline, title=title, comparison=comparison, validation=validation)
    # drawn here without a worker's: only then does this process import the plotting stack (0.35 s)
    pngs = fit_figures(result, baseline, title, result.profile) if figure is None else figure.result()
    html = fit_report_html(result, report_baseline, title=title, comparison=comparison, validation=validation,
                           figures=pngs)
    outputs = {
        "json": lambda path: write_json(path, doc),
        "csv": lambda path: write_csv_rows(path, header, rows),
        "md": lambda path: write_text(path, markdown),
        "png": lambda path: write_bytes(path, pngs["fit"]),
        "html": lambda path: write_text(path, html),
    }
    if pngs.get("profile"):
        outputs["profile"] = lambda path: write_bytes(path, pngs["profile"])
    return outputs


def fit_figures(result, baseline, title, profile=None) -> dict:
    """The fit's figures as PNG bytes: ``"fit"`` (data and model, fit.png), ``"residuals"`` and, for a
    :class:`~tenscell.fitting.profile.ProfileSet` that profiled something, ``"profile"`` (profile.png). For a
    worker process (a pickled result carries no profile: it is passed beside it); the images are those
    :func:`fit_outputs` draws."""
    from .. import plotting
    from ..plotting.fits import fit_panels, profile_panels, residual_panels

    pngs = {"fit": plotting.png_bytes(fit_panels(result, baseline=baseline, title=title)),
            "residuals": plotting.png_bytes(residual_panels(result, baseline=baseline))}
    if profile is not None and len(profile.profiles):
        pngs["profile"] = plotting.png_bytes(profile_panels(profile, title=f"Profile likelihood: {title}"))
    return pngs


def _warm_plotting() -> None:
    """Import the plotting stack in the worker while the fit runs, so that drawing the figure starts at once."""
    from ..plotting import fits  # noqa: F401


def _baseline_fit(data, spec, starts, seed, tolerance):
    """A baseline: it only shows what a simpler model does on the same data, so a short search suffices."""
    from .. import fitting

    return fitting.fit(data, model=spec, starts=starts, seed=seed, jobs=1, tolerance=tolerance, hops=10,
                       patience=3, max_points=None, progress=False)


def run_fit(data, spec, starts, seed, jobs, tolerance, baseline_starts, *, worker=None, warm_plotting: bool = False,
            **search):
    """The fit of ``spec`` and its baseline (:func:`tenscell.fitting.models.baseline_of`: the homogeneous cell for
    a Voigt fit, the lumped structure-free formula for a mechanism; the fit itself where there is none).

    The baseline runs in a worker process beside the fit (``worker``, from
    :func:`tenscell._parallel.background`, or one of its own): it is
    independent of the fit and, with the default one job, would otherwise wait
    for a core that sits idle. Its result does not depend on this (same seed).
    With ``warm_plotting`` the worker then imports the plotting stack, after
    the baseline (which is needed first), for a figure drawn there later.
    """
    from .. import fitting
    from .._parallel import background
    from .._progress import stage
    from ..fitting.models import baseline_of

    def main_fit():
        # the command has binned the data already, by its own --max-points
        return fitting.fit(data, model=spec, starts=starts, seed=seed, jobs=jobs, tolerance=tolerance,
                           max_points=None, **search)

    base = baseline_of(spec)
    if base is None and not warm_plotting:  # nothing for a worker to do
        result = main_fit()
        return result, result
    if base is not None:
        stage(f"baseline {base.name}: {baseline_starts} start(s), in a process of its own")
    with background() if worker is None else contextlib.nullcontext(worker) as bg:
        task = None if base is None else bg.submit(_baseline_fit, data, base, baseline_starts, seed, tolerance)
        if warm_plotting:
            bg.submit(_warm_plotting)
        result = main_fit()
        baseline = result if task is None else task.result()
    return result, baseline


class _Clock:
    """The command's own clock: seconds since :func:`tenscell.cli.main` began (or since the fit, when run directly)."""

    def __init__(self, started: float | None):
        self.started = time.monotonic() if started is None else started
        self.fit_started = self.now()

    def now(self) -> float:
        return round(time.monotonic() - self.started, 4)

    def timing(self, result) -> dict:
        """fit.json's "timing": when the fit began, first met its tolerance, and ended; then the baseline."""
        met = result.time_to_tolerance_s
        return {
            "clock": "seconds since the tenscell command started (after the interpreter and its first import)",
            "fit_started_s": self.fit_started,
            "tolerance_met_s": None if met is None else round(self.fit_started + met, 4),
            "fit_finished_s": round(self.fit_started + result.elapsed_s, 4),
            "baseline_finished_s": self.now(),
        }


def run(args) -> int:
    """``tenscell fit``: with one BLAS thread throughout, as on the library's hot paths (:mod:`tenscell._threads`):
    the report's quantities and the figures evaluate the fitted model outside them, and with several BLAS threads
    on a busy machine these small products cost several times the fit's CPU (measured: 21 s against 10 s for the
    whole command at a load of 2 on 2 CPUs); its worker processes inherit the setting. The fitting stack is imported
    first: it loads scipy's own BLAS, which a limit set before it was loaded would not reach."""
    from .. import fitting  # noqa: F401  (loads every BLAS library the command uses)
    from .._threads import limited

    with limited():
        return _run(args)


def _run(args) -> int:
    import sys

    from .._parallel import background, jobs_for
    from .._progress import stage
    from ..io.outputs import OutputSet
    from ._cost import announce

    spec = spec_from_args(args)
    check_contradictions(args)
    anchor_from_args(args)  # a bad --anchored: one line before any file is read
    _check_ensemble(args, spec)
    out = OutputSet(args.out, command=args.command_line, flag="--out")
    datasets, read_lines = read_inputs(args, _min_points(spec))
    held = None
    if args.holdout is not None:
        datasets, held = _split_holdout(args, datasets)
    space = search_space(args, datasets, spec)  # bad input: before any fitting
    for line in read_lines:  # what was read, now that every check has passed
        stage(line)
    args.jobs = jobs_for(args.starts, args.jobs)
    cost = fit_cost(spec, datasets, args)
    if cost.seconds > ANNOUNCE_S:
        announce(cost)
    stage(f"fitting {sum(d.n for d in datasets)} points with {spec.name}: {args.starts} start(s), "
          f"{args.jobs} process(es)")
    clock = _Clock(getattr(args, "started", None))
    names = " and ".join(Path(p).name for p in args.data)
    title = f"Fit of {spec.name} to {names}"
    with background() as worker:
        # while the fit runs, the worker fits the baseline and imports the plotting stack; then it draws the
        # figure while this process writes the report: the figure is most of the time after the fit
        cpu = _cpu_s()
        result, baseline = run_fit(datasets, spec, args.starts, args.seed, args.jobs, args.tolerance,
                                   args.baseline_starts, worker=worker, warm_plotting=True, **space)
        fit_cpu = _cpu_s() - cpu  # its worker processes included (joined when the search ended)
        _profile(args, result, fit_cpu)
        timing = clock.timing(result)
        timing["outputs_started_s"] = clock.now()
        # the report's ± need one model evaluation per parameter: half of them in the worker, before the figure
        result.compute_derived(worker)
        figure = worker.submit(fit_figures, result, baseline, title, result.profile)
        from ..fitting.scores import compare_models

        comparison = compare_models(result, homogeneous=baseline, held_out=held, holdout=args.holdout)
        validation = _validation(args, spec, datasets, space, result, fit_cpu)
        outputs = fit_outputs(result, baseline, title=title, comparison=comparison, timing=timing, figure=figure,
                              validation=validation)
    ensemble = _ensemble(args, result, datasets)
    with out as d:
        files = {**FIT_FILES, "profile": PROFILE_FILE}
        for key, write in outputs.items():
            write(d / files[key])
        if ensemble is not None:
            write_ensemble(d, ensemble, f"Ensemble of the fitted `{spec.name}`")
    each = "; ".join(f"{Path(f.data.source).name} {f.rms_log10_error:.5f}" for f in result.fits)
    base = "" if baseline is result else f"; baseline {baseline.spec.name} {baseline.rms_log10_error:.5f}"
    print(f"tenscell fit: {spec.name}: rms log10 error {each} (tolerance {result.tolerance:g}): {result.verdict}"
          f"{base}; {result.elapsed_s:.1f} s; wrote {out.target}/", file=sys.stderr)
    return 0 if result.converged else 1


#: free parameters above which --validate auto skips the refits (the per-tendon cell: 36 parameters per refit)
VALIDATE_AUTO_MAX_PARAMETERS = 12
#: --validate auto and --profile auto run their refits when expected to cost at most this share of the fit's CPU
AUTO_SHARE = 0.25


def _cpu_s() -> float:
    """CPU seconds of this process and of its finished children (a search's worker processes)."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + r.ru_utime + r.ru_stime


def _validation(args, spec, datasets, space, result, fit_cpu: float):
    """The model and its structure-free baselines out of sample (``--validate``), or None: the model's refits start
    warm at its fit (``result``) and are checked against it, each baseline's at its own fit to all the data.
    ``fit_cpu``: the fit's own CPU seconds, against which auto weighs the refits (each split: the model refitted
    with half the fit's starts, each baseline formula for about a tenth of that)."""
    from .._progress import stage
    from ..fitting.validation import compare_out_of_sample, splits, standard_baselines

    if args.validate == "no":
        return None
    if args.validate == "auto" and spec.problem(datasets).n_free > VALIDATE_AUTO_MAX_PARAMETERS:
        stage(f"out of sample: not run for {spec.name} ({VALIDATE_AUTO_MAX_PARAMETERS}+ parameters per refit; "
              "--validate yes runs it)")
        return None
    n = len(splits(datasets))
    cost = n * fit_cpu * (2 / args.starts) * (1 + 0.1 * (1 + len(standard_baselines(datasets))))
    if args.validate == "auto" and cost > AUTO_SHARE * fit_cpu:
        stage(f"out of sample: not run by default ({n} splits, refits of about {cost:.0f} s of CPU against "
              f"{fit_cpu:.1f} s for the fit; --validate yes runs them)")
        return None
    validation = compare_out_of_sample(spec, datasets, standard_baselines(datasets), model_options=space,
                                       full={spec.name: result}, notify=stage, starts=2, seed=args.seed, hops=8,
                                       patience=3, tolerance=args.tolerance, max_points=None)
    return validation if validation.splits else None  # no split leaves enough points to fit every model


#: an estimated run longer than this (s) is announced before it starts (`tenscell fit`, its profile)
ANNOUNCE_S = 10.0
#: basin-hopping moves of a fit (fitting.fit's default; the command line does not change it)
FIT_HOPS = 30


def _evaluation_time(problem, theta) -> float:
    """Seconds of one model evaluation (residuals and Jacobian) of ``problem`` at ``theta``, measured now (under the
    machine's present load) with the BLAS threads the search uses."""
    from .._threads import limited
    from ._cost import measure

    with limited():
        return measure(lambda: problem.jacobian(theta), max_calls=5)


def fit_cost(spec, datasets, args) -> Cost:
    """The fit's estimated cost (:class:`tenscell.cli._cost.Cost`): one model evaluation timed here, × the
    evaluations its search is expected to take (:data:`tenscell.fitting.search.EVALUATIONS_PER_START_HOP` × starts ×
    (hops + 1)), over its processes; the baseline runs beside it, the profile is estimated when its parameters are
    known."""
    import numpy as np

    from ..fitting.entry import prepare
    from ..fitting.models.catalog import PER_TENDON_VOIGT
    from ..fitting.search import EVALUATIONS_PER_START_HOP

    problem = spec.problem(*prepare(datasets, None, args.max_points, spec))
    per = _evaluation_time(problem, problem.initial_guess(np.random.default_rng(args.seed)))
    rate = EVALUATIONS_PER_START_HOP["voigt-per-tendon" if spec.name == PER_TENDON_VOIGT else "mechanism"]
    runs = args.starts * (FIT_HOPS + 1)
    return Cost("model evaluation", int(round(rate * runs)), per, max(1, min(args.jobs, args.starts)),
                detail=f"of {problem.n_free} free parameters: {args.starts} start(s) × up to {FIT_HOPS + 1} "
                       f"least-squares runs × about {rate:g} evaluations; fewer when the tolerance is met early")


def profile_cost(result, names, fit_cpu: float | None = None) -> Cost:
    """The profile's estimated cost: per parameter, at most the refits its bar counts (the grid, the thresholds,
    the refinements), each about :data:`~tenscell.fitting.profile.REFIT_EVALUATIONS` model evaluations (a warm run
    and one move), at the CPU per evaluation of the fit itself (``fit_cpu`` s over its evaluations: the search's
    own overhead included, as the refits pay it), or of one evaluation timed here without ``fit_cpu``."""
    from ..fitting.profile import DEFAULT_POINTS, DEFAULT_REFINE, REFIT_EVALUATIONS

    if fit_cpu is not None and result.n_evaluations > 0:
        per, basis = fit_cpu / result.n_evaluations, "the fit's CPU per evaluation"
    else:
        per, basis = _evaluation_time(result.problem, result.theta), "one evaluation timed"
    per_parameter = DEFAULT_POINTS + 4 + 4 * DEFAULT_REFINE
    return Cost("refit", len(names) * per_parameter, per * REFIT_EVALUATIONS, 1,
                detail=f"at most: {len(names)} parameter(s) × {per_parameter} refits, each about "
                       f"{REFIT_EVALUATIONS} evaluations of {result.n_free - 1} free parameters at {basis}")


def _profile(args, result, fit_cpu: float) -> None:
    """``--profile``: the profile intervals of the parameters that need them, kept on the result (or none); the
    estimate first when it is long. ``auto`` runs them when they are expected to cost at most :data:`AUTO_SHARE` of
    the fit's own CPU (``fit_cpu`` s), and otherwise says what they would cost."""
    if args.profile == "no":
        return
    from .._progress import stage
    from ..fitting.profile import profile_plan
    from ._cost import announce

    mode = "needed" if args.profile == "yes" else "auto"
    todo, _ = profile_plan(result, mode)
    if todo:
        cost = profile_cost(result, [n for n, _ in todo], fit_cpu)
        if args.profile == "auto" and cost.seconds > AUTO_SHARE * fit_cpu:
            stage(f"profile: not run by default ({', '.join(n for n, _ in todo[:8])}"
                  f"{', ...' if len(todo) > 8 else ''}: {cost.line()}, against {fit_cpu:.1f} s of CPU for the fit; "
                  "--profile yes runs it)")
            return
        if cost.seconds > ANNOUNCE_S:
            stage(f"profile of {len(todo)} parameter(s) the local analysis cannot bound: "
                  f"{', '.join(n for n, _ in todo[:8])}{', ...' if len(todo) > 8 else ''}")
            announce(cost)
    profile = result.compute_profile(mode, notify=lambda line: stage(line))
    stage(f"profile: {profile.not_run}" if profile.not_run else
          f"profile: {len(profile)} parameter(s), {profile.refits} refits, {profile.cpu_s:.1f} s CPU")


def _min_points(spec) -> int:
    """Points a single data set needs for this model (the layout's own check is exact; this one reads early)."""
    return spec.min_points()


def _split_holdout(args, datasets):
    """``--holdout FMIN:FMAX``: (the training data, the held-out points) of one frequency sweep."""
    if len(datasets) != 1:
        raise ValueError(f"--holdout applies to one frequency sweep, got {len(datasets)} data sets")
    if datasets[0].kind == "creep":
        raise ValueError(f"--holdout applies to a frequency sweep of G', G''; {args.data[0]} holds creep "
                         "compliance J(t)")
    from ..fitting.scores import split_holdout

    try:
        train, held = split_holdout(datasets[0], *args.holdout)
    except ValueError as err:
        raise ValueError(f"--holdout {args.holdout[0]:g}:{args.holdout[1]:g}: {err}") from None
    return [train], held


def _check_ensemble(args, spec) -> None:
    """``--ensemble K``: a mechanism drawn from a distribution, and K >= 2 (or 0: none), before any fitting."""
    if not args.ensemble:
        return
    if not spec.capabilities.heterogeneous:
        raise ValueError(f"--ensemble: model {spec.name} draws no tendon property from a distribution: every "
                         "assignment is the same cell, so it has no ensemble (0: none)")
    if args.ensemble == 1:
        raise ValueError("--ensemble: 1 assignment has no spread between assignments; give K >= 2, or 0 for none")


def _ensemble(args, result, datasets):
    """The fitted mechanism over ``--ensemble`` K assignments at the data's points (None without the flag)."""
    if not args.ensemble:
        return None
    from .._progress import stage
    from ..population.ensemble import ensemble_at_data

    return ensemble_at_data(result.model, datasets, args.ensemble, workers=getattr(args, "workers", None),
                            scheduler=getattr(args, "scheduler", None), notify=lambda line: stage(f"ensemble: {line}"))


def write_ensemble(out: Path, ensemble, title: str) -> None:
    """An ensemble's table, figure and Markdown into the directory ``out`` (of an open output set)."""
    from .. import plotting
    from ..io.outputs import write_csv_rows, write_text
    from ..reports.ensemble import ensemble_markdown

    df = ensemble.to_dataframe()
    write_csv_rows(out / "ensemble.csv", list(df.columns), (tuple(map(float, r)) for r in df.itertuples(index=False)))
    plotting.save(ensemble.plot(), out / "ensemble.png")
    write_text(out / "ensemble.md", ensemble_markdown(ensemble, title))
