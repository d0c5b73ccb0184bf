"""The pencil at the reference: K0 and C0 assembled from member tangents, and the continuum factor.

The one place K0 and C0 are put together (every linear model, the prestress
family, the grid, the dynamic kernel, the fits' batched kernel and the stability
test of trial references take them from here):

* ``K0 = P·Σ T0_j ∇²l_j + Σ k_j a_j a_jᵀ`` (N/m) for tangent stiffnesses ``k_j``
  (N/m) of the members (:func:`assemble_stiffness`);
* for Voigt tendons ``k_j = (EA_j + P·T0_j)/l_j``, so ``K0 = P·Kp + Km`` with the
  prestress stiffness ``Kp`` of the cell and the spring part
  ``Km = Σ EA_j a_j a_jᵀ/l_j`` (:func:`spring_stiffness`, :func:`voigt_stiffness`);
* ``C0 = Σ c_j a_j a_jᵀ`` (N·s/m) (:func:`assemble_damping`).

The geometric pieces (the Gram product ``A diag(w) Aᵀ`` and the member
Hessians) belong to the geometry stage, :mod:`tenscell.model.equilibrium`,
which needs them at any configuration; this module only combines them for a
linear model.

The continuum factor (:func:`continuum_factor`, :func:`modulus`):
``G = (0.5/L)/J`` (Pa) with strut length L (m), the paper's equivalent
continuum; ``J(t)·2L`` is the creep compliance in 1/Pa.
"""
from __future__ import annotations

import numpy as np

from ..model.equilibrium import member_stiffness, weighted_gram

__all__ = ["continuum_factor", "modulus", "assemble_stiffness", "stiffness_stack", "stiffness_rows", "gram_table",
           "assemble_damping", "spring_stiffness", "voigt_stiffness"]


def continuum_factor(L: float) -> float:
    """The paper's equivalent-continuum factor ``0.5/L`` (1/m) for strut length ``L`` (m): ``G = (0.5/L)/J``."""
    return 0.5 / L


def modulus(J, L: float):
    """Complex modulus ``G' + iG'' = (0.5/L)/J`` (Pa) from a compliance ``J`` (m/N) and strut length ``L`` (m)."""
    return continuum_factor(L) / np.asarray(J) if np.ndim(J) else continuum_factor(L) / J


def assemble_stiffness(cell, P: float, k):
    """``K0 = P·Σ T0_j ∇²l_j + Σ k_j a_j a_jᵀ`` (N/m), dense or sparse like the cell.

    Parameters
    ----------
    cell : Cell
    P : float
        Prestress scale (N): member forces ``P·T0``.
    k : ndarray, shape (m,)
        Tangent stiffness ``dT_j/dl_j`` of each member at the reference (N/m), real or complex
        (a dynamic tangent ``k*(ω)``). For the Voigt spring with the rest lengths of Eq. 11 it is
        ``(EA_j + P·T0_j)/l_j`` (:func:`voigt_stiffness`).
    """
    if cell.sparse and cell.geometry.point_nodes:  # one pass over the members on the cell's node-block pattern
        return member_stiffness(cell.geometry, P * cell.T0, k, A=cell.A, sparse=True)
    return P * cell.prestress_hessian + weighted_gram(cell.A, k)


def stiffness_stack(cell, P: float, k: np.ndarray) -> np.ndarray:
    """:func:`assemble_stiffness` for many sets of member tangents at once, dense: shape (q, n, n) for ``k`` of
    shape (q, m) (N/m, real or complex, e.g. a dynamic tangent ``k*(ω)`` at q frequencies)."""
    A = np.asarray(cell.A)
    H = np.asarray(cell.prestress_hessian, dtype=float)
    return P * H[None] + (A[None] * k[:, None, :]) @ A.T


def gram_table(A) -> np.ndarray:
    """The members' ``a_j a_jᵀ`` flattened, shape (m, n·n), for ``A`` (n, m, dense): with it
    :func:`stiffness_rows` assembles many stiffness matrices in one matrix product."""
    A = np.asarray(A, dtype=float)
    return np.einsum("im,jm->mij", A, A).reshape(A.shape[1], A.shape[0] ** 2)


def stiffness_rows(H, gram, P, k) -> np.ndarray:
    """:func:`assemble_stiffness` at many points, each with its own prestress: ``K_r = P_r·H + Σ_j k_rj a_j a_jᵀ``.

    Parameters
    ----------
    H : ndarray, shape (n, n)
        ``Σ T0_j ∇²l_j`` (N/m per N), dense (or its restriction to a subspace, with ``gram`` of the same one).
    gram : ndarray, shape (m, n·n)
        :func:`gram_table` of the members' ``a_j``.
    P : ndarray, shape (R,)
        Prestress scale of each point (N).
    k : ndarray of complex, shape (R, m)
        Member tangents at each point (N/m), e.g. a dynamic tangent ``k*(ω)``.

    Returns
    -------
    ndarray of complex, shape (R, n, n)
    """
    R, n = k.shape[0], H.shape[0]
    # real and imaginary parts in one real product (half the work of a complex one against a real table)
    parts = np.concatenate([k.real, k.imag]) @ gram
    K = np.empty((R, n, n), dtype=complex)
    np.multiply(P[:, None, None], H, out=K.real)
    K.real += parts[:R].reshape(R, n, n)
    K.imag = parts[R:].reshape(R, n, n)
    return K


def spring_stiffness(cell, EA):
    """The spring part of a Voigt cell's K0, ``Km = Σ EA_j a_j a_jᵀ/l_j`` (N/m), for ``EA`` (N, shape (m,))."""
    return _gram(cell, np.asarray(EA, dtype=float) / cell.lengths)


def voigt_stiffness(cell, P: float, EA):
    """``K0 = P·Kp + Σ EA_j a_j a_jᵀ/l_j`` (N/m) of Voigt tendons (EA in N) at prestress ``P`` (N).

    The same matrix as :func:`assemble_stiffness` with ``k = (EA + P·T0)/l``, written with the cell's
    prestress stiffness ``Kp`` (N/m per N), which a family of prestresses shares.
    """
    return P * cell.Kp + spring_stiffness(cell, EA)


def assemble_damping(cell, c):
    """``C0 = Σ c_j a_j a_jᵀ`` (N·s/m) for member damping ``c`` (N·s/m, shape (m,))."""
    return _gram(cell, c)


def _gram(cell, w):
    """``Σ w_j a_j a_jᵀ``: the cell's equilibrium matrix ``A diag(w) Aᵀ``, or its node blocks (large lattices)."""
    return member_stiffness(cell.geometry, gram_weights=w, A=cell.A, sparse=cell.sparse)
