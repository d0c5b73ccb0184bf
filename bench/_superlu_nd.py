"""Sparse symmetric factorization for large structures (internal).

scipy's SuperLU, given a fill-reducing nested-dissection ordering computed
here and told to keep diagonal pivots (``SymmetricMode``,
``diag_pivot_thresh=0``), factors a symmetric matrix as ``P A Pᵀ = L U``
with ``U = D Lᵀ``. By Sylvester's law of inertia the matrix is positive
definite exactly when every pivot ``D_ii`` is positive and no row was
interchanged, so one factorization both proves positive definiteness and
serves the solves (the Lanczos iteration of :mod:`tenscell.linear.krylov`).

The ordering is George's nested dissection on the matrix graph: a
breadth-first level structure from a pseudo-peripheral vertex, the middle
level as separator, recursively; separators are numbered last. On the 3D
lattices of :mod:`tenscell.model.lattices` it gives several times less fill than
SuperLU's own column orderings.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph
import scipy.sparse.linalg as spla

__all__ = ["NotPositiveDefinite", "SymmetricFactor", "factorize_spd", "nested_dissection", "coordinate_locations"]

_LEAF = 48


class NotPositiveDefinite(ValueError):
    """The matrix has a pivot <= 0 (or needed a row interchange): it is not positive definite."""

    def __init__(self, message: str, smallest_pivot: float):
        super().__init__(message)
        self.smallest_pivot = smallest_pivot


@dataclass(frozen=True, eq=False)
class SymmetricFactor:
    """``P A Pᵀ = L D Lᵀ`` of a symmetric positive definite sparse matrix.

    Attributes
    ----------
    lu : scipy.sparse.linalg.SuperLU
        Factor of the permuted matrix.
    perm : ndarray of int
        The fill-reducing permutation (row/column ``i`` of the factored
        matrix is ``perm[i]`` of ``A``).
    n : int
    """

    lu: object
    perm: np.ndarray
    n: int

    @property
    def fill(self) -> int:
        """Stored nonzeros of L and U."""
        return int(self.lu.L.nnz + self.lu.U.nnz)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``A⁻¹ b`` for a vector or an (n, k) array (real or complex)."""
        b = np.asarray(b)
        out = np.empty_like(b, dtype=np.result_type(b.dtype, float))
        out[self.perm] = self.lu.solve(np.ascontiguousarray(b[self.perm]))
        return out


def nested_dissection(A, points: np.ndarray | None = None, leaf: int = _LEAF) -> np.ndarray:
    """A fill-reducing ordering of a structurally symmetric sparse matrix (nested dissection).

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
    points : ndarray, shape (n, d), optional
        A location for each unknown (e.g. the node a coordinate moves). With
        them, each set is cut by the median plane across its longest extent
        (geometric dissection, the best choice for lattices); without them
        the middle level of a breadth-first level structure is used.
    leaf : int
        Sets at most this large are not split further.

    Returns
    -------
    ndarray of int, shape (n,)
        ``perm`` such that ``A[perm][:, perm]`` factors with little fill.
    """
    G = sp.csr_matrix(A, copy=True)
    G.data = np.ones_like(G.data, dtype=np.int8)
    G = ((G + G.T) > 0).astype(np.int8).tocsr()
    G.setdiag(0)
    G.eliminate_zeros()
    n = G.shape[0]
    if points is not None:
        points = np.asarray(points, dtype=float).reshape(n, -1)
    order: list[np.ndarray] = []
    # explicit stack in post-order: ("split", set) is dissected, ("emit", set) is numbered as is
    tasks: list = [("split", np.arange(n))]
    while tasks:
        kind, idx = tasks.pop()
        if kind == "emit" or idx.size <= leaf:
            order.append(idx)
            continue
        sub = G[idx][:, idx]
        if points is None:
            ncomp, labels = csgraph.connected_components(sub, directed=False)
            if ncomp > 1:
                for c in reversed(range(ncomp)):
                    tasks.append(("split", idx[labels == c]))
                continue
            parts = _level_split(sub)
        else:
            parts = _geometric_split(sub, points[idx])
        if parts is None:
            order.append(idx)
            continue
        a, b, sep = parts
        tasks.append(("emit", idx[sep]))
        tasks.append(("split", idx[b]))
        tasks.append(("split", idx[a]))
    return np.concatenate(order) if order else np.zeros(0, dtype=int)


def _geometric_split(sub, pts: np.ndarray):
    """Median cut across the longest extent; the separator is the smaller one-sided boundary."""
    ext = pts.max(axis=0) - pts.min(axis=0)
    ax = int(np.argmax(ext))
    if ext[ax] <= 0:
        return None
    med = np.median(pts[:, ax])
    left = pts[:, ax] < med
    if left.all() or not left.any():
        left = pts[:, ax] <= med
        if left.all() or not left.any():
            return None
    rows = np.repeat(np.arange(sub.shape[0]), np.diff(sub.indptr))
    cross = left[rows] != left[sub.indices]
    boundary = np.zeros(sub.shape[0], dtype=bool)
    boundary[rows[cross]] = True
    bl, br = boundary & left, boundary & ~left
    sep = bl if bl.sum() <= br.sum() else br
    a = left & ~sep
    b = ~left & ~sep
    return np.flatnonzero(a), np.flatnonzero(b), np.flatnonzero(sep)


def _level_split(sub):
    levels = _level_structure(sub)
    l = _separator_level(levels)
    if l is None:
        return None
    return np.flatnonzero(levels < l), np.flatnonzero(levels > l), np.flatnonzero(levels == l)


def _level_structure(sub) -> np.ndarray:
    """BFS levels from a pseudo-peripheral vertex (two sweeps)."""
    start = 0
    lv = None
    for _ in range(3):
        d = csgraph.shortest_path(sub, method="D", unweighted=True, indices=start, directed=False)
        far = int(np.argmax(d))
        if lv is not None and d[far] <= lv.max():
            break
        lv = d
        start = far
    return lv.astype(int)


def _separator_level(levels: np.ndarray):
    counts = np.bincount(levels)
    if counts.size < 3:
        return None
    cum = np.cumsum(counts)
    half = cum[-1] / 2.0
    mid = int(np.searchsorted(cum, half))
    best, best_cost = None, np.inf
    for l in range(max(1, mid - 2), min(counts.size - 1, mid + 3)):
        below, above = cum[l - 1], cum[-1] - cum[l]
        if min(below, above) < 0.3 * cum[-1]:
            continue
        cost = counts[l]
        if cost < best_cost:
            best, best_cost = l, cost
    if best is None:
        best = min(max(mid, 1), counts.size - 2)
    return best


def factorize_spd(A, what: str = "the matrix", points: np.ndarray | None = None) -> SymmetricFactor:
    """Factor a sparse symmetric matrix, proving it positive definite.

    Raises
    ------
    NotPositiveDefinite
        If a pivot is not positive (or SuperLU had to interchange rows or
        found the matrix exactly singular).
    """
    A = sp.csc_matrix(A)
    n = A.shape[0]
    perm = nested_dissection(A, points)
    Ap = A[perm][:, perm].tocsc()
    try:
        lu = spla.splu(Ap, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError:
        raise NotPositiveDefinite(f"{what} is singular (a zero pivot)", 0.0) from None
    d = lu.U.diagonal()
    if not np.array_equal(lu.perm_r, lu.perm_c) or np.any(d <= 0):
        raise NotPositiveDefinite(f"{what} is not positive definite (a pivot <= 0)", float(d.min()))
    return SymmetricFactor(lu=lu, perm=perm, n=n)


def coordinate_locations(coords) -> np.ndarray:
    """A location (m) for each generalized coordinate: the mean reference position of the nodes it moves.

    ``coords`` is a :class:`tenscell.model.coordinates.Coordinates`; returns shape (n, 3). Used for the
    geometric nested-dissection ordering.
    """
    x = coords.structure.nodes
    idx = coords.node_index
    acc = np.zeros((coords.n + 1, 3))
    cnt = np.zeros(coords.n + 1)
    for k in range(idx.shape[1]):
        np.add.at(acc, idx[:, k], x)
        np.add.at(cnt, idx[:, k], 1.0)
    return acc[:-1] / np.maximum(cnt[:-1], 1.0)[:, None]
