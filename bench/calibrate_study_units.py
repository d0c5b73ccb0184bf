"""The constants of the studies' estimates: each task's work and each figure in units of its kind's probe.

For every study of ``tenscell study`` on the protocol (``tenscell.cli.study.STUDIES``; data studies on the bundled
data), runs its plan's calibration (:func:`tenscell.studies.protocol.calibrate`), then each task in this process,
timing its CPU, and each figure, drawn and saved; prints, per task and per figure, the units it took (CPU over
its kind's rate) beside the units the plan declares. A ratio far from 1 means the constant in the study's module
(``NO_IF_UNITS``, ``ROOT_UNITS``, ``Plan.figures``...) should be the measured value. CPU time, so the ratios hold
at any load (the load average is printed).

    PYTHONPATH=src python bench/calibrate_study_units.py [NAMES]
"""
from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path


def _cpu(fn, *args):
    c = time.process_time()
    out = fn(*args)
    return out, time.process_time() - c


def main(names) -> None:
    from tenscell import plotting
    from tenscell.cli.study import STUDIES, load_study
    from tenscell.io.data import bundled
    from tenscell.studies.protocol import FIGURE, Task, calibrate, figure_probe

    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    for name in names or STUDIES:
        study = load_study(name)
        options = {"data": (bundled("fabry2001"),), "decades": (3.0, 2.0), "starts": 1} if "data" in study.options \
            else {}
        plan = study.plan(options)
        rates, machine = calibrate(plan, (Task("one figure", FIGURE, figure_probe),))
        print(f"== {name}: rates " + ", ".join(f"{k} {v * 1e3:.3g} ms" for k, v in rates.items()))
        results = {}
        for t in plan.tasks:
            results[t.key], cpu = _cpu(t.fn, *t.args, *(results[k] for k in t.needs))
            print(f"   {t.key}: {cpu:.3f} s = {cpu / rates[t.kind]:.3g} units of {t.kind} (declared {t.weight:.3g})")
        result = study.assemble(plan, results)
        units = 0.0
        with tempfile.TemporaryDirectory() as tmp:
            for f in result.figures:
                _, cpu = _cpu(lambda f=f: plotting.save(f.draw(), Path(tmp) / f.name))
                units += cpu / rates[FIGURE]
                print(f"   {f.name}: {cpu:.3f} s = {cpu / rates[FIGURE]:.3g} figure units")
        print(f"   figures: {units:.3g} units (declared {plan.figures:.3g})")


if __name__ == "__main__":
    main(sys.argv[1:])
