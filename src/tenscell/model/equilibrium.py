"""Tendon lengths, the equilibrium matrix, self-stress and prestress.

The paper's Eq. (6)–(11) at the level of geometry:

* ``l(q)``: working-tendon lengths (m);
* ``A(q) = ∂l/∂q`` (the paper's equilibrium matrix, shape ``(n_q, m)``, Eq. 7)
  and the exact Hessians ``∂²l_j/∂q²``;
* the self-stress space ``{T : A(q0) T = 0}`` by SVD, the state ``T0``
  (``‖T0‖₂ = 1``, equal tension within the structure's equal-tension groups,
  all cable tensions strictly positive), ``T = P·T0`` (Eq. 10);
* (rest lengths, Eq. (11), are the tendon law's: :func:`tenscell.laws.rest_lengths`).

A :class:`Cell` bundles a structure with its prestressable reference and the
per-cell geometry (A, Hessians; ``Kp`` and ``Σ T0_j ∇²l_j`` assembled on first use)
that every later stage reuses, so that linearizing at many prestresses costs only
a few small matrix products.
"""
from __future__ import annotations

import math

from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import Any

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from .._errors import TenscellError
from .coordinates import _W, Coordinates, NodeKinematics, kinematics, make_coordinates
from .structure import Point, Structure, cable_mask

__all__ = [
    "NotPrestressableError",
    "MemberGeometry",
    "Cell",
    "member_geometry",
    "equilibrium_matrix",
    "assemble_hessian",
    "member_stiffness",
    "NodeBlocks",
    "point_nodes_only",
    "point_vector",
    "self_stress_basis",
    "self_stress",
    "self_stress_lp",
    "equilibrate",
    "generalized_forces",
    "damping_matrix",
    "tangent_stiffness",
    "weighted_gram",
    "SPARSE_THRESHOLD",
]

#: structures with more generalized coordinates than this use scipy.sparse matrices
SPARSE_THRESHOLD = 1500


class NotPrestressableError(TenscellError, ValueError):
    """The requested reference admits no self-stress with all tendons in tension."""


@dataclass(frozen=True, eq=False, repr=False)
class MemberGeometry:
    """Lengths and exact derivatives of all members at one configuration.

    Attributes
    ----------
    lengths : ndarray, shape (m,)
        Member lengths (m).
    grad : ndarray, shape (m, 10)
        ``∂l_j/∂q`` on the member's local coordinate block (m/rad or 1).
    hess : ndarray, shape (m, 10, 10), or None
        ``∂²l_j/∂q²`` on the same block (None if not requested).
    index : ndarray of int, shape (m, 10)
        Global coordinate indices of the block, -1 where unused.
    n : int
        Number of generalized coordinates.
    directions : ndarray, shape (m, 3), or None
        Unit vectors ``e_j = (x_a − x_b)/l_j`` from the second end to the first (dimensionless).
    point_nodes : bool
        Every node that moves is a point node with its three coordinates (no rigid struts, no rollers): then
        ``∇l_j = [e_j, −e_j]`` and ``∇²l_j = [[Π_j, −Π_j], [−Π_j, Π_j]]`` with ``Π_j = (I − e_j e_jᵀ)/l_j``, and
        large stiffness matrices are assembled from 3×3 node blocks (:attr:`blocks`) without the Hessians.
    """

    lengths: np.ndarray
    grad: np.ndarray
    hess: np.ndarray | None
    index: np.ndarray
    n: int
    directions: np.ndarray | None = None
    point_nodes: bool = False

    def __repr__(self) -> str:
        return f"<MemberGeometry: {self.lengths.size} members, {self.n} coordinates>"

    @cached_property
    def blocks(self) -> NodeBlocks:
        """The node-block pattern of this geometry's stiffness matrices (point nodes only), computed once."""
        return NodeBlocks(self.index[:, 0], self.index[:, _W], self._point_directions(), self.n)

    def block_matrix(self, hessian_weights=None, gram_weights=None):
        """``Σ h_j ∇²l_j + Σ g_j a_j a_jᵀ`` on :attr:`blocks` (point nodes only; real weights, shape (m,) each)."""
        return self.blocks.assemble(self._point_directions(), self.lengths, hessian_weights, gram_weights)

    def _point_directions(self) -> np.ndarray:
        if not self.point_nodes or self.directions is None:
            raise ValueError("node blocks exist only for structures of point nodes (no rigid struts, no rollers)")
        return self.directions


class NodeBlocks:
    """The sparsity pattern shared by every stiffness and damping matrix of a structure of point nodes.

    Member j joining nodes a and b adds one 3×3 block ``B_j`` as ``[[B_j, −B_j], [−B_j, B_j]]`` on the
    coordinates of a and b (a fixed end adds nothing), with ``B_j = s_j I + t_j e_j e_jᵀ`` for every matrix
    (:meth:`assemble`): its entry (x, y), x ≠ y, is zero whatever the weights where ``e_jx·e_jy = 0`` (a member
    along an axis or in a coordinate plane). The union of the other entries is the pattern of
    ``Σ h_j ∇²l_j + Σ g_j a_j a_jᵀ`` for any weights, the one a sum of sparse products gives. It is laid out
    once as a CSR structure (sorted indices) with the place of each entry of each member's four blocks in its
    data array, so that each matrix is one ``bincount`` over the members (no COO sort, no sparse products or
    sums), and every matrix assembled here shares one ``indptr``/``indices`` (K0 + σC0 is then a sum of data
    arrays, and the fill-reducing ordering reads one pattern).

    Parameters
    ----------
    first_a, first_b : ndarray of int, shape (m,)
        The first coordinate of each member's ends (3·k for the k-th moving node), -1 for a fixed end.
    directions : ndarray, shape (m, 3)
        The members' unit vectors.
    n : int
        Number of generalized coordinates (3 per moving node).
    """

    def __init__(self, first_a: np.ndarray, first_b: np.ndarray, directions: np.ndarray, n: int):
        nb, m = n // 3, first_a.size
        ra, rb = first_a // 3, first_b // 3
        fa, fb = first_a >= 0, first_b >= 0
        # each member's four blocks (a, a), (b, b), (a, b), (b, a), in this order, and where they can be nonzero
        valid = np.concatenate([fa, fb, fa & fb, fa & fb])
        brow = np.concatenate([ra, rb, ra, rb])[valid]
        bcol = np.concatenate([ra, rb, rb, ra])[valid]
        member = np.flatnonzero(valid) % m
        # the distinct blocks, by row then column (scipy's conversion: linear time, sorts only within rows)
        G = sp.csr_matrix((np.ones(brow.size, dtype=np.int8), (brow, bcol)), shape=(nb, nb))
        G.sum_duplicates()
        bptr = G.indptr.astype(np.int64)
        nk = G.indices.size
        krow = np.repeat(np.arange(nb, dtype=np.int64), np.diff(bptr))
        kcol = G.indices.astype(np.int64)
        which = np.searchsorted(krow * nb + kcol, brow * np.int64(nb) + bcol)
        # entry (x, y) of a distinct block is kept when some member on it has e_x·e_y ≠ 0 (the diagonal always):
        # the blocks are symmetric, so three off-diagonal pairs, one bincount each
        nonzero = directions != 0
        kept = np.zeros((nk, 3, 3), dtype=bool)
        kept[:, (0, 1, 2), (0, 1, 2)] = True
        for x, y in ((0, 1), (0, 2), (1, 2)):
            on = np.bincount(which[(nonzero[:, x] & nonzero[:, y])[member]], minlength=nk) > 0
            kept[:, x, y] = kept[:, y, x] = on
        # coordinate row 3r + x: block row r's blocks in column order, within each its kept columns y in order
        k8 = kept.view(np.int8)
        before_y = np.zeros((nk, 3, 3), dtype=np.int64)  # kept entries left of (x, y) within its block
        before_y[:, :, 1] = k8[:, :, 0]
        before_y[:, :, 2] = k8[:, :, 0] + k8[:, :, 1]
        per_row = before_y[:, :, 2] + k8[:, :, 2]  # (blocks, 3)
        upto = np.zeros((nk + 1, 3), dtype=np.int64)  # kept entries of the blocks before each, per x
        np.cumsum(per_row, axis=0, out=upto[1:])
        indptr = np.zeros(n + 1, dtype=np.int64)
        np.cumsum((upto[bptr[1:]] - upto[bptr[:-1]]).ravel(), out=indptr[1:])
        nnz = int(indptr[-1])
        index_type = np.int32 if max(n, nnz) < 2 ** 31 - 1 else np.int64
        start = indptr[:-1].reshape(nb, 3)[krow] + upto[:-1] - upto[bptr[krow]]  # (blocks, 3): row x's first
        place = (start[:, :, None] + before_y).astype(index_type)
        place[~kept] = nnz  # an entry zero in every matrix: the spare slot, dropped
        indices = np.empty(nnz + 1, dtype=index_type)
        indices[place] = (3 * kcol).astype(index_type)[:, None, None] + np.arange(3, dtype=index_type)
        # a fixed end's blocks: the spare slot too; kept in the index type (half the memory at int32: 29 MB at
        # 106,641 coordinates, alive as long as the cell, beside the two Cholesky factors of its models)
        pos = np.full((4 * m, 9), nnz, dtype=index_type)
        pos[np.flatnonzero(valid)] = place.reshape(nk, 9)[which]
        self.n, self.nnz = n, nnz
        self.indptr, self.indices = indptr.astype(index_type), indices[:nnz]
        self.positions = pos.ravel()

    def assemble(self, directions: np.ndarray, lengths: np.ndarray, hessian_weights=None, gram_weights=None):
        """``Σ h_j ∇²l_j + Σ g_j a_j a_jᵀ`` as a CSR matrix on the shared pattern (real weights, shape (m,) each).

        Node block ``B_j = (h_j/l_j)(I − e_j e_jᵀ) + g_j e_j e_jᵀ = s_j I + t_j e_j e_jᵀ``.
        """
        m = lengths.size
        s = np.zeros(m) if hessian_weights is None else np.asarray(hessian_weights, dtype=float) / lengths
        t = -s if gram_weights is None else np.asarray(gram_weights, dtype=float) - s
        B = np.empty((4, m, 3, 3))
        np.multiply(directions[:, :, None], directions[:, None, :], out=B[0])  # e eᵀ, symmetric to the bit
        B[0] *= t[:, None, None]
        B[0, :, (0, 1, 2), (0, 1, 2)] += s
        B[1] = B[0]
        np.negative(B[0], out=B[2])
        B[3] = B[2]
        data = np.bincount(self.positions, weights=B.ravel(), minlength=self.nnz + 1)[:-1]
        M = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))
        M.has_sorted_indices = True  # the layout of __init__: one entry per (row, column), columns ascending
        M.has_canonical_format = True
        return M


def member_geometry(coords: Coordinates, q: np.ndarray, kin: NodeKinematics | None = None, *,
                    hessians: bool = True) -> MemberGeometry:
    """Member lengths, gradients and Hessians at ``q`` (all analytic).

    With ``d = x_a − x_b``, ``l = |d|``, ``e = d/l`` and ``M = [J_a, −J_b]``
    the chain rule gives ``∇l = Mᵀe`` and
    ``∇²l = Mᵀ (I − eeᵀ)/l M + Σ_x e_x (H_a ⊕ −H_b)_x``.
    With ``hessians=False`` the (costlier) Hessians are skipped and ``hess``
    is None: enough for lengths, A(q) and C(q).
    """
    kin = kinematics(coords, q) if kin is None else kin
    a, b = coords.tendon_nodes[:, 0], coords.tendon_nodes[:, 1]
    d = kin.x[a] - kin.x[b]
    l = np.linalg.norm(d, axis=1)
    if np.any(l <= 0):
        j = int(np.flatnonzero(l <= 0)[0])
        raise ValueError(f"tendon {j} has zero length in this configuration")
    e = d / l[:, None]
    index = np.concatenate([kin.index[a], kin.index[b]], axis=1)
    if point_nodes_only(coords):
        return _point_geometry(l, e, index, coords.n, hessians)
    if not hessians:
        grad = np.concatenate([np.einsum("mxk,mx->mk", kin.jac[a], e), -np.einsum("mxk,mx->mk", kin.jac[b], e)], axis=1)
        return MemberGeometry(lengths=l, grad=grad, hess=None, index=index, n=coords.n, directions=e)
    M = np.concatenate([kin.jac[a], -kin.jac[b]], axis=2)  # (m, 3, 10)
    grad = np.einsum("mxk,mx->mk", M, e)
    proj = (np.eye(3)[None] - e[:, :, None] * e[:, None, :]) / l[:, None, None]
    hess = np.matmul(M.transpose(0, 2, 1), np.matmul(proj, M))  # batched MᵀPM: far faster than a 3-operand einsum
    if coords.structure.struts:  # node positions are linear in q without rigid struts: no curvature term
        w = kin.hess.shape[-1]
        hess[:, :w, :w] += np.einsum("mx,mxkl->mkl", e, kin.hess[a])
        hess[:, w:, w:] -= np.einsum("mx,mxkl->mkl", e, kin.hess[b])
    return MemberGeometry(lengths=l, grad=grad, hess=hess, index=index, n=coords.n, directions=e)


def point_nodes_only(coords: Coordinates) -> bool:
    """Whether every node that moves is a point node with its three coordinates (no rigid struts, no rollers):
    node positions are then the coordinates themselves (unit Jacobians, no curvature)."""
    return not coords.structure.struts and coords.point_axes is None


def _point_geometry(l: np.ndarray, e: np.ndarray, index: np.ndarray, n: int, hessians: bool) -> MemberGeometry:
    """:func:`member_geometry` of a structure of point nodes: ``∇l = [e, −e]``, ``∇²l = [[Π, −Π], [−Π, Π]]``.

    The same numbers as the general chain rule with unit Jacobians (a fixed end has none: its slots are -1
    and its entries 0), without forming the Jacobians' products.
    """
    m = l.size
    free = index >= 0
    grad = np.zeros((m, 2 * _W))
    grad[:, :3] = e
    grad[:, _W:_W + 3] = -e
    grad *= free
    hess = None
    if hessians:
        proj = (np.eye(3)[None] - e[:, :, None] * e[:, None, :]) / l[:, None, None]
        hess = np.zeros((m, 2 * _W, 2 * _W))
        hess[:, :3, :3] = hess[:, _W:_W + 3, _W:_W + 3] = proj
        hess[:, :3, _W:_W + 3] = hess[:, _W:_W + 3, :3] = -proj
        hess *= free[:, :, None] & free[:, None, :]
    return MemberGeometry(lengths=l, grad=grad, hess=hess, index=index, n=n, directions=e, point_nodes=True)


def _use_sparse(n: int) -> bool:
    return n > SPARSE_THRESHOLD


def equilibrium_matrix(geom: MemberGeometry, sparse: bool | None = None):
    """The equilibrium matrix ``A = ∂l/∂q``, shape ``(n_q, m)``.

    Dense ndarray for small structures, ``scipy.sparse.csr_matrix`` above
    :data:`SPARSE_THRESHOLD` coordinates (or as ``sparse`` demands).
    """
    m, w = geom.grad.shape
    rows = geom.index.ravel()
    cols = np.repeat(np.arange(m), w)
    use_sparse = _use_sparse(geom.n) if sparse is None else sparse
    if not use_sparse:
        # dense: one bincount (the -1 padding lands in a dropped extra row), on the time integrator's hot path
        flat = np.where(rows >= 0, rows, geom.n) * m + cols
        return np.bincount(flat, weights=geom.grad.ravel(), minlength=(geom.n + 1) * m).reshape(geom.n + 1, m)[:-1]
    keep = rows >= 0
    return sp.csr_matrix((geom.grad.ravel()[keep], (rows[keep], cols[keep])), shape=(geom.n, m))


def assemble_hessian(geom: MemberGeometry, weights: np.ndarray, sparse: bool | None = None):
    """``Σ_j w_j ∇²l_j`` assembled into an ``(n_q, n_q)`` matrix."""
    if _node_blocks(geom, sparse):
        return geom.block_matrix(hessian_weights=weights)
    index, hess = geom.index, geom.hess
    if hess is None:
        raise ValueError("assemble_hessian needs a MemberGeometry with Hessians (member_geometry(..., hessians=True))")
    used = np.flatnonzero((index >= 0).any(axis=0))
    if used.size < index.shape[1]:  # block slots no member uses (e.g. a point node's two spare ones): drop them first
        index, hess = index[:, used], hess[:, used[:, None], used]
    m, w = index.shape
    data = (hess * np.asarray(weights, dtype=float)[:, None, None]).ravel()
    # entry (j, a, b) sits at (index[j, a], index[j, b]); int32 and contiguous repeats: half the memory traffic
    # of raveling broadcast int64 views (10⁴-node lattices: 2·10⁶ entries)
    idx = index.astype(np.int32) if geom.n < 2 ** 31 else index
    r = np.repeat(idx, w, axis=1).ravel()
    c = np.tile(idx, (1, w)).ravel()
    if np.any(index < 0):
        keep = (r >= 0) & (c >= 0)
        r, c, data = r[keep], c[keep], data[keep]
    H = sp.csr_matrix((data, (r, c)), shape=(geom.n, geom.n))
    use_sparse = _use_sparse(geom.n) if sparse is None else sparse
    return H if use_sparse else H.toarray()


def _node_blocks(geom: MemberGeometry, sparse: bool | None) -> bool:
    """Whether a matrix of this geometry is assembled from node blocks: sparse, of point nodes."""
    return geom.point_nodes and (_use_sparse(geom.n) if sparse is None else sparse)


def member_stiffness(geom: MemberGeometry, hessian_weights=None, gram_weights=None, *, A=None,
                     sparse: bool | None = None):
    """``Σ_j h_j ∇²l_j + Σ_j g_j a_j a_jᵀ`` (either sum may be left out): every stiffness and damping matrix.

    Parameters
    ----------
    geom : MemberGeometry
    hessian_weights : ndarray, shape (m,), optional
        ``h``: member forces (N) for a stiffness (``P·T0``, or ``T0`` for the prestress stiffness per N).
    gram_weights : ndarray, shape (m,), optional
        ``g``: tangent stiffnesses (N/m) or dampings (N·s/m), real or complex.
    A : ndarray or sparse matrix, shape (n, m), optional
        The equilibrium matrix of ``geom`` when already formed (computed otherwise).
    sparse : bool, optional
        Sparse or dense result (default: by size, :data:`SPARSE_THRESHOLD`).

    Large structures of point nodes (lattices) are assembled from node blocks in one pass over the members
    (:class:`NodeBlocks`: one shared pattern, no sparse products); the others as the Hessian sum plus the Gram
    product ``A diag(g) Aᵀ``. The two agree to rounding.
    """
    real = gram_weights is None or not np.iscomplexobj(gram_weights)
    if real and _node_blocks(geom, sparse):
        return geom.block_matrix(hessian_weights, gram_weights)
    use_sparse = _use_sparse(geom.n) if sparse is None else sparse
    H = None if hessian_weights is None else assemble_hessian(geom, hessian_weights, sparse=use_sparse)
    if gram_weights is None:
        return H
    if A is None:
        A = equilibrium_matrix(geom, use_sparse)
    G = weighted_gram(A, gram_weights)
    return G if H is None else H + G


def point_vector(coords: Coordinates, point: Point, kin: NodeKinematics) -> np.ndarray:
    """``∂(d·x_p)/∂q`` for a load or probe point ``p``, shape ``(n_q,)``.

    For the load this is ``−H(q)`` (a unit force along the direction does
    virtual work ``(∂x_p/∂q)ᵀd``); for the probe it is ``D(q)``.
    """
    v = np.zeros(coords.n + 1)  # last slot swallows the -1 padding
    d = np.asarray(point.direction)
    for node, wgt in zip(point.nodes, point.weights):
        np.add.at(v, kin.index[node], wgt * (kin.jac[node].T @ d))
    return v[:-1]


def self_stress_basis(A, rtol: float = 1e-10) -> tuple[np.ndarray, int]:
    """Orthonormal basis of ``null(A)`` (columns, shape ``(m, k)``) and ``rank A``."""
    A = A.toarray() if sp.issparse(A) else np.asarray(A)
    _, s, vt = scipy.linalg.svd(A, full_matrices=True)
    tol = rtol * (s[0] if s.size else 1.0)
    rank = int(np.sum(s > tol))
    return vt[rank:].T.copy(), rank


def self_stress(
    A,
    families: tuple[str, ...],
    equal_tension_groups: tuple[tuple[int, ...], ...] = (),
    *,
    describe: str = "this reference",
    rtol: float = 1e-9,
) -> tuple[np.ndarray, int]:
    """The self-stress state ``T0`` and the dimension of the self-stress space.

    ``T0`` satisfies ``A T0 = 0``, ``‖T0_cables‖₂ = 1`` (the norm over the
    members that are not struts), equal tensions inside each
    equal-tension group, and strictly positive tension in every cable (every
    member whose family is not ``"strut"``). When the constraints leave a
    single state it is used; when several remain, the state maximizing the
    smallest cable tension (a linear program) is chosen.

    Raises
    ------
    NotPrestressableError
        If no such state exists, with the reason.
    """
    N, rank = self_stress_basis(A)
    m = len(families)
    if N.shape[1] == 0:
        raise NotPrestressableError(
            f"{describe} is not prestressable: the equilibrium matrix has full column rank {rank} "
            f"for {m} tendons, so no self-stress exists (A(q0)·T = 0 only for T = 0)"
        )
    dim = N.shape[1]
    rows = []
    for g in equal_tension_groups:
        for j in g[1:]:
            r = np.zeros(m)
            r[g[0]], r[j] = 1.0, -1.0
            rows.append(r)
    if rows:
        E = np.array(rows) @ N
        Z, _ = self_stress_basis(E) if E.size else (np.eye(dim), 0)
        N = N @ Z
        if N.shape[1] == 0:
            raise NotPrestressableError(
                f"{describe} is not prestressable with equal tensions in the requested groups: "
                f"the {dim}-dimensional self-stress space contains no such state"
            )
    cable = cable_mask(families)
    if N.shape[1] == 1:
        T = N[:, 0]
        if T[cable].sum() < 0:
            T = -T
    else:
        T = _max_min_tension(N, cable)
    # normalize over the cables only, so a cell whose struts are listed as elastic members
    # (negative force) has the same T0 on its tendons as its rigid-strut twin
    T = T / np.linalg.norm(T[cable])
    floor = rtol * np.abs(T).max()
    slack = np.flatnonzero(cable & (T <= floor))
    if slack.size:
        fams = sorted({families[j] for j in slack})
        worst = float(T[slack].min())
        raise NotPrestressableError(
            f"{describe} is not prestressable: in its self-stress state {slack.size} tendon(s) "
            f"({', '.join(fams)}; indices {slack.tolist()}) are not in tension "
            f"(smallest normalized tension {worst:.3g}); a tensegrity needs every tendon strictly in tension"
        )
    return T, dim


def _max_min_tension(N: np.ndarray, cable: np.ndarray) -> np.ndarray:
    """The self-stress in span(N) maximizing the smallest cable tension (sum of cables = 1)."""
    m, k = N.shape
    # variables: x (k), s;  maximize s  s.t.  s - N_c x <= 0,  sum(N_c x) = 1
    Nc = N[cable]
    c = np.zeros(k + 1)
    c[-1] = -1.0
    A_ub = np.hstack([-Nc, np.ones((Nc.shape[0], 1))])
    A_eq = np.hstack([Nc.sum(axis=0)[None], [[0.0]]])
    from scipy.optimize import linprog  # here, not at import: scipy.optimize costs ~0.25 s to load

    res = linprog(
        c, A_ub=A_ub, b_ub=np.zeros(Nc.shape[0]), A_eq=A_eq, b_eq=[1.0],
        bounds=[(None, None)] * k + [(None, 1.0)], method="highs",
    )
    if res.status != 0:
        return N[:, 0]
    return N @ res.x[:k]


def self_stress_lp(
    A,
    families: tuple[str, ...],
    equal_tension_groups: tuple[tuple[int, ...], ...] = (),
    *,
    describe: str = "this reference",
) -> np.ndarray:
    """A self-stress maximizing the smallest cable tension, by a sparse linear program.

    For structures too large for the SVD of :func:`self_stress`: solves
    ``max s`` subject to ``A T = 0``, equal tensions within each group,
    ``T_j >= s`` on every cable and ``Σ_cables T_j = (number of cables)``
    with scipy's HiGHS on the sparse ``A``. Returns ``T0`` normalized over the
    cables (``‖T0_cables‖₂ = 1``).

    Raises
    ------
    NotPrestressableError
        If the best state leaves some cable without tension.
    """
    A = sp.csr_matrix(A)
    n, m = A.shape
    cable = cable_mask(families)
    nc = int(cable.sum())
    rows = [sp.hstack([A, sp.csr_matrix((n, 1))])]
    rhs = [np.zeros(n)]
    for g in equal_tension_groups:
        if len(g) > 1:
            k = len(g) - 1
            E = sp.csr_matrix((np.r_[np.ones(k), -np.ones(k)], (np.r_[np.arange(k), np.arange(k)], np.r_[np.full(k, g[0]), list(g[1:])])),
                              shape=(k, m + 1))
            rows.append(E)
            rhs.append(np.zeros(k))
    rows.append(sp.csr_matrix(np.r_[cable.astype(float), 0.0][None, :]))
    rhs.append(np.array([float(nc)]))
    A_eq = sp.vstack(rows).tocsr()
    ci = np.flatnonzero(cable)
    A_ub = sp.csr_matrix((np.r_[-np.ones(nc), np.ones(nc)], (np.r_[np.arange(nc), np.arange(nc)], np.r_[ci, np.full(nc, m)])),
                         shape=(nc, m + 1))
    c = np.zeros(m + 1)
    c[-1] = -1.0
    from scipy.optimize import linprog  # here, not at import (see _max_min_tension)

    res = linprog(c, A_ub=A_ub, b_ub=np.zeros(nc), A_eq=A_eq, b_eq=np.concatenate(rhs),
                  bounds=[(None, None)] * m + [(None, 1.0)], method="highs")
    if res.status != 0 or res.x is None:
        raise NotPrestressableError(
            f"{describe} is not prestressable: no self-stress with every cable in tension exists "
            f"(linear program: {res.message})"
        )
    T, smin = res.x[:m], res.x[-1]
    if smin <= 1e-9:
        slack = np.flatnonzero(cable & (T <= 1e-9))
        raise NotPrestressableError(
            f"{describe} is not prestressable: every self-stress leaves {slack.size} tendon(s) without tension "
            f"(indices {slack[:10].tolist()}{'...' if slack.size > 10 else ''}); a tensegrity needs every tendon strictly in tension"
        )
    return T / np.linalg.norm(T[cable])


@dataclass(frozen=True, eq=False, repr=False)
class Cell:
    """A structure at its prestressable reference configuration.

    Created by :func:`equilibrate` (or a built-in such as
    :func:`tenscell.paper_cell`). Everything that depends only on the
    geometry and the self-stress is computed once here.

    Attributes
    ----------
    structure : Structure
    coords : Coordinates
    q0 : ndarray, shape (n,)
        Reference generalized coordinates (m, rad).
    lengths : ndarray, shape (m,)
        Tendon lengths at the reference, ``l_j(q0)`` (m).
    A : ndarray or sparse, shape (n, m)
        Equilibrium matrix ``A(q0)`` (Eq. 7).
    T0 : ndarray, shape (m,)
        Self-stress state, ``‖T0‖₂ = 1`` over the cables; tensions are ``P·T0`` (N).
    Kp : ndarray or sparse, shape (n, n)
        Prestress stiffness ``Σ T0_j (∇²l_j + a_j a_jᵀ/l_j)`` (N/m per N of P), assembled on first use.
    load : ndarray, shape (n,)
        ``−H0``: generalized force of a unit load (1/N·N; m or m/rad).
    probe : ndarray, shape (n,)
        ``D0``: output row, probe displacement per unit ``q`` (m/m, m/rad).
    self_stress_dim : int
        Dimension of the self-stress space ``null A(q0)``; -1 when not
        computed (sparse-sized structures, where it would need a rank
        decision on the full equilibrium matrix).
    parameters : mapping
        The named parameters the cell was built from (for messages and reports).
    L : float
        Strut length for the equivalent-continuum factor 0.5/L (m).
    """

    structure: Structure
    coords: Coordinates
    q0: np.ndarray
    lengths: np.ndarray
    A: Any  # ndarray or scipy.sparse matrix
    T0: np.ndarray
    load: np.ndarray
    probe: np.ndarray
    self_stress_dim: int
    geometry: MemberGeometry
    parameters: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    L: float = 1.0

    @property
    def n(self) -> int:
        """Number of generalized coordinates."""
        return self.coords.n

    @property
    def m(self) -> int:
        """Number of working tendons."""
        return len(self.T0)

    @property
    def sparse(self) -> bool:
        """Whether the matrices are scipy.sparse (large structures)."""
        return sp.issparse(self.A)

    @cached_property
    def prestress_hessian(self):
        """``Σ_j T0_j ∇²l_j`` (N/m per N of P), dense or sparse like ``A``; ``Kp`` is it plus ``Σ T0_j a_j a_jᵀ/l_j``."""
        return assemble_hessian(self.geometry, self.T0, sparse=self.sparse)

    @cached_property
    def Kp(self):
        """Prestress stiffness ``Σ T0_j (∇²l_j + a_j a_jᵀ/l_j)`` (N/m per N of P), dense or sparse like ``A``.

        Computed on first use: linearizing needs only :attr:`prestress_hessian`.
        """
        if _node_blocks(self.geometry, self.sparse):  # Σ T0_j/l_j [[I, −I], [−I, I]]: one pass, no Hessian
            return member_stiffness(self.geometry, self.T0, self.T0 / self.lengths, A=self.A, sparse=True)
        return self.prestress_hessian + weighted_gram(self.A, self.T0 / self.lengths)

    @property
    def strut_length(self) -> float:
        """The strut length L used in the equivalent-continuum factor 0.5/L (m).

        The mean strut length when struts differ; the ``L`` parameter (or
        1 m) when there are no rigid struts.
        """
        return self.L

    def describe(self) -> str:
        """A short description with the cell's parameters."""
        return self._description

    @cached_property
    def _description(self) -> str:  # every linear model's messages name its cell: format it once
        return _label(self.structure.name, self.parameters)

    # a read-only mapping does not pickle: carry it as a dict (cells go to worker processes, fits come back)
    def __getstate__(self) -> dict:
        return {**self.__dict__, "parameters": dict(self.parameters)}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, parameters=MappingProxyType(state["parameters"]))

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from .._results import counts, format_repr, span

        st = self.structure
        dim = "not computed (sparse size)" if self.self_stress_dim < 0 else str(self.self_stress_dim)
        return format_repr(
            f"Cell {self.describe()}",
            f"{st.n_nodes} nodes, {len(st.struts)} rigid struts, {self.m} tendons ({counts(st.families)}); "
            f"{self.n} coordinates ({self.coords.kind}, {'sparse' if self.sparse else 'dense'})",
            f"self-stress T0 {span(self.T0)} (tensions P·T0 N), self-stress space dimension {dim}",
            f"strut length L = {self.L:.4g} m (continuum factor 0.5/L)",
            *((f"note: {self.coords.note}",) if self.coords.note else ()),
        )

    def to_dataframe(self):
        """One row per tendon: ``tendon, family, node_a, node_b, length_m, T0`` (tensions are ``P·T0`` N)."""
        df = self.structure.to_dataframe("tendons", length_m=self.lengths, T0=self.T0)
        df.attrs["cell"] = self.describe()
        return df

    def _repr_html_(self) -> str:
        from .._results import reporter

        return reporter("structure_html")(self)  # the repr's lines and the interactive 3D view (reports/html.py)

    def view(self, **kw):
        """The interactive 3D view (plotly, ``pip install 'tenscell[view]'``):
        :func:`tenscell.plotting.structure_view`; returns the plotly Figure (``.show()``, ``.write_html(path)``)."""
        from .._results import plotter

        return plotter("structure_view")(self, **kw)

    def plot(self, ax=None, **kw):
        """The cell's structure in 3D (:func:`tenscell.plotting.structure_3d`)."""
        from .._results import plotter

        structure_3d = plotter("structure_3d")

        return structure_3d(self.structure, ax=ax, **{"title": self.describe(), **kw})


def _label(name: str, parameters) -> str:
    if not parameters:
        return name
    ps = ", ".join(_show_parameter(k, v) for k, v in parameters.items())
    return f"{name} ({ps})"


def _show_parameter(key: str, value) -> str:
    """``key=value``; angles (alpha, delta, theta_*) in degrees, as people (and the CLI flags) give them."""
    if isinstance(value, float) and (key in ("alpha", "delta") or key.startswith("theta")):
        return f"{key}={math.degrees(value):.6g}°"
    return f"{key}={value:.6g}" if isinstance(value, float) else f"{key}={value}"


def equilibrate(
    structure: Structure,
    parametrization: str = "auto",
    *,
    T0: np.ndarray | None = None,
    parameters: dict | None = None,
) -> Cell:
    """Find the self-stress of a structure at its reference and build a :class:`Cell`.

    Parameters
    ----------
    structure : Structure
        Its node positions are the reference configuration q0.
    parametrization : {"auto", "angles", "local"}
        Strut direction coordinates (see :mod:`tenscell.model.coordinates`); ``"auto"``: the paper's
        angles, or the local chart when a strut is vertical (where the angles are singular), which the
        cell's ``repr`` notes (``cell.coords.note``).
    T0 : ndarray, optional
        A self-stress to use instead of the computed one; it is checked
        (``A T0 = 0``, cables in tension) and normalized. Without it, the
        state comes from the SVD of A (:func:`self_stress`), or for
        structures above :data:`SPARSE_THRESHOLD` coordinates from a sparse
        linear program (:func:`self_stress_lp`, and ``self_stress_dim`` is
        then -1).
    parameters : dict, optional
        Named parameters to record in the cell.

    Raises
    ------
    NotPrestressableError
        If the reference admits no self-stress with every tendon in tension.
    """
    coords = make_coordinates(structure, parametrization)
    kin = kinematics(coords, coords.q0)
    # a large structure of point nodes assembles its matrices from node blocks: its Hessians are never formed
    geom = member_geometry(coords, coords.q0, kin,
                           hessians=not (point_nodes_only(coords) and _use_sparse(coords.n)))
    A = equilibrium_matrix(geom)
    label = _label(structure.name, parameters or {})
    if T0 is None:
        if sp.issparse(A):
            # large structures: no SVD; the self-stress space's dimension is then not computed (-1)
            T0, dim = self_stress_lp(A, structure.families, structure.equal_tension_groups, describe=label), -1
        else:
            T0, dim = self_stress(A, structure.families, structure.equal_tension_groups, describe=label)
    else:
        T0 = _check_given_self_stress(A, structure.families, T0, label)
        dim = -1 if sp.issparse(A) else self_stress_basis(A)[0].shape[1]
    l = geom.lengths
    load = point_vector(coords, structure.load, kin)
    probe = point_vector(coords, structure.probe, kin)
    for arr in (T0, l, load, probe):
        arr.setflags(write=False)
    return Cell(
        structure=structure, coords=coords, q0=coords.q0, lengths=l, A=A, T0=T0, load=load,
        probe=probe, self_stress_dim=dim, geometry=geom,
        parameters=MappingProxyType(dict(parameters or {})), L=_continuum_length(structure, parameters or {}),
    )


def _continuum_length(structure: Structure, parameters: dict) -> float:
    Ls = structure.strut_lengths
    return float(Ls.mean()) if Ls.size else float(parameters.get("L", 1.0))


def _check_given_self_stress(A, families, T0, label) -> np.ndarray:
    T0 = np.array(T0, dtype=float)
    if T0.shape != (len(families),) or not np.all(np.isfinite(T0)):
        raise ValueError(f"T0 must be {len(families)} finite tensions, got shape {T0.shape}")
    cable = cable_mask(families)
    T0 = T0 / np.linalg.norm(T0[cable])
    resid = np.linalg.norm(A @ T0) / max(np.abs(A).max() if not sp.issparse(A) else abs(A).max(), 1e-300)
    if resid > 1e-8:
        raise NotPrestressableError(f"the given T0 is not a self-stress of {label}: |A·T0| = {resid:.3g}")
    if np.any(T0[cable] <= 0):
        bad = np.flatnonzero(cable & (T0 <= 0)).tolist()
        raise NotPrestressableError(f"the given T0 has tendons {bad} not in tension")
    return T0


def weighted_gram(A, w: np.ndarray):
    """``A diag(w) Aᵀ`` for dense or sparse A: ``Σ_j w_j a_j a_jᵀ`` (the material part of K, and C)."""
    if sp.issparse(A):
        return (A @ sp.diags(w) @ A.T).tocsr()
    return (A * w) @ A.T


def generalized_forces(cell: Cell, q: np.ndarray, tensions_fn):
    """Elastic generalized forces ``A(q)·T(q)`` and the member geometry at ``q``.

    Parameters
    ----------
    cell : Cell
    q : ndarray, shape (n,)
    tensions_fn : callable
        ``l (m,) -> T (m,)``: member tensions (N) from lengths (m).

    Returns
    -------
    f : ndarray, shape (n,)
        ``A(q) T(l(q))`` (N or N·m per coordinate).
    geom : MemberGeometry
    """
    geom = member_geometry(cell.coords, q)
    T = tensions_fn(geom.lengths)
    f = np.zeros(cell.n + 1)
    np.add.at(f, geom.index.ravel(), (geom.grad * T[:, None]).ravel())
    return f[:-1], geom


def damping_matrix(geom: MemberGeometry, c: np.ndarray):
    """``C(q) = Σ c_j a_j a_jᵀ`` (paper Eq. 8), in N·s/m, from a member geometry."""
    return member_stiffness(geom, gram_weights=np.broadcast_to(c, geom.lengths.shape))


def tangent_stiffness(geom: MemberGeometry, T: np.ndarray, dT_dl: np.ndarray, A=None, sparse: bool | None = None):
    """Exact Jacobian of ``A(q)T(l(q))``: ``Σ T_j ∇²l_j + Σ (dT_j/dl_j) a_j a_jᵀ`` (N/m).

    The one formula for a stiffness matrix: ``Kp`` (``T = T0``, ``dT/dl = T0/l``),
    K0 of a linear model and the tangent of the time integrator. ``A`` (the
    equilibrium matrix of ``geom``) is computed when not given.
    """
    return member_stiffness(geom, T, dT_dl, A=A, sparse=sp.issparse(A) if A is not None else sparse)
