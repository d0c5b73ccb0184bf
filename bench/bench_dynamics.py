"""Benchmark: 20 forcing cycles at 1 Hz of the default cell, analytic vs finite-difference Jacobian.

The baseline is the same integration with solve_ivp's own finite-difference
Jacobian (``jac=None``), run in the same process on the same problem. Both
stiff solvers are timed (BDF, the default, and Radau), and the trajectories
are compared so that the speed is not bought with accuracy.

Each configuration is run twice and the faster run is reported (the machine may be shared).

Run: ``PYTHONPATH=src python bench/bench_dynamics.py``
"""
from __future__ import annotations

import time

import numpy as np

import tenscell
from tenscell.laws import voigt_law
from tenscell.dynamics import EquationsOfMotion, SineForce, simulate

CYCLES = 20
FREQ = 1.0  # Hz
AMPLITUDE = 10.0  # N: THD ~2.5 %, a genuinely nonlinear but slack-free state
SAMPLES = 64  # per cycle


def _time(fn, repeat=1):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main() -> None:
    cell = tenscell.paper_cell()
    law = voigt_law(cell, P=1000.0, EA=1.0, c=1.0)
    load = SineForce(AMPLITUDE, FREQ)
    T = CYCLES / FREQ
    t_eval = np.linspace(0.0, T, CYCLES * SAMPLES + 1)

    # cost of one Jacobian: analytic vs n + 1 right-hand sides (what a forward-difference Jacobian needs)
    eq = EquationsOfMotion(cell, law, load)
    y = 1e-3 * np.random.default_rng(0).standard_normal(cell.n)
    eq.velocity(0.1, y)
    tj, _ = _time(lambda: [eq.jacobian(0.1, y + k * 1e-12) for k in range(50)])
    tf, _ = _time(lambda: [eq.velocity(0.1, y + k * 1e-12) for k in range(50)])
    print(f"one Jacobian: analytic {1e3 * tj / 50:.3f} ms; one right-hand side {1e3 * tf / 50:.3f} ms "
          f"(a finite-difference Jacobian needs {cell.n} of them: {1e3 * tf / 50 * cell.n:.2f} ms)")

    print(f"{CYCLES} cycles at {FREQ:g} Hz, F = {AMPLITUDE:g} N, default cell (P = 1000 N, EA = c = 1), rtol = 1e-8")
    print(f"{'solver':7s} {'Jacobian':10s} {'wall (s)':>9s} {'nfev':>7s} {'njev':>5s} {'nlu':>5s}")
    results = {}
    for method in ("BDF", "Radau"):
        for jac in ("analytic", "numeric"):
            wall, sim = _time(lambda: simulate(cell, law, load, T, t_eval=t_eval, method=method, jacobian=jac),
                              repeat=2)
            results[method, jac] = (wall, sim)
            st = sim.stats
            print(f"{method:7s} {jac:10s} {wall:9.2f} {st['nfev']:7d} {st['njev']:5d} {st['nlu']:5d}")
    for method in ("BDF", "Radau"):
        wa, sa = results[method, "analytic"]
        wn, sn = results[method, "numeric"]
        dz = np.abs(sa.z - sn.z).max() / np.abs(sa.z).max()
        print(f"{method}: finite-difference / analytic wall-time ratio = {wn / wa:.2f} "
              f"(trajectories agree to {dz:.1e} of the amplitude)")


if __name__ == "__main__":
    main()
