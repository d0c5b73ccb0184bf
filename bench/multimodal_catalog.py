"""Which catalog mechanisms have fits with several basins: the measurement behind ``Mechanism.multimodal``.

For each mechanism of :data:`tenscell.fitting.models.catalog.MECHANISMS`, fitted jointly to the bundled pair
(``bundled:stamenovic2002`` with ``bundled:fabry2001`` at 1000 Pa, as ``study mechanisms`` fits them), this runs
one trust-region fit (:func:`tenscell.fitting.search.local_fit`, the search's own step, 400 evaluations at most)
from each of ``--starts`` starts of the mechanism's own rule (``problem.initial_guess``) for each of ``--seeds``
seeds, and groups the local optima reached: two optima are the same basin when their RMS agree within
``--rtol`` (relative) and their free log-parameters within ``--ptol`` (natural-log units, the largest difference).
A mechanism is **multimodal** when a level of RMS above the best (by more than ``--rtol``) holds at least two of the
local optima: two starts can then agree on a worse optimum, and a search that stops when two starts agree would stop
there (the stop rule keeps its basin hops for these; ``Mechanism.multimodal`` in the catalog). Prints one row per
mechanism with the CPU time and the load.

    PYTHONPATH=src python bench/multimodal_catalog.py [--seeds 2] [--starts 6] [--only NAME ...]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np


def basins(problem, optima, rtol: float, ptol: float) -> list[tuple[float, int]]:
    """The distinct optima (rms, how many starts reached it), best first."""
    groups: list[list] = []
    for rms, theta in sorted(optima, key=lambda o: o[0]):
        for g in groups:
            if abs(rms - g[0]) <= rtol * g[0] and float(np.max(np.abs(theta - g[1]))) <= ptol:
                g[2] += 1
                break
        else:
            groups.append([rms, theta, 1])
    return [(g[0], g[2]) for g in groups]


def main(argv=None) -> int:
    from tenscell.fitting.models.catalog import MECHANISMS
    from tenscell.fitting.search import local_fit
    from tenscell.io.data import bundled

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--starts", type=int, default=6)
    ap.add_argument("--max-nfev", type=int, default=400)
    ap.add_argument("--rtol", type=float, default=0.01)
    ap.add_argument("--ptol", type=float, default=0.5)
    ap.add_argument("--near", type=float, default=0.25)
    ap.add_argument("--only", nargs="*", default=None)
    args = ap.parse_args(argv)
    data = [bundled("stamenovic2002"), bundled("fabry2001").with_prestress(1000.0)]
    print(f"load average {os.getloadavg()[0]:.2f} at the start; {args.seeds} seed(s) x {args.starts} start(s), "
          f"{args.max_nfev} evaluations per local fit")
    print(f"{'mechanism':34s} {'best rms':>9s} {'basins near best':>17s} {'RMS levels (rms: starts)':40s} "
          f"{'multimodal':10s} cpu_s")
    for name, mech in MECHANISMS.items():
        if args.only and name not in args.only:
            continue
        t0 = time.process_time()
        problem = mech.problem(data)
        optima = []
        for seed in range(args.seeds):
            rng = np.random.default_rng(seed)
            for _ in range(args.starts):
                theta, _, _ = local_fit(problem, problem.initial_guess(rng), args.max_nfev)
                optima.append((problem.rms(theta), np.asarray(theta)))
        found = basins(problem, optima, args.rtol, args.ptol)
        levels = basins(problem, optima, args.rtol, np.inf)  # the same RMS, wherever the parameters are
        best = found[0][0]
        near = [b for b in found if b[0] <= (1 + args.near) * best]
        multimodal = any(n >= 2 for _, n in levels[1:])
        listed = ", ".join(f"{r:.4f}: {n}" for r, n in levels[:5]) + (" ..." if len(levels) > 5 else "")
        print(f"{name:34s} {best:9.4f} {len(near):17d} {listed:40s} {str(multimodal):10s} "
              f"{time.process_time() - t0:.1f}", flush=True)
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
