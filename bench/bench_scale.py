"""Scale: time to G', G'' at 100 frequencies against degrees of freedom, for 3D lattices of 6-strut modules.

Each row builds a block lattice (``tenscell.lattice_cell``: node-sharing modules, assembled
self-stress), linearizes it (with the positive-definiteness check) and computes G', G'' at 100
frequencies from 10⁻² to 10³ Hz — the library's own path: dense below 1500 coordinates, sparse
(one nested-dissection LDLᵀ factorization + a shifted Lanczos run) above. For comparison, in
the same process:

* dense: the same model with dense matrices (relaxation spectrum, O(n³)), where it still runs in
  reasonable time; its answer is compared with the library's;
* naive: one sparse complex LU per frequency with scipy's default ordering — measured on all 100
  frequencies for small models, on two frequencies (×50) for larger ones.

The exponent is fitted to the library's total time for dof ≥ 10³ (below that, fixed overheads
dominate). The last two lines are the 10⁴-node lattice and the exponent.

Usage: python bench/bench_scale.py [--max-dof N]
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import tenscell
from tenscell.linear.krylov import krylov_compliance
from tenscell.io.structure_files import member_values

SHAPES = [(2, 2, 1), (3, 2, 2), (3, 3, 3), (5, 4, 4), (6, 6, 6), (8, 8, 8), (11, 11, 12), (13, 13, 13), (17, 17, 17)]
HEADLINE = (11, 11, 12)  # 10 934 nodes
DENSE_MAX = 5000
NAIVE_FULL_MAX = 2000
NAIVE_PARTIAL_MAX = 12000
F = np.logspace(-2, 3, 100)


def _naive(lin, freqs):
    K, C = sp.csc_matrix(lin.K0), sp.csc_matrix(lin.C0)
    b = -lin.H0.astype(complex)
    return np.array([lin.D0 @ spla.splu((K + 2j * np.pi * f * C).tocsc()).solve(b) for f in freqs])


def run(shape):
    t0 = time.perf_counter()
    cell = tenscell.lattice_cell(*shape)
    t1 = time.perf_counter()
    EA = member_values(cell.structure, {"strut": 1e3, "default": 1.0})
    lin = tenscell.linearize(cell, P=1000.0, EA=EA, c=1.0)
    t2 = time.perf_counter()
    Gp, Gpp = tenscell.moduli(lin, F)
    t3 = time.perf_counter()
    row = {"shape": shape, "nodes": cell.structure.n_nodes, "dof": cell.n, "members": cell.m,
           "build": t1 - t0, "linearize": t2 - t1, "moduli": t3 - t2, "total": t3 - t0, "G": Gp + 1j * Gpp}
    if cell.sparse:
        kr = krylov_compliance(lin, F)  # again, for the step count and fill (not timed)
        row["steps"], row["fill"] = kr.steps, kr.fill
    dense_lin = lin if not cell.sparse else None
    if cell.n <= DENSE_MAX:
        if dense_lin is None:
            dense_lin = dataclasses.replace(lin, K0=lin.K0.toarray(), C0=lin.C0.toarray())
        t = time.perf_counter()
        Gd = (0.5 / lin.L) / tenscell.compliance(dense_lin, F)
        row["dense"] = time.perf_counter() - t
        row["dense_diff"] = float(np.max(np.abs(Gd - row["G"]) / np.abs(Gd)))
    if cell.n <= NAIVE_FULL_MAX:
        t = time.perf_counter()
        Jn = _naive(lin, F)
        row["naive"], row["naive_note"] = time.perf_counter() - t, ""
        row["naive_diff"] = float(np.max(np.abs((0.5 / lin.L) / Jn - row["G"]) / np.abs(row["G"])))
    elif cell.n <= NAIVE_PARTIAL_MAX:
        t = time.perf_counter()
        _naive(lin, F[[0, -1]])
        row["naive"], row["naive_note"] = (time.perf_counter() - t) * 50, "*"
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-dof", type=int, default=None, help="skip lattices with more coordinates")
    args = ap.parse_args(argv)
    print(f"# tenscell bench_scale: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start; "
          f"100 frequencies 1e-2..1e3 Hz; EA = 1 N (tendons), 1e3 N (struts), c = 1 N·s/m, P = 1000 N")
    head = (f"{'modules':>9} {'nodes':>7} {'dof':>7} {'members':>8} {'build':>7} {'linear.':>7} {'moduli':>7} "
            f"{'total':>7} {'steps':>5} {'fill':>10} {'dense':>8} {'naive':>9} {'max|ΔG|/G':>10}")
    print(head)
    print(f"{'':>9} {'':>7} {'':>7} {'':>8} {'(s)':>7} {'(s)':>7} {'(s)':>7} {'(s)':>7}")
    rows = []
    for shape in SHAPES:
        nodes_est = 13 * shape[0] * shape[1] * shape[2]
        if args.max_dof is not None and 3 * nodes_est * 0.55 > args.max_dof and shape != HEADLINE:
            continue
        r = run(shape)
        rows.append(r)
        mods = "x".join(map(str, r["shape"]))
        dense = f"{r['dense']:8.2f}" if "dense" in r else f"{'-':>8}"
        naive = f"{r['naive']:8.2f}{r['naive_note']:1}" if "naive" in r else f"{'-':>9}"
        diffs = [r[k] for k in ("dense_diff", "naive_diff") if k in r]
        diff = f"{max(diffs):10.1e}" if diffs else f"{'-':>10}"
        steps = f"{r['steps']:5d}" if "steps" in r else f"{'dense':>5}"
        fill = f"{r['fill']:10d}" if "fill" in r else f"{'-':>10}"
        print(f"{mods:>9} {r['nodes']:7d} {r['dof']:7d} {r['members']:8d} {r['build']:7.2f} {r['linearize']:7.2f} "
              f"{r['moduli']:7.2f} {r['total']:7.2f} {steps} {fill} {dense} {naive} {diff}", flush=True)
    print("# dense: the same model with dense matrices (O(n³) relaxation spectrum); '-' where skipped")
    print("# naive: one sparse complex LU per frequency (scipy defaults); * = timed on 2 of the 100 frequencies, x50")
    print("# max|ΔG|/G: largest relative difference of the library's G' + iG'' from the dense / naive answers")
    full = [r for r in rows if "naive" in r and not r["naive_note"]]
    if full:
        r = full[-1]
        print(f"ratio naive/library at dof={r['dof']}: {r['naive'] / r['total']:.1f}x (all 100 frequencies)")
    partial = [r for r in rows if "naive" in r and r["naive_note"]]
    if partial:
        r = partial[-1]
        print(f"ratio naive/library at dof={r['dof']}: {r['naive'] / r['total']:.0f}x "
              "(naive extrapolated from 2 frequencies)")
    dense_rows = [r for r in rows if "dense" in r and r["dof"] > 1500]
    if dense_rows:
        r = dense_rows[-1]
        print(f"ratio dense/library at dof={r['dof']}: {r['dense'] / r['total']:.1f}x")
    fit = [r for r in rows if r["dof"] >= 1000]
    if len(fit) >= 2:
        expo = np.polyfit(np.log([r["dof"] for r in fit]), np.log([r["total"] for r in fit]), 1)[0]
    else:
        expo = float("nan")
    head = [r for r in rows if r["shape"] == HEADLINE]
    if head:
        r = head[0]
        print(f"lattice nodes={r['nodes']} dof={r['dof']} frequencies={len(F)} seconds={r['total']:.2f}")
    print(f"growth exponent: {expo:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
