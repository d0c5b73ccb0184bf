"""Option parsers shared by every command: one implementation of each concept.

Building the parser imports only the standard library (``tenscell --help``
must be quick); the values are checked here, at parse time, so that a bad
flag is refused with one line naming it before any computation or file.

Concepts and their flags (the same everywhere):

``--prestress``  prestress P (N, the paper's Pa): one value, or a comma list where a command sweeps it
``--freq``       frequencies (Hz): a comma list or ``a:b:n`` (n log-spaced points), or one value
``--amplitude``  load amplitude(s): one value, or a comma list where a command sweeps it
``--EA``, ``--c`` member values: one value, ``family=value`` pairs, or one value per member
``--L``          strut length (m); ``--alpha-deg``, ``--delta-deg`` the reference angles (degrees)
"""
from __future__ import annotations

import argparse
import math
import sys

# the allowed range of each physical quantity (closed interval, in the flag's unit): one table, which the data
# readers check files against too (tenscell._ranges explains the bounds)
from .._ranges import RANGES

__all__ = [
    "Parser", "HelpFormatter", "number", "integer", "number_list", "frequencies", "member_values",
    "lattice_size", "grid_cost", "add_model_options", "add_prestress", "add_out", "hidden_alias", "add_from_fit",
    "fitted_from_args", "prestress_from_args", "model_from_args", "RANGES", "MAX_GRID_POINTS", "path",
    "add_data_options", "data_options_from_args", "DATA_COLUMNS", "DATA_UNITS", "FLAG_SPELLING", "user_message",
    "add_cluster_options",
]

#: most (prestress, frequency) points one command evaluates: each point costs a complex
#: solve and a CSV row; 10^6 rows are ~50 MB of CSV, 0.4 GB of memory and ~20 s.
MAX_GRID_POINTS = 1_000_000
#: most assignments of an ensemble (--ensemble; tenscell.population.ensemble.MAX_K: the parser imports no numpy)
ENSEMBLE_MAX_K = 100_000
#: measured cost of one (P, f) point of `tenscell moduli` (10^6 points: 370 MB, 19 s on the 2-core machine)
_BYTES_PER_POINT, _SECONDS_PER_POINT = 400, 2e-5


class HelpFormatter(argparse.HelpFormatter):
    """Shows each option's default (unless the help already says it, or there is none)."""

    def _get_help_string(self, action):
        text = action.help or ""
        if "%(default)" in text or "default" in text.lower():
            return text
        if action.default is None or action.default is False or action.default is argparse.SUPPRESS \
                or not action.option_strings:
            return text
        shown = action.default
        if isinstance(shown, tuple):
            shown = ",".join(_fmt(v) for v in shown)
        elif isinstance(shown, float):
            shown = _fmt(shown)
        return text + f" (default: {shown})".replace("%", "%%")


class Parser(argparse.ArgumentParser):
    """argparse with a one-line error (``tenscell CMD: error: ...``) and exit status 2."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _fmt(x: float) -> str:
    return f"{x:g}"


def _float(text: str) -> float:
    text = str(text).strip()
    if not text:
        raise argparse.ArgumentTypeError("empty value; expected a number")
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a number") from None


def _in_range(v: float, lo: float | None, hi: float | None, unit: str, *, open_lo: bool = False,
              open_hi: bool = False) -> float:
    u = f" {unit}" if unit else ""
    allowed = _range_text(lo, hi, unit, open_lo, open_hi)
    if math.isnan(v):
        raise argparse.ArgumentTypeError(f"got nan; expected a number{allowed}")
    bad = (lo is not None and (v <= lo if open_lo else v < lo)) or (hi is not None and (v >= hi if open_hi else v > hi))
    if bad or math.isinf(v):
        raise argparse.ArgumentTypeError(f"{_fmt(v)}{u} is out of range; allowed{allowed}")
    return v


def _range_text(lo, hi, unit, open_lo=False, open_hi=False) -> str:
    u = f" {unit}" if unit else ""
    if lo is None and hi is None:
        return " a finite number" + (f" ({unit})" if unit else "")
    if hi is None:
        return f" {'>' if open_lo else '>='} {_fmt(lo)}{u}"
    if lo is None:
        return f" {'<' if open_hi else '<='} {_fmt(hi)}{u}"
    return f" {'(' if open_lo else '['}{_fmt(lo)}, {_fmt(hi)}{')' if open_hi else ']'}{u}"


def number(lo: float | None = None, hi: float | None = None, unit: str = "", *, open_lo: bool = False,
           open_hi: bool = False, quantity: str | None = None):
    """An argparse ``type``: one finite float in [lo, hi] (``open_lo``, ``open_hi``: the bound excluded).

    ``quantity`` names an entry of :data:`RANGES` to take the bounds and unit from.
    """
    if quantity is not None:
        lo, hi, unit = RANGES[quantity]

    def convert(text):
        return _in_range(_float(text), lo, hi, unit, open_lo=open_lo, open_hi=open_hi)

    convert.__name__ = "number"
    return convert


def integer(lo: int | None = None, hi: int | None = None, what: str = ""):
    """An argparse ``type``: a whole number in [lo, hi]."""
    def convert(text):
        text = str(text).strip()
        try:
            v = int(text)
        except ValueError:
            shown = text if len(text) <= 40 else text[:37] + "..."
            raise argparse.ArgumentTypeError(f"{shown!r} is not a whole number") from None
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            shown = str(v) if len(str(v)) <= 20 else f"a {len(str(v))}-digit number"
            rng = (f"at least {lo}" if hi is None else f"{lo}..{hi}") if lo is not None else f"at most {hi}"
            raise argparse.ArgumentTypeError(f"{shown} is out of range; allowed {rng}{(' ' + what) if what else ''}")
        return v

    convert.__name__ = "integer"
    return convert


def number_list(lo=None, hi=None, unit="", *, quantity=None, max_items: int = 10_000, open_lo: bool = False):
    """An argparse ``type``: a comma list of numbers, each in range; returns a tuple of floats."""
    if quantity is not None:
        lo, hi, unit = RANGES[quantity]

    def convert(text):
        items = str(text).split(",")
        if len(items) > max_items:
            raise argparse.ArgumentTypeError(f"{len(items)} values; at most {max_items}")
        return tuple(_in_range(_float(item), lo, hi, unit, open_lo=open_lo) for item in items)

    convert.__name__ = "list"
    return convert


def ensemble_size(text):
    """An argparse ``type`` for ``--ensemble K`` (every command alike): 0 for none, or 2 to ENSEMBLE_MAX_K
    assignments; 1 is refused (one assignment has no spread between assignments)."""
    k = integer(0, ENSEMBLE_MAX_K, "assignments (0: none)")(text)
    if k == 1:
        raise argparse.ArgumentTypeError("1 assignment has no spread between assignments; give K >= 2, or 0 for none")
    return k


ensemble_size.__name__ = "integer"


def frequencies(max_points: int = MAX_GRID_POINTS):
    """An argparse ``type``: ``a:b:n`` (n log-spaced points from a to b Hz) or a comma list (Hz)."""
    lo, hi, unit = RANGES["frequency"]
    as_list = number_list(quantity="frequency", max_items=max_points)

    def convert(text):
        text = str(text)
        if ":" not in text:
            return as_list(text)
        parts = text.split(":")
        if len(parts) != 3:
            raise argparse.ArgumentTypeError(f"expected a:b:n or a comma list, got {text[:40]!r}")
        a = _in_range(_float(parts[0]), lo, hi, unit)
        b = _in_range(_float(parts[1]), lo, hi, unit)
        n = integer(1, None, "points")(parts[2])
        if n > max_points:
            raise argparse.ArgumentTypeError(
                f"{n:,} points would cost {grid_cost(n)}; "
                f"at most {max_points:,}")
        if n == 1:
            return (a,)
        la, lb = math.log10(a), math.log10(b)
        return tuple(10.0 ** (la + (lb - la) * k / (n - 1)) for k in range(n))

    convert.__name__ = "frequencies"
    return convert


def grid_cost(n: int) -> str:
    """What ``n`` (P, f) points cost: ``"about 37.3 GiB of memory and 2e+03 s"`` (calibrated rates, above)."""
    from ._cost import duration, size

    return f"about {size(n * _BYTES_PER_POINT)} of memory and {duration(n * _SECONDS_PER_POINT)}"


def path(what: str = "a path"):
    """An argparse ``type``: a non-empty path (an empty one would silently mean the current directory or a default)."""
    def convert(text):
        text = str(text)
        if not text.strip():
            raise argparse.ArgumentTypeError(f"empty value; expected {what}")
        if "\0" in text:
            raise argparse.ArgumentTypeError(f"{text[:40]!r} holds a NUL byte; expected {what}")
        return text

    convert.__name__ = "path"
    return convert


def member_values(quantity: str):
    """An argparse ``type``: one value, ``family=value`` pairs, or one value per member (comma list).

    Returns a float, a dict {family: float} or a tuple of floats; each value in
    the range of ``quantity`` (see :data:`RANGES`).
    """
    lo, hi, unit = RANGES[quantity]

    def convert(text):
        text = str(text).strip()
        if "=" in text:
            out = {}
            for item in text.split(","):
                key, _, val = item.partition("=")
                key = key.strip()
                if not key or not _:
                    raise argparse.ArgumentTypeError(f"expected family=value items, got {item[:40]!r}")
                out[key] = _in_range(_float(val), lo, hi, unit)
            return out
        vals = number_list(lo, hi, unit)(text)
        return vals[0] if len(vals) == 1 else vals

    convert.__name__ = "member values"
    return convert


def lattice_size(max_modules: int):
    """An argparse ``type``: ``NXxNY`` or ``NXxNYxNZ`` module counts (each >= 1), product <= max_modules.

    The refusal states the cost: a module adds about 24 coordinates, and the
    sparse factorization's memory grows as coordinates^1.4 (1.25 GB at 1.07e5).
    """
    def convert(text):
        parts = str(text).lower().split("x")
        if len(parts) not in (2, 3):
            raise argparse.ArgumentTypeError(f"expected NXxNY or NXxNYxNZ, got {str(text)[:40]!r}")
        dims = tuple(integer(1, max_modules, "modules per direction")(p) for p in parts)
        total = math.prod(dims)
        if total > max_modules:
            from ._cost import size

            coords = 24 * total
            factorization = 1.25e9 * (coords / 1.07e5) ** 1.4  # bytes, calibrated (docstring)
            raise argparse.ArgumentTypeError(
                f"{'x'.join(map(str, dims))} is {total:,} modules: about {coords:,} coordinates and "
                f"{size(factorization)} for the factorization alone; at most {max_modules:,} modules "
                f"(about {24 * max_modules:,} coordinates)")
        return dims

    convert.__name__ = "size"
    return convert


def hidden_alias(p: argparse.ArgumentParser, alias: str, dest: str, **kw) -> None:
    """Accept an old spelling of an option without showing it in --help."""
    p.add_argument(alias, dest=dest, help=argparse.SUPPRESS, default=argparse.SUPPRESS, **kw)


def add_prestress(p: argparse.ArgumentParser, *, sweep: bool, default: str = "1000", from_fit: bool = False) -> None:
    """``--prestress`` (with the old ``--P`` as a hidden alias): a list where the command sweeps it.

    With ``from_fit`` the command also takes ``--from-fit`` (:func:`add_from_fit`); the parsed
    default is then None (see :func:`prestress_from_args`) so that a prestress typed with a fit is seen.
    """
    kind = number_list(quantity="prestress", max_items=MAX_GRID_POINTS) if sweep else number(quantity="prestress")
    help_ = ("prestresses P (N, the paper's Pa; comma list)" if sweep else "prestress P (N, the paper's Pa)")
    if from_fit:
        help_ += (f" (default {default}; with --from-fit: the measured prestress in Pa of a fit to data that state "
                  "one, default their median, and refused for a fit with its own prestress P)")
    p.add_argument("--prestress", type=kind, default=None if from_fit else kind(default), metavar="P", help=help_)
    hidden_alias(p, "--P", "prestress", type=kind)
    if from_fit:
        p.set_defaults(prestress_default=kind(default))
        add_from_fit(p)


def add_from_fit(p: argparse.ArgumentParser) -> None:
    """``--from-fit FIT_JSON``: the fitted cell of a ``tenscell fit`` run instead of the model options."""
    p.add_argument("--from-fit", metavar="FIT_JSON", default=None, type=path("a fit.json file"),
                   help="use the fitted cell of a `tenscell fit` run (its fit.json): cell, strut length, EA, c and "
                        "prestress; the cell and tendon options are then refused")


#: the model options' defaults: with --from-fit any other value is a conflict
_MODEL_DEFAULTS = {"alpha_deg": (0.0, "--alpha-deg"), "delta_deg": (None, "--delta-deg"), "EA": (1.0, "--EA"),
                   "c": (1.0, "--c"), "L": (1.0, "--L"), "no_if": (False, "--no-if")}


def fitted_from_args(args, conflicts: dict | None = None):
    """(FittedModel, P in N) from ``--from-fit`` and ``--prestress``; None if ``--from-fit`` is not given.

    Raises
    ------
    ValueError
        A model option given with ``--from-fit`` (naming it), an unreadable fit.json, or a
        ``--prestress`` the fit cannot use.
    """
    if getattr(args, "from_fit", None) is None:
        return None
    for dest, (default, flag) in (_MODEL_DEFAULTS if conflicts is None else conflicts).items():
        if hasattr(args, dest) and getattr(args, dest) != default:
            raise ValueError(f"{flag} cannot be combined with --from-fit: the fit gives the cell and its tendons")
    from ..fitting.fitted import load_fit

    model = load_fit(args.from_fit)
    if args.prestress is not None and model.s is None:
        raise ValueError(f"--prestress cannot be combined with --from-fit {args.from_fit}: that fit has its own "
                         f"prestress P = {model.P:.6g} N (its data state no prestress)")
    try:
        P = model.prestress(args.prestress)
    except ValueError as err:
        raise ValueError(f"--prestress: {err}") from None
    return model, P


def prestress_from_args(args) -> float:
    """``--prestress`` (N) of a command that also takes ``--from-fit`` but was run without it."""
    return args.prestress if args.prestress is not None else args.prestress_default


def add_out(p: argparse.ArgumentParser, default: str | None = None, *, derived: str | None = None) -> None:
    """``--out``: the output directory, replaced as a whole by a successful run.

    Required unless ``default`` is given, or ``derived`` describes the default
    the command derives from its other arguments (``args.out`` is then None).
    """
    text = "output directory (created, or replaced as a whole by a successful run)"
    directory = path("a directory")
    if derived is not None:
        p.add_argument("--out", type=directory, default=None, help=f"{text} (default: {derived})")
    elif default is None:
        p.add_argument("--out", type=directory, required=True, help=text)
    else:
        p.add_argument("--out", type=directory, default=default, help=text)


def add_model_options(p: argparse.ArgumentParser) -> None:
    """The options that choose the paper cell and its tendon properties (shared by commands)."""
    p.add_argument("--alpha-deg", type=number(-180.0, 180.0, "degrees"), default=0.0,
                   help="reference azimuth α (degrees)")
    p.add_argument("--delta-deg", type=number(0.0, 90.0, "degrees", open_lo=True, open_hi=True), default=None,
                   help="reference declination δ (degrees; default 50 with IFs, the IF-free curve without)")
    p.add_argument("--EA", type=member_values("EA"), default=1.0,
                   help="tendon stiffness EA (N): one value, family=value pairs or one per tendon (comma list)")
    p.add_argument("--c", type=member_values("c"), default=1.0,
                   help="tendon damping c (N·s/m): same forms as --EA")
    p.add_argument("--L", type=number(quantity="L"), default=1.0, help="strut length L (m)")
    p.add_argument("--no-if", action="store_true", help="remove the 12 intermediate filaments")


def model_from_args(args):
    """(cell, EA, c) from the shared model options; EA and c expanded to one value per tendon."""
    from ..io.structure_files import member_values as expand
    from ..model.shapes import paper_cell

    delta = None if args.delta_deg is None else math.radians(args.delta_deg)
    try:
        cell = paper_cell(alpha=math.radians(args.alpha_deg), delta=delta, L=args.L,
                          intermediate_filaments=not args.no_if)
    except ValueError as err:  # a reference the model does not have: say which flags chose it
        chosen = [f"{flag} {_fmt(v)}" for flag, v in (("--alpha-deg", args.alpha_deg), ("--delta-deg", args.delta_deg),
                                                      ("--L", args.L)) if v is not None]
        chosen += ["--no-if"] if args.no_if else []
        raise type(err)(f"{', '.join(chosen)}: {err}") from None
    EA = expand(cell.structure, _arrayish(args.EA), "--EA", "N")
    c = expand(cell.structure, _arrayish(args.c), "--c", "N·s/m")
    return cell, EA, c


def _arrayish(v):
    if isinstance(v, tuple):
        import numpy as np
        return np.asarray(v, dtype=float)
    return v


def command_line(argv) -> str:
    """The command as typed (for manifests)."""
    import shlex
    return "tenscell " + shlex.join(str(a) for a in (sys.argv[1:] if argv is None else argv))


# ---- a lab's own files: what each column holds, in which unit --------------------------------------------
#: --columns QUANTITY=NAME: the fields of tenscell.io.importers.ColumnMap that name a column
DATA_COLUMNS = ("frequency", "storage", "loss", "magnitude", "phase", "loss_tangent", "prestress", "storage_sd",
                "loss_sd", "time", "compliance", "compliance_sd")
#: --units QUANTITY=UNIT -> the ColumnMap field holding that unit
DATA_UNITS = {"frequency": "frequency_unit", "modulus": "modulus_unit", "phase": "phase_unit",
              "prestress": "prestress_unit", "time": "time_unit", "compliance": "compliance_unit"}


#: how the command line spells an option a library message names (tenscell._errors.option): the flag with its
#: syntax, ``{value}`` the value the message gives, after "|" what it reads when the message gives none
FLAG_SPELLING = {
    **{field: f"--units {quantity}={{value}}|UNIT" for quantity, field in DATA_UNITS.items()},
    **{quantity: f"--columns {quantity}={{value}}|NAME" for quantity in DATA_COLUMNS},
    "columns": "--columns QUANTITY=NAME (or --columns-file)",
    "geometric_factor": "the \"geometric_factor\" field of --columns-file",
    "step": "--step {value}|N",
    "interval": "--step {value}|N",
    "temperature": "--temperature {value}|C",
    "sheet": "--sheet {value}|NAME",
    "accept": "--accept {value}|CHECK",
    "slack": "--slack {value}|allow",
    "min_points": "the {value} points this fit needs (one per free parameter; fewer parameters: --tendons uniform, "
                  "or a mechanism with --model NAME)",
}


def user_message(err: BaseException) -> str:
    """The message of ``err`` for the command line: every option it names spelled as the flag
    (:data:`FLAG_SPELLING`, ``--units modulus=UNIT`` for ``modulus_unit=``); an operating system's error as its
    file and reason (``out/fit.json: No space left on device``), not Python's ``[Errno 28]`` form."""
    from .._errors import TenscellError, raw_message, spelled

    if isinstance(err, OSError) and not isinstance(err, TenscellError) and err.strerror:
        where = err.filename if err.filename is not None else "writing the results"
        return f"{where}: {err.strerror}"
    text = raw_message(err) if isinstance(err, TenscellError) else str(err)
    return spelled(text, FLAG_SPELLING)


#: commands whose results go to standard output (the others write an output set and report on stderr)
STDOUT_COMMANDS = ("moduli", "simulate", "creep", "show", "study")


def check_stdout(command: str | None) -> None:
    """ValueError before any work when ``command`` writes results to a standard output that cannot take them:
    closed, open for reading only, or /dev/full (``tenscell moduli > /dev/full``)."""
    import os
    import stat

    if command not in STDOUT_COMMANDS:
        return
    if sys.stdout is None:  # Python's standard output when descriptor 1 was closed (>&-)
        raise ValueError("standard output is closed; the results go there (redirect it to a file: > FILE)")
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, ValueError, OSError):  # replaced by an object without a descriptor (captured)
        return
    try:
        st = os.fstat(fd)
    except OSError:
        raise ValueError("standard output is closed; the results go there (redirect it to a file: > FILE)") from None
    if stat.S_ISCHR(st.st_mode) and st.st_rdev == os.makedev(1, 7):
        raise ValueError("standard output is /dev/full, which takes no data; redirect it to a file (> FILE) or a "
                         "program (| ...)")
    try:
        import fcntl

        readonly = fcntl.fcntl(fd, fcntl.F_GETFL) & os.O_ACCMODE == os.O_RDONLY
    except (ImportError, OSError):
        return
    if readonly:
        raise ValueError("standard output is open for reading only; the results go there (> FILE)")


def _assignment(keys, flag: str, example: str):
    """An argparse ``type``: ``KEY=VALUE`` with KEY one of ``keys``."""

    def convert(text):
        key, sep, value = str(text).partition("=")
        key = key.strip()
        if not sep or not value.strip():
            raise argparse.ArgumentTypeError(f"expected QUANTITY=VALUE (e.g. {example}), got {text!r}")
        if key not in keys:
            raise argparse.ArgumentTypeError(f"{key!r} is not one of {', '.join(keys)}")
        return key, value.strip()

    convert.__name__ = flag
    return convert


#: the reader's checks --accept can skip (tenscell.io.checks.CHECKS, written out for a quick parser; a test checks
#: they agree)
ACCEPT_CHECKS = ("one-frequency", "outliers", "decreasing", "point-count", "truncated", "one-time", "repeated-times",
                 "collapse")


def add_data_options(p: argparse.ArgumentParser) -> None:
    """``--columns``, ``--units``, ``--columns-file``, ``--step``, ``--temperature``, ``--sheet``, ``--accept``:
    reading a lab's own files.

    The same rules as :func:`tenscell.io.readers.read_data`: without them a file's layout and units are
    recognised from its content (tenscell's CSV, TRIOS, RheoCompass, Excel, a table with recognised headers)."""
    g = p.add_argument_group("reading your own files (see docs/importing-data.md)")
    g.add_argument("--columns", action="append", default=None, metavar="QUANTITY=NAME",
                   type=_assignment(DATA_COLUMNS, "--columns", "storage=\"G' [Pa]\""),
                   help=f"which column holds QUANTITY ({', '.join(DATA_COLUMNS)}); repeatable; default "
                        "recognised from the headers")
    g.add_argument("--units", action="append", default=None, metavar="QUANTITY=UNIT",
                   type=_assignment(tuple(DATA_UNITS), "--units", "modulus=kPa"),
                   help="unit of QUANTITY (frequency Hz|rad/s, modulus Pa|kPa|MPa, phase deg|rad, prestress Pa|kPa, "
                        "time s|ms|min, compliance 1/Pa|1/kPa|1/MPa) when the file does not state it; repeatable")
    g.add_argument("--columns-file", default=None, metavar="FILE.json", type=path("a JSON file"),
                   help="a JSON object of tenscell.io.ColumnMap fields (e.g. {\"frequency\": \"omega\", "
                        "\"frequency_unit\": \"rad/s\", ...}); --columns and --units override it")
    g.add_argument("--step", default=None, metavar="N|NAME", type=_step,
                   help="TRIOS step or RheoCompass interval to read (its number, or its name) when the file holds "
                        "several")
    g.add_argument("--temperature", type=number(-273.15, 1e4, "°C"), default=None, metavar="C",
                   help="read the TRIOS step or RheoCompass interval at this temperature (°C)")
    g.add_argument("--sheet", default=None, metavar="NAME", type=path("a sheet name"),
                   help="the sheet of an Excel workbook to read (default the first)")
    g.add_argument("--accept", action="append", default=None, choices=ACCEPT_CHECKS, metavar="CHECK",
                   help="read data that a reader's check refuses, when you know they are right (repeatable): "
                        "one-frequency (moduli at one frequency), outliers (a value decades from its neighbours), "
                        "decreasing (a creep compliance that decreases), point-count (a TRIOS step shorter or "
                        "longer than its 'Number of points'); recorded in what was read")


def _step(text):
    text = str(text).strip()
    if not text:
        raise argparse.ArgumentTypeError("empty value; expected a step's number or name")
    if text.isdigit():
        if int(text) < 1:
            raise argparse.ArgumentTypeError(f"{text}: steps are numbered from 1")
        return int(text)
    return text


_step.__name__ = "step"


def data_options_from_args(args) -> dict:
    """keyword arguments of :func:`tenscell.io.readers.read_data` from :func:`add_data_options`' flags, the column
    map checked before any file is read (ValueError naming the flag otherwise)."""
    import json

    fields: dict = {}
    source = getattr(args, "columns_file", None)
    if source:
        try:
            with open(source, encoding="utf-8") as fh:
                loaded = json.load(fh)
        except OSError as err:
            raise ValueError(f"--columns-file {source}: {err.strerror or err}") from None
        except json.JSONDecodeError as err:
            raise ValueError(f"--columns-file {source}, line {err.lineno}: not JSON ({err.msg})") from None
        except (UnicodeDecodeError, ValueError) as err:
            raise ValueError(f"--columns-file {source}: not a JSON text file ({type(err).__name__})") from None
        if not isinstance(loaded, dict):
            raise ValueError(f"--columns-file {source}: expected a JSON object of column-map fields "
                             "({\"frequency\": \"omega\", \"frequency_unit\": \"rad/s\", ...})")
        fields.update(loaded)
    fields.update(dict(getattr(args, "columns", None) or ()))
    units = {DATA_UNITS[k]: v for k, v in (getattr(args, "units", None) or ())}
    if getattr(args, "step", None) is not None and getattr(args, "temperature", None) is not None:
        raise ValueError("--step and --temperature both choose the step; give one")
    out = {"columns": fields or None, "step": getattr(args, "step", None),
           "temperature": getattr(args, "temperature", None), "sheet": getattr(args, "sheet", None),
           "accept": tuple(getattr(args, "accept", None) or ())}
    if units:
        if fields:
            fields.update(units)
        else:
            out["units"] = units
    _check_column_map(fields or None, units, source)
    return out


def _check_column_map(fields, units, source) -> None:
    """The map these flags give, built once before any file is read: an unknown field or unit is refused here."""
    if fields is None and not units:
        return
    from ..io.columns import ColumnMap

    known = list(ColumnMap.__dataclass_fields__)
    for key in fields or ():
        if key not in known:
            where = f"--columns-file {source}" if source else "--columns"
            raise ValueError(f"{where}: {key!r} is not a field of a column map; the fields are {', '.join(known)}")
    if fields is not None:
        ColumnMap(**fields)  # ColumnMapError naming the field as its flag
        return
    creep = ("time_unit", "compliance_unit")
    ColumnMap(frequency="f", storage="a", loss="b", **{k: v for k, v in units.items() if k not in creep})
    ColumnMap(time="t", compliance="j", **{k: v for k, v in units.items() if k in creep})


def add_cluster_options(p) -> None:
    """``--workers N | --scheduler ADDRESS``: where the tasks run (shared by every Dask command)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=integer(0, 4096), default=None,
                   help="local Dask workers started for this run (default: one per CPU when the work pays for starting "
                        "them, judged from the first task's time, else in this process; 0: no Dask)")
    g.add_argument("--scheduler", type=path("an address or a scheduler file"), default=None,
                   help="an existing Dask scheduler: tcp://HOST:PORT or a scheduler file (dask scheduler "
                        "--scheduler-file F)")
