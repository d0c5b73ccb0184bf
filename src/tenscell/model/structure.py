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
from functools import cached_property

import numpy as np

from .._errors import TenscellError

__all__ = ["Point", "Structure", "StructureError", "ACTIN", "INTERMEDIATE_FILAMENT", "STRUT", "NUCLEUS",
           "COMPRESSIBLE_FAMILIES", "cable_mask", "member_values"]

ACTIN = "actin"
INTERMEDIATE_FILAMENT = "intermediate_filament"
STRUT = "strut"  # an elastic (non-rigid) compression member listed among the members
NUCLEUS = "nucleus"  # a member of the nucleus body: elastic, may carry either sign of force (not a cable)
#: families whose members may carry compression in the self-stress (every other member is a cable: tension only)
COMPRESSIBLE_FAMILIES = frozenset({STRUT, NUCLEUS})


def cable_mask(families) -> np.ndarray:
    """Whether each member is a cable (tension only), shape (m,): its family is not in :data:`COMPRESSIBLE_FAMILIES`."""
    return np.array([f not in COMPRESSIBLE_FAMILIES for f in families], dtype=bool)


class StructureError(TenscellError, ValueError):
    """A structure that is not well formed; the message names the element."""


def _as_readonly(a, dtype=float) -> np.ndarray:
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


def _pairs(members) -> np.ndarray:
    """Node pairs as an int array of shape (k, 2); anything but an integer array goes through ``int()``."""
    arr = np.asarray(members)
    if arr.ndim == 2 and arr.shape[1] == 2 and arr.dtype.kind in "iu":
        return arr.astype(np.int64)
    return np.array([(int(a), int(b)) for a, b in members], dtype=np.int64).reshape(-1, 2)


def _first_flag(flags: np.ndarray) -> tuple[int, int] | None:
    """``(row, check)`` of the first True of a (rows, checks) table in row-major order, or None.

    The checks of one member are the columns in the order a member-by-member
    loop would make them, so this is the error that loop would raise first.
    """
    hit = np.flatnonzero(flags.ravel())
    return None if hit.size == 0 else divmod(int(hit[0]), flags.shape[1])


def first_occurrence(*keys: np.ndarray) -> np.ndarray:
    """For each row, the index of the first row with the same keys (its own index if it is the first).

    ``keys``: arrays of shape (k,) compared together (a row is the tuple of its keys). Internal to
    :mod:`tenscell.model`: duplicate members here, coinciding lattice nodes in :mod:`.lattices`.
    """
    order = np.lexsort(keys[::-1])  # stable: equal keys keep their original (ascending) order
    new = np.zeros(order.size, dtype=bool)
    new[:1] = True
    for key in keys:
        ks = key[order]
        new[1:] |= ks[1:] != ks[:-1]
    start = np.maximum.accumulate(np.where(new, np.arange(order.size), 0))
    first = np.empty_like(order)
    first[order] = order[start]
    return first


def _member_flags(nodes: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per member: tail unknown, head unknown, joins a node to itself, zero length (in this order)."""
    n = nodes.shape[0]
    unknown = (pairs < 0) | (pairs >= n)
    ends = np.clip(pairs, 0, n - 1)  # placeholders where unknown: those rows fail earlier
    d = nodes[ends[:, 0]] - nodes[ends[:, 1]]
    return unknown[:, 0], unknown[:, 1], pairs[:, 0] == pairs[:, 1], np.linalg.norm(d, axis=1) <= 0


def _unknown_node(what: str, i: int, n: int) -> str:
    return f"{what} refers to unknown node {i} (there are {n} nodes)"


def _member_message(what: str, check: int, a: int, b: int, n: int) -> str:
    if check < 2:
        return _unknown_node(what, (a, b)[check], n)
    return f"{what} joins node {a} to itself" if check == 2 else f"{what} has zero length"


def _fixed_ends(n: int, pairs: np.ndarray, fixed: tuple[int, ...]) -> np.ndarray:
    """Whether each end of each member is a fixed node (False for unknown nodes), shape (k, 2)."""
    is_fixed = np.zeros(n + 1, dtype=bool)  # the extra slot stands for every unknown node
    is_fixed[list(fixed)] = True
    return is_fixed[np.where((pairs >= 0) & (pairs < n), pairs, n)]


def _raise_first(what: str, nodes: np.ndarray, pairs: np.ndarray, extra: list, messages: list) -> None:
    """Raise the first failing check: each member's four checks of :func:`_member_flags`, then its ``extra``
    columns (bool, one per member), whose message is ``messages[c](i, a, b)`` for member i = (a, b)."""
    found = _first_flag(np.column_stack([*_member_flags(nodes, pairs), *extra]))
    if found is None:
        return
    i, check = found
    a, b = (int(v) for v in pairs[i])
    if check < 4:
        raise StructureError(_member_message(f"{what} {i}", check, a, b, nodes.shape[0]))
    raise StructureError(messages[check - 4](i, a, b))


def _check_struts(nodes: np.ndarray, S: np.ndarray, fixed: tuple[int, ...]) -> None:
    """Raise the first error of a strut-by-strut check (ends, length, head not fixed, one strut per node)."""
    fx = _fixed_ends(nodes.shape[0], S, fixed)
    ends = S.ravel()  # strut k's tail, then its head: the order the ends are claimed
    owner = first_occurrence(ends) // 2
    shared = ((owner != np.arange(ends.size) // 2) & ~fx.ravel()).reshape(-1, 2)
    _raise_first("strut", nodes, S, [fx[:, 1] & ~fx[:, 0], shared[:, 0], shared[:, 1]], [
        lambda k, a, b: f"strut {k}: its head node {b} is fixed; put the anchored (fixed) node first",
        lambda k, a, b: f"node {a} belongs to struts {owner[2 * k]} and {k}",
        lambda k, a, b: f"node {b} belongs to struts {owner[2 * k + 1]} and {k}",
    ])


def _check_tendons(nodes: np.ndarray, T: np.ndarray, fixed: tuple[int, ...]) -> None:
    """Raise the first error of a tendon-by-tendon check (ends, length, duplicates)."""
    first = first_occurrence(T.min(axis=1), T.max(axis=1))
    _raise_first("tendon", nodes, T, [first != np.arange(T.shape[0])], [
        lambda j, a, b: f"tendon {j} duplicates tendon {first[j]} (nodes {a}-{b})",
    ])


def _immovable(n: int, S: np.ndarray, T: np.ndarray, fixed: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Masks of the struts and tendons whose two ends are fixed nodes: they cannot move or work."""
    return np.asarray(_fixed_ends(n, S, fixed).all(axis=1)), np.asarray(_fixed_ends(n, T, fixed).all(axis=1))


def _check_supports(supports, n: int, fixed: set, S: np.ndarray) -> tuple[tuple[int, str], ...]:
    """Per-direction supports as sorted ``(node, axes)`` pairs, axes in x-y-z order; StructureError otherwise."""
    out: dict[int, str] = {}
    on_strut = set(S.ravel().tolist())
    for item in supports:
        node, axes = check_support(item, n, fixed, on_strut)
        if node in out:
            raise StructureError(f"supports: node {node} is listed twice")
        out[node] = axes
    return tuple(sorted(out.items()))


def check_support(item, n: int, fixed: set, on_strut: set) -> tuple[int, str]:
    """One support ``(node, axes)`` checked and normalized (axes in x-y-z order); StructureError otherwise.

    The rules shared by :class:`Structure` and structure files: a point node among ``n``, not fixed, not the
    end of a rigid strut (``on_strut``), held in one or two of the directions x, y, z, each named once.
    """
    try:
        node, axes = int(item[0]), str(item[1]).lower()
    except (TypeError, ValueError, IndexError):
        raise StructureError(f"supports: expected (node, axes) pairs such as (3, 'z'), got {item!r}") from None
    if not 0 <= node < n:
        raise StructureError(_unknown_node("supports", node, n))
    if not axes or set(axes) - set("xyz") or len(set(axes)) != len(axes):
        raise StructureError(f"supports: node {node}: axes {axes!r} must be some of 'x', 'y', 'z', each once")
    if len(axes) == 3 or node in fixed:
        raise StructureError(f"supports: node {node} is held in every direction; list it among the fixed nodes")
    if node in on_strut:
        # a strut end's position is a nonlinear function of the strut's coordinates (its angles): holding one
        # direction of it is a constraint on them, not a coordinate removed, which these coordinates cannot express
        raise StructureError(f"supports: node {node} is the end of a rigid strut; a strut end is held fully "
                             "(fixed) or not at all (use pin_jointed() for elastic struts on rollers)")
    return node, "".join(a for a in "xyz" if a in axes)


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



def _checked_nodes(nodes) -> np.ndarray:
    """The node coordinates as a read-only (n, 3) array of finite numbers (StructureError otherwise)."""
    nodes = np.array(nodes, dtype=float)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or nodes.shape[0] == 0:
        raise StructureError(f"nodes must have shape (n, 3), got {nodes.shape}")
    if not np.all(np.isfinite(nodes)):
        bad = int(np.argwhere(~np.isfinite(nodes))[0, 0])
        raise StructureError(f"node {bad} has a non-finite coordinate")
    nodes.setflags(write=False)
    return nodes


def _check_node(i, what: str, n: int) -> None:
    if not 0 <= i < n:
        raise StructureError(_unknown_node(what, i, n))


def _check_point(what: str, p, n: int, fixed: set) -> None:
    """StructureError unless ``p`` (the load or the probe) is a Point on known nodes, not all of them fixed."""
    if not isinstance(p, Point):
        raise StructureError(f"{what} must be a Point")
    for i in p.nodes:
        _check_node(i, what, n)
    if all(i in fixed for i in p.nodes):
        raise StructureError(f"the {what} acts on fixed node(s) {list(p.nodes)}; it must move")


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
        ``"strut"`` marks an elastic compression member and ``"nucleus"`` a
        member of a nucleus body; both may carry a negative force in the
        self-stress (every other member is a cable).
    fixed : sequence of int
        Fixed nodes (ball-joint anchors, supports). A strut or tendon between
        two fixed nodes cannot move and carries no load the model sees: it is
        left out, as the peers' analyses do, and :attr:`notes` says so (the
        remaining members keep their order, numbered without it).
    supports : sequence of (int, str), optional
        Per-direction supports (rollers, sliders) of point nodes: ``(node,
        axes)`` with ``axes`` the directions held, among ``"x"``, ``"y"``,
        ``"z"`` (``(3, "z")``: node 3 rolls in the x-y plane). A node held in
        all three directions is a fixed node. Strut ends are held fully (fixed)
        or not at all.
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
    notes: tuple[str, ...] = field(default=())
    supports: tuple[tuple[int, str], ...] = field(default=())

    def __post_init__(self):
        nodes = _checked_nodes(self.nodes)
        object.__setattr__(self, "nodes", nodes)
        n = nodes.shape[0]
        S, Tn = _pairs(self.struts), _pairs(self.tendons)
        families = tuple(str(f) for f in self.families)
        fixed = tuple(sorted({int(i) for i in self.fixed}))
        object.__setattr__(self, "struts", tuple(map(tuple, S.tolist())))
        object.__setattr__(self, "tendons", tuple(map(tuple, Tn.tolist())))
        object.__setattr__(self, "families", families)
        object.__setattr__(self, "fixed", fixed)
        object.__setattr__(
            self, "equal_tension_groups", tuple(tuple(int(j) for j in g) for g in self.equal_tension_groups)
        )
        if self.node_names and len(self.node_names) != n:
            raise StructureError(f"{len(self.node_names)} node names for {n} nodes")
        object.__setattr__(self, "node_names", tuple(str(s) for s in self.node_names))

        for i in fixed:
            _check_node(i, "fixed list", n)
        fixed_set = set(fixed)
        _check_struts(nodes, S, fixed)
        if len(families) != len(Tn):
            raise StructureError(f"{len(families)} families for {len(Tn)} tendons")
        _check_tendons(nodes, Tn, fixed)
        for g in self.equal_tension_groups:
            for j in g:
                if not 0 <= j < len(Tn):
                    raise StructureError(f"equal-tension group refers to unknown tendon {j}")
        for what, p in (("load", self.load), ("probe", self.probe)):
            _check_point(what, p, n, fixed_set)
        self._leave_out_immovable(*_immovable(n, S, Tn, fixed))
        object.__setattr__(self, "supports", _check_supports(self.supports, n, fixed_set, S))

    def _leave_out_immovable(self, strut_out: np.ndarray, tendon_out: np.ndarray) -> None:
        """Drop the members between two fixed nodes, renumber the equal-tension groups, and say so in ``notes``."""
        notes = list(self.notes)
        if strut_out.any():
            notes.append("left out strut(s) between two fixed nodes (they cannot move): " + ", ".join(
                f"{k} ({a}-{b})" for k, (a, b) in enumerate(self.struts) if strut_out[k]))
            object.__setattr__(self, "struts", tuple(p for k, p in enumerate(self.struts) if not strut_out[k]))
        if tendon_out.any():
            notes.append("left out tendon(s) between two fixed nodes (they cannot work): " + ", ".join(
                f"{j} ({a}-{b}, {f})" for j, ((a, b), f) in enumerate(zip(self.tendons, self.families))
                if tendon_out[j]))
            new = np.cumsum(~tendon_out) - 1  # old tendon index -> new one
            object.__setattr__(self, "tendons", tuple(p for j, p in enumerate(self.tendons) if not tendon_out[j]))
            object.__setattr__(self, "families", tuple(f for j, f in enumerate(self.families) if not tendon_out[j]))
            groups = (tuple(int(new[j]) for j in g if not tendon_out[j]) for g in self.equal_tension_groups)
            object.__setattr__(self, "equal_tension_groups", tuple(g for g in groups if g))
        object.__setattr__(self, "notes", tuple(str(t) for t in notes))

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

    @cached_property
    def held_by_fixed_nodes(self) -> bool:
        """Whether three fixed nodes not on one line hold every rigid-body motion (computed once: every
        linearization asks)."""
        fixed = self.nodes[list(self.fixed)]
        if len(fixed) < 3:
            return False
        span = fixed - fixed[0]
        far = span[int(np.argmax(np.einsum("ij,ij->i", span, span)))]
        size = float(far @ far)
        return bool(size > 0 and np.linalg.norm(np.cross(span, far), axis=1).max() > 1e-9 * size)

    def is_anchored(self, k: int) -> bool:
        """Whether strut ``k`` is anchored by a ball joint at its tail."""
        return self.struts[k][0] in self.fixed

    @property
    def point_nodes(self) -> tuple[int, ...]:
        """Nodes that are neither fixed nor on a strut, in index order."""
        free = np.ones(self.n_nodes, dtype=bool)
        free[[i for s in self.struts for i in s]] = False
        free[list(self.fixed)] = False
        return tuple(np.flatnonzero(free).tolist())

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
            *(f"note: {t}" for t in self.notes),
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

    def _repr_html_(self) -> str:
        from .._results import reporter

        return reporter("structure_html")(self)  # the repr's lines and the interactive 3D view (reports/html.py)

    def view(self, **kw):
        """The interactive 3D view (plotly, ``pip install 'tenscell[view]'``):
        :func:`tenscell.plotting.structure_view`; returns the plotly Figure (``.show()``, ``.write_html(path)``)."""
        from .._results import plotter

        return plotter("structure_view")(self, **kw)

    def plot(self, ax=None, **kw):
        """The structure in 3D, coloured as the paper's Fig. 1 (:func:`tenscell.plotting.structure_3d`)."""
        from .._results import plotter

        structure_3d = plotter("structure_3d")

        return structure_3d(self, ax=ax, **kw)


def member_values(structure: Structure, values, name: str = "value", unit: str = "") -> np.ndarray:
    """Expand a per-member property to an array over the structure's tendons.

    Parameters
    ----------
    structure : Structure
    values : float, dict or array_like
        One value for all members; a dict ``{family: value}`` (every family
        present must be given; key ``"default"`` covers the rest); or one
        value per member, shape (m,).
    name, unit : str
        For error messages, e.g. ``"EA"``, ``"N"``.

    Returns
    -------
    ndarray, shape (m,)
    """
    m = structure.n_tendons
    if isinstance(values, dict):
        out = np.empty(m)
        for j, fam in enumerate(structure.families):
            if fam in values:
                out[j] = values[fam]
            elif "default" in values:
                out[j] = values["default"]
            else:
                raise ValueError(f"{name}: no value for family {fam!r} (tendon {j}); give it or a 'default'")
        return out
    arr = np.asarray(values, dtype=float)
    if arr.ndim == 0:
        return np.full(m, float(arr))
    if arr.shape != (m,):
        raise ValueError(f"{name} must be a scalar, a {{family: value}} dict or have shape ({m},){' (' + unit + ')' if unit else ''}, got shape {arr.shape}")
    return arr.copy()
