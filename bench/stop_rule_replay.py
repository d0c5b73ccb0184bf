"""The search's "starts agree" rules replayed on searches run without stopping: how soon each ends, and at which optimum.

For each mechanism and seed, the search (:func:`tenscell.fitting.search.run_search`, 4 starts) runs ``--rounds``
rounds with no stopping rule (every start runs every move), fitted jointly to the bundled pair, and records every
step: its CPU time, the start's RMS, cost, free log-parameters and its moves since its last 5 % gain. A step does
not depend on the rules (each start has its own random stream), so each rule is then replayed exactly on the
record: after each step, in round order, it either ends the search there or not. Printed per rule: the mean CPU of
the steps run, the steps per seed, and the seeds it ends at a worse optimum than the best the record holds (RMS
more than 0.1 % above). The rules:

* ``agree(P)``: two starts hold the best fit and the moves of the starts that hold it add up to P (the search's
  first count; P = ``patience``, 12);
* ``every(P)``: two starts hold the best fit and the moves of every start add up to P;
* ``agree(12) or every(P)``: the search's rule (P = :data:`~tenscell.fitting.search.EVERY_START` × 12 = 16).

Chains that made ``patience`` moves without a gain stop stepping, as in the search; the plateau and the
polishing rules are not replayed (none of these fits meets its tolerance).

    PYTHONPATH=src python bench/stop_rule_replay.py [--models A B] [--seeds 0,1,2,3,4,5] [--rounds 15]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

MODELS = ("springpot-alpha-family+visc", "springpot+visc", "springpot", "maxwell", "voigt-compact+visc")
PATIENCE = 12


def record(problem, seed: int, rounds: int) -> list[tuple]:
    """Every step of a search without stopping rules: (start, move, CPU s, rms, cost, moves without a gain, theta)."""
    import tenscell.fitting.search as search

    log: list[tuple] = []
    step = search._step

    def timed(pb, chain, settings, max_nfev):
        c = time.process_time()
        out = step(pb, chain, settings, max_nfev)
        log.append((out.start, out.hops, time.process_time() - c, out.rms, out.cost, out.stale, out.theta.copy()))
        return out

    search._step = timed
    try:
        search.run_search(problem, starts=4, hops=rounds - 1, patience=10**6, tolerance=1e-9, seed=seed,
                          progress=False, multimodal=True)
    finally:
        search._step = step
    return log


def replay(log, rule, starts: int = 4) -> tuple[float, int, float]:
    """(CPU s, steps, best rms) of the search that ``rule(state, agree)`` ends, on the record ``log``."""
    from tenscell.fitting.search import AGREE_LOG, AGREE_RMS

    steps = {(e[0], e[1]): e for e in log}
    rounds = 1 + max(e[1] for e in log)
    state: dict[int, tuple] = {}  # start -> (rms, cost, theta, moves without a gain)
    done: set[int] = set()
    cpu, n = 0.0, 0
    for r in range(rounds):
        for k in range(starts):
            if k in done or (k, r) not in steps:
                continue
            _, _, c, rms, cost, stale, theta = steps[(k, r)]
            cpu, n = cpu + c, n + 1
            state[k] = (rms, cost, theta, stale)
            if stale >= PATIENCE:
                done.add(k)
            best = state[min(state, key=lambda j: (state[j][1], j))]
            agree = [j for j in state if state[j][0] <= best[0] * (1 + AGREE_RMS)
                     and float(np.max(np.abs(state[j][2] - best[2]))) <= AGREE_LOG]
            if len(agree) >= 2 and rule(state, agree):
                return cpu, n, best[0]
    return cpu, n, min(v[0] for v in state.values())


def agree(p):
    return lambda state, held: sum(state[j][3] for j in held) >= p


def every(p):
    return lambda state, held: sum(v[3] for v in state.values()) >= p


def main(argv=None) -> int:
    from tenscell._threads import limited
    from tenscell.fitting.models import get_model
    from tenscell.fitting.search import EVERY_START
    from tenscell.io.data import bundled

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    ap.add_argument("--seeds", default="0,1,2,3,4,5")
    ap.add_argument("--rounds", type=int, default=15)
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    data = [bundled("stamenovic2002"), bundled("fabry2001")]
    p = int(round(EVERY_START * PATIENCE))
    rules = {"agree(8)": agree(8), "agree(10)": agree(10), "agree(12)": agree(12), "every(12)": every(12),
             f"every({p})": every(p),
             f"agree(12) or every({p})": lambda state, held: agree(12)(state, held) or every(p)(state, held)}
    print(f"load {', '.join(f'{x:.1f}' for x in os.getloadavg())}; 4 starts x {args.rounds} rounds, seeds {seeds}")
    for name in args.models:
        problem = get_model(name).problem(data)
        with limited():
            logs = {seed: record(problem, seed, args.rounds) for seed in seeds}
        optimum = {seed: min(e[3] for e in log) for seed, log in logs.items()}
        print(f"{name}: the records' optima {sorted({round(v, 6) for v in optimum.values()})}")
        for label, rule in rules.items():
            runs = {seed: replay(log, rule) for seed, log in logs.items()}
            lost = [seed for seed, r in runs.items() if r[2] > optimum[seed] * (1 + 1e-3)]
            print(f"   {label:22s} mean {np.mean([r[0] for r in runs.values()]):.2f} s CPU, steps "
                  f"{[runs[s][1] for s in seeds]}, worse optimum at seeds {lost or 'none'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
