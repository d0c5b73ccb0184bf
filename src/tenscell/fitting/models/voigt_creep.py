"""Creep compliance J(t) from the relaxation spectrum, and its analytic derivatives (for fits to creep data).

The linear model's compliance is ``J(s) = Σ_k α_k β_k/(s + λ_k)`` (m/N) with the
relaxation rates ``K0 v = λ C0 v`` (C0-orthonormal modes, ``α = D0·v``,
``β = −H0·v``; see :mod:`tenscell.linear.linearize`). A unit force step is
``1/s`` in Laplace space, so the creep compliance is

``J(t) = Σ_k α_k β_k g(λ_k, t)``,  ``g(λ, t) = (1 − e^{−λt})/λ``,

the same as :func:`tenscell.timedomain.creep_compliance` (``ρ_k = α_kβ_k/λ_k``,
``τ_k = 1/λ_k``); in 1/Pa it is ``J(t)·2L`` (the continuum factor of
``G = (0.5/L)/J``). A parameter entering ``Z(s) = K0 + sC0`` as ``∂Z`` changes
``J(s)`` by ``−yᵀ∂Z x`` with ``x = Z⁻¹(−H0)``, ``y = Z⁻ᵀD0ᵀ``; in modal
coordinates ``yᵀa = Σ_k α_k (a·v_k)/(s + λ_k)``, so each derivative of J(t) is
the inverse Laplace transform of ``1/(s (s+λ_k)(s+λ_l))`` (stiffness and
prestress: ``∂Z`` does not depend on s) or ``1/((s+λ_k)(s+λ_l))`` (damping:
``∂Z = s·a aᵀ``), summed over mode pairs:

``φ(λ_k, λ_l, t) = t²·F(λ_k t, λ_l t)``, ``F(x, y) = (E(y) − E(x))/(x − y)``,
``h(λ_k, λ_l, t) = t·e^{−y}·E(x − y)`` (x ≥ y), with ``E(z) = (1 − e^{−z})/z``.

Both are evaluated without cancellation: ``h`` as written; ``F`` by its Taylor
series ``Σ_n (−1)^n h_n(x, y)/(n+2)!`` (complete homogeneous polynomials)
for small arguments, and as ``(1 − e^{−y} − y e^{−y} E(x − y))/(x y)``
(y ≤ x) otherwise, so that equal and nearly equal rates (the symmetric
modes of a homogeneous cell) need no special case.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["step_kernel", "pair_kernels", "creep_from_modes", "creep_derivatives"]

_SERIES_BELOW = 0.5  # both arguments below this: Taylor series of F
_SERIES_TERMS = 24  # 0.5^24/26! ~ 1e-34: exact to rounding


def _E(z):
    """``(1 − e^{−z})/z`` for z ≥ 0 (1 at z = 0), without cancellation."""
    z = np.asarray(z, dtype=float)
    small = z < 1e-8
    safe = np.where(small, 1.0, z)
    return np.where(small, 1.0 - 0.5 * z, -np.expm1(-safe) / safe)


def step_kernel(rates, t) -> np.ndarray:
    """``g(λ_k, t) = (1 − e^{−λ_k t})/λ_k`` (s), shape (len(t), len(rates)); rates > 0 (1/s), t ≥ 0 (s)."""
    t = np.asarray(t, dtype=float)[:, None]
    return t * _E(t * np.asarray(rates, dtype=float)[None, :])


def pair_kernels(rates, t) -> tuple[np.ndarray, np.ndarray]:
    """``φ`` and ``h`` for every mode pair, each shape (len(t), n, n), symmetric in the pair.

    ``φ(λ_k, λ_l, t)`` (s²) is the inverse Laplace transform of
    ``1/(s (s+λ_k)(s+λ_l))`` and ``h(λ_k, λ_l, t)`` (s) that of
    ``1/((s+λ_k)(s+λ_l))`` (module docstring).
    """
    lam = np.asarray(rates, dtype=float)
    t = np.asarray(t, dtype=float)
    X = t[:, None, None] * lam[None, :, None]  # (T, n, 1) → broadcast to pairs
    Y = t[:, None, None] * lam[None, None, :]
    X, Y = np.broadcast_arrays(X, Y)
    hi, lo = np.maximum(X, Y), np.minimum(X, Y)
    d = hi - lo
    t2 = (t * t)[:, None, None]
    h = t[:, None, None] * np.exp(-lo) * _E(d)
    F = np.empty_like(hi)
    small = hi < _SERIES_BELOW
    if small.any():
        x, y = hi[small], lo[small]
        term = np.ones_like(x)  # h_0
        xn = np.ones_like(x)
        total = term / 2.0
        for n in range(1, _SERIES_TERMS):
            xn = xn * x
            term = xn + y * term  # h_n = x^n + y·h_{n−1}
            total += (-1) ** n * term / math.factorial(n + 2)
        F[small] = total
    big = ~small
    if big.any():
        x, y = hi[big], lo[big]
        F[big] = (-np.expm1(-y) - y * np.exp(-y) * _E(x - y)) / (x * y)
    return t2 * F, h


def creep_from_modes(rates, alpha, beta, t) -> np.ndarray:
    """``J(t) = Σ_k α_k β_k g(λ_k, t)`` (m/N) at times ``t`` (s), shape (len(t),)."""
    return step_kernel(rates, t) @ (np.asarray(alpha) * np.asarray(beta))


def creep_derivatives(rates, alpha, beta, AV, M, t, dk, deta, P) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Log-derivatives of J(t) by each tendon's stiffness and damping and by the prestress.

    Parameters
    ----------
    rates : ndarray, shape (n,)
        Relaxation rates λ_k (1/s).
    alpha, beta : ndarray, shape (n,)
        Probe and load projections of the C0-orthonormal modes.
    AV : ndarray, shape (m, n)
        ``a_j·v_k``: tendon j's direction against mode k.
    M : ndarray, shape (n, n)
        ``Vᵀ Kp V``: the prestress stiffness in modal coordinates.
    t : ndarray, shape (T,)
        Times (s).
    dk : ndarray, shape (m,)
        ``∂k_j/∂ln EA_j`` (N/m): the change of tendon j's stiffness ``a_j a_jᵀ``
        coefficient per e-fold of its EA (``EA_j/l_j`` for a Voigt tendon).
    deta : ndarray, shape (m,)
        ``∂η_j/∂ln c_j`` (N·s/m) (``c_j`` for a Voigt tendon).
    P : float
        Prestress (N): K0 contains ``P·Kp``.

    Returns
    -------
    dJ_EA : ndarray, shape (T, m)
        ``∂J(t)/∂ln EA_j`` (m/N).
    dJ_c : ndarray, shape (T, m)
        ``∂J(t)/∂ln c_j`` (m/N).
    dJ_P : ndarray, shape (T,)
        ``∂J(t)/∂ln P`` (m/N).
    """
    phi, h = pair_kernels(rates, t)
    Aa = AV * alpha[None, :]  # (m, n): a_j·v_k α_k
    Ab = AV * beta[None, :]
    # Σ_kl (a_j v_k α_k) K_kl (a_j v_l β_l) for every tendon j and time
    quad_phi = np.einsum("jk,tkl,jl->tj", Aa, phi, Ab, optimize=True)
    quad_h = np.einsum("jk,tkl,jl->tj", Aa, h, Ab, optimize=True)
    dJ_EA = -quad_phi * dk[None, :]
    dJ_c = -quad_h * deta[None, :]
    dJ_P = -P * np.einsum("k,tkl,kl,l->t", alpha, phi, M, beta, optimize=True)
    return dJ_EA, dJ_c, dJ_P
