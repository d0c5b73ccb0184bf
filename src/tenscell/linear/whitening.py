"""The basis in which a cell's damping matrix is the identity: the fits' view of the pencil (K0, C0).

A fit evaluates the pencil of one cell at thousands of parameter vectors and
at every prestress of its data, so it never forms K0 and C0 themselves. With
``C0 = A diag(η) Aᵀ = Lc Lcᵀ`` (Cholesky), the tendon directions, the
prestress Hessian, the load and the probe are taken once into the basis where
C0 is the identity (``B = Lc⁻¹A``, ``H̃ = Lc⁻¹ H Lc⁻ᵀ``, ``b̃ = Lc⁻¹b``,
``d̃ = Lc⁻¹d``); the whitened stiffness at any tangent stiffnesses ``k`` is
then ``P·H̃ + B diag(k) Bᵀ``, whose symmetric eigensolve
(:func:`tenscell.linear.family.prestress_grid_modes`) gives the relaxation
spectrum ``K0 v = λ C0 v`` with C0-orthonormal modes. With one damping for all
tendons (``η = c``) the basis of unit damping is only rescaled.

Whether C0 may be whitened by is the one conditioning rule of
:mod:`tenscell.linear.definite` (:func:`~tenscell.linear.definite.damping_factor`)
at the fits' tolerance :data:`~tenscell.linear.definite.FIT_RTOL`: the fits
have no other route, so they whiten by any C0 whose basis costs them at most
that relative accuracy, and call a C0 beyond it singular.
"""
from __future__ import annotations

import numpy as np

from .definite import FIT_RTOL, damping_factor, tri

__all__ = ["whiten", "whitened_basis", "unit_damping_basis", "rescaled_basis"]


def whiten(Lc: np.ndarray, A: np.ndarray, H: np.ndarray, load: np.ndarray, probe: np.ndarray) -> tuple:
    """``(B, H̃, b̃, d̃)``: A, the symmetric H, load and probe in the basis where ``C0 = Lc Lcᵀ`` is the identity."""
    B = tri(Lc, np.asarray(A, dtype=float))
    X = tri(Lc, np.asarray(H, dtype=float))
    Ht = tri(Lc, X.T)
    bt = tri(Lc, np.asarray(load, dtype=float))
    Dt = tri(Lc, np.asarray(probe, dtype=float))
    return B, 0.5 * (Ht + Ht.T), bt, Dt


def whitened_basis(A: np.ndarray, eta: np.ndarray, H: np.ndarray, load: np.ndarray, probe: np.ndarray):
    """:func:`whiten` for ``C0 = A diag(η) Aᵀ`` (η in N·s/m per tendon); None if C0 may not be whitened by
    (:func:`~tenscell.linear.definite.damping_factor` at the fits' tolerance)."""
    Lc = damping_factor((A * eta) @ A.T, FIT_RTOL)
    return None if Lc is None else whiten(Lc, A, H, load, probe)


def unit_damping_basis(A: np.ndarray, H: np.ndarray, load: np.ndarray, probe: np.ndarray):
    """:func:`whiten` for ``C0 = A Aᵀ`` (every tendon's damping 1 N·s/m); None if that C0 is singular.

    Singular by the conditioning rule (:func:`~tenscell.linear.definite.damping_factor` at the fits'
    tolerance): a Cholesky factorization alone can pass a singular matrix on rounding noise (the
    nucleated cell's squared pivots span 2·10¹⁶), so the rule compares its pivots with each other.
    """
    Lc = damping_factor(A @ A.T, FIT_RTOL)
    return None if Lc is None else whiten(Lc, A, H, load, probe)


def rescaled_basis(unit: tuple, c: float) -> tuple:
    """The basis of ``C0 = c·A Aᵀ`` from that of unit damping (:func:`unit_damping_basis`): a rescaling by 1/√c."""
    s = 1.0 / np.sqrt(c)
    B0, Ht0, bt0, Dt0 = unit
    return B0 * s, Ht0 * (s * s), bt0 * s, Dt0 * s
