"""Cost of the power-law study (issue 34): each family's 10⁴-coordinate spectrum against the lattice benchmark's.

For each family of :mod:`tenscell.studies.powerlaw`, a structure of at least 10⁴ generalized coordinates: its build
(form-finding included) and, at one prestrain, its spectrum (linearization and the moduli at the lattice
benchmark's 100 frequencies, 10⁻²–10³ Hz, on the sparse path), against the tensegrity lattice of
``bench/bench_scale.py`` built, linearized and solved the same way in the same run (the lattice nearest in
coordinates, and the benchmark's 10⁴-node headline). Then, with ``--map``, the whole study's map, its CPU time
against the goal of 10 minutes.

Every time is CPU seconds (``time.process_time``), the best of ``--repeats`` runs; the load average is printed
beside them (2 cores shared with other work).

    PYTHONPATH=src python bench/bench_powerlaw.py [--map] [--repeats N]
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

import tenscell
from tenscell import _threads
from tenscell.model.lattices import LATTICE_STRUT_EA
from tenscell.model.structure import member_values
from tenscell.studies import powerlaw as pl

cpu = time.process_time
#: the lattice benchmark's frequencies (bench/bench_scale.py)
F = np.logspace(-2, 3, 100)
#: the lattices timed beside the families: about 10⁴ coordinates, and bench_scale's 10⁴-node headline
LATTICES = ((8, 8, 8), (11, 11, 12))
#: per family, a structure of at least 10⁴ coordinates
FAMILY_POINTS = (
    pl.MapPoint("diluted", "diluted net", (("size", 10), ("connectivity", 6.0), ("seed", 0))),
    pl.MapPoint("diluted", "diluted net", (("size", 10), ("connectivity", 5.0), ("seed", 0)), law="maxwell"),
    pl.MapPoint("hierarchical", "simplex net", (("module_nodes", 4), ("depth", 6))),
    pl.MapPoint("hierarchical", "simplex net", (("module_nodes", 3), ("depth", 8))),
    pl.MapPoint("structural", "lattice", (("modules", 8),), damping="length", damping_value=2.0),
    pl.MapPoint("structural", "diluted net", (("size", 10), ("connectivity", 6.0), ("seed", 0)),
                damping="tension", damping_value=0.3),
)
#: goal: a family's 10⁴-coordinate spectrum within this factor of the lattice benchmark's time
GOAL_RATIO = 2.0


def _best(fn, repeats: int):
    out = [fn() for _ in range(repeats)]
    return min(out, key=lambda r: r[0])


def lattice(shape, repeats: int):
    """(CPU s of build + linearize + moduli at F, coordinates) of bench_scale's lattice."""
    def once():
        t0 = cpu()
        cell = tenscell.model.lattice_cell(*shape)
        EA = member_values(cell.structure, {"strut": LATTICE_STRUT_EA, "default": 1.0})
        tenscell.moduli(tenscell.linearize(cell, P=1000.0, EA=EA, c=1.0), F)
        return cpu() - t0, cell.n
    return _best(once, repeats)


def family(point, repeats: int):
    """(spectrum CPU s at F, build CPU s, coordinates, spectrum CPU s over the study's band) of ``point``."""
    t0 = cpu()
    cell = pl.build_cell(point)
    build = cpu() - t0
    P = pl.prestress_of(cell, pl.REFERENCE_PRESTRAIN)

    def spectrum(f):
        def once():
            t = cpu()
            lin = pl.point_model(point, cell, P)
            pl.sparse_compliance(lin, f)
            return (cpu() - t,)
        return _best(once, repeats)[0]

    return spectrum(F), build, cell.n, spectrum(pl.frequencies())


def nearest(rows, n):
    return min(rows, key=lambda r: abs(np.log(r[1] / n)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", action="store_true", help="also run the whole study's map (several minutes)")
    ap.add_argument("--repeats", type=int, default=2, help="runs per timing; the best is kept (default 2)")
    args = ap.parse_args(argv)
    print(f"# tenscell bench_powerlaw: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start; "
          f"BLAS threads {_threads.thread_count()}; CPU seconds, best of {args.repeats}")
    with _threads.limited():
        lattice((3, 3, 3), 1)  # warm-up: first-call imports, not timed
        lat = [(*lattice(s, args.repeats), s) for s in LATTICES]
        for t, n, s in lat:
            print(f"lattice {'x'.join(map(str, s)):>9}: {n:6d} coordinates, build + linearize + {F.size} frequencies "
                  f"{t:6.2f} s")
        headline = lat[-1]
        worst = 0.0
        print(f"{'family':>12} {'structure':<62} {'coords':>7} {'build':>6} {'spectrum':>8} {'lattice':>7} "
              f"{'ratio':>6} {'/headl.':>7} {'band':>6}")
        for p in FAMILY_POINTS:
            spec, build, n, band = family(p, args.repeats)
            ref = nearest(lat, n)
            ratio = spec / ref[0]
            worst = max(worst, ratio)
            print(f"{p.family:>12} {p.label:<62} {n:7d} {build:6.2f} {spec:8.2f} {ref[0]:7.2f} {ratio:6.2f} "
                  f"{spec / headline[0]:7.2f} {band:6.2f}", flush=True)
    print("# spectrum: linearize + moduli at one prestrain (ε = 0.1), 100 frequencies 1e-2..1e3 Hz, the study's sparse "
          "path (one Lanczos run per two decades); lattice: bench_scale's pipeline on the lattice nearest in "
          "coordinates (build included, as bench_scale times it); ratio = spectrum / lattice; /headl.: against the "
          f"10^4-node headline ({headline[1]} coordinates); band: the study's {pl.frequencies().size} frequencies "
          "1e-4..1e5 Hz; build: the structure and its form-finding (not in the ratio)")
    print(f"goal: each family's >= 10^4-coordinate spectrum within {GOAL_RATIO:g}x the lattice benchmark's time: "
          f"worst ratio {worst:.2f} ({'met' if worst <= GOAL_RATIO else 'NOT met'}); load average "
          f"{os.getloadavg()[0]:.2f} at the end")
    if args.map:
        from tenscell.studies.protocol import run_study

        t0, w0 = cpu(), time.monotonic()
        res = run_study(pl.STUDY, {"scale": "full"})
        print(f"goal: the study's full map <= {pl.MAP_BUDGET_CPU_S:g} s CPU: tasks {res.cpu_s:.0f} s, this process "
              f"{cpu() - t0:.0f} s, wall {time.monotonic() - w0:.0f} s "
              f"({'met' if res.cpu_s <= pl.MAP_BUDGET_CPU_S else 'NOT met'}); load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
