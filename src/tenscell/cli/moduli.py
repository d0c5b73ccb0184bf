"""``tenscell moduli``: G', G'' of the paper cell as CSV on standard output."""
from __future__ import annotations

import sys

from ._args import MAX_GRID_POINTS, add_model_options, add_prestress, frequencies, grid_cost

DEFAULT_FREQ = "0.01:1000:61"


def register(sub) -> None:
    p = sub.add_parser("moduli", help="G', G'' of the paper cell as CSV on stdout",
                       description="Storage and loss moduli (Pa) of the paper cell, as CSV on standard output "
                                   "(columns prestress_Pa, frequency_Hz, G_storage_Pa, G_loss_Pa: the layout "
                                   "`tenscell fit` reads).")
    add_prestress(p, sweep=True, from_fit=True)
    p.add_argument("--freq", type=frequencies(), default=frequencies()(DEFAULT_FREQ), metavar="F",
                   help=f"frequencies (Hz): comma list or a:b:n log-spaced (default {DEFAULT_FREQ})")
    add_model_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    if args.from_fit is not None:
        return _run_from_fit(args)
    if args.prestress is None:
        args.prestress = args.prestress_default
    n = len(args.prestress) * len(args.freq)
    if n > MAX_GRID_POINTS:
        raise ValueError(f"--prestress × --freq is {len(args.prestress):,} × {len(args.freq):,} = {n:,} points, "
                         f"{grid_cost(n)}; at most {MAX_GRID_POINTS:,} per run")
    from ._args import model_from_args
    from .._progress import progress_bar
    from ..io.tables import check_finite_rows, moduli_table
    from ..response import frequency_response

    cell, EA, c = model_from_args(args)
    # one prestress at a time (a bar on a terminal for large grids); every row is checked before any is
    # written, so that bad numbers never reach the output
    rows = []
    for P in progress_bar(args.prestress, desc="moduli", unit="prestress", progress=None if n > 10**5 else False):
        resp = frequency_response(cell, args.freq, [P], EA=EA, c=c)
        header, block = moduli_table(resp)
        rows.extend(check_finite_rows(block, "G', G''", "(--prestress, --EA, --c, --L, --freq)"))
    _write_rows(header, rows)
    return 0


def _run_from_fit(args) -> int:
    """G', G'' of a fitted cell (per-tendon fit or any mechanism) at --prestress (Pa, the data's units) and --freq."""
    import numpy as np

    from ._args import _MODEL_DEFAULTS
    from ..fitting.mechanism_fit import load_any_fit
    from ..io.tables import check_finite_rows

    for dest, (default, flag) in _MODEL_DEFAULTS.items():
        if getattr(args, dest, default) != default:
            raise ValueError(f"{flag} cannot be combined with --from-fit: the fit gives the cell and its tendons")
    model = load_any_fit(args.from_fit)
    prestresses = [None] if args.prestress is None else list(args.prestress)
    if len(prestresses) * len(args.freq) > MAX_GRID_POINTS:
        raise ValueError(f"--prestress × --freq is {len(prestresses) * len(args.freq):,} points; at most "
                         f"{MAX_GRID_POINTS:,} per run")
    for P in prestresses:
        try:
            model.prestress(P)  # every prestress this fit cannot map: one line, before any computation
        except ValueError as err:
            raise ValueError(f"--prestress with --from-fit {args.from_fit}: {err}") from None
    rows = []
    f = np.asarray(args.freq, dtype=float)
    for P in prestresses:
        Gs, Gl = model.moduli(f, P)
        label = float(P) if P is not None else (model.default_prestress_pa if hasattr(model, "default_prestress_pa")
                                                else None)
        shown = label if label is not None else model.prestress(None)
        block = [(shown, fi, a, b) for fi, a, b in zip(f, Gs, Gl)]
        rows.extend(check_finite_rows(block, "G', G''", "(--from-fit, --prestress, --freq)"))
    header = ["prestress_Pa" if getattr(model, "s", None) is not None else "prestress_N", "frequency_Hz",
              "G_storage_Pa", "G_loss_Pa"]
    _write_rows(header, rows)
    return 0


def _write_rows(header, rows) -> None:
    """The moduli table on standard output: the header, then (prestress, f, G', G'') rows to 10 digits."""
    out = sys.stdout
    out.write(",".join(header) + "\n")
    for P, f, gs, gl in rows:
        out.write(f"{P:.10g},{f:.10g},{gs:.10g},{gl:.10g}\n")
    out.flush()
