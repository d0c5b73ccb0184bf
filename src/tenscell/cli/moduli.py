"""``tenscell moduli``: G', G'' of the paper cell as CSV on standard output."""
from __future__ import annotations

import sys

from ._args import MAX_GRID_POINTS, add_cluster_options, add_model_options, add_prestress, ensemble_size, frequencies, grid_cost

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
    e = p.add_argument_group("ensemble (with --from-fit of a mechanism whose tendon values are drawn from a "
                             "distribution)")
    e.add_argument("--ensemble", type=ensemble_size, default=None, metavar="K",
                   help="evaluate the fitted mechanism over K assignments of its tendon values (the fit averaged "
                        "a few; 0: none, as for fit and study) and write the mean G', G'' with the spread between assignments (sd, standard "
                        "error, 5-95%% band) and the fit's own average; runs on the population engine")
    add_cluster_options(e)
    p.set_defaults(func=run)


def run(args) -> int:
    args.ensemble = args.ensemble or None  # --ensemble 0: none, as for `fit` and `study`
    if args.ensemble is None and (args.workers is not None or args.scheduler is not None):
        raise ValueError(f"{'--workers' if args.workers is not None else '--scheduler'} applies to --ensemble")
    if args.ensemble is not None and args.from_fit is None:
        raise ValueError("--ensemble needs --from-fit: the fit.json of a mechanism whose tendon values are drawn "
                         "from a distribution")
    if args.from_fit is not None:
        return _run_from_fit(args)
    if args.prestress is None:
        args.prestress = args.prestress_default
    n = len(args.prestress) * len(args.freq)
    if n > MAX_GRID_POINTS:
        raise ValueError(f"--prestress × --freq is {len(args.prestress):,} × {len(args.freq):,} = {n:,} points, "
                         f"{grid_cost(n)}; at most {MAX_GRID_POINTS:,} per run")
    from ._args import model_from_args

    cell, EA, c = model_from_args(args)
    _write_grid(cell, args.freq, args.prestress, EA, c, progress=None if n > _ROWS_PER_BLOCK else False)
    return 0


#: rows formatted and written at a time (and the step of the progress bar of large grids)
_ROWS_PER_BLOCK = 100_000


def _write_grid(cell, f, prestress, EA, c, progress) -> None:
    """G', G'' of every (P, f) by the grid (:func:`tenscell.frequency_response`), checked finite before any row is
    written, then written in blocks of rows."""
    import numpy as np

    from .._progress import progress_bar
    from ..io.tables import MODULI_HEADER, check_finite_rows, moduli_table
    from ..response import frequency_response

    resp = frequency_response(cell, f, prestress, EA=EA, c=c)
    G = resp.G
    if not np.isfinite(G).all():  # the first bad point, named as a row of the table, before anything is written
        list(check_finite_rows(moduli_table(resp)[1], "G', G''", "(--prestress, --EA, --c, --L, --freq)"))
    nP, nf = G.shape
    table = np.column_stack([np.repeat(resp.prestress, nf), np.tile(resp.frequency_hz, nP), G.real.ravel(),
                             G.imag.ravel()])
    per = max(1, _ROWS_PER_BLOCK // nf)  # whole prestresses per block
    out = sys.stdout
    out.write(",".join(MODULI_HEADER) + "\n")
    for start in progress_bar(range(0, nP, per), desc="moduli", unit="block", progress=progress):
        block = table[start * nf:(start + per) * nf]
        # one C-level formatting of the block: the same text as f"{v:.10g}" row by row, several times faster
        out.write((_ROW * block.shape[0]) % tuple(block.ravel().tolist()))
    out.flush()


_ROW = "%.10g,%.10g,%.10g,%.10g\n"


def _run_from_fit(args) -> int:
    """G', G'' of a fitted cell (per-tendon fit or any mechanism) at --prestress (Pa, the data's units) and --freq."""
    import numpy as np

    from ._args import _MODEL_DEFAULTS
    from ..fitting.fitted import load_fit
    from ..io.tables import check_finite_rows

    for dest, (default, flag) in _MODEL_DEFAULTS.items():
        if getattr(args, dest, default) != default:
            raise ValueError(f"{flag} cannot be combined with --from-fit: the fit gives the cell and its tendons")
    model = load_fit(args.from_fit)
    prestresses = [None] if args.prestress is None else list(args.prestress)
    if len(prestresses) * len(args.freq) > MAX_GRID_POINTS:
        raise ValueError(f"--prestress × --freq is {len(prestresses) * len(args.freq):,} points; at most "
                         f"{MAX_GRID_POINTS:,} per run")
    for P in prestresses:
        try:
            model.prestress(P)  # every prestress this fit cannot map: one line, before any computation
        except ValueError as err:
            raise ValueError(f"--prestress with --from-fit {args.from_fit}: {err}") from None
    f = np.asarray(args.freq, dtype=float)
    if args.ensemble is not None:
        return _run_ensemble(args, model, f, prestresses)
    rows = []
    for P in prestresses:
        Gs, Gl = model.moduli(f, P)
        # the row's prestress: the one given, or the data's median (Pa) for a fit with a prestress scale, or the
        # fitted model prestress (N) when its data stated none
        column, shown = model.prestress_label(P)
        block = [(shown, fi, a, b) for fi, a, b in zip(f, Gs, Gl)]
        rows.extend(check_finite_rows(block, "G', G''", "(--from-fit, --prestress, --freq)"))
    header = [column, "frequency_Hz", "G_storage_Pa", "G_loss_Pa"]
    _write_rows(header, rows)
    return 0


def _ensemble_cost(model, K: int, n_points: int, parallel: int | None):
    """What ``--ensemble K`` costs: one assignment at one point timed here (a chunk of a few assignments)."""
    import numpy as np

    from ..fitting.models.mechanism import bare_problem
    from ..population.ensemble import ensemble_chunk
    from ._cost import Cost, measure

    k, w = 8, 2 * np.pi * np.logspace(-1, 1, 32)  # 256 stacked solves: the per-solve cost of a real chunk
    pb = bare_problem(model.mechanism, model.cell).assignments_subset(0, min(k, model.mechanism.K))
    phi = np.log([model.values[n] for n in pb.names])
    P = model.prestress(None)
    per = measure(lambda: ensemble_chunk(pb, phi, w, [P]), max_calls=5) / (pb.field_maps[0][1].shape[0] * w.size)
    # every member is held (16 bytes) and the statistics take a few copies of it
    return Cost("solve", K * n_points, per, parallel, memory_bytes=K * n_points * 16 * 4,
                detail=f"({K:,} assignments × {n_points:,} prestress-frequency points)")


def _run_ensemble(args, model, f, prestresses) -> int:
    """``--ensemble K``: the fitted mechanism over K assignments, the mean, spread and the fit's average on stdout."""
    from ..io.tables import check_finite_rows
    from ..population.ensemble import check_ensemble, mechanism_ensemble
    from ._cost import announce, check
    from ..population.scheduler import reach_scheduler
    from .population import _notifier, parallel_of

    try:
        model, K, workers, _ = check_ensemble(model, args.ensemble, args.workers)
    except ValueError as err:
        raise ValueError(f"--ensemble with --from-fit {args.from_fit}: {err}") from None
    if args.scheduler is not None:
        reach_scheduler(args.scheduler)
    announce(check(_ensemble_cost(model, K, len(prestresses) * f.size, parallel_of(args)), "--ensemble",
                   hint="fewer assignments or points, or give a --scheduler with more workers"))
    pres = None if prestresses == [None] else prestresses
    result = mechanism_ensemble(model, f, pres, K=K, workers=workers, scheduler=args.scheduler,
                                notify=_notifier("moduli"))
    df = result.to_dataframe()
    rows = check_finite_rows((tuple(float(v) for v in row) for row in df.itertuples(index=False)),
                             "the ensemble's G', G''", "(--from-fit, --prestress, --freq, --ensemble)")
    _write_rows(list(df.columns), list(rows))
    print(f"tenscell moduli: {result.K} assignments ({result.n_failed} not a stable cell), seed {result.seed}; "
          f"{result.elapsed_s:.1f} s on {result.workers or 'no'} Dask worker(s)", file=sys.stderr)
    return 0


def _write_rows(header, rows) -> None:
    """The moduli table on standard output: the header, then rows of numbers to 10 digits."""
    out = sys.stdout
    out.write(",".join(header) + "\n")
    for row in rows:
        out.write(",".join(f"{v:.10g}" for v in row) + "\n")
    out.flush()
