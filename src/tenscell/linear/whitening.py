"""The basis in which a cell's damping matrix is the identity: the fits' view of the pencil (K0, C0).

A fit evaluates the pencil of one cell at thousands of parameter vectors and
at every prestress of its data, so it never forms K0 and C0 themselves. With
``C0 = A diag(η) Aᵀ = Lc Lcᵀ`` (Cholesky), the tendon directions, the
prestress Hessian, the load and the probe are taken once into the basis where
C0 is the identity (``B = Lc⁻¹A``, ``H̃ = Lc⁻¹ H Lc⁻ᵀ``, ``b̃ = Lc⁻¹b``,
``d̃ = Lc⁻¹d``); the whitened stiffness at any tangent stiffnesses ``k`` is
then ``P·H̃ + B diag(k) Bᵀ``, whose symmetric eigensolve
(:func:`tenscell.linear.modal.prestress_grid_modes`) gives the relaxation
spectrum ``K0 v = λ C0 v`` with C0-orthonormal modes. With one damping for all
tendons (``η = c``) the basis of unit damping is only rescaled.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["whiten", "whitened_basis", "unit_damping_basis", "rescaled_basis"]

#: C0 = A Aᵀ counts as singular when its smallest eigenvalue is below this fraction of its largest
SINGULAR_DAMPING = 1e-10


def whiten(Lc: np.ndarray, A: np.ndarray, H: np.ndarray, load: np.ndarray, probe: np.ndarray) -> tuple:
    """``(B, H̃, b̃, d̃)``: A, the symmetric H, load and probe in the basis where ``C0 = Lc Lcᵀ`` is the identity."""
    solve = scipy.linalg.solve_triangular
    B = solve(Lc, A, lower=True, check_finite=False)
    X = solve(Lc, H, lower=True, check_finite=False)
    Ht = solve(Lc, X.T, lower=True, check_finite=False)
    bt = solve(Lc, load, lower=True, check_finite=False)
    Dt = solve(Lc, probe, lower=True, check_finite=False)
    return B, 0.5 * (Ht + Ht.T), bt, Dt


def whitened_basis(A: np.ndarray, eta: np.ndarray, H: np.ndarray, load: np.ndarray, probe: np.ndarray):
    """:func:`whiten` for ``C0 = A diag(η) Aᵀ`` (η in N·s/m per tendon); None if that C0 is not positive definite."""
    try:
        Lc = np.linalg.cholesky((A * eta) @ A.T)
    except np.linalg.LinAlgError:
        return None
    return whiten(Lc, A, H, load, probe)


def unit_damping_basis(A: np.ndarray, H: np.ndarray, load: np.ndarray, probe: np.ndarray):
    """:func:`whiten` for ``C0 = A Aᵀ`` (every tendon's damping 1 N·s/m); None if that C0 is singular.

    Singular means an eigenvalue below :data:`SINGULAR_DAMPING` of the
    largest: a Cholesky factorization alone can pass a singular matrix on
    rounding noise, so the test compares with the matrix's own scale.
    """
    AAt = A @ A.T
    ev = np.linalg.eigvalsh(AAt)
    if not ev[0] > SINGULAR_DAMPING * ev[-1]:
        return None
    return whiten(np.linalg.cholesky(AAt), A, H, load, probe)


def rescaled_basis(unit: tuple, c: float) -> tuple:
    """The basis of ``C0 = c·A Aᵀ`` from that of unit damping (:func:`unit_damping_basis`): a rescaling by 1/√c."""
    s = 1.0 / np.sqrt(c)
    B0, Ht0, bt0, Dt0 = unit
    return B0 * s, Ht0 * (s * s), bt0 * s, Dt0 * s
