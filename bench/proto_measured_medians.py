"""Prototype (issue 26, G3): mechanisms and baselines on the measured Xie et al. 2024 medians, out of sample.

For each cell line (MCF-10A, MDA-MB-436; the medians of ``../shared/data/real-cells``, read by
:mod:`tenscell.studies.real_cells`; weighted by their bootstrap standard errors of the median) and each split

* train 1-30 Hz -> score 100 and 200 Hz (G3's split),
* train 3-100 Hz -> score 1 and 200 Hz,

every model is fitted on the training frequencies and scored (unweighted RMS of log10 G', log10 G'', decades) on
the held-out ones: the mechanisms on the paper cell (no prestress is measured: P is fitted in N), each
mechanism's structure-free formula (:class:`proto_common.Lumped`), the power law (structural damping) with and
without a Newtonian term (:func:`proto_common.power_law_fit`).

Caveats the numbers inherit (real_cells.FACTS): the authors' selection of monotone curves, the undocumented drag
correction at 100-200 Hz, unreliable 1 Hz points, medians over the cells positive at all 6 frequencies.

Run: .venv/bin/python bench/proto_measured_medians.py [--unweighted] [names...]
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from proto_common import fit, load_banner, lumped_problem, power_law_fit, problem  # noqa: E402
from proto_geometric import candidates  # noqa: E402

from tenscell.io.data import RheologyData  # noqa: E402
from tenscell.studies.real_cells import XIE_LINES, real_cells_directory, xie_median  # noqa: E402

SPLITS = {"1-30 -> 100,200 Hz": ((1.0, 30.0), (100.0, 200.0)), "3-100 -> 1,200 Hz": ((3.0, 100.0), (1.0, 200.0))}
DIRECTORY = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "real-cells")


def subset(d: RheologyData, fs) -> RheologyData:
    sel = np.isin(d.frequency_hz, fs)
    return RheologyData(frequency_hz=d.frequency_hz[sel], G_storage=d.G_storage[sel], G_loss=d.G_loss[sel],
                        G_storage_sd=None if d.G_storage_sd is None else d.G_storage_sd[sel],
                        G_loss_sd=None if d.G_loss_sd is None else d.G_loss_sd[sel], source=d.source)


def window(d, lo, hi):
    return subset(d, d.frequency_hz[(d.frequency_hz >= lo) & (d.frequency_hz <= hi)])


def rms(model_G, d):
    r = np.r_[np.log10(model_G.real) - np.log10(d.G_storage), np.log10(model_G.imag) - np.log10(d.G_loss)]
    return float(np.sqrt(np.mean(r ** 2)))


def mech_scores(mech, cell, train, test, lumped=False, starts=6, hops=6, fixed=None):
    if lumped:
        pb = lumped_problem(train, mech, fixed_law=fixed)
    else:
        pb = problem(train, mech, cell, anchored=False, fixed=fixed)
    fo = fit(pb, starts=starts, hops=hops)
    phi = pb.full(fo.theta)
    w = 2 * np.pi * test.frequency_hz
    if lumped:
        P = np.full(w.size, pb.model_P(phi)[0])
        G = pb.moduli_phi(phi, w, P)
    else:
        P = np.full(w.size, pb.group_prestress(fo.theta)[0])
        out = pb.evaluate(phi, w, P, jac=False)
        G = out.G if out is not None else np.full(w.size, np.nan + 1j * np.nan)
    return max(fo.rms), rms(G, test), int(pb.free.sum()), fo.cpu_s


def baseline_scores(train, test, newtonian):
    f = power_law_fit(train, newtonian)
    Gs, Gl = f.moduli(test.frequency_hz)
    G = Gs + 1j * Gl
    Gt_s, Gt_l = f.moduli(train.frequency_hz)
    return rms(Gt_s + 1j * Gt_l, train), rms(G, test), 3 if newtonian else 2


def unweighted(d: RheologyData) -> RheologyData:
    return RheologyData(frequency_hz=d.frequency_hz, G_storage=d.G_storage, G_loss=d.G_loss, source=d.source)


def main(argv):
    real_cells_directory(DIRECTORY)
    cands = candidates()
    weighted = "--unweighted" not in argv
    argv = [a for a in argv if a != "--unweighted"]
    names = argv or ["springpot-alpha-family+visc", "springpot+visc", "springpot-tension+visc (free gauge)",
                     "springpot-lognormal-kappa+visc", "maxwell+visc"]
    how = "weighted by the medians' bootstrap standard errors" if weighted else "unweighted"
    print(f"# proto_measured_medians: {load_banner()}; fits {how}")
    print("| line | split | model | free | train RMS | held-out RMS | CPU s |")
    print("|---|---|---|---|---|---|---|")
    for line in XIE_LINES:
        d = xie_median(line, DIRECTORY)
        d = d if weighted else unweighted(d)
        for split, ((lo, hi), held) in SPLITS.items():
            train, test = window(d, lo, hi), subset(d, np.array(held))
            for newt in (True, False):
                tr, te, k = baseline_scores(train, test, newt)
                print(f"| {line} | {split} | power law{' + Newtonian' if newt else ''} | {k} | {tr:.3f} | {te:.3f} | 0 |",
                      flush=True)
            for name in names:
                mech, cell_of, _, fixed = cands[name]
                for lumped in (False, True):
                    t0 = time.process_time()
                    tr, te, k, _ = mech_scores(mech, cell_of(), train, test, lumped=lumped, fixed=fixed)
                    label = f"{name} formula" if lumped else name
                    print(f"| {line} | {split} | {label} | {k} | {tr:.3f} | {te:.3f} | "
                          f"{time.process_time() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
