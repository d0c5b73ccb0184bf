"""Generalized coordinates q -> node positions, with exact derivatives.

Every movable part of a :class:`~tenscell.model.structure.Structure` owns a block of
generalized coordinates, laid out in this order: the struts in the
structure's order, then the point nodes in index order.

* anchored strut: 2 direction coordinates;
* free strut: its centre ``(X, Y, Z)`` (m) then 2 direction coordinates;
* point node: ``(X, Y, Z)`` (m), or the directions a per-direction support
  (:attr:`Structure.supports <tenscell.model.structure.Structure.supports>`)
  leaves free, in x-y-z order.

For the paper's cell this is exactly the order of the paper's Eq. (2):
``[δ11 α11 δ21 α21 δ31 α31 X1 Y1 Z1 δ12 α12 ... X Y Z]``.

Two direction parametrizations are offered:

``"angles"``
    the paper's declination δ (from b3) and azimuth α (from b1), in radians:
    ``u = (sin δ cos α, sin δ sin α, cos δ)``. Singular for vertical struts.
``"local"``
    a singularity-free chart around the reference direction ``u_ref``:
    ``u = w/|w|`` with ``w = u_ref + θ1 e1 + θ2 e2`` and ``e1, e2 ⊥ u_ref``
    (θ dimensionless, zero at the reference).

``"auto"``
    ``"angles"`` unless a strut lies within :data:`VERTICAL_SIN` (sin δ) of
    the z axis, where the angles are singular (α moves nothing); then
    ``"local"``, and :attr:`Coordinates.note` says so in one line.

Both give the same physics; the test suite checks that the compliance is the
same in either chart.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .structure import Structure

__all__ = ["Coordinates", "NodeKinematics", "make_coordinates", "kinematics", "positions", "PARAMETRIZATIONS",
           "VERTICAL_SIN"]

PARAMETRIZATIONS = ("angles", "local", "auto")
#: "auto" leaves the paper's angles for the local chart when a strut has sin δ below this (within 0.57° of
#: vertical): ∂u/∂α = sin δ, so the stiffness in α scales as sin²δ (1e-4 of the other terms here) and vanishes
#: at δ = 0, where K0 is singular whatever the structure
VERTICAL_SIN = 1e-2
_W = 5  # widest coordinate block a node depends on (a free strut)


@dataclass(frozen=True, eq=False, repr=False)
class Coordinates:
    """How a structure's generalized coordinates map to its nodes.

    Attributes
    ----------
    structure : Structure
    kind : str
        ``"angles"`` or ``"local"``.
    n : int
        Number of generalized coordinates.
    q0 : ndarray, shape (n,)
        Coordinates of the reference configuration (m or rad).
    node_index : ndarray of int, shape (n_nodes, 5)
        For each node, the global indices of the coordinates it depends on,
        padded with -1 (fixed nodes depend on none).
    labels : tuple of str
        A name for each coordinate, e.g. ``"delta[0]"``, ``"Z[3]"``.
    """

    structure: Structure
    kind: str
    n: int
    q0: np.ndarray
    node_index: np.ndarray
    labels: tuple[str, ...]
    # strut bookkeeping (arrays over struts)
    strut_start: np.ndarray  # first coordinate of each strut's block
    anchored: np.ndarray  # bool per strut
    lengths: np.ndarray  # strut lengths (m)
    frame: np.ndarray  # (n_struts, 3, 3): rows u_ref, e1, e2 (used by "local")
    point_start: np.ndarray  # first coordinate of each point node
    tendon_nodes: np.ndarray  # (m, 2) node pairs of the working tendons, as an array once
    point_axes: np.ndarray | None = None  # (n_points, 3) bool: the free directions of each point node (rollers)
    note: str = ""  # why "auto" chose the local chart, if it did

    def __repr__(self) -> str:
        return f"<Coordinates: {self.n} {self.kind!r} coordinates of {self.structure.name!r}>"


@dataclass(frozen=True, eq=False, repr=False)
class NodeKinematics:
    """Node positions and their exact derivatives at one configuration.

    Attributes
    ----------
    x : ndarray, shape (n_nodes, 3)
        Positions (m).
    jac : ndarray, shape (n_nodes, 3, 5)
        ``∂x/∂q`` restricted to the node's coordinate block ``index``.
    hess : ndarray, shape (n_nodes, 3, 5, 5)
        ``∂²x/∂q∂q`` on the same block.
    index : ndarray of int, shape (n_nodes, 5)
        Global coordinate indices of the block, -1 where unused.
    """

    x: np.ndarray
    jac: np.ndarray
    hess: np.ndarray
    index: np.ndarray

    def __repr__(self) -> str:
        return f"<NodeKinematics: {self.x.shape[0]} nodes>"


def make_coordinates(structure: Structure, kind: str = "angles") -> Coordinates:
    """Lay out the generalized coordinates of a structure.

    Parameters
    ----------
    structure : Structure
    kind : {"angles", "local", "auto"}
        Direction parametrization of the struts (see module docstring).

    Returns
    -------
    Coordinates
        With ``q0`` reproducing the structure's reference node positions; ``kind`` the chart used.
    """
    if kind not in PARAMETRIZATIONS:
        raise ValueError(f"parametrization must be one of {PARAMETRIZATIONS}, got {kind!r}")
    kind, note = _chart(structure) if kind == "auto" else (kind, "")
    s = structure
    ns = len(s.struts)
    struts = np.asarray(s.struts, dtype=int).reshape(ns, 2)
    anchored = np.array([s.is_anchored(k) for k in range(ns)], dtype=bool)
    lengths = s.strut_lengths
    node_index = -np.ones((s.n_nodes, _W), dtype=int)
    labels: list[str] = []
    q0: list[float] = []
    starts = np.zeros(ns, dtype=int)
    frame = np.zeros((ns, 3, 3))
    pos = 0
    for k in range(ns):
        tail, head = struts[k]
        u = (s.nodes[head] - s.nodes[tail]) / lengths[k]
        frame[k] = _frame(u)
        starts[k] = pos
        if kind == "angles":
            delta = float(np.arccos(np.clip(u[2], -1.0, 1.0)))
            alpha = float(np.arctan2(u[1], u[0]))
            if alpha < -1e-12:
                alpha += 2 * np.pi
            alpha = max(alpha, 0.0)
            dirq, dirl = [delta, alpha], [f"delta[{k}]", f"alpha[{k}]"]
        else:
            dirq, dirl = [0.0, 0.0], [f"theta1[{k}]", f"theta2[{k}]"]
        if anchored[k]:
            node_index[head, :2] = [pos, pos + 1]
            q0 += dirq
            labels += dirl
            pos += 2
        else:
            centre = 0.5 * (s.nodes[head] + s.nodes[tail])
            node_index[head] = node_index[tail] = np.arange(pos, pos + 5)
            q0 += list(centre) + dirq
            labels += [f"X[{k}]", f"Y[{k}]", f"Z[{k}]"] + dirl
            pos += 5
    points = np.asarray(s.point_nodes, dtype=int)
    held = dict(s.supports)
    free = np.array([[a not in held.get(int(p), "") for a in "xyz"] for p in points], dtype=bool).reshape(-1, 3)
    sizes = free.sum(axis=1)
    pstart = pos + np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int) if points.size else np.zeros(0, int)
    # point nodes, vectorized (10⁴-node lattices): node p's free axes take pstart[p], pstart[p] + 1, ...
    first = np.arange(3) < sizes[:, None]
    node_index[np.repeat(points, sizes), np.nonzero(first)[1]] = pos + np.arange(int(sizes.sum()))
    q0a = np.concatenate([np.array(q0, dtype=float), s.nodes[points][free]])
    axis_of = np.nonzero(free)
    labels += [f"{'XYZ'[a]}(node {p})" for p, a in zip(points[axis_of[0]].tolist(), axis_of[1].tolist())]
    pos += int(sizes.sum())
    tendon_nodes = np.asarray(s.tendons, dtype=int).reshape(-1, 2)
    for a in (q0a, node_index, starts, anchored, frame, pstart, tendon_nodes, free):
        a.setflags(write=False)
    return Coordinates(
        structure=s, kind=kind, n=pos, q0=q0a, node_index=node_index, labels=tuple(labels),
        strut_start=starts, anchored=anchored, lengths=lengths, frame=frame, point_start=pstart,
        tendon_nodes=tendon_nodes, point_axes=None if free.all() else free, note=note,
    )


def _chart(s: Structure) -> tuple[str, str]:
    """``("angles", "")``, or ``("local", why)`` when a strut is vertical within :data:`VERTICAL_SIN`."""
    if not s.struts:
        return "angles", ""
    S = np.asarray(s.struts, dtype=int)
    u = (s.nodes[S[:, 1]] - s.nodes[S[:, 0]]) / s.strut_lengths[:, None]
    sin_delta = np.hypot(u[:, 0], u[:, 1])
    vertical = np.flatnonzero(sin_delta < VERTICAL_SIN)
    if not vertical.size:
        return "angles", ""
    which = ", ".join(map(str, vertical[:5].tolist())) + (" …" if vertical.size > 5 else "")
    return "local", (f"strut(s) {which} vertical: the paper's angles δ, α are singular there, so the struts' "
                     "directions use the local chart (parametrization='local'; the same physics)")


def _frame(u: np.ndarray) -> np.ndarray:
    """Rows (u, e1, e2): an orthonormal frame with e1, e2 spanning the plane ⊥ u."""
    helper = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    return np.array([u, e1, e2])


def _directions(coords: Coordinates, theta: np.ndarray):
    """Unit strut directions and exact derivatives w.r.t. the 2 direction coordinates.

    Returns u (ns, 3), du (ns, 3, 2), d2u (ns, 3, 2, 2).
    """
    ns = theta.shape[0]
    du = np.zeros((ns, 3, 2))
    d2u = np.zeros((ns, 3, 2, 2))
    if coords.kind == "angles":
        d, a = theta[:, 0], theta[:, 1]
        sd, cd, sa, ca = np.sin(d), np.cos(d), np.sin(a), np.cos(a)
        u = np.stack([sd * ca, sd * sa, cd], axis=1)
        du[:, :, 0] = np.stack([cd * ca, cd * sa, -sd], axis=1)
        du[:, :, 1] = np.stack([-sd * sa, sd * ca, np.zeros(ns)], axis=1)
        d2u[:, :, 0, 0] = -u
        d2u[:, :, 0, 1] = d2u[:, :, 1, 0] = np.stack([-cd * sa, cd * ca, np.zeros(ns)], axis=1)
        d2u[:, :, 1, 1] = np.stack([-sd * ca, -sd * sa, np.zeros(ns)], axis=1)
        return u, du, d2u
    # local gnomonic chart: u = w/r, w = u_ref + θ1 e1 + θ2 e2
    uref, E = coords.frame[:, 0], coords.frame[:, 1:]  # E: (ns, 2, 3)
    w = uref + np.einsum("sk,skx->sx", theta, E)
    r = np.linalg.norm(w, axis=1)
    u = w / r[:, None]
    ue = np.einsum("sx,skx->sk", u, E)  # u·e_k
    # ∂u/∂θ_k = (e_k − u (u·e_k)) / r
    du = (np.transpose(E, (0, 2, 1)) - u[:, :, None] * ue[:, None, :]) / r[:, None, None]
    # ∂²u/∂θ_k∂θ_l = −[du_l (u·e_k) + u (du_l·e_k)]/r − du_k (u·e_l)/r
    due = np.einsum("sxl,skx->skl", du, E)  # (du_l · e_k) at [s, k, l]
    for k in range(2):
        for l in range(2):
            d2u[:, :, k, l] = (
                -(du[:, :, l] * ue[:, k, None] + u * due[:, k, l, None]) - du[:, :, k] * ue[:, l, None]
            ) / r[:, None]
    return u, du, d2u


def kinematics(coords: Coordinates, q: np.ndarray) -> NodeKinematics:
    """Node positions and their exact first and second derivatives.

    Parameters
    ----------
    coords : Coordinates
    q : ndarray, shape (n,)
        Generalized coordinates (m and rad).

    Returns
    -------
    NodeKinematics
    """
    q = np.asarray(q, dtype=float)
    if q.shape != (coords.n,):
        raise ValueError(f"q must have shape ({coords.n},), got {q.shape}")
    s = coords.structure
    x = np.array(s.nodes, dtype=float)  # fixed nodes keep their reference positions
    jac = np.zeros((s.n_nodes, 3, _W))
    hess = np.zeros((s.n_nodes, 3, _W, _W))
    ns = len(s.struts)
    if ns:
        struts = np.asarray(s.struts, dtype=int)
        st = coords.strut_start
        anch = coords.anchored
        off = np.where(anch, 0, 3)  # direction coordinates follow the centre in free struts
        theta = np.stack([q[st + off], q[st + off + 1]], axis=1)
        u, du, d2u = _directions(coords, theta)
        L = coords.lengths
        # anchored: head = tail(fixed) + L u
        ia = np.flatnonzero(anch)
        if ia.size:
            tails, heads = struts[ia, 0], struts[ia, 1]
            x[heads] = x[tails] + L[ia, None] * u[ia]
            jac[heads, :, :2] = L[ia, None, None] * du[ia]
            hess[heads, :, :2, :2] = L[ia, None, None, None] * d2u[ia]
        # free: head/tail = G ± (L/2) u
        iff = np.flatnonzero(~anch)
        if iff.size:
            G = np.stack([q[st[iff]], q[st[iff] + 1], q[st[iff] + 2]], axis=1)
            half = 0.5 * L[iff]
            for sign, nodes in ((1.0, struts[iff, 1]), (-1.0, struts[iff, 0])):
                x[nodes] = G + sign * half[:, None] * u[iff]
                jac[nodes, :, :3] = np.eye(3)
                jac[nodes, :, 3:] = sign * half[:, None, None] * du[iff]
                hess[nodes, :, 3:, 3:] = sign * half[:, None, None, None] * d2u[iff]
    pts = np.asarray(s.point_nodes, dtype=int)
    mask = coords.point_axes
    if pts.size and mask is None:
        ps = coords.point_start
        x[pts] = np.stack([q[ps], q[ps + 1], q[ps + 2]], axis=1)
        jac[pts, :, :3] = np.eye(3)
    elif pts.size and mask is not None:  # rollers: a held direction keeps its reference coordinate
        for i, p in enumerate(pts.tolist()):
            axes = np.flatnonzero(mask[i])
            x[p, axes] = q[coords.point_start[i] + np.arange(axes.size)]
            jac[p, axes, np.arange(axes.size)] = 1.0
    return NodeKinematics(x=x, jac=jac, hess=hess, index=coords.node_index)


def positions(coords: Coordinates, q: np.ndarray) -> np.ndarray:
    """Node positions (m), shape (n_nodes, 3), at generalized coordinates ``q``."""
    return kinematics(coords, q).x
