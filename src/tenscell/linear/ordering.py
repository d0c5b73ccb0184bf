"""Fill-reducing orderings for the sparse Cholesky factorization (internal), chosen by size.

:func:`fill_reducing` picks one ordering per sparse pencil, shared by the
factors of K0 and of every K0 + σC0:

* below :data:`MIN_SIZE` coordinates, none: CHOLMOD's own AMD does as well;
* up to :data:`METIS_FROM` coordinates, or when pymetis is not installed,
  **geometric nested dissection** (:func:`nested_dissection`, George 1973):
  every set of unknowns is cut by the median plane across its longest
  extent, the unknowns on the side of the cut with fewer matrix entries
  reaching across it form the separator, and separators are numbered after
  the two halves they separate, recursively. Vectorized by levels (all sets
  of one level are cut together with a few sorts and reductions), it costs
  about as much as one assembly of the matrix (0.05 s at 32,076 coordinates);
* from :data:`METIS_FROM` coordinates, **METIS's multilevel nested
  dissection** (:func:`metis_dissection`, through pymetis, the ``large``
  extra) of the graph whose vertices are the structure's *locations* (the
  coordinates of one node move together and share their neighbours) weighted
  by their coordinates, given as METIS wants it: the symmetric adjacency
  ``xadj/adjncy`` of both triangles, no diagonal (passing one triangle of K0,
  as an earlier attempt did, is what crashed it). When the unknowns come in
  triples at one location (point nodes: a lattice), that graph is the graph of
  the matrix's 3×3 blocks, read from scipy's BSR conversion without sorting the
  locations (0.005 s against 0.016 s at 32,076 coordinates, 0.018 against 0.061 s
  at 106,641; the same graph up to the numbering of its vertices).

The crossover, measured on the 3D lattices of ``bench/bench_scale.py``
(docs/large-structures.md has the table): METIS's factor of K0 has 1.2×,
1.4× and 1.4× less fill than the geometric one at 32k, 48k and 107k
coordinates (7.35·10⁶ against 8.95·10⁶ nonzeros at 32,076), its numeric
factorization is 1.3–1.9× faster and each Lanczos solve 1.2–1.3× faster;
ordering the location graph costs 0.1 s at 32k and 0.4 s at 107k (the
coordinate graph took 0.38 and 1.4 s). Ordering, two factorizations and 41
solves took 0.34 s with METIS against 0.43 s at 16,281 coordinates, and 0.15
against 0.12 s at 11,520, where the fills are equal: hence :data:`METIS_FROM`.

Why not CHOLMOD's own nested dissection: the cvxopt wheels build CHOLMOD
without METIS, and no maintained wheel of scikit-sparse exists for this Python.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["coordinate_locations", "fill_reducing", "nested_dissection", "metis_dissection", "MIN_SIZE",
           "METIS_FROM"]

#: sets of at most this many unknowns are not cut further (dense enough to factor as one block)
LEAF = 64
#: below this many unknowns CHOLMOD's AMD is as good (measured: equal fill at 1,896 coordinates, 1.6x more at
#: 11,520) and the ordering is not computed
MIN_SIZE = 5000
#: from this many unknowns METIS's nested dissection (when pymetis is installed) replaces the geometric one
#: (measured: ordering + two factorizations + 41 solves took 0.12 s geometric against 0.15 s METIS at 11,520
#: coordinates, 0.43 against 0.34 s at 16,281: docs/large-structures.md)
METIS_FROM = 15000


def fill_reducing(A, points: np.ndarray | None) -> np.ndarray | None:
    """The fill-reducing permutation for a sparse symmetric pattern ``A`` (n × n), chosen by size; None for AMD.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        Structurally symmetric; only its pattern is read (the union of K0's and C0's).
    points : ndarray, shape (n, 3), or None
        A location (m) for each unknown (:func:`coordinate_locations`); without them, AMD.

    Returns
    -------
    ndarray of int, shape (n,), or None
        ``perm`` (row ``i`` of the factored matrix is row ``perm[i]`` of A), or None for CHOLMOD's AMD.
    """
    n = A.shape[0]
    if points is None or n < MIN_SIZE:
        return None
    if n >= METIS_FROM and _pymetis() is not None:
        return metis_dissection(A, points)
    return nested_dissection(A, points)


def _pymetis():
    """The pymetis module, or None when it is not installed (the geometric ordering serves instead)."""
    try:
        import pymetis
    except ImportError:
        return None
    return pymetis


def metis_dissection(A, points: np.ndarray) -> np.ndarray:
    """METIS's multilevel nested dissection of a sparse pattern, on the graph of its unknowns' locations.

    Unknowns at one location (the coordinates of one node) form one vertex, weighted by their number,
    adjacent to every location one of them couples to: a graph 3× smaller than the matrix's, ordered
    4× faster with the same fill. The unknowns of one location are numbered together.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        Structurally symmetric; only its pattern is read.
    points : ndarray, shape (n, d)
        A location for each unknown (m).

    Returns
    -------
    ndarray of int, shape (n,)
        ``perm`` as :func:`nested_dissection` returns it.
    """
    pymetis = _pymetis()
    if pymetis is None:  # pragma: no cover - fill_reducing asks only when it is there
        raise ImportError("metis_dissection needs pymetis: pip install 'tenscell[large]'")
    n = A.shape[0]
    points = np.asarray(points, dtype=float).reshape(n, -1)
    group, count, xadj, adjncy = _node_graph(A, points) if _in_triples(points) else _location_graph(A, points)
    g = count.size
    adjacency = pymetis.CSRAdjacency(xadj, adjncy)
    gperm = np.asarray(pymetis.nested_dissection(adjacency=adjacency, vweights=count.astype(np.int64))[0])
    rank = np.empty(g, dtype=np.int64)
    rank[gperm] = np.arange(g)
    return np.argsort(rank[group], kind="stable")


def _location_graph(A, points: np.ndarray):
    """``(group, count, xadj, adjncy)``: each unknown's location, the unknowns per location, and the symmetric
    adjacency of the locations METIS expects (both triangles, no diagonal, duplicates merged)."""
    group, count = _locations(points)
    i, j = _edges(A)
    gi, gj = group[i], group[j]
    keep = gi != gj
    g = count.size
    G = sp.coo_matrix((np.ones(2 * int(keep.sum())), (np.concatenate([gi[keep], gj[keep]]),
                                                      np.concatenate([gj[keep], gi[keep]]))), shape=(g, g)).tocsr()
    G.sum_duplicates()
    return group, count, G.indptr.astype(np.int64), G.indices.astype(np.int64)


def _in_triples(points: np.ndarray) -> bool:
    """Whether the unknowns come in consecutive triples at one location (the coordinates of point nodes)."""
    n = points.shape[0]
    return n > 0 and n % 3 == 0 and bool(np.array_equal(points[0::3], points[1::3])
                                         and np.array_equal(points[0::3], points[2::3]))


def _node_graph(A, points: np.ndarray):
    """:func:`_location_graph` when the unknowns come in triples (point nodes, e.g. a lattice): the graph of the
    matrix's 3×3 blocks from scipy's BSR conversion (a node per triple, a node at a shared location counted on
    its own), without sorting the unknowns' locations or a pass over every entry."""
    n = points.shape[0]
    M = sp.csr_matrix(A)
    pattern = sp.csr_matrix((np.ones(M.nnz, dtype=np.int8), M.indices, M.indptr), shape=M.shape)
    B = sp.bsr_matrix(pattern, blocksize=(3, 3))
    nb = n // 3
    rows = np.repeat(np.arange(nb), np.diff(B.indptr))
    off = B.indices != rows
    xadj = np.zeros(nb + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows[off], minlength=nb), out=xadj[1:])
    return np.arange(n) // 3, np.full(nb, 3), xadj, B.indices[off].astype(np.int64)


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


def _locations(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct location of each unknown (an index) and the number of unknowns at each location.

    One lexicographic sort of the rows (``np.unique(axis=0)`` sorts a structured view, 3× slower here).
    """
    order = np.lexsort(points.T[::-1])
    p = points[order]
    first = np.empty(points.shape[0], dtype=bool)
    first[:1] = True
    np.any(p[1:] != p[:-1], axis=1, out=first[1:])
    sorted_group = np.cumsum(first) - 1
    group = np.empty_like(sorted_group)
    group[order] = sorted_group
    return group, np.bincount(sorted_group)


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
