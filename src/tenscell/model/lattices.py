"""Larger built-in cells: spherical tensegrities of 6, 12 and 30 struts, and multi-module lattices.

Spherical tensegrities (:func:`sphere_cell`)
--------------------------------------------
One family contains the paper's 6-strut "expanded octahedron" and its 12-
and 30-strut relatives. It is built from a rectified polyhedron ``P`` (the
octahedron, cuboctahedron or icosidodecahedron; every vertex has degree 4):

* each edge of ``P`` is a node (at the edge midpoint, for the rough shape);
* each vertex of ``P`` is a rigid strut joining two of its four edges that
  lie opposite each other around it; the choice is made so that every edge
  belongs to exactly one strut (there are exactly two such choices, mirror
  images; the first is taken);
* each face of ``P`` is a closed polygon of actin cables through the nodes
  of its edges (8 triangles for 6 struts; 8 triangles + 6 squares for 12;
  20 triangles + 12 pentagons for 30), so every node has four cables;
* one intermediate filament from every node to a nucleus (point) node.

The rough shape is then form-found (:func:`tenscell.model.formfinding.find_form`)
with actin force density 1 N/m and rest length ``0.1·L`` and intermediate
filament force density ``if_force_density`` (default 0.2 N/m), which gives
a stable prestressable configuration with every tendon in tension. Finally,
as in the paper, the three nodes of one actin triangle are fixed (ball
joints of three anchored struts), that triangle's three cables are dropped,
and the structure is turned so that the base lies in z = 0 with the cell
above it. (For 6 and 12 struts the triangles are faces of the convex hull,
so every node lies at z ≥ 0; the 30-strut sphere's triangles are slightly
dented, and a few nodes reach 0.035·L below the base plane.) The self-stress is the form-found one. Load and probe: vertical,
at the centre of the strut whose centre is highest.

Multi-module lattices (:func:`lattice_cell`)
--------------------------------------------
Copies of the 6-strut module (struts parallel to x, y, z at offsets ±b from
the module centre, 24 actin cables, optionally 12 intermediate filaments to
a module-centre node) on a cubic grid of spacing L (the strut length). The
end nodes of collinear struts of neighbouring modules coincide, so modules
share nodes across every common face: an ``nx × ny × 1`` lattice is a 2D
sheet, ``nx × ny × nz`` a 3D block.

A node shared by two modules ends two struts, which the rigid-strut
coordinates do not allow (a node belongs to at most one rigid strut), so
lattices use the node-based formulation: every node is a point node with
three coordinates, and each strut is an elastic member of family
``"strut"`` (it carries a negative force in the self-stress; give it a
large EA in :func:`tenscell.linearize`). The self-stress is assembled from
the modules': each module's symmetric self-stress (equal actin tensions,
equal strut compressions, equal IF tensions) is in equilibrium at each of
its nodes by itself, so their sum is a self-stress of the lattice, with
every cable in tension, at no cost (no SVD of the lattice's equilibrium
matrix). The regular module (``b = L/4``) has zero IF tension, as the
paper's regular member does; ``b < L/4`` puts the IFs in tension (default
``b = 0.21·L``). The bottom nodes of the bottom layer are fixed (the
substrate). Load and probe: vertical, at the centre of the upper x-strut of
the top module nearest the middle of the top face.
"""
from __future__ import annotations

import itertools
import math

import numpy as np
import scipy.linalg

from .._checks import positive_scalar
from .equilibrium import Cell, NotPrestressableError, equilibrate
from .formfinding import find_form
from .structure import ACTIN, INTERMEDIATE_FILAMENT, STRUT, Point, Structure, first_occurrence

__all__ = [
    "sphere_structure",
    "sphere_cell",
    "lattice_structure",
    "lattice_cell",
    "lattice_module_tensions",
    "expanded_octahedron",
    "SPHERE_STRUTS",
    "DEFAULT_OFFSET",
    "LATTICE_STRUT_EA",
]

#: numbers of struts of the built-in spherical tensegrities
SPHERE_STRUTS = (6, 12, 30)
#: default strut offset b/L of the lattice module (IFs in tension for b < 1/4)
DEFAULT_OFFSET = 0.21
#: suggested EA (N) of the lattices' elastic struts: stiff next to tendons of EA = 1 N, and well above the
#: strut compression P·|T0| at the paper's prestresses, so the struts' axial stiffness (EA + P·T0)/l stays positive
LATTICE_STRUT_EA = 1e3

_PHI = (1.0 + math.sqrt(5.0)) / 2.0


# ---- spherical tensegrities ---------------------------------------------------------
def _rectified(n_struts: int) -> np.ndarray:
    def cyclic(v):
        x, y, z = v
        return [(x, y, z), (y, z, x), (z, x, y)]

    def signs(v):
        return {tuple(s * c for s, c in zip(sg, v)) for sg in itertools.product((-1.0, 1.0), repeat=3)}

    pts: set = set()
    seeds = {6: [(1.0, 0.0, 0.0)], 12: [(1.0, 1.0, 0.0)],
             30: [(0.0, 0.0, _PHI), (0.5, _PHI / 2, _PHI ** 2 / 2)]}[n_struts]
    for seed in seeds:
        for v in cyclic(seed):
            pts |= signs(v)
    return np.array(sorted(pts))


def _faces(P: np.ndarray) -> list[list[int]]:
    """Faces of a convex polyhedron as vertex cycles (coplanar hull triangles merged)."""
    from scipy.spatial import ConvexHull  # only sphere cells need it: not on every command's import path

    hull = ConvexHull(P)
    groups: dict = {}
    for simplex, eq in zip(hull.simplices, np.round(hull.equations, 9)):
        groups.setdefault(tuple(eq), set()).update(int(v) for v in simplex)
    faces = []
    for eq, vs in sorted(groups.items()):
        vs = sorted(vs)
        n = np.array(eq[:3])
        c = P[vs].mean(axis=0)
        e1 = P[vs[0]] - c
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        ang = [math.atan2((P[v] - c) @ e2, (P[v] - c) @ e1) for v in vs]
        faces.append([vs[i] for i in np.argsort(ang)])
    return faces


def _sphere_topology(n_struts: int):
    """Rough nodes, struts, actin cables and the actin triangles of the n-strut sphere."""
    P = _rectified(n_struts)
    faces = _faces(P)
    edges = sorted({tuple(sorted((f[i], f[(i + 1) % len(f)]))) for f in faces for i in range(len(f))})
    eidx = {e: i for i, e in enumerate(edges)}
    pairs = []
    for v in range(len(P)):
        nb = [u for e in edges if v in e for u in e if u != v]
        n = P[v] / np.linalg.norm(P[v])
        e1 = P[nb[0]] - P[v]
        e1 -= (e1 @ n) * n
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        nb = [nb[i] for i in np.argsort([math.atan2((P[u] - P[v]) @ e2, (P[u] - P[v]) @ e1) for u in nb])]
        es = [eidx[tuple(sorted((v, u)))] for u in nb]
        pairs.append(((es[0], es[2]), (es[1], es[3])))
    choice = _exact_cover(pairs, len(edges))
    X = np.array([(P[a] + P[b]) / 2 for a, b in edges])
    struts = [pairs[v][choice[v]] for v in range(len(P))]
    s = np.asarray(struts)
    X /= np.linalg.norm(X[s[:, 0]] - X[s[:, 1]], axis=1).mean()
    cables, triangles = [], []
    for f in faces:
        ring = [eidx[tuple(sorted((f[i], f[(i + 1) % len(f)])))] for i in range(len(f))]
        for i in range(len(ring)):
            a, b = ring[i], ring[(i + 1) % len(ring)]
            cables.append((min(a, b), max(a, b)))
        if len(ring) == 3:
            triangles.append(tuple(ring))
    return X, struts, cables, triangles


def _exact_cover(pairs, n_edges) -> list[int]:
    """For each vertex choose one of its two opposite-edge pairs so that every edge is chosen once."""
    choice: list[int] = []
    used = np.zeros(n_edges, dtype=bool)

    def search(v):
        if v == len(pairs):
            return True
        for c in (0, 1):
            a, b = pairs[v][c]
            if used[a] or used[b]:
                continue
            used[a] = used[b] = True
            choice.append(c)
            if search(v + 1):
                return True
            used[a] = used[b] = False
            choice.pop()
        return False

    if not search(0):  # pragma: no cover - the three polyhedra used all have solutions
        raise RuntimeError("no strut assignment")
    return choice


def sphere_structure(n_struts: int = 12, L: float = 1.0, if_force_density: float = 0.2,
                     intermediate_filaments: bool = True) -> tuple[Structure, np.ndarray]:
    """The anchored spherical tensegrity of ``n_struts`` struts and its self-stress.

    Parameters
    ----------
    n_struts : {6, 12, 30}
    L : float
        Strut length (m).
    if_force_density : float
        Force density of the intermediate filaments relative to actin's
        (dimensionless; actin has 1). Larger values pull the nodes further
        towards the nucleus.
    intermediate_filaments : bool
        Include the nucleus node and one IF per strut end.

    Returns
    -------
    structure : Structure
        Node 0..2·n_struts−1 are strut ends, the last node is the nucleus.
    T0 : ndarray, shape (m,)
        Its form-found self-stress (every tendon in tension; any scale).

    Raises
    ------
    ValueError
        For an unsupported ``n_struts`` or bad parameters.
    """
    if n_struts not in SPHERE_STRUTS:
        raise ValueError(f"n_struts must be one of {SPHERE_STRUTS}, got {n_struts!r}")
    L = positive_scalar("L", L, "m")
    wif = positive_scalar("if_force_density", if_force_density, "dimensionless, relative to actin")
    X, struts, cables, triangles = _sphere_topology(n_struts)
    tendons = list(cables)
    families = [ACTIN] * len(cables)
    nodes = X * L
    if intermediate_filaments:
        centre = len(X)
        nodes = np.vstack([nodes, np.zeros((1, 3))])
        tendons += [(i, centre) for i in range(len(X))]
        families += [INTERMEDIATE_FILAMENT] * len(X)
    top = int(np.argmax(nodes[np.asarray(struts)].mean(axis=1)[:, 2]))
    probe = Point(nodes=struts[top], weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    free = Structure(nodes=nodes, struts=tuple(struts), tendons=tuple(tendons), families=tuple(families),
                     fixed=(), load=probe, probe=probe, name=f"{n_struts}-strut sphere (free)")
    found = find_form(free, force_density={ACTIN: 1.0, INTERMEDIATE_FILAMENT: wif},
                      rest_length={ACTIN: 0.1 * L, INTERMEDIATE_FILAMENT: 0.0})
    if found.stable is False:  # pragma: no cover - checked for the built-in parameters by the tests
        raise NotPrestressableError(f"the {n_struts}-strut sphere with if_force_density={wif:g} is not stable")
    x = found.structure.nodes
    base = _base_triangle(x[: len(X)], triangles)
    c = x[list(base)].mean(axis=0)
    nrm = np.cross(x[base[1]] - x[base[0]], x[base[2]] - x[base[0]])
    nrm /= np.linalg.norm(nrm)
    if nrm @ (x.mean(axis=0) - c) < 0:
        nrm = -nrm
    Rm = _rotation_to_z(nrm)
    e1 = Rm @ (x[base[2]] - x[base[0]])  # b1 along A1 -> A3, as in the paper's frame
    Rz = _rotation_about_z(-math.atan2(e1[1], e1[0]))
    xr = (Rz @ Rm @ (x - c).T).T
    xr[list(base), 2] = 0.0
    keep = [j for j, (a, b) in enumerate(tendons) if not (a in base and b in base)]
    anchored = []
    for a, b in struts:
        anchored.append((b, a) if b in base else (a, b))
    top = int(np.argmax(xr[np.asarray(anchored)].mean(axis=1)[:, 2]))
    probe = Point(nodes=anchored[top], weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    st = Structure(
        nodes=xr, struts=tuple(anchored), tendons=tuple(tendons[j] for j in keep),
        families=tuple(families[j] for j in keep), fixed=tuple(base), load=probe, probe=probe,
        name=f"{n_struts}-strut sphere" + ("" if intermediate_filaments else " without intermediate filaments"),
    )
    return st, np.asarray(found.tensions)[keep]


def _base_triangle(x: np.ndarray, triangles) -> tuple[int, int, int]:
    """The actin triangle to anchor: the one with the fewest nodes reaching below its plane (first on ties)."""
    def dip(t):
        nrm = np.cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]])
        d = (x - x[t[0]]) @ (nrm / np.linalg.norm(nrm))
        d = d if d.mean() > 0 else -d
        return round(float(-d.min()), 9)

    return min(triangles, key=dip)


def _rotation_to_z(n: np.ndarray) -> np.ndarray:
    """Rotation taking the unit vector ``-n`` to ``-e_z`` (so ``n`` goes to ``+e_z``)."""
    z = np.array([0.0, 0.0, 1.0])
    v = np.cross(n, z)
    s, c = np.linalg.norm(v), float(n @ z)
    if s < 1e-15:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]]) / s
    ang = math.atan2(s, c)
    return np.eye(3) + math.sin(ang) * K + (1 - math.cos(ang)) * K @ K


def _rotation_about_z(t: float) -> np.ndarray:
    return np.array([[math.cos(t), -math.sin(t), 0.0], [math.sin(t), math.cos(t), 0.0], [0.0, 0.0, 1.0]])


def sphere_cell(n_struts: int = 12, L: float = 1.0, if_force_density: float = 0.2,
                intermediate_filaments: bool = True, parametrization: str = "local") -> Cell:
    """A spherical tensegrity cell with ``n_struts`` ∈ {6, 12, 30} rigid struts (see the module docstring).

    Parameters
    ----------
    n_struts : {6, 12, 30}
    L : float
        Strut length (m).
    if_force_density : float
        IF/actin force-density ratio used in form-finding (dimensionless).
    intermediate_filaments : bool
    parametrization : {"local", "angles"}

    Returns
    -------
    Cell
        Anchored at one actin triangle; ``T0`` the form-found self-stress,
        normalized over the cables.
    """
    st, T0 = sphere_structure(n_struts, L, if_force_density, intermediate_filaments)
    return equilibrate(st, parametrization, T0=T0,
                       parameters={"n_struts": n_struts, "L": L, "if_force_density": float(if_force_density)})


# ---- lattices -------------------------------------------------------------------------
def _module_nodes(L: float, b: float) -> np.ndarray:
    a = L / 2
    X = []
    for s1 in (-1, 1):  # z-struts at y = ±b
        for s2 in (-1, 1):
            X.append((0.0, s2 * b, s1 * a))
    for s1 in (-1, 1):  # x-struts at z = ±b
        for s2 in (-1, 1):
            X.append((s1 * a, 0.0, s2 * b))
    for s1 in (-1, 1):  # y-struts at x = ±b
        for s2 in (-1, 1):
            X.append((s2 * b, s1 * a, 0.0))
    return np.array(X)


def _module(L: float, b: float):
    """Node offsets (12, 3), struts, actin cables of the 6-strut module with strut offset b."""
    X = _module_nodes(L, b)
    struts = [(0, 2), (1, 3), (4, 6), (5, 7), (8, 10), (9, 11)]
    # the topology is the regular member's (b = L/4): its cables are the 24 edges of length sqrt(3/8)·L
    R = _module_nodes(L, L / 4)
    d = math.sqrt(3.0 / 8.0) * L
    cables = [(i, j) for i in range(12) for j in range(i + 1, 12) if abs(np.linalg.norm(R[i] - R[j]) - d) < 1e-9 * L]
    return X, struts, cables


def expanded_octahedron(L: float = 1.0, offset: float = 0.25) -> Structure:
    """The free-standing 6-strut "expanded octahedron" (tensegrity icosahedron) with rigid struts.

    Struts of length ``L`` (m) parallel to x, y and z in pairs at ±``offset``·L from the centre,
    24 actin cables (the edges of length √(3/8)·L of the regular member, ``offset = 0.25``), no
    fixed node (6 rigid-body motions), load and probe vertical at the centre of the x-strut at
    z = +offset·L. At ``offset = 0.25`` it is prestressable (one self-stress, cables equal,
    struts −√6 times a cable).
    """
    L = positive_scalar("L", L, "m")
    b = _offset(offset)
    X, struts, cables = _module(L, b * L)
    p = Point(nodes=(5, 7), weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    return Structure(nodes=X, struts=tuple(struts), tendons=tuple(cables), families=(ACTIN,) * len(cables),
                     fixed=(), load=p, probe=p, name="6-strut expanded octahedron (free-standing)")


def lattice_module_tensions(offset: float = DEFAULT_OFFSET, intermediate_filaments: bool = True) -> dict:
    """Member forces of one lattice module's symmetric self-stress (actin = 1).

    Parameters
    ----------
    offset : float
        Strut offset b/L (dimensionless), between 0.05 and 0.45.
    intermediate_filaments : bool

    Returns
    -------
    dict
        ``{"actin": 1.0, "strut": s (< 0), "intermediate_filament": t}``.

    Raises
    ------
    NotPrestressableError
        If the IFs are not in tension at this offset (b ≥ L/4), or without
        IFs if b ≠ L/4 (the module then has no self-stress).
    """
    b = _offset(offset)
    X, struts, cables = _module(1.0, b)
    members = cables + struts
    groups = [list(range(24)), list(range(24, 30))]
    if intermediate_filaments:
        X = np.vstack([X, np.zeros((1, 3))])
        members = members + [(i, 12) for i in range(12)]
        groups.append(list(range(30, 42)))
    A = np.zeros((3 * len(X), len(members)))
    for j, (p, q) in enumerate(members):
        e = (X[p] - X[q]) / np.linalg.norm(X[p] - X[q])
        A[3 * p:3 * p + 3, j] += e
        A[3 * q:3 * q + 3, j] -= e
    # member forces constant within each family: A·(G t) = 0 for the 2 or 3 family values t
    G = np.zeros((len(members), len(groups)))
    for k, g in enumerate(groups):
        G[g, k] = 1.0
    N = scipy.linalg.null_space(A @ G, rcond=1e-10)
    if N.shape[1] != 1:
        raise NotPrestressableError(
            f"the lattice module with offset b/L={b:g}"
            + ("" if intermediate_filaments else " and no intermediate filaments")
            + " has no symmetric self-stress" + ("" if intermediate_filaments else " (only b/L = 0.25 has one)")
        )
    t = N[:, 0] / N[0, 0]
    out = {ACTIN: 1.0, STRUT: float(t[1])}
    if intermediate_filaments:
        out[INTERMEDIATE_FILAMENT] = float(t[2])
        if t[2] <= 1e-12:
            raise NotPrestressableError(
                f"the lattice module with offset b/L={b:g} has intermediate filaments not in tension "
                f"(IF/actin = {t[2]:.3g}); use an offset below 0.25 (default {DEFAULT_OFFSET})"
            )
    return out


def _offset(offset) -> float:
    b = positive_scalar("offset", offset, "b/L, dimensionless")
    if not 0.05 <= b <= 0.45:
        raise ValueError(f"offset must lie between 0.05 and 0.45 (b/L, dimensionless), got {b!r}")
    return b


def lattice_structure(nx: int, ny: int, nz: int = 1, L: float = 1.0, offset: float = DEFAULT_OFFSET,
                      intermediate_filaments: bool = True) -> tuple[Structure, np.ndarray]:
    """A sheet (``nz = 1``) or block of 6-strut modules sharing nodes, and its self-stress.

    Parameters
    ----------
    nx, ny, nz : int
        Modules along x, y, z (≥ 1).
    L : float
        Strut length = grid spacing (m).
    offset : float
        Strut offset b/L of every module (dimensionless).
    intermediate_filaments : bool
        Give each module a centre node with 12 IFs (the default needs them
        for ``offset`` ≠ 0.25).

    Returns
    -------
    structure : Structure
        Point nodes only; struts are members of family ``"strut"``.
    T0 : ndarray, shape (m,)
        The assembled self-stress (actin 1 per module, struts negative).
    """
    dims = []
    for name, v in (("nx", nx), ("ny", ny), ("nz", nz)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a whole number >= 1, got {v!r}")
        dims.append(int(v))
    nx, ny, nz = dims
    L = positive_scalar("L", L, "m")
    b = _offset(offset)
    t = lattice_module_tensions(b, intermediate_filaments)
    Xm, struts, cables = _module(L, b * L)
    # every module's nodes in construction order (module by module, x fastest; its 12 nodes, then its centre)
    grid = np.array([(i, j, k) for k, j, i in itertools.product(range(nz), range(ny), range(nx))], dtype=float) * L
    local = np.vstack([Xm, np.zeros((1, 3))]) if intermediate_filaments else Xm
    pos = (grid[:, None, :] + local[None]).reshape(-1, 3)
    # node identity by position on the grid: module-node coordinates are multiples of L/2 plus 0 or ±b;
    # a node is numbered when it first appears
    key = np.rint(pos * (1e6 / L)).astype(np.int64)
    first = first_occurrence(key[:, 0], key[:, 1], key[:, 2])
    is_new = first == np.arange(first.size)
    ids = (np.cumsum(is_new) - 1)[first].reshape(len(grid), len(local))
    local_members = [(cables, ACTIN), (struts, STRUT)]
    if intermediate_filaments:
        local_members.append(([(p, 12) for p in range(12)], INTERMEDIATE_FILAMENT))
    pairs = np.array([pq for ms, _ in local_members for pq in ms])
    tendons = ids[:, pairs].reshape(-1, 2)
    families = tuple(f for ms, f in local_members for _ in ms) * len(grid)
    T0 = np.tile([t[f] for ms, f in local_members for _ in ms], len(grid))
    fixed = ids[: nx * ny, :2].ravel()  # the lower ends of the bottom modules' z-struts rest on the substrate
    top = ((nz - 1) * ny + ny // 2) * nx + nx // 2  # the top module nearest the middle of the top face
    load_nodes = (int(ids[top, 5]), int(ids[top, 7]))  # its upper x-strut (z = +b)
    load = Point(nodes=load_nodes, weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    kind = "sheet" if nz == 1 else "block"
    st = Structure(
        nodes=pos[is_new], struts=(), tendons=tendons, families=families, fixed=fixed,
        load=load, probe=load, name=f"{nx}x{ny}x{nz} lattice {kind}",
    )
    return st, T0


def lattice_cell(nx: int, ny: int, nz: int = 1, L: float = 1.0, offset: float = DEFAULT_OFFSET,
                 intermediate_filaments: bool = True) -> Cell:
    """A lattice of 6-strut modules (see the module docstring) at its assembled self-stress.

    ``self_stress_dim`` is not computed for sparse-sized lattices (it would
    need the rank of the full equilibrium matrix) and is then -1.

    Examples
    --------
    >>> cell = lattice_cell(4, 4, 1)                     # a 2D sheet of 16 modules  # doctest: +SKIP
    >>> EA = member_values(cell.structure, {"strut": 1e3, "default": 1.0})  # doctest: +SKIP
    >>> lin = linearize(cell, P=1000.0, EA=EA, c=1.0)     # doctest: +SKIP
    """
    st, T0 = lattice_structure(nx, ny, nz, L, offset, intermediate_filaments)
    return equilibrate(st, "local", T0=T0, parameters={"nx": nx, "ny": ny, "nz": nz, "L": L, "offset": float(offset)})
