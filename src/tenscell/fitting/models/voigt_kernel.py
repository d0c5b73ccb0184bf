"""The model of a fit and its derivatives: moduli, creep, prestress share and elasticity, each with its analytic Jacobian.

Everything here is a function of a :class:`~tenscell.fitting.models.voigt.FitProblem`
``p`` (its cell arrays and parameter layout) and a log-parameter vector
``phi``, through the relaxation spectrum ``K0 v = λ C0 v`` per prestress
group (:func:`spectrum`). With ``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀ D0ᵀ`` and
``Z = K0 + iωC0``: ``∂J/∂EA_j = −(yᵀa_j)(a_jᵀx)/l_j``,
``∂J/∂c_j = −iω(yᵀa_j)(a_jᵀx)``, ``∂J/∂P = −yᵀKp x``, all frequencies at
once from a few matrix products. The residuals built from these live in
:mod:`~tenscell.fitting.models.voigt`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...laws import Voigt
from ...linear.assembly import modulus
from ...linear.definite import first_indefinite
from ...linear.family import prestress_grid_modes

if TYPE_CHECKING:
    from .voigt import FitProblem

__all__ = ["spectrum", "evaluate", "log_derivatives", "activity", "static_share", "storage_elasticity",
           "creep_compliance", "modal_products"]


def _tangents(EA, c, lengths, T0, P):
    """The Voigt law's tangents at tensions ``P_g·T0`` for every prestress group (the one place the fit meets the law).

    Returns ``(k, dk, dk_dT·T0, eta, deta)``: tangent stiffness ``k`` (groups, m)
    in N/m with its derivative by ``ln EA_j`` and the prestress derivative
    ``∂k/∂P = (∂k/∂T)·T0`` (groups, m); tangent damping ``η`` (m,) in N·s/m with
    its derivative by ``ln c_j``. From :meth:`tenscell.laws.Voigt.tangent`.
    """
    g, m = P.size, EA.size
    law = Voigt._trusted(EA=np.tile(EA, g), c=np.tile(c, g))
    tg = law.tangent(np.tile(lengths, g), (P[:, None] * T0[None]).ravel())
    i_ea, i_c = tg.row("EA"), tg.row("c")
    shape = (g, m)
    k = tg.k.reshape(shape)
    dk = (tg.dk[i_ea] * law.EA).reshape(shape)
    kP = (tg.dk_dT * np.tile(T0, g)).reshape(shape)
    eta, deta = tg.c[:m], tg.dc[i_c][:m] * c
    return k, dk, kP, eta, deta


@dataclass(frozen=True, eq=False)
class _Spectrum:
    """The relaxation spectrum of the model at one parameter vector, per prestress group."""

    P: np.ndarray  # (groups,) effective prestress (N) on the reference cell
    dk: np.ndarray  # (groups, m) d k_j / d ln EA_j (N/m)
    deta: np.ndarray  # (m,) d η_j / d ln c_j (N·s/m)
    B: np.ndarray  # (n, m) whitened tendon directions
    Kpt: np.ndarray  # (groups, n, n) whitened ∂K0/∂P = Σ T0_j ∇²l_j + Σ (∂k_j/∂P) a_j a_jᵀ
    lam: np.ndarray  # (groups, n) relaxation rates (1/s)
    W: np.ndarray  # (groups, n, n) C0-orthonormal modes (whitened)
    alpha: np.ndarray  # (groups, n) probe projections
    beta: np.ndarray  # (groups, n) load projections


@dataclass(frozen=True, eq=False)
class _Evaluation:
    """Moduli, their log-derivatives and the prestress share at one parameter vector."""

    G: np.ndarray  # (N,) complex moduli (Pa)
    dlogG: np.ndarray | None  # (N, n_params) d ln G / d phi
    share: np.ndarray | None  # (groups,) prestress share of the static stiffness
    dshare: np.ndarray | None  # (groups, n_params) d ln share / d phi
    elasticity: np.ndarray | None = None  # (groups,) ∂ln G'/∂ln P at elasticity_omega
    delasticity: np.ndarray | None = None  # (groups, n_params) its d ln / d phi
    Jc: np.ndarray | None = None  # (Nc,) creep compliance at the creep data's times (1/Pa)
    dlogJc: np.ndarray | None = None  # (Nc, n_params) d ln Jc / d phi


def spectrum(p: FitProblem, phi) -> _Spectrum | None:
    """Relaxation spectrum per prestress group; None where the model is not a stable cell.

    ``K0 = P·Σ T0_j ∇²l_j + Σ k_j a_j a_jᵀ`` with the law's tangent
    stiffness ``k_j`` at tension ``P·T0_j`` (it depends on P), ``C0 = Σ η_j a_j a_jᵀ``.
    """
    EA, c, P = p._effective(phi)
    k, dk, kP, eta, deta = _tangents(EA, c, p.lengths, p.T0, P)
    wh = p._whitening(eta)
    if wh is None:
        return None
    B, Ht, bt, Dt = wh
    Kmt = np.matmul(B[None] * k[:, None, :], B.T[None])
    # the one criterion (linear.definite): the whitened K0 of each group is congruent to K0 (C0 is definite)
    if first_indefinite(P[:, None, None] * Ht[None] + Kmt) is not None:
        return None
    lam, W = prestress_grid_modes(Ht, Kmt, P)
    alpha = np.einsum("gnk,n->gk", W, Dt)  # probe projections, D0·v_k
    beta = np.einsum("gnk,n->gk", W, bt)  # load projections, −H0·v_k
    Kpt = Ht[None] + np.matmul(B[None] * kP[:, None, :], B.T[None])
    return _Spectrum(P=P, dk=dk, deta=deta, B=B, Kpt=Kpt, lam=lam, W=W, alpha=alpha, beta=beta)


def evaluate(p: FitProblem, phi, jac: bool, share: bool = False, elasticity: bool = False) -> _Evaluation | None:
    """Moduli (and, if asked, their log-derivatives, the prestress share and elasticity); None if unstable."""
    spec = spectrum(p, phi)
    if spec is None:
        return None
    g = p.group_index
    R = 1.0 / (spec.lam[g] + 1j * p.omega[:, None])  # (N, n)
    aR = spec.alpha[g] * R
    bR = spec.beta[g] * R
    J = np.sum(spec.alpha[g] * bR, axis=1)
    G = modulus(J, p.L_ref)
    dG = log_derivatives(p, spec, J, aR, bR) if jac else None
    sh, dsh = static_share(p, spec, jac) if share else (None, None)
    el, de = storage_elasticity(p, spec, jac) if elasticity else (None, None)
    Jc, dJc = creep_compliance(p, spec, jac) if p.n_creep else (None, None)
    return _Evaluation(G=G, dlogG=dG, share=sh, dshare=dsh, elasticity=el, delasticity=de, Jc=Jc,
                       dlogJc=dJc)


def creep_compliance(p: FitProblem, spec, jac: bool):
    """Creep compliance (1/Pa) at the creep points and, if ``jac``, d ln J / d phi (module :mod:`.creep`)."""
    from .voigt_creep import creep_derivatives, creep_from_modes

    Jc = np.empty(p.n_creep)
    dJ = np.zeros((p.n_creep, p.n_params)) if jac else None
    AV, M = modal_products(spec) if jac else (None, None)
    for g in np.unique(p.creep_group):
        sel = np.flatnonzero(p.creep_group == g)
        t = p.creep_t[sel]
        # J in 1/Pa is the cell's compliance (m/N) times 2L (the continuum factor of G = (0.5/L)/J)
        Jc[sel] = 2.0 * p.L_ref * creep_from_modes(spec.lam[g], spec.alpha[g], spec.beta[g], t)
        if jac:
            assert dJ is not None and AV is not None and M is not None  # computed above when jac
            d_EA, d_c, d_Pg = creep_derivatives(spec.lam[g], spec.alpha[g], spec.beta[g], AV[g], M[g], t,
                                                spec.dk[g], spec.deta, spec.P[g])
            d_P = np.zeros((sel.size, p.n_groups))
            d_P[:, g] = d_Pg
            dJ[sel] = 2.0 * p.L_ref * p._to_params(d_EA, d_c, d_P)
    return Jc, (None if dJ is None else dJ / Jc[:, None])


def modal_products(spec):
    """AV = a_jᵀ v_k (groups, m, n) and M = Vᵀ Kp V (groups, n, n)."""
    AV = np.matmul(spec.B.T[None], spec.W)
    M = np.matmul(np.transpose(spec.W, (0, 2, 1)), np.matmul(spec.Kpt, spec.W))
    return AV, M


def log_derivatives(p: FitProblem, spec, J, aR, bR):
    """d ln G / d phi at the data points, shape (N, n_params)."""
    AV, M = modal_products(spec)
    g = p.group_index
    if spec.lam.shape[0] == 1:  # one prestress: plain matrix products
        ax = bR @ AV[0].T  # a_jᵀ x(ω_i), (N, m)
        ay = aR @ AV[0].T  # a_jᵀ y(ω_i)
        dJ_P = -np.einsum("ik,kl,il->i", aR, M[0], bR) * spec.P[0]  # P ∂J/∂P
    else:
        ax = np.einsum("imk,ik->im", AV[g], bR)
        ay = np.einsum("imk,ik->im", AV[g], aR)
        dJ_P = -np.einsum("ik,ikl,il->i", aR, M[g], bR) * spec.P[g]
    pr = ax * ay
    dJ_EA = -pr * spec.dk[g]  # EA_j ∂J/∂EA_j
    dJ_c = -1j * p.omega[:, None] * pr * spec.deta  # c_j ∂J/∂c_j
    d_P = np.zeros((J.size, p.n_groups), dtype=complex)
    d_P[np.arange(J.size), g] = dJ_P
    return -p._to_params(dJ_EA, dJ_c, d_P) / J[:, None]


def activity(p: FitProblem, spec, w: float, jac: bool):
    """The prestress elasticity ``e = ∂ln G/∂ln P = P·yᵀKp x / J`` per group at ω = ``w`` (rad/s), complex.

    With ``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀD0ᵀ``, ``Z = K0 + iωC0`` and
    ``J = D0·x``. Returns ``(e, J, d ln e/d phi, d ln J/d phi)``, the
    derivatives (groups, n_params) from ``∂x = −Z⁻¹(∂Z)x`` and its
    transpose (None without ``jac``). At ``w = 0``, ``e`` is real: the
    prestress share of the static stiffness.
    """
    P = spec.P
    r = 1.0 / (spec.lam + 1j * w)
    xs, ys = spec.beta * r, spec.alpha * r  # x, y in modal coordinates
    J = np.sum(spec.alpha * xs, axis=1)
    AV, M = modal_products(spec)
    Mx, My = np.einsum("gkl,gl->gk", M, xs), np.einsum("gkl,gl->gk", M, ys)
    Q = np.sum(ys * Mx, axis=1)  # yᵀ Kp x
    e = P * Q / J
    if not jac:
        return e, J, None, None
    ax, ay = np.einsum("gmk,gk->gm", AV, xs), np.einsum("gmk,gk->gm", AV, ys)
    au, av = np.einsum("gmk,gk->gm", AV, Mx * r), np.einsum("gmk,gk->gm", AV, My * r)
    # by ln EA_j (∂Z = dk_j a_j a_jᵀ) and ln c_j (∂Z = iω dη_j a_j a_jᵀ): Q and J both move
    both, single = ay * au + av * ax, ay * ax
    sc = 1j * w * spec.deta
    d_EA = -spec.dk * (both / Q[:, None] - single / J[:, None])
    d_c = -sc * (both / Q[:, None] - single / J[:, None])
    # by the group's own ln P (∂Z = P Kp; the Voigt law's ∂k/∂T depends on neither T nor EA)
    R = np.sum(My * Mx * r, axis=1)  # yᵀ Kp Z⁻¹ Kp x
    d_P = np.diag(1.0 - 2.0 * P * R / Q + P * Q / J)
    dlnJ = p._to_params(-spec.dk * single / J[:, None], -sc * single / J[:, None], np.diag(-P * Q / J))
    return e, J, p._to_params(d_EA, d_c, d_P), dlnJ


def static_share(p: FitProblem, spec, jac: bool):
    """Prestress share of the static stiffness per group (real), and d ln share / d phi."""
    e, _, de, _ = activity(p, spec, 0.0, jac)
    return e.real, (None if de is None else de.real)


def storage_elasticity(p: FitProblem, spec, jac: bool):
    """``∂ln G'/∂ln P`` per group at :attr:`elasticity_omega`, and its d ln / d phi.

    ``E' = Re(G·e)/Re(G)`` with ``G ∝ 1/J``.
    """
    e, J, de, dJ = activity(p, spec, p.elasticity_omega, jac)
    G = 1.0 / J
    E = (G * e).real / G.real
    if not jac:
        return E, None
    dG = -dJ * G[:, None]  # dG = G·d ln G
    dA = (G * e)[:, None] * (de - dJ)
    dE = (dA.real * G.real[:, None] - (G * e).real[:, None] * dG.real) / (G.real**2)[:, None]
    return E, dE / E[:, None]
