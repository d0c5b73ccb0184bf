"""Free-standing structures: their rigid-body motions removed before linearization.

A structure whose supports do not hold it (no fixed node, or fewer than three
non-collinear ones) has ``k`` infinitesimal rigid-body motions ``R`` (n × k,
:func:`tenscell.model.formfinding.rigid_body_modes`): no tendon stretches
along them, so K0 and C0 are singular there and no compliance exists. As the
peers' tangent-stiffness analyses do, :func:`~tenscell.linear.linearize.linearize`
then works on the orthonormal complement ``N`` of ``R``
(:func:`~tenscell.linear.pencil.complement_basis`, ``q = N r``): the model's
pencil is ``(NᵀK0N, NᵀC0N)`` with load ``NᵀH0`` and probe ``NᵀD0``
(:meth:`~tenscell.linear.pencil.Pencil.restricted`), whose stiffness
eigenvalues are the non-zero ones of K0. The part of the load along ``R`` —
the net force and moment of a load on an unsupported body — is resisted by
nothing and left out; :func:`unresisted_share` says how much of it there is.
"""
from __future__ import annotations

import weakref

import numpy as np

from .pencil import complement_basis

__all__ = ["deformation_basis", "unresisted_share", "solve_full", "resolvent_full"]


#: per cell, its basis (a cache: it depends on the cell's reference alone; weak keys, it lives as long as the cell)
_bases: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def deformation_basis(cell) -> np.ndarray | None:
    """Orthonormal basis ``N`` (n, n − k) of the coordinates orthogonal to the cell's ``k`` rigid-body motions,
    or None when its supports hold it (k = 0). Computed once per cell (read-only: every model of the cell shares it)."""
    if cell.structure.held_by_fixed_nodes:  # three fixed nodes not on one line: nothing to remove
        return None
    if cell in _bases:
        return _bases[cell]
    from ..model.formfinding import rigid_body_modes

    R = rigid_body_modes(cell.coords)
    N = complement_basis(R, cell.n) if R.shape[1] else None
    if N is not None:
        N.flags.writeable = False
    _bases[cell] = N
    return N


def unresisted_share(vector, N: np.ndarray) -> float:
    """Fraction of ``|v|`` along the rigid-body motions (what the restriction to ``N`` leaves out), in [0, 1]."""
    v = np.asarray(vector, dtype=float)
    norm = float(np.linalg.norm(v))
    if norm == 0.0:
        return 0.0
    kept = float(np.linalg.norm(N.T @ v))
    return float(np.sqrt(max(0.0, 1.0 - (kept / norm) ** 2)))


def solve_full(lin, shift: complex, rhs) -> np.ndarray:
    """``(K0 + s·C0)⁻¹ rhs`` in the model's full coordinates, through its pencil (:meth:`Pencil.solve_at`).

    For a free-standing model (``lin.basis`` = N) the solve on the complement of the rigid-body motions, lifted
    back: ``N (NᵀK0N + s·NᵀC0N)⁻¹ Nᵀ rhs`` (the part of ``rhs`` along the rigid-body motions is resisted by
    nothing and left out, as for every compliance).
    """
    N = lin.basis
    if N is None:
        return lin.pencil.solve_at(shift, rhs)
    return N @ lin.pencil.solve_at(shift, N.T @ np.asarray(rhs))


def resolvent_full(lin, w, rhs) -> np.ndarray:
    """``(K0 + iωC0)⁻¹ rhs`` for every ω (rad/s), shape (nf, n), in the full coordinates (:meth:`Pencil.resolvent`;
    for a free-standing model on the complement of the rigid-body motions, lifted back as in :func:`solve_full`)."""
    N = lin.basis
    if N is None:
        return lin.pencil.resolvent(w, rhs)
    return lin.pencil.resolvent(w, np.asarray(rhs, dtype=float) @ N) @ N.T
