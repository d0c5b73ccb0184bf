"""Networks of plain members for the structural power-law study (issue 34).

Three families of structures, each a pure function of a frozen specification, each giving a prestressable
:class:`~tenscell.model.equilibrium.Cell` of point nodes (every member a cable, no struts but the anchors):

* :class:`DilutedNet` → :func:`diluted_net`: a **diluted prestressed cable network near its rigidity
  threshold**. The nearest-neighbour bonds of a face-centred cubic lattice in a cube, its surface nodes anchored
  (the substrate and the rest of the cell that hold the network in tension, as the paper's anchored struts hold
  its cables), bonds removed at random (never below three cables at a free node) until the network has
  ``connectivity`` = 2·(cables)/(free nodes) — 6 is the isostatic point of central-force networks in three
  dimensions (Maxwell's count: as many cables as free coordinates), 12 the full lattice. Its shape is
  form-found by the force-density method (:func:`force_density_shape`, force density 1 on every cable), so every cable is in tension and ``A·T0 = 0`` by construction. Below 6 the cables alone leave
  floppy modes, which only the prestress holds (``P·Kp`` is the force-density Laplacian, positive definite
  with the anchors).
* :class:`SimplexNet` → :func:`simplex_net`: a **hierarchical (self-similar) planar cable net**, modules made
  of modules: the level-1 module is ``module_nodes`` nodes joined pairwise by cables (a triangle, a
  tetrahedron's six edges, ...); the level-(n+1) module is ``module_nodes`` level-n modules, each two sharing
  one corner node (the Sierpiński gasket for 3 nodes, the Sierpiński tetrahedron's graph for 4; Hilfer and
  Blumen's simplex fractals). Its ``module_nodes`` outer corners are anchored on a circle in the plane z = 0
  and the net is form-found there (force density 1), and every free node is tied to two anchors straight
  above and below it by **tethers** (family ``"tether"``: the soft, damped links to the rest of the cell that
  the Voigt law turns into dashpots), whose tensions balance. The probe pulls a node out of the plane: the
  restoring spring of that motion is the prestress itself (``P·Kp`` is, in z, ``P·q`` times the graph
  Laplacian of the net), and the tethers are its only damping, so the out-of-plane compliance is the local
  resolvent of diffusion on the net, a power law ``J ∝ (iω)^(d_s/2 − 1)`` between the net's slowest and
  fastest rates, with ``d_s = 2 ln(module_nodes)/ln(module_nodes + 2)`` its spectral dimension: the exponent
  of ``G'`` is ``α = 1 − d_s/2`` (0.317 for 3 nodes, 0.226 for 4, 0.173 for 5), set by the topology alone.
* member time constants set by the structure (:func:`damping_by_length`, :func:`damping_by_tension`): the
  damping of each member of any cell follows from its own length (``c ∝ l^k``: a rod dragged through the
  cytoplasm has k = 1) or from the force it carries (Bell's law: a crosslinked filament's friction ∝ the
  lifetime of its bonds, ``exp(−T/F)``), so the spread of time constants is the structure's spread of lengths
  or tensions, nothing drawn from a distribution.

Everything here is geometry and self-stress; the laws (Voigt, Maxwell, standard linear solid) and the moduli
come later in the pipeline (:mod:`tenscell.studies.powerlaw`).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .._checks import positive_scalar
from .equilibrium import Cell, equilibrate
from .formfinding import FormFindingError, _lm_step
from .structure import ACTIN, Point, Structure, cable_mask

__all__ = [
    "TETHER",
    "ISOSTATIC_CONNECTIVITY",
    "DilutedNet",
    "SimplexNet",
    "diluted_net",
    "diluted_net_structure",
    "simplex_net",
    "simplex_net_structure",
    "simplex_exponent",
    "free_connectivity",
    "force_density_shape",
    "damping_by_length",
    "damping_by_tension",
]

#: family of the simplex nets' tethers: cables (tension only) whose Voigt law makes them the net's dashpots
TETHER = "tether"
#: 2·(cables)/(free nodes) at which a central-force network in three dimensions is isostatic (Maxwell)
ISOSTATIC_CONNECTIVITY = 6.0
#: the fewest cables a free node of a diluted net keeps (fewer would let the form-finding fold it onto a line)
MIN_CABLES_PER_NODE = 3


def force_density_shape(nodes: np.ndarray, cables: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """The force-density method for a cable net (Schek 1974), force density 1 on every cable: the free nodes sit
    where ``Σ_j (x_other − x_node) = 0`` with the ``fixed`` nodes held, a linear solve of the net's graph Laplacian
    (m). Every cable then carries ``T = l`` (N) and ``A·T = 0``: the net is prestressable by construction, the
    minimum of ``½ Σ l²`` that :func:`tenscell.model.formfinding.find_form` would reach by Newton steps.

    Parameters
    ----------
    nodes : ndarray, shape (n, 3)
        Positions (m); only the fixed nodes' are used.
    cables : ndarray of int, shape (m, 2)
    fixed : ndarray of bool, shape (n,)

    Raises
    ------
    FormFindingError
        If a cable comes out of zero length (two joined nodes with the same other neighbours).
    """
    n = len(nodes)
    a, b = cables[:, 0], cables[:, 1]
    one = np.ones(len(cables))
    L = sp.coo_matrix((np.r_[one, one, -one, -one], (np.r_[a, b, a, b], np.r_[a, b, b, a])), shape=(n, n)).tocsr()
    free = np.flatnonzero(~fixed)
    held = np.flatnonzero(fixed)
    x = np.array(nodes, dtype=float)
    # the Newton step of form-finding's own solver from x = 0: exact, the energy being quadratic
    x[free] = _lm_step(L[free][:, free].tocsc(), np.ones(free.size), L[free][:, held] @ x[held], 0.0)
    l = np.linalg.norm(x[a] - x[b], axis=1)
    if not l.min() > 1e-9 * l.max():
        j = int(np.argmin(l))
        raise FormFindingError(f"the force-density shape puts cable {j} ({a[j]}-{b[j]}) at zero length: its two "
                               "nodes have the same other neighbours")
    return x


def _whole(name: str, value, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise ValueError(f"{name} must be a whole number from {low} to {high}, got {value!r}")
    return int(value)


# ---- (a) diluted prestressed networks --------------------------------------------------------------------
@dataclass(frozen=True)
class DilutedNet:
    """A diluted face-centred cubic cable network, anchored at its surface (see the module docstring).

    Attributes
    ----------
    size : int
        Cubic unit cells along each side of the box (2 to 24; ``size = 8`` has about 1,500 free nodes).
    connectivity : float
        Target 2·(cables)/(free nodes), dimensionless (3.5 to 12): 6 is isostatic. Bonds are removed at
        random until the network reaches it or no bond can go without leaving a free node with fewer than
        three cables; the cell records the value reached (``cell.parameters["connectivity"]``).
    seed : int
        Seed of the order in which bonds are removed (the structure is a pure function of the spec).
    span : float
        Side of the box (m).
    """

    size: int = 6
    connectivity: float = ISOSTATIC_CONNECTIVITY
    seed: int = 0
    span: float = 1.0

    def __post_init__(self):
        _whole("size", self.size, 2, 24)
        z = positive_scalar("connectivity", self.connectivity, "cables per free node, dimensionless")
        if not 3.5 <= z <= 12.0:
            raise ValueError(f"connectivity must lie between 3.5 and 12 (2·cables/free nodes), got {z!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed must be a whole number >= 0, got {self.seed!r}")
        positive_scalar("span", self.span, "m")


def _fcc(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Integer sites (in half lattice constants) of the FCC lattice in [0, 2·size]³ and its nearest-neighbour
    bonds, shape (k, 2)."""
    r = np.arange(2 * size + 1)
    g = np.array(np.meshgrid(r, r, r, indexing="ij")).reshape(3, -1).T
    sites = g[g.sum(axis=1) % 2 == 0]  # FCC: even coordinate sums on the half-constant grid
    index = {tuple(s): i for i, s in enumerate(sites.tolist())}
    steps = [d for d in itertools.product((-1, 0, 1), repeat=3) if sum(map(abs, d)) == 2 and d > (0, 0, 0)]
    bonds = [(i, index[t]) for i, s in enumerate(sites.tolist()) for d in steps
             if (t := (s[0] + d[0], s[1] + d[1], s[2] + d[2])) in index]
    return sites, np.array(bonds, dtype=np.int64)


def _dilute(bonds: np.ndarray, free: np.ndarray, target: float, rng: np.random.Generator) -> np.ndarray:
    """Which bonds to keep: removed in random order while 2·(bonds)/(free nodes) exceeds ``target``, never taking
    a free node below :data:`MIN_CABLES_PER_NODE` cables and never making two joined free nodes twins (the same
    other neighbours), which the force-density shape would put at one point (a cable of zero length)."""
    n_free = int(free.sum())
    near: list[set[int]] = [set() for _ in range(free.size)]
    for a, b in bonds.tolist():
        near[a].add(b)
        near[b].add(a)
    keep = np.ones(len(bonds), dtype=bool)
    m = len(bonds)

    def twins_after(a: int, b: int) -> bool:
        rest = near[a] - {b}
        return free[a] and any(free[u] and len(near[u]) == len(rest) and rest - {u} == near[u] - {a} for u in rest)

    for j in rng.permutation(len(bonds)).tolist():
        if 2.0 * m / n_free <= target:
            break
        a, b = (int(v) for v in bonds[j])
        if (free[a] and len(near[a]) <= MIN_CABLES_PER_NODE) or (free[b] and len(near[b]) <= MIN_CABLES_PER_NODE):
            continue
        if twins_after(a, b) or twins_after(b, a):
            continue
        keep[j] = False
        near[a].discard(b)
        near[b].discard(a)
        m -= 1
    return keep


def _anchored_part(bonds: np.ndarray, anchored: np.ndarray) -> np.ndarray:
    """Which nodes belong to a connected part of the bond graph that contains an anchored node."""
    n = anchored.size
    adj = sp.coo_matrix((np.ones(len(bonds)), (bonds[:, 0], bonds[:, 1])), shape=(n, n))
    _, label = connected_components(adj, directed=False)
    held = np.zeros(label.max() + 1, dtype=bool)
    held[label[anchored]] = True
    return held[label]


def free_connectivity(structure: Structure) -> float:
    """2·(members with a free end)/(free nodes) of a structure of point nodes (dimensionless): 6 is isostatic in 3D."""
    fixed = np.zeros(structure.n_nodes, dtype=bool)
    fixed[list(structure.fixed)] = True
    return 2.0 * structure.n_tendons / int((~fixed).sum())


def diluted_net_structure(spec: DilutedNet) -> tuple[Structure, np.ndarray]:
    """The form-found diluted network of ``spec`` and its self-stress (force density 1: ``T0 = l``, N).

    Raises
    ------
    tenscell.model.FormFindingError
        If a cable comes out of zero length (the dilution keeps twins apart, so it does not for these nets).
    """
    sites, bonds = _fcc(spec.size)
    surface = ((sites == 0) | (sites == 2 * spec.size)).any(axis=1)
    bonds = bonds[~surface[bonds].all(axis=1)]  # a bond between two anchors carries nothing the model sees
    keep = _dilute(bonds, ~surface, float(spec.connectivity), np.random.default_rng(int(spec.seed)))
    bonds = bonds[keep]
    used = np.zeros(len(sites), dtype=bool)
    used[bonds.ravel()] = True
    used &= _anchored_part(bonds, surface)
    bonds = bonds[used[bonds].all(axis=1)]
    number = np.cumsum(used) - 1
    nodes = sites[used] * (0.5 * spec.span / spec.size)
    anchored = surface[used]
    bonds = number[bonds]
    centre = np.full(3, 0.5 * spec.span)
    free = np.flatnonzero(~anchored)
    probe_node = int(free[np.argmin(np.linalg.norm(nodes[free] - centre, axis=1))])
    probe = Point(nodes=(probe_node,), weights=(1.0,), direction=(0.0, 0.0, 1.0))
    x = force_density_shape(nodes, bonds, anchored)
    st = Structure(nodes=x, struts=(), tendons=bonds, families=(ACTIN,) * len(bonds),
                   fixed=tuple(np.flatnonzero(anchored).tolist()), load=probe, probe=probe,
                   name=f"diluted FCC net {spec.size}³")
    return st, np.linalg.norm(x[bonds[:, 0]] - x[bonds[:, 1]], axis=1)


def diluted_net(spec: DilutedNet) -> Cell:
    """The diluted network of ``spec`` at its form-found self-stress (see :class:`DilutedNet`).

    ``cell.parameters`` records ``size``, ``seed``, the ``connectivity`` reached and ``L`` (the box side, m: the
    length of the equivalent-continuum factor 0.5/L).
    """
    st, T0 = diluted_net_structure(spec)
    z = free_connectivity(st)
    return equilibrate(st, "local", T0=T0, parameters={"size": int(spec.size), "connectivity": round(z, 4),
                                                        "seed": int(spec.seed), "L": float(spec.span)})


# ---- (b) hierarchical simplex nets -----------------------------------------------------------------------
@dataclass(frozen=True)
class SimplexNet:
    """A self-similar planar cable net of modules made of modules, with tethers (see the module docstring).

    Attributes
    ----------
    module_nodes : int
        Nodes of the level-1 module, joined pairwise by cables (3: triangles, the Sierpiński gasket; 4: the
        Sierpiński tetrahedron's graph; up to 6).
    depth : int
        Levels of the hierarchy (1: one module). The net has about ``module_nodes**depth`` modules.
    span : float
        Radius of the circle on which the outer corners are anchored (m).
    tether_length : float
        Length of each tether, relative to ``span`` (dimensionless).
    tether_tension : float
        Force density of the tethers relative to the cables' (dimensionless, > 0: a tether is a cable). Their
        prestress adds ``2·P·q·tether_tension`` to every node's out-of-plane stiffness, a floor under the net's
        rates; the default puts it below what any depth up to 8 resolves.
    """

    module_nodes: int = 4
    depth: int = 5
    span: float = 1.0
    tether_length: float = 0.5
    tether_tension: float = 1e-6

    def __post_init__(self):
        _whole("module_nodes", self.module_nodes, 3, 6)
        _whole("depth", self.depth, 1, 9)
        positive_scalar("span", self.span, "m")
        positive_scalar("tether_length", self.tether_length, "relative to span")
        t = positive_scalar("tether_tension", self.tether_tension, "relative to the cables' force density")
        if t > 1.0:
            raise ValueError(f"tether_tension must be at most 1 (relative to the cables' force density), got {t!r}")
        if self.module_nodes ** self.depth > 5e5:
            raise ValueError(f"a simplex net of {self.module_nodes}-node modules and depth {self.depth} has "
                             f"{self.module_nodes ** self.depth:,} modules; at most 500,000")


def simplex_exponent(module_nodes: int) -> float:
    """``α = 1 − d_s/2`` of the infinite simplex net, ``d_s = 2 ln(k)/ln(k + 2)`` for modules of ``k`` nodes
    (Hilfer and Blumen 1984; dimensionless)."""
    k = _whole("module_nodes", module_nodes, 3, 64)
    return 1.0 - math.log(k) / math.log(k + 2)


def _simplex_graph(k: int, depth: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes of the simplex net as integer barycentric vectors (k entries summing to 2**depth) and its cables."""
    S = 2 ** depth
    simplices = (np.eye(k, dtype=np.int64) * S)[None]  # (modules, corner, barycentric)
    for _ in range(depth):
        # module i of the next level: corner i of the parent and the midpoints of its edges from corner i
        simplices = ((simplices[:, :, None, :] + simplices[:, None, :, :]) // 2).reshape(-1, k, k)
    flat = simplices.reshape(-1, k)
    nodes, label = np.unique(flat, axis=0, return_inverse=True)
    label = label.reshape(-1, k)
    pairs = np.array(list(itertools.combinations(range(k), 2)))
    cables = np.sort(label[:, pairs].reshape(-1, 2), axis=1)  # modules share corners only: no cable repeats
    return nodes, cables


def simplex_net_structure(spec: SimplexNet) -> tuple[Structure, np.ndarray]:
    """The form-found simplex net of ``spec`` with its tethers, and its self-stress (N: force density 1 on the
    net's cables, ``tether_tension`` on the tethers)."""
    k, depth, R = int(spec.module_nodes), int(spec.depth), float(spec.span)
    bary, cables = _simplex_graph(k, depth)
    S = 2 ** depth
    corner_of = {int(np.argmax(b)): i for i, b in enumerate(bary) if b.max() == S}
    angle = 2 * np.pi * np.arange(k) / k
    ring = R * np.c_[np.cos(angle), np.sin(angle), np.zeros(k)]
    rough = (bary / S) @ ring  # the barycentric map onto the corner polygon (only the corners' positions are kept)
    corners = [corner_of[i] for i in range(k)]
    middle = np.zeros(k, dtype=np.int64)
    middle[:2] = S // 2  # the probe: the node midway between corners 0 and 1 (a node of the coarsest level)
    probe_node = int(np.flatnonzero((bary == middle).all(axis=1))[0])
    probe = Point(nodes=(probe_node,), weights=(1.0,), direction=(0.0, 0.0, 1.0))
    anchored = np.zeros(len(rough), dtype=bool)
    anchored[corners] = True
    x = force_density_shape(rough, cables, anchored)
    free = np.setdiff1d(np.arange(len(x)), corners)
    h = float(spec.tether_length) * R
    n, nf = len(x), len(free)
    nodes = np.vstack([x, x[free] + [0.0, 0.0, h], x[free] - [0.0, 0.0, h]])
    tethers = np.vstack([np.c_[free, n + np.arange(nf)], np.c_[free, n + nf + np.arange(nf)]])
    st = Structure(nodes=nodes, struts=(), tendons=cast(Any, np.vstack([cables, tethers])),
                   families=(ACTIN,) * len(cables) + (TETHER,) * (2 * nf),
                   fixed=tuple(corners) + tuple(range(n, n + 2 * nf)), load=probe, probe=probe,
                   name=f"simplex net of {k}-node modules, depth {depth}")
    T0 = np.r_[np.linalg.norm(x[cables[:, 0]] - x[cables[:, 1]], axis=1),
               np.full(2 * nf, float(spec.tether_tension) * h)]
    return st, T0


def simplex_net(spec: SimplexNet) -> Cell:
    """The simplex net of ``spec`` at its self-stress (see :class:`SimplexNet`); ``cell.parameters`` records
    ``module_nodes``, ``depth`` and ``L`` (= ``span``, m)."""
    st, T0 = simplex_net_structure(spec)
    return equilibrate(st, "local", T0=T0, parameters={"module_nodes": int(spec.module_nodes),
                                                        "depth": int(spec.depth), "L": float(spec.span)})


# ---- (c) member time constants set by the structure ------------------------------------------------------
def _reference(values: np.ndarray, cell: Cell) -> float:
    return float(np.mean(values[cable_mask(cell.structure.families)]))


def damping_by_length(cell: Cell, c: float, exponent: float) -> np.ndarray:
    """Each member's damping from its own length: ``c_j = c·(l_j/l̄)^k`` (N·s/m), l̄ the cables' mean length.

    With one EA the member's time constant ``c_j·l_j/EA`` goes as ``l^(k+1)``; a rod dragged through a viscous
    medium has ``k = 1``.

    Parameters
    ----------
    cell : Cell
    c : float
        Damping of a member of the mean cable length (N·s/m).
    exponent : float
        k, dimensionless (−4 to 8).
    """
    c = positive_scalar("c", c, "N·s/m")
    k = float(exponent)
    if not -4.0 <= k <= 8.0:
        raise ValueError(f"exponent must lie between -4 and 8 (dimensionless), got {exponent!r}")
    l = np.asarray(cell.lengths)
    return c * (l / _reference(l, cell)) ** k


def damping_by_tension(cell: Cell, c: float, P: float, force_scale: float) -> np.ndarray:
    """Each member's damping from the force it carries (Bell's law): ``c_j = c·exp(−(P·|T0_j| − T̄)/F)`` (N·s/m).

    A crosslinked filament's friction goes as the lifetime of its crosslinks, which force shortens as
    ``exp(−T/F)``; T̄ is the cables' mean force ``P·mean(T0)``, so a member at the mean force has ``c``. The
    spread of time constants is the structure's spread of forces, widened as P rises.

    Parameters
    ----------
    cell : Cell
    c : float
        Damping of a member at the mean cable force (N·s/m).
    P : float
        Prestress (N): member forces are ``P·T0``.
    force_scale : float
        F (N).
    """
    c = positive_scalar("c", c, "N·s/m")
    P = positive_scalar("P", P, "N")
    F = positive_scalar("force_scale", force_scale, "N")
    T = P * np.abs(np.asarray(cell.T0))
    x = -(T - _reference(T, cell)) / F
    if x.max() > 700:
        raise ValueError(f"force_scale={F:g} N makes the damping of the least loaded member overflow "
                         f"(exp({x.max():.0f})); use a larger force scale")
    return c * np.exp(x)
