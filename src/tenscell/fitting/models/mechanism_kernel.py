"""The mechanism's moduli and their exact derivatives: per-tendon law values, the dynamic kernel, averages.

For parameters ``φ`` (natural logs), each field of the :class:`~tenscell.fitting.models.mechanism.Mechanism`
gives the law parameter of every tendon in every assignment k (K × m values,
:mod:`~tenscell.fitting.models.heterogeneity`), the law gives the dynamic tangent ``k*_j(ω)`` at the tensions
``P·T0`` and its exact derivatives (``complex_stiffness_derivatives``), and the kernel
:func:`tenscell.linear.dynamic.dynamic_compliance` gives J(ω) and the exact ``dJ`` along any set of directions in
k* (:mod:`~tenscell.fitting.models.mechanism` explains the three kinds of direction). The functions take a
:class:`~tenscell.fitting.models.mechanism.MechanismProblem` (its maps and arrays).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ... import laws as _laws
from ...linear.assembly import modulus
from .heterogeneity import DISTRIBUTIONS

__all__ = ["MechanismEvaluation", "law_values", "evaluate"]


@dataclass(frozen=True, eq=False)
class MechanismEvaluation:
    """Moduli at one parameter vector (points of a problem, or any grid)."""

    G: np.ndarray  # (N,) complex moduli (Pa), averaged over assignments, viscosity included
    G_assign: np.ndarray  # (K, N) complex moduli of each assignment (structure + viscosity)
    dG: np.ndarray | None  # (N, n_params) complex dG/dφ


def law_values(problem, phi) -> tuple[dict, dict]:
    """Per law parameter: values (K, m) and d ln value / d φ (K, m, n_params), at log-parameters ``phi``."""
    vals, dln = {}, {}
    for name, D, const in problem.field_maps:
        lnx = const + D @ phi
        dl = D.copy()
        for fname, idx, dist, u in problem.shape_maps:
            if fname == name:  # ln x = ln scale + q(u; shape), with q the distribution's log quantile at scale 1
                q, _, dq = DISTRIBUTIONS[dist](1.0, math.exp(phi[idx])).log_quantile(u)
                lnx = lnx + q
                dl[..., idx] = dq
        vals[name], dln[name] = np.exp(lnx), dl
    return vals, dln


def evaluate(problem, phi, omega, P, jac: bool, dP=None) -> MechanismEvaluation | None:
    """Moduli at angular frequencies ``omega`` (rad/s) and model prestresses ``P`` (N), per point.

    ``dP`` (N, n_params): d ln P / d φ of each point (for the Jacobian). None where not a stable cell.
    """
    from ...linear.dynamic import dynamic_compliance

    vals, dln = law_values(problem, phi)
    law_cls = getattr(_laws, problem.mechanism.law)
    K, m = next(iter(vals.values())).shape
    N = omega.size
    G_assign = np.empty((K, N), dtype=complex)
    dG = np.zeros((N, problem.n_params), dtype=complex) if jac else None
    l, T0 = np.tile(problem.lengths, K), np.tile(problem.T0, K)
    law = law_cls._trusted(**{n: v.ravel() for n, v in vals.items()})
    for Pg in np.unique(P):
        sel = np.flatnonzero(P == Pg)
        w = omega[sel]
        out = _kernel(problem, dynamic_compliance, law, l, float(Pg), Pg * T0, w, vals, dln, K, m, jac)
        if out is None:
            return None
        G_assign[:, sel], dGk, dGP = out
        if jac:
            assert dG is not None and dP is not None
            dG[sel] = dGk + dGP[:, None] * dP[sel]
    if problem.eta_index is not None:
        visc = 1j * omega * math.exp(phi[problem.eta_index])
        G_assign = G_assign + visc[None]
        if jac:
            assert dG is not None
            dG[:, problem.eta_index] += visc
    return MechanismEvaluation(G=G_assign.mean(axis=0), G_assign=G_assign, dG=dG)

def _kernel(problem, dynamic_compliance, law, l, P, T, w, vals, dln, K, m, jac):
    """Structural G of each assignment (K, n_w) and, with ``jac``, dG by φ (n_w, n_params), P dG/dP (n_w,)."""
    nw = w.size

    def stack(a):  # (n_w, K·m) -> (K·n_w, m): assignments stacked along the frequency axis of the kernel
        return np.transpose(a.reshape(nw, K, m), (1, 0, 2)).reshape(K * nw, m)

    ks = law.complex_stiffness(l, T, w)
    kstar = stack(ks)
    if jac:
        dk_dT, dk = law.complex_stiffness_derivatives(l, T, w)
        dirs = np.zeros((problem.n_params + 2, K * nw, m), dtype=complex)
        for p, name in enumerate(law.names):
            if name not in vals:
                continue
            chain = (vals[name][..., None] * dln[name]).reshape(K * m, problem.n_params)  # x_p ∂ln x_p/∂φ
            contrib = dk[p][:, :, None] * chain[None]  # (n_w, K·m, n_params)
            for q in np.flatnonzero(np.any(chain != 0, axis=0)):
                dirs[q] += stack(contrib[..., q])
        dirs[-2] = stack(dk_dT * T[None])  # P ∂k*/∂P at fixed parameters: (∂k*/∂T)·P·T0
        dirs[-1] = kstar  # the Euler direction
    try:
        if jac:
            J, dJ = dynamic_compliance(problem.cell, P, kstar, dirs)
        else:
            J = dynamic_compliance(problem.cell, P, kstar)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(J)):
        return None
    G = modulus(J, problem.L_ref)
    Gk = G.reshape(K, nw)
    if not jac:
        return Gk, None, None
    dlnG = -dJ / J[None]  # (q, K·n_w)
    dG = (G[None] * dlnG).reshape(-1, K, nw).mean(axis=1)  # d mean_k G_k, (q, n_w)
    dGP = G * (1.0 + (dJ[-1] - dJ[-2]) / J)  # P dG/dP = −G·P ∂ln J/∂P (module docstring)
    dGP = dGP.reshape(K, nw).mean(axis=0)
    return Gk, dG[: problem.n_params].T, dGP
