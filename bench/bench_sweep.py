"""Benchmark: G', G'' of the paper cell on 100 prestresses × 1000 frequencies.

Written as a user would write it::

    for P in prestresses:
        moduli(linearize(cell, P=P), f)

and compared, in the same process, with a naive loop of one dense complex
solve of (K0 + iωC0) x = −H0 per (P, f) point. Prints the times and the ratio.
Target (issue 2): grid ≤ 20 ms, ≥ 70× the naive loop.
"""
from __future__ import annotations

import time

import numpy as np

import tenscell


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times), float(np.median(times))


def main() -> None:
    cell = tenscell.paper_cell()
    prestresses = np.linspace(500.0, 4500.0, 100)
    f = np.logspace(-2, 3, 1000)

    def sweep():
        return [tenscell.moduli(tenscell.linearize(cell, P=P), f) for P in prestresses]

    def naive():
        out = np.empty((prestresses.size, f.size), complex)
        for i, P in enumerate(prestresses):
            lin = tenscell.linearize(cell, P=P)
            for k, fk in enumerate(f):
                x = np.linalg.solve(lin.K0 + 2j * np.pi * fk * lin.C0, -lin.H0)
                out[i, k] = (0.5 / lin.L) / (lin.D0 @ x)
        return out

    fast = np.array([g[0] + 1j * g[1] for g in sweep()])
    slow = naive()
    err = float(np.max(np.abs(fast - slow) / np.abs(slow)))
    t_fast, med_fast = best_of(sweep, 15)
    t_naive, _ = best_of(naive, 2)
    print("bench_sweep: paper cell, 100 prestresses x 1000 frequencies (Hz 0.01-1000)")
    print(f"  moduli(linearize(cell, P), f) loop : best {t_fast * 1e3:8.2f} ms   median {med_fast * 1e3:8.2f} ms")
    print(f"  naive: one complex solve per point : best {t_naive * 1e3:8.2f} ms")
    print(f"  ratio naive/fast                   : {t_naive / t_fast:8.1f}x   (target >= 70x; grid target <= 20 ms)")
    print(f"  max relative difference            : {err:.2e}")


if __name__ == "__main__":
    main()
