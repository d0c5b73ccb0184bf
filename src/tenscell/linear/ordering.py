"""Fill-reducing orderings for the sparse Cholesky factorization (internal).

Geometric nested dissection (George 1973): every set of unknowns is cut by
the median plane across its longest extent, the unknowns on the side of the
cut with fewer matrix entries reaching across it form the separator, and separators are
numbered after the two halves they separate, recursively. On the 3D lattices
of :mod:`tenscell.model.lattices` it gives less fill and fewer flops than
CHOLMOD's default (AMD): measured at 32,076 coordinates in
``bench/bench_scale.py``.

Why our own: CHOLMOD's nested dissection needs METIS, which the cvxopt wheels
do not include; no maintained wheel of scikit-sparse exists for this Python;
``pymetis`` crashed (segmentation fault) at 32k coordinates when it was tried.
Why vectorized by levels: all sets of one level are cut together with a few
sorts and reductions, so the ordering costs about as much as one assembly of
the matrix (about 20 ms at 32k coordinates) instead of a Python loop over sets
(1 s).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["coordinate_locations", "nested_dissection", "MIN_SIZE"]

#: sets of at most this many unknowns are not cut further (dense enough to factor as one block)
LEAF = 64
#: below this many unknowns CHOLMOD's AMD is as good (measured: equal fill at 1,896 coordinates, 1.6x more at
#: 11,520) and the ordering is not computed
MIN_SIZE = 5000


def coordinate_locations(coords) -> np.ndarray:
    """A location (m) for each generalized coordinate: the mean reference position of the nodes it moves.

    Parameters
    ----------
    coords : tenscell.model.coordinates.Coordinates

    Returns
    -------
    ndarray, shape (n, 3)
    """
    x = coords.structure.nodes
    idx = coords.node_index
    acc = np.zeros((coords.n + 1, 3))
    cnt = np.zeros(coords.n + 1)
    for k in range(idx.shape[1]):  # index -1 (no coordinate) collects into the spare last row
        np.add.at(acc, idx[:, k], x)
        np.add.at(cnt, idx[:, k], 1.0)
    return acc[:-1] / np.maximum(cnt[:-1], 1.0)[:, None]


def _edges(A) -> tuple[np.ndarray, np.ndarray]:
    """Both endpoints of every off-diagonal entry of the (structurally symmetric) pattern of A, i < j."""
    M = sp.coo_matrix(A)
    keep = M.row < M.col
    return M.row[keep].astype(np.int64), M.col[keep].astype(np.int64)


def _box_groups(box: np.ndarray, active: np.ndarray):
    """Active unknowns sorted by set, with each set's start offset and size."""
    idx = np.flatnonzero(active)
    idx = idx[np.argsort(box[idx], kind="stable")]
    labels, start, size = np.unique(box[idx], return_index=True, return_counts=True)
    return idx, labels, start, size


def _median_sides(points: np.ndarray, idx: np.ndarray, start: np.ndarray, size: np.ndarray) -> np.ndarray:
    """For each unknown of ``idx`` (grouped by set), True on the upper side of its set's median plane.

    The plane is normal to the set's longest extent; unknowns at the same
    location land on the same side, so a node's coordinates are never cut apart.
    """
    p = points[idx]
    lo = np.minimum.reduceat(p, start, axis=0)
    hi = np.maximum.reduceat(p, start, axis=0)
    axis = np.argmax(hi - lo, axis=1)
    set_of = np.repeat(np.arange(start.size), size)
    key = p[np.arange(idx.size), axis[set_of]]
    order = np.lexsort((key, set_of))
    median = key[order[start + size // 2]]
    return key >= median[set_of]


def _separator(i, j, box, active, upper) -> np.ndarray:
    """The unknowns that separate the two halves of every set: the smaller of its two one-sided boundaries.

    A boundary is the set's unknowns on one side with a matrix entry (i, j)
    reaching the other side; removing either boundary leaves no entry between
    the halves, and the smaller one means less fill.
    """
    n = box.size
    crossing = active[i] & active[j] & (box[i] == box[j]) & (upper[i] != upper[j])
    ends = np.concatenate([i[crossing], j[crossing]])
    on_boundary = np.zeros(n, dtype=bool)
    on_boundary[ends] = True
    sets, where = np.unique(box[on_boundary], return_inverse=True)
    members = np.flatnonzero(on_boundary)
    n_upper = np.bincount(where, weights=upper[members].astype(float), minlength=sets.size)
    n_lower = np.bincount(where, minlength=sets.size) - n_upper
    take_upper = n_upper <= n_lower
    sep = np.zeros(n, dtype=bool)
    sep[members[upper[members] == take_upper[where]]] = True
    return sep


def nested_dissection(A, points: np.ndarray, leaf: int = LEAF) -> np.ndarray:
    """A fill-reducing permutation of a structurally symmetric sparse matrix by geometric nested dissection.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        Only its pattern is read (K0 and K0 + σC0 share one).
    points : ndarray, shape (n, d)
        A location for each unknown (m), e.g. :func:`coordinate_locations`.
    leaf : int
        Sets of at most this many unknowns are not cut further.

    Returns
    -------
    ndarray of int, shape (n,)
        ``perm`` such that ``A[perm][:, perm]`` factors with little fill
        (row ``i`` of the factored matrix is row ``perm[i]`` of A).
    """
    n = A.shape[0]
    points = np.asarray(points, dtype=float).reshape(n, -1)
    i, j = _edges(A)
    box = np.zeros(n, dtype=np.int64)  # the set each unknown is in at the current level
    code = np.zeros(n, dtype=np.int64)  # base-3 path: 0 lower half, 1 upper half, 2 separator (numbered last)
    active = np.ones(n, dtype=bool)
    while active.any():
        idx, labels, start, size = _box_groups(box, active)
        cut = np.repeat(size > leaf, size)
        active[idx[~cut]] = False  # small sets stay as they are
        upper = np.zeros(n, dtype=bool)
        upper[idx] = _median_sides(points, idx, start, size) & cut
        sep = _separator(i, j, box, active, upper)
        digit = np.where(sep, 2, upper.astype(np.int64))
        code = 3 * code + np.where(active, digit, 0)
        degenerate = np.bincount(np.searchsorted(labels, box[idx]), weights=(~upper[idx]).astype(float),
                                 minlength=labels.size) == 0  # every location equal: nothing to cut
        active[sep] = False
        active[idx[np.repeat(degenerate, size)]] = False
        box = 2 * box + upper
    return np.argsort(code, kind="stable")
