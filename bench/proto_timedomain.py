"""Prototype (issue 26, item 5c): the candidate mechanisms in the time domain, on one HL60 cell and one oocyte.

* HL60 optical-stretcher creep J(t) (1/Pa, 0.15-4 s after the step; ggf example data): each mechanism's creep
  compliance ``J̄(s) = 1/(s·G*(s))`` with ``G*(s)`` the assignments' mean of ``(0.5/L)/J_cell(s) + sη`` (the same
  average the frequency-domain fits use), inverted exactly at each time (:func:`tenscell.timedomain.invert_laplace`
  on the law's ``k*(s)``); fitted (all its material parameters and P) by least squares on log10 J; against the
  power law ``J = A t^x`` (2 parameters).
* Oocyte AFM stress relaxation (Battistella et al. 2022; force at constant height, 15 curves, 0.004-28 s): the
  probe radius is unknown, so only the shape F(t)/F(t_ref) is compared, with the relaxation modulus
  ``G(t)/G(t_ref)``, ``Ḡ(s) = G*(s)/s − η`` (the cytoplasm's impulse removed); against the power law
  ``(t/t_ref)^(-x)`` (1 shape parameter). The AFM approach ramp (1 s) is not a step: the first second is
  reported separately.

The fits are local (a few starts); RMS in decades of the fitted quantity.
Run: .venv/bin/python bench/proto_timedomain.py [mechanism...]
"""
from __future__ import annotations

import math
import os
import sys
import time

import numpy as np
import scipy.optimize as so

sys.path.insert(0, os.path.dirname(__file__))
from proto_common import load_banner  # noqa: E402
from proto_geometric import candidates  # noqa: E402

import tenscell.laws as laws  # noqa: E402
from tenscell.fitting.models.mechanism import make_mechanism_problem  # noqa: E402
from tenscell.io.data import RheologyData  # noqa: E402
from tenscell.linear.dynamic import dynamic_compliance  # noqa: E402
from tenscell.linear.assembly import modulus  # noqa: E402
from tenscell.studies.real_cells import hl60_creep, oocyte_relaxation  # noqa: E402
from tenscell.timedomain import invert_laplace  # noqa: E402

DIRECTORY = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "real-cells")


def layout(mech, fixed):
    """A mechanism problem on a dummy frequency sweep: its parameter layout and law values (no data used)."""
    f = np.logspace(-1, 1, 6)
    d = RheologyData(frequency_hz=f, G_storage=np.ones(6), G_loss=np.ones(6), source="layout")
    return make_mechanism_problem(d, mech, fixed=fixed)


def G_of_s(pb, phi, s):
    """G*(s) (Pa): the assignments' mean of (0.5/L)/J(s) at the fitted P, plus s·η."""
    vals, _ = pb.law_values(phi)
    law_cls = getattr(laws, pb.mechanism.law)
    P = math.exp(phi[list(pb.names).index("P")])
    K = next(iter(vals.values())).shape[0]
    G = np.zeros(s.size, complex)
    for k in range(K):
        law = law_cls._trusted(**{n: v[k] for n, v in vals.items()})
        kstar = law.laplace_stiffness(pb.lengths, P * pb.T0, s)
        G += modulus(dynamic_compliance(pb.cell, P, kstar), pb.L_ref)
    G /= K
    if pb.eta_index is not None:
        G = G + s * math.exp(phi[pb.eta_index])
    return G


def fit_curve(pb, model, y_obs, starts=4, seed=0):
    """Least squares of log10 model(phi) against y_obs over the problem's free log-parameters (FD Jacobian)."""
    rng = np.random.default_rng(seed)
    lo, hi = pb.bounds

    def res(th):
        try:
            y = model(pb.full(th))
        except (ValueError, np.linalg.LinAlgError):
            return np.full(y_obs.size, 10.0)
        if not np.all(np.isfinite(y)) or np.any(y <= 0):
            return np.full(y_obs.size, 10.0)
        return np.log10(y) - y_obs

    best = None
    for _ in range(starts):
        th0 = pb.initial_guess(rng)
        r = so.least_squares(res, th0, bounds=(lo, hi), method="trf", x_scale="jac", max_nfev=150, diff_step=1e-6)
        if best is None or r.cost < best.cost:
            best = r
    return best, float(np.sqrt(np.mean(best.fun ** 2)))


def main(argv):
    cands = candidates()
    names = argv or ["springpot+visc", "springpot-alpha-family+visc", "springpot-lognormal-kappa+visc",
                     "springpot-tension+visc (free gauge)", "maxwell+visc"]
    creep = hl60_creep(DIRECTORY)
    t, J = creep.time_s, creep.compliance
    oo = oocyte_relaxation(DIRECTORY)
    to, shape = oo.shape()
    keep = shape > 0
    to, shape = to[keep], shape[keep]
    print(f"# proto_timedomain: {load_banner()}")
    x, lnA = np.polyfit(np.log(t), np.log(J), 1)
    rms_pl = float(np.sqrt(np.mean((np.log10(J) - (lnA + x * np.log(t)) / math.log(10)) ** 2)))
    xo = -np.polyfit(np.log(to / to[0]), np.log(shape), 1)[0]
    late = to >= 1.0
    rms_po = float(np.sqrt(np.mean((np.log10(shape) + xo * np.log10(to / to[0])) ** 2)))
    rms_po_late = float(np.sqrt(np.mean((np.log10(shape[late]) + xo * np.log10(to[late] / to[0])) ** 2)))
    print("| data | model | free | RMS (decades) | RMS t ≥ 1 s | note | CPU s |")
    print("|---|---|---|---|---|---|---|")
    print(f"| HL60 creep | power law A t^x | 2 | {rms_pl:.3f} | — | x = {x:.3f} | 0 |")
    print(f"| oocyte relaxation shape | power law (t/t0)^-x | 1 | {rms_po:.3f} | {rms_po_late:.3f} | x = {xo:.3f} | 0 |",
          flush=True)
    for name in names:
        mech, _, _, fixed = cands[name]
        pb = layout(mech, fixed)
        t0 = time.process_time()
        best, r = fit_curve(pb, lambda phi: invert_laplace(lambda s: 1.0 / (s * G_of_s(pb, phi, s)), t),
                            np.log10(J))
        y = invert_laplace(lambda s: 1.0 / (s * G_of_s(pb, pb.full(best.x), s)), np.array([1.0, 2.0]))
        print(f"| HL60 creep | {name} | {int(pb.free.sum())} | {r:.3f} | — | local exponent 1-2 s "
              f"{math.log(y[1] / y[0]) / math.log(2):.3f} | {time.process_time() - t0:.0f} |", flush=True)
        t0 = time.process_time()

        def relax(phi):
            eta = math.exp(phi[pb.eta_index]) if pb.eta_index is not None else 0.0
            g = invert_laplace(lambda s: G_of_s(pb, phi, s) / s - eta, to)
            return g / g[0]

        best, r = fit_curve(pb, relax, np.log10(shape))
        g = relax(pb.full(best.x))
        r_late = float(np.sqrt(np.mean((np.log10(g[late]) - np.log10(shape[late])) ** 2)))
        print(f"| oocyte relaxation shape | {name} | {int(pb.free.sum())} | {r:.3f} | {r_late:.3f} | "
              f"| {time.process_time() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
