"""Scale: G', G'' at 100 frequencies, creep and relaxation, against degrees of freedom (3D lattices).

Each row builds a block lattice of 6-strut modules (``tenscell.model.lattice_cell``: node-sharing
modules, assembled self-stress), linearizes it (with the positive-definiteness check) and computes
G', G'' at 100 frequencies from 10⁻² to 10³ Hz — the library's own sparse path: CHOLMOD
(cvxopt) factors K0 once for the check and K0 + σC0 once for a shifted Lanczos run. In the same
process, the previous path ("old"): SuperLU with the hand-written nested-dissection ordering
(``bench/_superlu_nd.py``) for the same two factorizations and the same Lanczos run.

Printed: times (build, linearize+check, moduli, total), factorizations per model, the old/new
ratio of linearize+moduli, the largest difference of the answers, the growth exponent of the
library's total time for 2·10³–10⁵ coordinates, the 10⁴-node lattice's time, and creep plus
relaxation of the 1,896-coordinate lattice against the old dense path (generalized eigensolves of
the dense matrices: one for the creep spectrum, one again inside stress_relaxation).

Usage: python bench/bench_scale.py [--full]   (--full adds the 1.1·10⁵-coordinate lattice, ~2 min)
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
import scipy.linalg
import scipy.sparse as sp

import tenscell
import tenscell.linear.modal as modal
from tenscell import _threads
from tenscell.io.structure_files import member_values
from tenscell.linear.krylov import LanczosRun, converge, default_shift

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _superlu_nd  # noqa: E402  (the previous factorization, kept as the baseline)

SHAPES = [(5, 4, 4), (6, 6, 6), (8, 8, 8), (11, 11, 12), (13, 13, 13)]
FULL_SHAPES = [(17, 17, 17)]
HEADLINE = (11, 11, 12)  # 10 934 nodes
CREEP_SHAPE = (5, 4, 4)  # 1 896 coordinates
F = np.logspace(-2, 3, 100)
W = 2 * np.pi * F
P, C = 1000.0, 1.0


def _EA(cell):
    return member_values(cell.structure, {"strut": 1e3, "default": 1.0})


class _Counter:
    """Counts the library's sparse factorizations."""

    def __init__(self):
        self.n, self.real = 0, modal.factorize_spd

    def __call__(self, A, what="the matrix", perm=None):
        self.n += 1
        return self.real(A, what, perm)


def _old_moduli(cell, lin):
    """The previous path: SuperLU + nested dissection for the check and for K0 + σC0, the same Lanczos."""
    pts = _superlu_nd.coordinate_locations(cell.coords)
    K, Cm = sp.csc_matrix(lin.K0), sp.csc_matrix(lin.C0)
    t0 = time.perf_counter()
    _superlu_nd.factorize_spd(K, what="K0", points=pts)  # linearize(check=True)
    t1 = time.perf_counter()
    sigma = default_shift(F)
    Ks = (K + sigma * Cm).tocsc()
    factor = _superlu_nd.factorize_spd(Ks, points=pts)
    run = LanczosRun(factor, Ks.tocsr(), Cm.tocsr(), -lin.H0, sigma, min(cell.n, 2000))
    converge(run, lambda r: float(r.compliance(1j * W)[1].max()), 1e-12, "compliance")
    J = run.compliance(1j * W)[0]
    t2 = time.perf_counter()
    return J, t1 - t0, t2 - t1, factor.fill


def run(shape):
    t0 = time.perf_counter()
    cell = tenscell.model.lattice_cell(*shape)
    t1 = time.perf_counter()
    count = _Counter()
    modal.factorize_spd = count
    try:
        lin = tenscell.linearize(cell, P=P, EA=_EA(cell), c=C)
        t2 = time.perf_counter()
        Gp, Gpp = tenscell.moduli(lin, F)
        t3 = time.perf_counter()
    finally:
        modal.factorize_spd = count.real
    G = Gp + 1j * Gpp
    row = {"shape": shape, "nodes": cell.structure.n_nodes, "dof": cell.n, "build": t1 - t0, "linearize": t2 - t1,
           "moduli": t3 - t2, "total": t3 - t0, "factorizations": count.n,
           "steps": max((r.steps for runs in lin.pencil._runs.values() for r in runs), default=0)}
    J_old, t_check, t_mod, fill = _old_moduli(cell, lin)
    row.update(old_linearize=t_check, old_moduli=t_mod, old_fill=fill,
               diff=float(np.max(np.abs(modal.modulus(J_old, lin.L) - G) / np.abs(G))))
    return row


def creep_relaxation():
    """Creep + relaxation of the 1,896-coordinate lattice: the library (sparse) against the old dense path."""
    cell = tenscell.model.lattice_cell(*CREEP_SHAPE)
    lin = tenscell.linearize(cell, P=P, EA=_EA(cell), c=C)
    t0 = time.perf_counter()
    spec = tenscell.timedomain.creep_spectrum(lin)
    rel = tenscell.stress_relaxation(lin)
    t_new = time.perf_counter() - t0
    K0, C0 = lin.K0.toarray(), lin.C0.toarray()
    t0 = time.perf_counter()
    for _ in range(2):  # the old creep_spectrum and, inside stress_relaxation, creep_spectrum again
        tau, V = scipy.linalg.eigh(C0, K0)
    t_old = time.perf_counter() - t0
    rho = (lin.D0 @ V) * (-lin.H0 @ V)
    t = np.logspace(-5, 2, 50)
    J_old = (-np.expm1(-np.multiply.outer(t, 1.0 / np.maximum(tau, 1e-300)))) @ rho
    diff = float(np.max(np.abs(spec.compliance(t) - J_old) / J_old))
    return {"dof": cell.n, "new": t_new, "old": t_old, "diff": diff, "modes": spec.times.size,
            "relaxation_times": rel.times.size, "error_estimate": spec.error_estimate}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="add the 1.1e5-coordinate lattice (about 2 minutes more)")
    args = ap.parse_args(argv)
    print(f"# tenscell bench_scale: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start; "
          f"BLAS threads {_threads.thread_count()}; 100 frequencies 1e-2..1e3 Hz; EA = 1 N (tendons), 1e3 N (struts), "
          f"c = {C:g} N·s/m, P = {P:g} N")
    head = (f"{'modules':>9} {'nodes':>7} {'dof':>7} {'build':>7} {'linear.':>7} {'moduli':>7} {'total':>7} "
            f"{'fact.':>5} {'steps':>5} {'old lin':>8} {'old mod':>8} {'old/new':>8} {'max|ΔG|/G':>10}")
    print(head)
    print(f"{'':>9} {'':>7} {'':>7} {'(s)':>7} {'(s)':>7} {'(s)':>7} {'(s)':>7} {'':>5} {'':>5} {'(s)':>8} {'(s)':>8}")
    rows = []
    with _threads.limited():
        run((2, 2, 2))  # warm-up: first-call imports and caches, not timed
        for shape in SHAPES + (FULL_SHAPES if args.full else []):
            r = run(shape)
            rows.append(r)
            new, old = r["linearize"] + r["moduli"], r["old_linearize"] + r["old_moduli"]
            print(f"{'x'.join(map(str, shape)):>9} {r['nodes']:7d} {r['dof']:7d} {r['build']:7.2f} {r['linearize']:7.2f} "
                  f"{r['moduli']:7.2f} {r['total']:7.2f} {r['factorizations']:5d} {r['steps']:5d} "
                  f"{r['old_linearize']:8.2f} {r['old_moduli']:8.2f} {old / new:7.2f}x {r['diff']:10.1e}", flush=True)
        cr = creep_relaxation()
    print("# linear.: linearize with the positive-definiteness check (CHOLMOD factor of K0); moduli: the factor of "
          "K0 + σC0 and the Lanczos run; fact.: sparse factorizations per model")
    print("# old: SuperLU + nested dissection for the same two factorizations and the same Lanczos run; "
          "old/new: ratio of linearize + moduli; max|ΔG|/G: the two answers' largest relative difference")
    big = rows[-1]
    print(f"ratio old/new (linearize + moduli) at dof={big['dof']}: "
          f"{(big['old_linearize'] + big['old_moduli']) / (big['linearize'] + big['moduli']):.2f}x; "
          f"end to end (with the build): {(big['build'] + big['old_linearize'] + big['old_moduli']) / big['total']:.2f}x")
    fit = [r for r in rows if r["dof"] >= 1500]
    expo = np.polyfit(np.log([r["dof"] for r in fit]), np.log([r["total"] for r in fit]), 1)[0]
    expo_old = np.polyfit(np.log([r["dof"] for r in fit]),
                          np.log([r["build"] + r["old_linearize"] + r["old_moduli"] for r in fit]), 1)[0]
    for r in rows:
        if r["shape"] == HEADLINE:
            print(f"lattice nodes={r['nodes']} dof={r['dof']} frequencies={len(F)} seconds={r['total']:.2f} "
                  f"(issue 21 goal <= 1.5 s build included, quiet machine; issue 9: <= 3 s)")
    print(f"growth exponent, dof {fit[0]['dof']}..{fit[-1]['dof']}: {expo:.2f} (old path {expo_old:.2f}; issue 21 goal <= 1.2; issue 9: <= 1.4)")
    print(f"creep + relaxation, {cr['dof']}-coordinate lattice: library {cr['new']:.3f} s (sparse, "
          f"{cr['modes']} Ritz modes, estimated error {cr['error_estimate']:.1e}), old dense path {cr['old']:.2f} s: "
          f"ratio {cr['old'] / cr['new']:.0f}x (goal >= 30x); max |ΔJ(t)|/J(t) {cr['diff']:.1e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
