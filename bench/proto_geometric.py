"""Prototype (issue 26, G1/G2): which mechanisms let the paper's geometric prestress stiffness do the work?

For each candidate (a mechanism spec on a reference cell) on the two bundled data sets jointly
(Stamenović 2002's prestress sweep at 0.1 Hz and Fabry 2001's frequency sweep, both generated from
published laws), with the **anchored gauge** (prestress scale s in [0.01, 100] m², i.e. the strut length
L = s^-1/2 in [0.1, 10] of the reference's 1 m when the model prestress equals the measured one, the paper's
convention) unless the row says "free":

* free parameters, RMS per data set (decades), BIC;
* the share of ΔG' and ΔG'' over 350-1900 Pa (0.1 Hz) carried by the geometric prestress stiffness P·Kp
  (:func:`tenscell.fitting.shares.structure_shares`, exact from the kernel);
* the mechanism's structure-free formula (its law's k* on one lumped element, T = s·P, + iωη) on the same data;
* G2: the same mechanism refitted to the two unlike joint sets (:func:`tenscell.studies.falsification.unlike_sets`:
  stiffness independent of prestress; exponent rising with prestress), its RMS there and the ratio to its RMS
  on the cell data (worst data set against worst; and the changed prestress sweep against the real one);
* held out: trained on the prestress sweep and the frequency sweep up to 1, 10 or 30 Hz, the RMS on the
  frequency sweep above the cut-off (mean and worst of the three), for the mechanism and for its formula
  (``PROTO_HOLDOUT=0`` skips it).

Run: .venv/bin/python bench/proto_geometric.py [names...]   (default: every candidate; about 10 min on 2 cores)
"""
from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, __import__("os").path.dirname(__file__))
from proto_common import bic, fit, load_banner, lumped_problem, problem, values  # noqa: E402

from tenscell.fitting.models.catalog import ACTIVE_BETA, MECHANISMS  # noqa: E402
from tenscell.fitting.models.mechanism import Field as F, Mechanism  # noqa: E402
from tenscell.fitting.shares import structure_shares  # noqa: E402
from tenscell.io import bundled  # noqa: E402
from tenscell.io.data import RheologyData  # noqa: E402
from tenscell.model.shapes import nucleated_cell, paper_cell  # noqa: E402
from tenscell.studies.falsification import unlike_sets  # noqa: E402


def sp(name, ea="family", kappa="family", alpha="shared", kappa_dist=None, visc=True):
    return Mechanism(name, "Springpot", (F("EA", "stiffness", ea), F("kappa", "coefficient", kappa, kappa_dist),
                                         F("alpha", "exponent", alpha)), viscosity=visc)


def tsp(name, beta):
    return Mechanism(name, "TensionSpringpot", (
        F("EA", "stiffness", "shared"), F("kappa", "coefficient", "shared"), F("alpha", "exponent", "shared"),
        F("beta", "ratio", "fixed", value=beta), F("alpha_T", "exponent", "shared")), viscosity=True)


def candidates():
    deg = np.pi / 180
    c = {
        # (mechanism, cell builder, anchored)
        "springpot+visc (free gauge)": (MECHANISMS["springpot+visc"], paper_cell, False),
        "springpot+visc": (MECHANISMS["springpot+visc"], paper_cell, True),
        "springpot-shared+visc": (sp("springpot-shared+visc", "shared", "shared"), paper_cell, True),
        "springpot-alpha-family+visc": (sp("springpot-alpha-family+visc", "shared", "family", "family"), paper_cell, True),
        "springpot-lognormal-kappa+visc": (sp("springpot-lognormal-kappa+visc", "shared", "shared", kappa_dist="lognormal"),
                                           paper_cell, True),
        "springpot-alpha-family-lognormal-kappa+visc": (Mechanism(
            "springpot-alpha-family-lognormal-kappa+visc", "Springpot",
            (F("EA", "stiffness", "shared"), F("kappa", "coefficient", "shared", "lognormal"),
             F("alpha", "exponent", "family")), viscosity=True), paper_cell, True),
        "springpot+visc, delta 47 deg": (MECHANISMS["springpot+visc"], lambda: paper_cell(delta=47 * deg), True),
        "springpot+visc, delta 53 deg": (MECHANISMS["springpot+visc"], lambda: paper_cell(delta=53 * deg), True),
        "springpot-shared+visc, nucleus": (sp("springpot-shared+visc", "shared", "shared"), nucleated_cell, True),
        "maxwell+visc": (MECHANISMS["maxwell+visc"], paper_cell, True),
        "springpot-tension+visc (beta 1000)": (MECHANISMS["springpot-tension+visc"], paper_cell, True),
        "springpot-tension+visc (free gauge)": (MECHANISMS["springpot-tension+visc"], paper_cell, False),
    }
    # exponents held at physical values, so that the cell's 0.2 power law must come from the structure's mixing
    # of prestress (elastic, geometric) and tendon (fractional) stiffness: G ~ P^(1-g) (k s^a)^g with a·g = 0.2
    # (1/2: Rouse-like; 3/4: semiflexible filaments, Gittes & MacKintosh 1998)
    c["springpot+visc, alpha held 0.5"] = (MECHANISMS["springpot+visc"], paper_cell, True, {"alpha": 0.5})
    c["springpot+visc, alpha held 0.75"] = (MECHANISMS["springpot+visc"], paper_cell, True, {"alpha": 0.75})
    c["springpot-alpha-family+visc, actin alpha held 0.75"] = (
        c["springpot-alpha-family+visc"][0], paper_cell, True, {"alpha_actin": 0.75})
    for a_act, a_if in ((1 / 3, 2 / 3), (1 / 3, 3 / 4), (1 / 2, 2 / 3), (1 / 2, 3 / 4), (1 / 3, 1 / 2), (1 / 4, 3 / 4)):
        c[f"springpot-alpha-family+visc, alphas held {a_act:.3g}, {a_if:.3g}"] = (
            c["springpot-alpha-family+visc"][0], paper_cell, True,
            {"alpha_actin": a_act, "alpha_intermediate_filament": a_if})
    for beta in (1.0, 3.0, 10.0, 30.0):
        c[f"springpot-tension+visc (beta {beta:g})"] = (tsp(f"springpot-tension-b{beta:g}+visc", beta), paper_cell, True)
    return {k: v if len(v) == 4 else (*v, None) for k, v in c.items()}


CUTOFFS_HZ = (1.0, 10.0, 30.0)
HOLDOUT = os.environ.get("PROTO_HOLDOUT", "1") != "0"


def truncated(d: RheologyData, f_max: float, above: bool = False) -> RheologyData:
    sel = d.frequency_hz > f_max if above else d.frequency_hz <= f_max
    return RheologyData(frequency_hz=d.frequency_hz[sel], G_storage=d.G_storage[sel], G_loss=d.G_loss[sel],
                        source=d.source)


def predict(pb, theta, f_hz, lumped: bool) -> np.ndarray:
    """G* of the fitted problem at frequencies f_hz at the frequency sweep's (last group's) fitted prestress."""
    phi = pb.full(theta)
    w = 2 * np.pi * np.asarray(f_hz, float)
    if lumped:
        P = pb.model_P(phi)[-1]
        return pb.moduli_phi(phi, w, np.full(w.size, P))
    P = pb.group_prestress(theta)[-1]
    out = pb.evaluate(phi, w, np.full(w.size, P), jac=False)
    return out.G if out is not None else np.full(w.size, np.nan + 1j * np.nan)


def heldout(ds, make, lumped):
    """RMS (decades) on the frequency sweep above each cut-off, trained on the prestress sweep + the sweep below."""
    out = []
    for cut in CUTOFFS_HZ:
        train = (ds[0], truncated(ds[1], cut))
        test = truncated(ds[1], cut, above=True)
        pb = make(train)
        fo = fit(pb, starts=4, hops=4)
        G = predict(pb, fo.theta, test.frequency_hz, lumped)
        r = np.r_[np.log10(G.real) - np.log10(test.G_storage), np.log10(G.imag) - np.log10(test.G_loss)]
        out.append(float(np.sqrt(np.mean(r ** 2))))
    return out


def main(argv):
    ds = (bundled("stamenovic2002"), bundled("fabry2001"))
    unlike = unlike_sets(ds)
    cands = candidates()
    names = argv or list(cands)
    print(f"# proto_geometric: {load_banner()}; ACTIVE_BETA = {ACTIVE_BETA:g}", flush=True)
    print("| candidate | free | gauge | RMS S/F | BIC | geo share dG'/dP, dG''/dP | s (m²) | at bound | formula RMS S/F "
          "(free) | unlike flat RMS S/F (worst/worst; S/S) | unlike exp-rising RMS S/F (worst/worst; S/S) "
          "| held-out F above 1, 10, 30 Hz: mean, worst | formula held-out: mean, worst | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        mech, cell_of, anchored, fixed = cands[name]
        t0 = time.process_time()
        cell = cell_of()
        pb = problem(ds, mech, cell, anchored=anchored, fixed=fixed)
        fo = fit(pb, starts=4, hops=4)
        sh = structure_shares(pb, fo.theta)
        v = values(pb, fo.theta)
        lp = lumped_problem(ds, mech, fixed_law=fixed)
        lf = fit(lp, starts=6, hops=4)
        worst = max(fo.rms)
        un = []
        for uds in unlike.values():
            pu = problem(uds, mech, cell, anchored=anchored, fixed=fixed)
            fu = fit(pu, starts=3, hops=3, x0=fo.theta)
            un.append(f"{fu.rms[0]:.4f}/{fu.rms[1]:.4f} ({max(fu.rms) / worst:.2f}; {fu.rms[0] / fo.rms[0]:.2f})")
        # held out: fresh starts only (a start at the full-data optimum would carry the held-out points in)
        ho = heldout(ds, lambda d: problem(d, mech, cell, anchored=anchored, fixed=fixed), False) \
            if HOLDOUT else [math.nan]
        hf = heldout(ds, lambda d: lumped_problem(d, mech, fixed_law=fixed), True) if HOLDOUT else [math.nan]
        print(f"| {name} | {int(pb.free.sum())} | {'anchored' if anchored else 'free'} | {fo.rms[0]:.4f}/{fo.rms[1]:.4f} "
              f"| {bic(pb, fo.theta):.1f} | {sh.geometric_share_storage:.1%}, {sh.geometric_share_loss:.1%} "
              f"| {v.get('s', float('nan')):.3g} | {', '.join(fo.at_bound) or '—'} "
              f"| {lf.rms[0]:.4f}/{lf.rms[1]:.4f} ({int(lp.free.sum())}) | {un[0]} | {un[1]} "
              f"| {np.mean(ho):.3f}, {max(ho):.3f} | {np.mean(hf):.3f}, {max(hf):.3f} "
              f"| {time.process_time() - t0:.0f} |", flush=True)
        print("    " + ", ".join(f"{k}={x:.4g}" for k, x in v.items()), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
