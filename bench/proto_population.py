"""Prototype (issue 26, G4): a population model on the Xie et al. 2024 single cells against per-cell power laws.

Per cell line (59 MCF-10A, 46 MDA-MB-436 cells; 1-200 Hz, up to 6 frequencies each, no standard deviations):

* **population model** — a mechanism on the paper cell whose material parameters (law, cytoplasm η) are shared by
  every cell of the line, with per cell either its prestress P_i only, or P_i and a scale a_i multiplying its
  moduli (how much structure the probe meets), or P_i with the scale set by the cell's measured aspect ratio,
  a_i = AR_i^γ (one shared γ: the structure input from a measurement); fitted jointly by one
  ``scipy.optimize.least_squares`` (trf) on the stacked residuals, with the block Jacobian assembled from the
  per-cell problems' exact Jacobians (shared columns dense, per-cell columns block-diagonal);
* **baselines** — independent per-cell power laws (the structural-damping law, 2 parameters per cell) and power
  law + Newtonian (3 per cell), :func:`proto_common.power_law_fit`.

Scores (unweighted log10 residuals, decades):

* BIC of each (Gaussian residuals, σ estimated: :func:`tenscell.fitting.records.information_criteria`);
* **held-out cells**, 5-fold (cells in a seeded order): the shared parameters from the other 4/5 of the cells;
  each held-out cell gets *one measured number*, its G'(10 Hz): the population model sets P_i to reproduce it (a_i
  at the training cells' median), a baseline power law takes the training cells' median exponent (and
  viscosity) and scales to it; scored on the cell's other points (RMS over cells of the per-cell RMS);
* **Spearman** of a cell's exponent with its stiffness G'(10 Hz), the exponent defined as the authors did:
  a springpot G* ∝ (iω)^x fitted to G', G'' over 1-100 Hz, to the model's moduli and, for the reference, to the
  data's (the authors' own springpot exponents give -0.72 / -0.77; this definition on the data -0.66 / -0.82).

Run: .venv/bin/python bench/proto_population.py [--line=MCF-10A] [--modes=1,2,ar] [mechanism...]
"""
from __future__ import annotations

import math
import os
import sys
import time

import numpy as np
import scipy.optimize as so
from scipy.stats import spearmanr

sys.path.insert(0, os.path.dirname(__file__))
from proto_common import fit, load_banner, power_law_fit  # noqa: E402
from proto_geometric import candidates  # noqa: E402

from tenscell.fitting.models.mechanism import make_mechanism_problem  # noqa: E402
from tenscell.fitting.records import information_criteria  # noqa: E402
from tenscell.io.data import RheologyData  # noqa: E402
from tenscell.studies.real_cells import XIE_LINES, xie_cells, xie_median  # noqa: E402

DIRECTORY = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "real-cells")
LN10 = math.log(10.0)
F_REF = 10.0  # Hz: the one measured number of a held-out cell is G'(F_REF)
#: per-cell parameters: P_i; P_i and a scale a_i; P_i with a_i = AR_i^gamma (one shared gamma, the measured aspect ratio)
MODES = (1, 2, "ar")
FOLDS = 5


def strip_sd(d: RheologyData) -> RheologyData:
    return RheologyData(frequency_hz=d.frequency_hz, G_storage=d.G_storage, G_loss=d.G_loss, source=d.source)


class Population:
    """Shared mechanism parameters + per-cell log P_i (+ log a_i) over many cells; residuals and block Jacobian."""

    def __init__(self, cells, mech, fixed=None, per_cell=1, ar=None):
        self.probs = [make_mechanism_problem(c, mech, fixed=fixed) for c in cells]
        self.mode = per_cell
        self.log_ar = None if ar is None else np.log10(np.asarray(ar, float))
        per_cell = 1 if per_cell == "ar" else per_cell
        pb0 = self.probs[0]
        self.ip = list(pb0.names).index("P")
        self.free0 = pb0.free.copy()
        self.shared_idx = [i for i in np.flatnonzero(pb0.free) if i != self.ip]
        self.ns, self.N, self.k = len(self.shared_idx), len(cells), per_cell
        self.n = self.ns + self.k * self.N + (self.mode == "ar")
        # every cell's problem has its own default bounds (they scale with its data): take their union
        lo = np.min([p.lower for p in self.probs], axis=0)
        hi = np.max([p.upper for p in self.probs], axis=0)
        self.lower = np.r_[lo[self.shared_idx], np.full(self.N, lo[self.ip])] if per_cell == 1 else \
            np.r_[lo[self.shared_idx], np.full(self.N, lo[self.ip]), np.full(self.N, -5 * LN10)]
        self.upper = np.r_[hi[self.shared_idx], np.full(self.N, hi[self.ip])] if per_cell == 1 else \
            np.r_[hi[self.shared_idx], np.full(self.N, hi[self.ip]), np.full(self.N, 5 * LN10)]
        if self.mode == "ar":  # one shared exponent: log10 a_i = gamma·log10(aspect ratio_i)
            self.lower, self.upper = np.r_[self.lower, -5.0], np.r_[self.upper, 5.0]
        self.rows = np.cumsum([0] + [p.y_obs.size for p in self.probs])

    def cell_theta(self, x, i):
        pb = self.probs[i]
        th = np.zeros(int(pb.free.sum()))
        free_pos = {j: q for q, j in enumerate(np.flatnonzero(pb.free))}
        for q, j in enumerate(self.shared_idx):
            th[free_pos[j]] = x[q]
        th[free_pos[self.ip]] = x[self.ns + i]
        return th

    def scale(self, x, i):
        if self.mode == "ar":
            return x[-1] * self.log_ar[i]
        return x[self.ns + self.N + i] / LN10 if self.k == 2 else 0.0

    def residuals(self, x):
        out = []
        for i, pb in enumerate(self.probs):
            out.append(pb.residuals(self.cell_theta(x, i)) + pb.weights * self.scale(x, i))
        return np.concatenate(out)

    def jacobian(self, x):
        J = np.zeros((self.rows[-1], self.n))
        for i, pb in enumerate(self.probs):
            Ji = pb.jacobian(self.cell_theta(x, i))
            free_pos = {j: q for q, j in enumerate(np.flatnonzero(pb.free))}
            r = slice(self.rows[i], self.rows[i + 1])
            J[r, : self.ns] = Ji[:, [free_pos[j] for j in self.shared_idx]]
            J[r, self.ns + i] = Ji[:, free_pos[self.ip]]
            if self.k == 2:
                J[r, self.ns + self.N + i] = pb.weights / LN10
            if self.mode == "ar":
                J[r, -1] = pb.weights * self.log_ar[i]
        return J

    def fit(self, x0, max_nfev=200):
        r = so.least_squares(self.residuals, np.clip(x0, self.lower, self.upper), jac=self.jacobian,
                             bounds=(self.lower, self.upper), method="trf", x_scale="jac", max_nfev=max_nfev)
        return r

    def moduli(self, x, i, f_hz):
        pb = self.probs[i]
        phi = pb.full(self.cell_theta(x, i))
        w = 2 * np.pi * np.asarray(f_hz, float)
        out = pb.evaluate(phi, w, np.full(w.size, math.exp(phi[self.ip])), jac=False)
        return out.G * 10 ** self.scale(x, i)


def power_exponent(f, G):
    """The exponent of a springpot G* ∝ (iω)^x fitted to G', G'' over the given frequencies (≤ 100 Hz).

    The authors' own 1-100 Hz springpot exponents (``alpha_1to100``) give Spearman -0.72 / -0.77 with G'(10 Hz);
    this fit (the structural-damping law without its Newtonian term) on the same cells gives -0.66 / -0.82 and
    correlates 0.96 / 0.95 with theirs: the one definition applied to data and models alike here
    (:func:`proto_common.power_law_fit`).
    """
    f = np.asarray(f, float)
    d = RheologyData(frequency_hz=f, G_storage=np.real(G), G_loss=np.imag(G), source="exponent")
    return power_law_fit(d, newtonian=False).x


def rms(G, d, skip_ref=False):
    r_s = np.log10(G.real) - np.log10(d.G_storage)
    if skip_ref:
        r_s = r_s[d.frequency_hz != F_REF]
    r = np.r_[r_s, np.log10(G.imag) - np.log10(d.G_loss)]
    return float(np.sqrt(np.mean(r ** 2)))


def start(cells, mech, fixed, med):
    """Shared parameters and P from a fit of the mechanism to the line's median spectrum."""
    pb = make_mechanism_problem(strip_sd(med), mech, fixed=fixed)
    fo = fit(pb, starts=4, hops=4)
    free = np.flatnonzero(pb.free)
    ip = list(pb.names).index("P")
    shared = [fo.theta[q] for q, j in enumerate(free) if j != ip]
    P = fo.theta[list(free).index(ip)]
    return np.array(shared), P


def population_fit(cells, mech, fixed, med, per_cell):
    pop = Population([c.data for c in cells], mech, fixed, per_cell, ar=[c.aspect_ratio for c in cells])
    shared, P = start(cells, mech, fixed, med)
    x0 = np.r_[shared, np.full(pop.N, P)] if per_cell != 2 else np.r_[shared, np.full(pop.N, P), np.zeros(pop.N)]
    if per_cell == "ar":
        x0 = np.r_[x0, 0.0]
    # per-cell P first (shared held: each cell's own scalar least squares), then everything jointly
    for i in range(pop.N):
        def g(p, i=i):
            return pop.probs[i].residuals(pop.cell_theta(np.r_[x0[: pop.ns + i], p, x0[pop.ns + i + 1:]], i))

        x0[pop.ns + i] = so.least_squares(g, [x0[pop.ns + i]], bounds=(pop.lower[pop.ns + i], pop.upper[pop.ns + i]),
                                          max_nfev=50).x[0]
    r = pop.fit(x0)
    return pop, r


def heldout_population(cells, mech, fixed, med, per_cell, rng):
    order = rng.permutation(len(cells))
    scores = []
    for k in range(FOLDS):
        test = order[k::FOLDS]
        train = [cells[i] for i in order if i not in set(test)]
        pop, r = population_fit(train, mech, fixed, med, per_cell)
        a_med = np.median(r.x[pop.ns + pop.N:]) if per_cell == 2 else 0.0  # the training cells' median scale
        for i in test:
            d = cells[i].data
            if F_REF not in d.frequency_hz or d.n < 3:
                continue
            one = Population([d], mech, fixed, per_cell, ar=[cells[i].aspect_ratio])
            target = math.log10(d.G_storage[d.frequency_hz == F_REF][0])

            def cell_x(p):
                if per_cell == 2:
                    return np.r_[r.x[: pop.ns], p, a_med]
                return np.r_[r.x[: pop.ns], p, r.x[-1]] if per_cell == "ar" else np.r_[r.x[: pop.ns], p]

            def g(p):
                return [math.log10(one.moduli(cell_x(p), 0, [F_REF]).real[0]) - target]

            p0 = np.median(r.x[pop.ns: pop.ns + pop.N])
            p = so.least_squares(g, [p0], bounds=(pop.lower[pop.ns], pop.upper[pop.ns])).x
            x = cell_x(p)
            scores.append(rms(one.moduli(x, 0, d.frequency_hz), d, skip_ref=True))
    return float(np.sqrt(np.mean(np.square(scores))))


def baseline(cells, newtonian, rng):
    fits = [power_law_fit(c.data, newtonian) for c in cells]
    res = []
    for c, f in zip(cells, fits):
        Gs, Gl = f.moduli(c.data.frequency_hz)
        res.append(np.r_[np.log10(Gs) - np.log10(c.data.G_storage), np.log10(Gl) - np.log10(c.data.G_loss)])
    k = (3 if newtonian else 2) * len(cells)
    bic = information_criteria(np.concatenate(res), k, sigma_known=False)[1]
    rms_fit = float(np.sqrt(np.mean(np.concatenate(res) ** 2)))
    # held-out cells: the training cells' median exponent (and viscosity); scaled to the cell's G'(10 Hz)
    order = rng.permutation(len(cells))
    scores = []
    for k_ in range(FOLDS):
        test = set(order[k_::FOLDS].tolist())
        tr = [fits[i] for i in range(len(cells)) if i not in test]
        x = np.median([f.x for f in tr])
        mu = np.median([f.mu for f in tr]) if newtonian else 0.0
        for i in test:
            d = cells[i].data
            if F_REF not in d.frequency_hz or d.n < 3:
                continue
            w = 2 * np.pi * d.frequency_hz
            shape = (1j * w) ** x
            G10 = d.G_storage[d.frequency_hz == F_REF][0]
            w10 = 2 * np.pi * F_REF
            # G* = A (iω)^x + iωμ with A from G'(10 Hz) = Re(A (i w10)^x)
            A = G10 / ((1j * w10) ** x).real
            scores.append(rms(A * shape + 1j * w * mu, d, skip_ref=True))
    held = float(np.sqrt(np.mean(np.square(scores))))
    expo = []
    for c, f in zip(cells, fits):
        fs = c.data.frequency_hz[c.data.frequency_hz <= 100]
        Gs, Gl = f.moduli(fs)
        expo.append(power_exponent(fs, Gs + 1j * Gl))
    return bic, rms_fit, held, expo


def main(argv):
    cands = candidates()
    lines = [a.split("=", 1)[1] for a in argv if a.startswith("--line=")] or list(XIE_LINES)
    modes = [m if m == "ar" else int(m) for a in argv if a.startswith("--modes=") for m in a.split("=", 1)[1].split(",")]
    modes = modes or list(MODES)
    argv = [a for a in argv if not a.startswith("--")]
    names = argv or ["springpot-lognormal-kappa+visc", "springpot-alpha-family+visc", "springpot+visc"]
    print(f"# proto_population: {load_banner()}")
    print("| line | model | per cell | free | RMS (fit) | BIC | held-out cells RMS | Spearman(exponent, G'(10 Hz)) "
          "model / data | Spearman(G'(10 Hz), aspect ratio) model / data | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for line in lines:
        cells = [c for c in xie_cells(line, DIRECTORY) if c.data.n >= 4]
        med = xie_median(line, DIRECTORY)
        f100 = np.array([1.0, 3.0, 10.0, 30.0, 100.0])
        data_expo, g10 = [], []
        for c in cells:
            d = c.data
            sel = d.frequency_hz <= 100
            data_expo.append(power_exponent(d.frequency_hz[sel], d.G_storage[sel] + 1j * d.G_loss[sel]))
            g10.append(d.G_storage[d.frequency_hz == F_REF][0] if F_REF in d.frequency_hz else np.nan)
        g10 = np.array(g10)
        ok = np.isfinite(g10)
        rho_data = spearmanr(np.array(data_expo)[ok], g10[ok])[0]
        ar = np.array([c.aspect_ratio for c in cells])
        rho_ar_data = spearmanr(g10[ok], ar[ok])[0]
        for newt in (False, True):
            t0 = time.process_time()
            bic, r_fit, held, expo = baseline(cells, newt, np.random.default_rng(0))
            rho = spearmanr(np.array(expo)[ok], g10[ok])[0]
            print(f"| {line} ({len(cells)} cells) | per-cell power law{' + Newtonian' if newt else ''} | "
                  f"{3 if newt else 2} | {(3 if newt else 2) * len(cells)} | {r_fit:.3f} | {bic:.1f} | {held:.3f} | "
                  f"{rho:+.3f} / {rho_data:+.3f} | — / {rho_ar_data:+.2f} | {time.process_time() - t0:.0f} |", flush=True)
        for name in names:
            mech, _, _, fixed = cands[name]
            for per_cell in modes:
                t0 = time.process_time()
                pop, r = population_fit(cells, mech, fixed, med, per_cell)
                res = r.fun
                bic = information_criteria(res, pop.n, sigma_known=False)[1]
                model_expo = [power_exponent(f100[np.isin(f100, c.data.frequency_hz)],
                                             pop.moduli(r.x, i, f100[np.isin(f100, c.data.frequency_hz)]))
                              for i, c in enumerate(cells)]
                model_g10 = np.array([pop.moduli(r.x, i, [F_REF]).real[0] for i in range(len(cells))])
                rho = spearmanr(model_expo, model_g10)[0]
                rho_ar = spearmanr(model_g10, ar)[0]
                held = heldout_population(cells, mech, fixed, med, per_cell, np.random.default_rng(0))
                label = {1: "P_i", 2: "P_i, a_i", "ar": "P_i; a_i = AR_i^gamma"}[per_cell]
                print(f"| {line} ({len(cells)} cells) | {name} | {label} | {pop.n} | "
                      f"{float(np.sqrt(np.mean(res ** 2))):.3f} | {bic:.1f} | {held:.3f} | {rho:+.3f} / {rho_data:+.3f} "
                      f"| {rho_ar:+.3f} / {rho_ar_data:+.3f} | {time.process_time() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
