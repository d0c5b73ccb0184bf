"""Shared pieces of the science prototypes (issue 26): fits, structure-free formulas, scores. Not a package module.

* :func:`fit` — multi-start ``scipy.optimize.least_squares`` (trf, exact Jacobian of the problem) with a few
  basin-hopping moves (the problem's own ``perturb``): a fixed budget, reproducible by seed;
* :class:`Lumped` — a mechanism's *structure-free formula*: its tendon law's k*(ω; T) on one lumped element of
  unit length whose tension is ``s·P`` (the same prestress coupling: P in Pa scaled by ``s``, or a fitted P),
  plus the cytoplasm's iωη: ``G* = Σ_families k*_law(ω; l = 1, T = s·P) + iωη`` — one element per family in
  parallel when the mechanism lays a parameter out per family, one element otherwise; the law's parameters are its
  own (per family where the mechanism has them per family); a distributed field takes one value (its scale); the
  same data layout as a mechanism problem;
* :func:`rms_by_set`, :func:`bic`, :func:`score` — scores on any data, at fitted parameters.

Every number printed by a prototype comes from these functions run on the data named in the script.
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize as so

import tenscell.laws as laws
from tenscell.fitting.models.mechanism import make_mechanism_problem
from tenscell.fitting.parameters import prestress_layout, as_datasets
from tenscell.fitting.records import information_criteria

LN10 = math.log(10.0)
SHARED = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data")
ANCHORED = {"s": (0.01, 100.0)}  # model prestress (N) = s × measured (Pa) on the 1 m reference: L = s^-1/2 in 0.1-10


def load_banner():
    la = os.getloadavg()
    return f"load average {la[0]:.2f} {la[1]:.2f} {la[2]:.2f} on {os.cpu_count()} cores"


@dataclass
class FitOut:
    theta: np.ndarray
    cost: float
    rms: tuple
    nfev: int
    cpu_s: float
    at_bound: tuple = ()
    extra: dict = field(default_factory=dict)


def rms_by_set(pb, theta) -> tuple:
    """Unweighted RMS of the log10 residuals per data set (decades); inf where the model failed."""
    r = pb.residuals(theta) / pb.weights
    n = pb.n_points
    out = []
    for k in range(int(pb.dataset_index.max()) + 1):
        sel = pb.dataset_index == k
        rr = np.r_[r[:n][sel], r[n:][sel]]
        out.append(float(np.sqrt(np.mean(rr ** 2))) if np.all(np.abs(rr) < 1e5) else math.inf)
    return tuple(out)


def bic(pb, theta) -> float:
    sigma_known = bool(np.any(pb.weights != 1.0))
    return information_criteria(pb.residuals(theta), int(np.sum(pb.free)), sigma_known=sigma_known,
                                weights=pb.weights)[1]


def fit(pb, starts=6, hops=6, seed=0, max_nfev=200, x0=None) -> FitOut:
    """Best of ``starts`` least-squares runs, each followed by ``hops`` perturb-and-refit moves kept if better."""
    rng = np.random.default_rng(seed)
    lo, hi = pb.bounds
    t0 = time.process_time()
    nfev = 0
    best = None

    def ls(th):
        nonlocal nfev
        r = so.least_squares(pb.residuals, np.clip(th, lo, hi), jac=pb.jacobian, bounds=(lo, hi), method="trf",
                             max_nfev=max_nfev, x_scale="jac")
        nfev += r.nfev
        return r

    inits = [] if x0 is None else [np.asarray(x0, float)]
    inits += [None] * max(starts - len(inits), 0)
    for th0 in inits:
        r = ls(pb.initial_guess(rng) if th0 is None else th0)
        for _ in range(hops):
            r2 = ls(pb.perturb(r.x, rng))
            if r2.cost < r.cost * (1 - 1e-6):
                r = r2
        if best is None or r.cost < best.cost:
            best = r
    assert best is not None
    names = [n for n, f in zip(pb.names, pb.free) if f]
    tol = 1e-3
    at = tuple(n for n, v, a, b in zip(names, best.x, lo, hi) if v - a < tol or b - v < tol)
    return FitOut(best.x, float(best.cost), rms_by_set(pb, best.x), nfev, time.process_time() - t0, at)


def values(pb, theta) -> dict:
    """Free parameters by name, SI (exp of the log-parameters)."""
    return {n: float(math.exp(v)) for n, v, f in zip(pb.names, pb.full(theta), pb.free) if f}


def refit_on(pb_new, fo: FitOut, pb_old, starts=4, hops=4, seed=1) -> FitOut:
    """Fit a problem with the same parameters as ``pb_old`` (other data), starting from ``fo`` and fresh starts."""
    x0 = fo.theta if list(pb_new.names) == list(pb_old.names) else None
    return fit(pb_new, starts=starts, hops=hops, seed=seed, x0=x0)


# ---------------------------------------------------------------------------------------------
# the structure-free formula of a mechanism
# ---------------------------------------------------------------------------------------------
@dataclass
class Lumped:
    """``G* = k*_law(ω; l = 1, T = s·P) + iωη``: a mechanism's tendon law as one element (module docstring).

    Same interface as the mechanism problems for :func:`fit` (residuals, jacobian, bounds, free, full,
    initial_guess, perturb, names, weights, dataset_index, n_points).
    """

    law: str
    names: tuple
    kinds: tuple
    lower: np.ndarray
    upper: np.ndarray
    free: np.ndarray
    fixed_log: np.ndarray
    law_fields: tuple  # law parameter names in the law's order, each mapped to an index of names or a fixed value
    fixed_law: dict
    eta_index: int | None
    omega: np.ndarray
    group_index: np.ndarray
    group_log_offset: np.ndarray
    group_map: np.ndarray
    prestress_start: int
    y_obs: np.ndarray
    weights: np.ndarray
    dataset_index: np.ndarray
    families: tuple = ("all",)
    per_family: tuple = ()  # law parameters with one value per family

    def family_names(self, name):
        if name in self.per_family:
            return [f"{name}_{f}" for f in self.families]
        return [name] * len(self.families)

    @property
    def n_points(self):
        return self.omega.size

    @property
    def bounds(self):
        return self.lower[self.free], self.upper[self.free]

    def full(self, theta):
        phi = self.fixed_log.copy()
        phi[self.free] = theta
        return phi

    def moduli_phi(self, phi, omega, P):
        law_cls = getattr(laws, self.law)
        vals = {}
        for p in law_cls.parameters:  # one element per family (a shared parameter takes one value for all)
            if p.name in self.fixed_law:
                vals[p.name] = np.full(len(self.families), self.fixed_law[p.name])
            else:
                vals[p.name] = np.array([math.exp(phi[self.names.index(n)]) for n in self.family_names(p.name)])
        law = law_cls._trusted(**vals)
        G = np.empty(omega.size, complex)
        ones = np.ones(len(self.families))
        for Pg in np.unique(P):
            sel = P == Pg
            G[sel] = law.complex_stiffness(ones, Pg * ones, omega[sel]).sum(axis=1)
        if self.eta_index is not None:
            G = G + 1j * omega * math.exp(phi[self.eta_index])
        return G

    def model_P(self, phi):
        return np.exp(self.group_log_offset + self.group_map @ phi[self.prestress_start:])[self.group_index]

    def residuals(self, theta):
        phi = self.full(theta)
        try:
            G = self.moduli_phi(phi, self.omega, self.model_P(phi))
        except ValueError:
            return np.full(self.y_obs.size, 1e6)
        if not (np.all(G.real > 0) and np.all(G.imag > 0)):
            return np.full(self.y_obs.size, 1e6)
        return self.weights * (np.r_[np.log10(G.real), np.log10(G.imag)] - self.y_obs)

    def jacobian(self, theta):
        theta = np.asarray(theta, float)
        h = 1e-6
        cols = []
        for k in range(theta.size):
            e = np.zeros_like(theta)
            e[k] = h
            cols.append((self.residuals(theta + e) - self.residuals(theta - e)) / (2 * h))
        return np.stack(cols, axis=1)

    def initial_guess(self, rng):
        lo, hi = self.bounds
        best = None
        for _ in range(48):
            th = lo + (hi - lo) * rng.uniform(0.2, 0.8, lo.size)
            r = self.residuals(th)
            if np.all(np.abs(r) < 1e5):
                sc = float(np.sum(r ** 2))
                if best is None or sc < best[0]:
                    best = (sc, th)
        return best[1] if best else 0.5 * (lo + hi)

    def perturb(self, theta, rng):
        lo, hi = self.bounds
        step = np.minimum(0.5 * LN10, 0.25 * (hi - lo))
        return np.clip(theta + rng.normal(0, 1, theta.size) * step, lo, hi)


_LUMPED_BOUNDS = {"stiffness": (1e-6, 1e8), "coefficient": (1e-6, 1e8), "exponent": (0.01, 0.99),
                  "viscosity": (1e-6, 1e3), "damping": (1e-8, 1e6), "ratio": (1e-3, 1e5), "time": (1e-6, 1e6)}


def lumped_problem(data, mech, *, fixed_law=None, bounds=None) -> Lumped:
    """The structure-free formula of a mechanism spec (its law, its fixed fields; every free field one value)."""
    from tenscell.fitting.models.catalog import mechanism

    mech = mechanism(mech)
    datasets = as_datasets(data)
    law_cls = getattr(laws, mech.law)
    given = dict(fixed_law or {})
    law_names = {p.name for p in law_cls.parameters}
    fixed_law = {k: v for k, v in given.items() if k in law_names}
    fixed_names = {k: v for k, v in given.items() if k not in law_names}  # e.g. alpha_actin
    for f in mech.fields:
        if f.layout == "fixed":
            fixed_law[f.law_parameter] = f.value
    names, kinds = [], []
    per_family = tuple(f.law_parameter for f in mech.fields if f.layout == "family" and f.distribution is None)
    families = ("actin", "intermediate_filament") if per_family else ("all",)
    for p in law_cls.parameters:
        if p.name in fixed_law:
            continue
        kind = next(f.kind for f in mech.fields if f.law_parameter == p.name)
        for n in (dict.fromkeys(f"{p.name}_{fam}" for fam in families) if p.name in per_family else [p.name]):
            names.append(n)
            kinds.append(kind)
    eta_index = None
    if mech.viscosity:
        eta_index = len(names)
        names.append("eta_cytoplasm")
        kinds.append("viscosity")
    p_names, _, _, p_kinds, groups, point_group = prestress_layout(datasets)
    start = len(names)
    names += p_names
    kinds += p_kinds
    bounds = dict(bounds or {})
    known = [d.prestress for d in datasets if d.prestress is not None]
    P_med = float(np.median(np.concatenate(known))) if known else 1.0
    lo, hi = [], []
    for n, k in zip(names, kinds):
        b = bounds.get(n, bounds.get(k))
        if b is None:
            b = {"s": (1e-8, 1e4), "P_data": (1e-3 * P_med, 1e3 * P_med), "P": (1e-6, 1e8)}.get(k) or _LUMPED_BOUNDS[k]
        lo.append(math.log(b[0]))
        hi.append(math.log(b[1]))
    lo, hi = np.array(lo), np.array(hi)
    gm = np.zeros((len(groups), len(p_names)))
    for g, (_, _, _, links) in enumerate(groups):
        for j, v in links.items():
            gm[g, j] = v
    y = np.r_[np.log10(np.concatenate([d.G_storage for d in datasets])),
              np.log10(np.concatenate([d.G_loss for d in datasets]))]
    w = np.r_[np.concatenate([d.weights_storage for d in datasets]), np.concatenate([d.weights_loss for d in datasets])]
    free, fixed_log = np.ones(len(names), bool), 0.5 * (lo + hi)
    for k, v in fixed_names.items():
        free[names.index(k)] = False
        fixed_log[names.index(k)] = math.log(v)
    return Lumped(law=mech.law, names=tuple(names), kinds=tuple(kinds), lower=lo, upper=hi,
                  free=free, fixed_log=fixed_log,
                  law_fields=tuple(p.name for p in law_cls.parameters), fixed_law=fixed_law, eta_index=eta_index,
                  omega=2 * np.pi * np.concatenate([d.frequency_hz for d in datasets]),
                  group_index=np.concatenate(point_group).astype(int),
                  group_log_offset=np.array([g[2] for g in groups]), group_map=gm, prestress_start=start, y_obs=y,
                  weights=w, dataset_index=np.concatenate([np.full(d.n, k) for k, d in enumerate(datasets)]),
                  families=families, per_family=per_family)


def problem(data, mech, cell=None, anchored=True, bounds=None, fixed=None):
    b = dict(ANCHORED if anchored else {})
    b.update(bounds or {})
    return make_mechanism_problem(data, mech, cell, bounds=b or None, fixed=fixed)


@dataclass
class PowerLaw:
    """The structural-damping law ``G* = G0·Γ(1−x)·(iω)^x + iωμ`` fitted to one frequency sweep (x the exponent)."""

    G0: float
    x: float
    mu: float
    rms: float

    def complex(self, f_hz):
        w = 2 * np.pi * np.asarray(f_hz, float)
        return self.G0 * math.gamma(1 - self.x) * (1j * w) ** self.x + 1j * w * self.mu

    def moduli(self, f_hz):
        G = self.complex(f_hz)
        return G.real, G.imag


def power_law_fit(d, newtonian: bool) -> PowerLaw:
    """Least squares on log10 G', log10 G'' (weighted by the data's sd if any), a few starts in the exponent."""
    w = 2 * np.pi * d.frequency_hz
    wt = np.r_[d.weights_storage, d.weights_loss]
    y = np.r_[np.log10(d.G_storage), np.log10(d.G_loss)]

    def G(th):
        x = th[1]
        out = math.exp(th[0]) * math.gamma(1 - x) * (1j * w) ** x
        return out + (1j * w * math.exp(th[2]) if newtonian else 0.0)

    def res(th):
        g = G(th)
        if np.any(g.real <= 0) or np.any(g.imag <= 0):
            return np.full(y.size, 1e3)
        return wt * (np.r_[np.log10(g.real), np.log10(g.imag)] - y)

    lo = [-30.0, 0.01] + ([-30.0] if newtonian else [])
    hi = [30.0, 0.99] + ([10.0] if newtonian else [])
    best = None
    g0 = math.log(float(np.median(d.G_storage)))
    mu0 = math.log(max(float(np.median(d.G_loss / w)) * 0.1, 1e-9))
    for x0 in (0.1, 0.2, 0.35, 0.5):
        th0 = [g0 - x0 * float(np.mean(np.log(w))), x0] + ([mu0] if newtonian else [])
        r = so.least_squares(res, th0, bounds=(lo, hi), method="trf", x_scale="jac")
        if best is None or r.cost < best.cost:
            best = r
    th = best.x
    g = G(th)
    rr = np.r_[np.log10(g.real), np.log10(g.imag)] - y
    return PowerLaw(G0=math.exp(th[0]), x=float(th[1]), mu=math.exp(th[2]) if newtonian else 0.0,
                    rms=float(np.sqrt(np.mean(rr ** 2))))


def fmt(x, nd=3):
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.{nd}f}"
