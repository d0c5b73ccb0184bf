"""Tensegrity structures as pure, validated data.

A :class:`Structure` lists nodes, rigid struts, tendons, fixed nodes, one load
and one probe. It knows nothing about equilibrium or dynamics; the later
stages (:mod:`tenscell.model.coordinates`, :mod:`tenscell.model.equilibrium`, ...) read it.

Conventions
-----------
* Lengths in metres, forces in newtons.
* A strut is an ordered node pair ``(tail, head)``; its direction is
  ``u = (x_head - x_tail) / L``. If the tail is a fixed node the strut is
  *anchored* by a frictionless ball joint there; a strut with neither end
  fixed is *free*. A node belongs to at most one strut.
* A node that is neither fixed nor on a strut is a *point node* (three
  translational coordinates, no mass).
* Load and probe are :class:`Point` objects: a weighted average of node
  positions (e.g. the centre of a rigid strut is ``0.5*tail + 0.5*head``) and
  a unit direction. The load is a force along that direction; the probe
  measures the displacement of its point along its direction.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Point", "Structure", "StructureError", "ACTIN", "INTERMEDIATE_FILAMENT", "STRUT"]

ACTIN = "actin"
INTERMEDIATE_FILAMENT = "intermediate_filament"
STRUT = "strut"  # an elastic (non-rigid) compression member listed among the members


class StructureError(ValueError):
    """A structure that is not well formed; the message names the element."""


def _as_readonly(a, dtype=float) -> np.ndarray:
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class Point:
    """A point of the structure where a force acts or a displacement is read.

    Parameters
    ----------
    nodes : tuple of int
        Node indices whose weighted average is the point.
    weights : tuple of float
        Weights, summing to one (dimensionless).
    direction : tuple of 3 floats
        Unit vector of the force (load) or of the measured displacement (probe).
    """

    nodes: tuple[int, ...]
    weights: tuple[float, ...]
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self):
        object.__setattr__(self, "nodes", tuple(int(n) for n in self.nodes))
        object.__setattr__(self, "weights", tuple(float(w) for w in self.weights))
        object.__setattr__(self, "direction", tuple(float(d) for d in self.direction))
        if len(self.nodes) == 0 or len(self.nodes) != len(self.weights):
            raise StructureError("a point needs as many weights as nodes, and at least one node")
        if abs(sum(self.weights) - 1.0) > 1e-12:
            raise StructureError(f"point weights must sum to 1, got {sum(self.weights)!r}")
        d = np.asarray(self.direction)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or abs(np.linalg.norm(d) - 1) > 1e-12:
            raise StructureError(f"point direction must be a unit 3-vector, got {self.direction!r}")


@dataclass(frozen=True, eq=False, repr=False)
class Structure:
    """A tensegrity structure in its reference configuration.

    Parameters
    ----------
    nodes : array_like, shape (n_nodes, 3)
        Reference node positions (m).
    struts : sequence of (int, int)
        Rigid struts as ``(tail, head)`` node pairs; an anchored strut has its
        fixed node as the tail.
    tendons : sequence of (int, int)
        Working tendons (members whose tension enters the equations) as node pairs.
    families : sequence of str
        One family per tendon, e.g. ``"actin"``, ``"intermediate_filament"``;
        ``"strut"`` marks an elastic compression member, which may carry a
        negative force in the self-stress.
    fixed : sequence of int
        Fixed nodes (ball-joint anchors, supports).
    load, probe : Point
        Where the input force acts and where the output displacement is read.
    equal_tension_groups : tuple of tuple of int
        Groups of tendons required to carry equal tension in the self-stress
        (how the paper singles out its "isotropic" state).
    name : str
        A human-readable name.
    """

    nodes: np.ndarray
    struts: tuple[tuple[int, int], ...]
    tendons: tuple[tuple[int, int], ...]
    families: tuple[str, ...]
    fixed: tuple[int, ...]
    load: Point
    probe: Point
    equal_tension_groups: tuple[tuple[int, ...], ...] = ()
    name: str = "structure"
    node_names: tuple[str, ...] = field(default=())

    def __post_init__(self):
        nodes = np.array(self.nodes, dtype=float)
        if nodes.ndim != 2 or nodes.shape[1] != 3 or nodes.shape[0] == 0:
            raise StructureError(f"nodes must have shape (n, 3), got {nodes.shape}")
        if not np.all(np.isfinite(nodes)):
            bad = int(np.argwhere(~np.isfinite(nodes))[0, 0])
            raise StructureError(f"node {bad} has a non-finite coordinate")
        nodes.setflags(write=False)
        object.__setattr__(self, "nodes", nodes)
        n = nodes.shape[0]
        struts = tuple((int(a), int(b)) for a, b in self.struts)
        tendons = tuple((int(a), int(b)) for a, b in self.tendons)
        families = tuple(str(f) for f in self.families)
        fixed = tuple(sorted({int(i) for i in self.fixed}))
        object.__setattr__(self, "struts", struts)
        object.__setattr__(self, "tendons", tendons)
        object.__setattr__(self, "families", families)
        object.__setattr__(self, "fixed", fixed)
        object.__setattr__(
            self, "equal_tension_groups", tuple(tuple(int(j) for j in g) for g in self.equal_tension_groups)
        )
        if self.node_names and len(self.node_names) != n:
            raise StructureError(f"{len(self.node_names)} node names for {n} nodes")
        object.__setattr__(self, "node_names", tuple(str(s) for s in self.node_names))

        def check_node(i, what):
            if not 0 <= i < n:
                raise StructureError(f"{what} refers to unknown node {i} (there are {n} nodes)")

        def check_member(what, a, b):
            check_node(a, what)
            check_node(b, what)
            if a == b:
                raise StructureError(f"{what} joins node {a} to itself")
            if np.linalg.norm(nodes[a] - nodes[b]) <= 0:
                raise StructureError(f"{what} has zero length")

        for i in fixed:
            check_node(i, "fixed list")
        fixed_set = set(fixed)
        owner: dict[int, int] = {}
        for k, (a, b) in enumerate(struts):
            check_member(f"strut {k}", a, b)
            if b in fixed_set:
                raise StructureError(
                    f"strut {k}: its head node {b} is fixed; put the anchored (fixed) node first"
                )
            for end in (a, b):
                if end in owner and end not in fixed_set:
                    raise StructureError(f"node {end} belongs to struts {owner[end]} and {k}")
                owner[end] = k
        if len(families) != len(tendons):
            raise StructureError(f"{len(families)} families for {len(tendons)} tendons")
        seen: dict[frozenset, int] = {}
        for j, (a, b) in enumerate(tendons):
            check_member(f"tendon {j}", a, b)
            key = frozenset((a, b))
            if key in seen:
                raise StructureError(f"tendon {j} duplicates tendon {seen[key]} (nodes {a}-{b})")
            seen[key] = j
            if a in fixed_set and b in fixed_set:
                raise StructureError(f"tendon {j} joins two fixed nodes and cannot work; leave it out")
        for g in self.equal_tension_groups:
            for j in g:
                if not 0 <= j < len(tendons):
                    raise StructureError(f"equal-tension group refers to unknown tendon {j}")
        for what, p in (("load", self.load), ("probe", self.probe)):
            if not isinstance(p, Point):
                raise StructureError(f"{what} must be a Point")
            for i in p.nodes:
                check_node(i, what)
            if all(i in fixed_set for i in p.nodes):
                raise StructureError(f"the {what} acts on fixed node(s) {list(p.nodes)}; it must move")

    # ---- derived, read-only views -------------------------------------------------
    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return self.nodes.shape[0]

    @property
    def n_tendons(self) -> int:
        """Number of working tendons (members)."""
        return len(self.tendons)

    @property
    def strut_lengths(self) -> np.ndarray:
        """Strut lengths at the reference (m), shape (n_struts,)."""
        if not self.struts:
            return np.zeros(0)
        s = np.asarray(self.struts)
        return np.linalg.norm(self.nodes[s[:, 1]] - self.nodes[s[:, 0]], axis=1)

    def is_anchored(self, k: int) -> bool:
        """Whether strut ``k`` is anchored by a ball joint at its tail."""
        return self.struts[k][0] in self.fixed

    @property
    def point_nodes(self) -> tuple[int, ...]:
        """Nodes that are neither fixed nor on a strut, in index order."""
        on_strut = {i for s in self.struts for i in s}
        fixed = set(self.fixed)
        return tuple(i for i in range(self.n_nodes) if i not in on_strut and i not in fixed)

    def family_indices(self, family: str) -> np.ndarray:
        """Indices of the tendons of one family."""
        return np.array([j for j, f in enumerate(self.families) if f == family], dtype=int)

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from .._results import counts, format_repr

        def at(p: Point) -> str:
            where = f"node {p.nodes[0]}" if len(p.nodes) == 1 else f"{len(p.nodes)} nodes"
            return f"{where} along ({', '.join(f'{d:.3g}' for d in p.direction)})"

        return format_repr(
            f"Structure {self.name!r}",
            f"{self.n_nodes} nodes ({len(self.fixed)} fixed), {len(self.struts)} rigid struts, "
            f"{self.n_tendons} tendons ({counts(self.families) or 'none'})",
            f"load at {at(self.load)}; probe at {at(self.probe)}",
        )

    def to_dataframe(self, members: str = "tendons", **columns):
        """One row per tendon (default), per rigid strut, or per node, with lengths and positions in m.

        Parameters
        ----------
        members : {"tendons", "struts", "nodes"}
        **columns : array_like, one value per row
            Extra columns (unit-named, e.g. ``EA_N=...``) appended or replacing
            these; results built on a structure use this for their own tables.

        Returns
        -------
        pandas.DataFrame
            tendons: ``tendon, family, node_a, node_b, length_m``;
            struts: ``strut, node_a, node_b, length_m, anchored``;
            nodes: ``node, name, x_m, y_m, z_m, fixed``.
        """
        from .._results import dataframe

        cols: dict
        if members == "nodes":
            names = self.node_names or tuple(str(i) for i in range(self.n_nodes))
            fixed = set(self.fixed)
            cols = {"node": np.arange(self.n_nodes), "name": names, "x_m": self.nodes[:, 0],
                    "y_m": self.nodes[:, 1], "z_m": self.nodes[:, 2], "fixed": [i in fixed for i in range(self.n_nodes)]}
        elif members in ("tendons", "struts"):
            pairs = np.asarray(self.tendons if members == "tendons" else self.struts, dtype=int).reshape(-1, 2)
            cols = {members[:-1]: np.arange(len(pairs))}
            if members == "tendons":
                cols["family"] = list(self.families)
            cols.update(node_a=pairs[:, 0], node_b=pairs[:, 1],
                        length_m=np.linalg.norm(self.nodes[pairs[:, 1]] - self.nodes[pairs[:, 0]], axis=1))
            if members == "struts":
                cols["anchored"] = [self.is_anchored(k) for k in range(len(pairs))]
        else:
            raise ValueError(f"members: expected 'tendons', 'struts' or 'nodes', got {members!r}")
        return dataframe({**cols, **columns}, {"structure": self.name})

    def plot(self, ax=None, **kw):
        """The structure in 3D, coloured as the paper's Fig. 1 (:func:`tenscell.plotting.structure_3d`)."""
        from ..plotting import structure_3d

        return structure_3d(self, ax=ax, **kw)
