"""Built-in prestressable cells.

The paper's 6-strut cell (Fig. 1) and its reference family ``q0(α, δ)``,
following ``docs/model-notes.md``:

* base side ``s = L·√(3/8)``; anchors A1, A2, A3 on the base triangle;
* anchored struts A_iC_i with azimuths α, α+240°, α+120°; free struts B_iD_i,
  the point reflections of A3C3, A1C1, A2C2 through the sphere centre
  ``O = (0, 0, Z0)``; every strut has declination δ;
* 21 working actin tendons (the expanded octahedron's 24 triangle edges less
  the 3 base edges) and 12 intermediate filaments to a centre node at O;
* load and probe: vertical, at the centre of strut B1D1.

This module sits after :mod:`tenscell.model.equilibrium` because a built-in cell
is a *prestressable* reference: building one needs the self-stress (and, for
the cell without intermediate filaments, the curve δ*(α) on which a
self-stress exists).
"""
from __future__ import annotations

import math

import numpy as np

from .._checks import finite_scalar, positive_scalar
from .coordinates import kinematics, make_coordinates
from .equilibrium import Cell, NotPrestressableError, equilibrate, equilibrium_matrix, member_geometry
from .structure import ACTIN, INTERMEDIATE_FILAMENT, NUCLEUS, Point, Structure

__all__ = [
    "paper_cell",
    "paper_structure",
    "nucleated_cell",
    "nucleated_structure",
    "paper_nodes",
    "if_free_delta",
    "DEFAULT_DELTA",
    "REGULAR_DELTA",
    "PAPER_NODE_NAMES",
]

#: default declination of the reference (rad): 50°, inside the band where the equal-IF state is positive
DEFAULT_DELTA = math.radians(50.0)
#: declination of the regular member (rad): arctan √2 ≈ 54.7356°
REGULAR_DELTA = math.atan(math.sqrt(2.0))

PAPER_NODE_NAMES = ("A1", "A2", "A3", "C1", "C2", "C3", "B1", "D1", "B2", "D2", "B3", "D3", "N")
_A1, _A2, _A3, _C1, _C2, _C3, _B1, _D1, _B2, _D2, _B3, _D3, _N = range(13)


def _u(delta: float, alpha: float) -> np.ndarray:
    return np.array([math.sin(delta) * math.cos(alpha), math.sin(delta) * math.sin(alpha), math.cos(delta)])


def paper_nodes(alpha: float, delta: float, L: float) -> np.ndarray:
    """Node positions of the reference ``q0(α, δ)`` (m), shape (13, 3), order :data:`PAPER_NODE_NAMES`."""
    s = L * math.sqrt(3.0 / 8.0)
    A = np.array([[-s / 2, -s / (2 * math.sqrt(3)), 0.0], [0.0, s / math.sqrt(3), 0.0], [s / 2, -s / (2 * math.sqrt(3)), 0.0]])
    az = [alpha, alpha + math.radians(240), alpha + math.radians(120)]
    C = np.array([A[i] + L * _u(delta, az[i]) for i in range(3)])
    u0 = _u(delta, az[0])
    Z0 = (u0 @ A[0] + L / 2) / math.cos(delta)
    O = np.array([0.0, 0.0, Z0])
    # B1D1 <-> A3C3, B2D2 <-> A1C1, B3D3 <-> A2C2 (point reflection through O, same direction)
    mirror = [2, 0, 1]
    B = np.array([2 * O - A[k] for k in mirror])
    D = np.array([2 * O - C[k] for k in mirror])
    return np.vstack([A, C, B[0], D[0], B[1], D[1], B[2], D[2], O])


def _actin_pairs() -> tuple[tuple[int, int], ...]:
    """The 21 working actin tendons: edges of the expanded octahedron's 8 triangles, base excluded."""
    x = paper_nodes(0.0, REGULAR_DELTA, 1.0)[:12]
    s = math.sqrt(3.0 / 8.0)
    pairs = []
    for i in range(12):
        for j in range(i + 1, 12):
            if abs(np.linalg.norm(x[i] - x[j]) - s) < 1e-9 and not (i < 3 and j < 3):
                pairs.append((i, j))
    assert len(pairs) == 21, "expanded-octahedron topology"
    return tuple(pairs)


def paper_structure(alpha: float, delta: float, L: float, intermediate_filaments: bool = True) -> Structure:
    """The paper's cell as a :class:`Structure` at the reference ``q0(α, δ)`` (angles in rad, L in m)."""
    x = paper_nodes(alpha, delta, L)
    tendons = list(_actin_pairs())
    families = [ACTIN] * len(tendons)
    groups: tuple = ()
    names: tuple[str, ...] = PAPER_NODE_NAMES
    if intermediate_filaments:
        first_if = len(tendons)
        tendons += [(i, _N) for i in range(12)]
        families += [INTERMEDIATE_FILAMENT] * 12
        groups = (tuple(range(first_if, first_if + 12)),)
    else:
        x, names = x[:12], names[:12]
    centre = Point(nodes=(_B1, _D1), weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    return Structure(
        nodes=x,
        struts=((_A1, _C1), (_A2, _C2), (_A3, _C3), (_D1, _B1), (_D2, _B2), (_D3, _B3)),
        tendons=tuple(tendons),
        families=tuple(families),
        fixed=(_A1, _A2, _A3),
        load=centre,
        probe=centre,
        equal_tension_groups=groups,
        name="paper cell" if intermediate_filaments else "paper cell without intermediate filaments",
        node_names=names,
    )


def _if_free_det(alpha: float, delta: float) -> float:
    """det A(q0) of the IF-free cell (square, 21×21); zero exactly where a self-stress exists."""
    st = paper_structure(alpha, delta, 1.0, intermediate_filaments=False)
    co = make_coordinates(st, "angles")
    A = equilibrium_matrix(member_geometry(co, co.q0, kinematics(co, co.q0)), sparse=False)
    return float(np.linalg.det(A))


def if_free_delta(alpha: float = 0.0) -> float:
    """Declination δ*(α) (rad) of the IF-free prestressable curve through the regular member.

    The cell without intermediate filaments has a square 21×21 equilibrium
    matrix, so it admits a self-stress only where ``det A(q0(α, δ)) = 0``.
    The root nearest the regular member's δ = arctan √2 is returned
    (exactly arctan √2 at α = 0).
    """
    alpha = finite_scalar("alpha", alpha, "a finite angle in radians")
    grid = np.linspace(math.radians(20), math.radians(85), 131)
    vals = np.array([_if_free_det(alpha, d) for d in grid])
    brackets = [i for i in range(len(grid) - 1) if vals[i] == 0 or vals[i] * vals[i + 1] < 0]
    if not brackets:
        raise NotPrestressableError(
            f"the cell without intermediate filaments has no prestressable reference at alpha={math.degrees(alpha):.6g}° "
            "for declinations between 20° and 85°"
        )
    i = min(brackets, key=lambda k: abs(grid[k] - REGULAR_DELTA))
    if vals[i] == 0:
        return float(grid[i])
    from scipy.optimize import brentq  # here, not at import: scipy.optimize is slow to load

    return float(brentq(lambda d: _if_free_det(alpha, d), grid[i], grid[i + 1], xtol=1e-15))


def paper_cell(
    alpha: float = 0.0,
    delta: float | None = None,
    L: float = 1.0,
    intermediate_filaments: bool = True,
    parametrization: str = "angles",
) -> Cell:
    """The paper's 6-strut, 36-tendon cell at a prestressable reference.

    Parameters
    ----------
    alpha : float
        Azimuth parameter α of the reference family (rad). Default 0.
    delta : float, optional
        Declination δ of every strut (rad). Default: 50° (:data:`DEFAULT_DELTA`)
        with intermediate filaments; on the IF-free prestressable curve
        δ*(α) (:func:`if_free_delta`, arctan √2 at α = 0) without them.
    L : float
        Strut length (m). Default 1.
    intermediate_filaments : bool
        Include the 12 intermediate filaments and the centre node (24
        coordinates); without them the cell has 21 coordinates.
    parametrization : {"angles", "local"}
        Generalized coordinates: the paper's (δ, α) angles (Eq. 2 order) or
        a singularity-free local chart.

    Returns
    -------
    Cell

    Raises
    ------
    NotPrestressableError
        If the reference has no self-stress with all tendons in tension (for
        example the regular member with intermediate filaments, where the
        equal-IF state has zero IF tension).
    ValueError
        For non-numeric or out-of-range α, δ or L.
    """
    alpha = finite_scalar("alpha", alpha, "a finite angle in radians")
    L = positive_scalar("L", L, "m")
    if delta is None:
        delta = DEFAULT_DELTA if intermediate_filaments else if_free_delta(alpha)
    delta = finite_scalar("delta", delta, "a finite angle in radians")
    if not 0.0 < delta < math.pi / 2:
        raise ValueError(f"delta must lie strictly between 0 and pi/2 rad (0° and 90°), got {delta!r}")
    params = {"alpha": alpha, "delta": delta, "L": L, "intermediate_filaments": bool(intermediate_filaments)}
    st = paper_structure(alpha, delta, L, intermediate_filaments)
    try:
        return equilibrate(st, parametrization, parameters=params)
    except NotPrestressableError as err:
        if intermediate_filaments:
            hint = (
                f" With intermediate filaments at alpha=0 the equal-IF state is strictly positive only for "
                f"delta between about 45.5° and 54.74° (arctan √2, the regular member, where the IF tension is zero); "
                f"you asked for delta={math.degrees(delta):.4g}°."
            )
        else:
            star = if_free_delta(alpha)
            if abs(star - delta) < 1e-9:
                hint = (
                    f" This is the IF-free prestressable curve delta*(alpha) itself, but at alpha={math.degrees(alpha):.6g}° "
                    "its self-stress puts the tendons listed above in compression; at alpha=0 (the regular member) "
                    "every actin tendon is in tension."
                )
            else:
                hint = (
                    f" Without intermediate filaments a self-stress exists only on the curve delta*(alpha); "
                    f"at alpha={math.degrees(alpha):.6g}° that is delta={math.degrees(star):.6g}° (call with delta=None); "
                    f"you asked for {math.degrees(delta):.6g}°."
                )
        raise NotPrestressableError(str(err) + "." + hint) from None


# ---- variants of the discussion and the future work (issue 5) ---------------------------------
# imported here rather than at the top so this section merges cleanly with other additions
from types import MappingProxyType  # noqa: E402

from .equilibrium import point_vector, self_stress_basis  # noqa: E402
from .structure import STRUT  # noqa: E402

__all__ += [
    "regular_cell",
    "semiflexible_structure",
    "semiflexible_paper_cell",
    "cylindrical_nodes",
    "cylindrical_structure",
    "cylindrical_cell",
    "CYLINDRICAL_PARAMETERS",
]


def _assemble_cell(structure: Structure, parametrization: str, T0: np.ndarray, parameters: dict) -> Cell:
    """A :class:`Cell` with a given, already checked self-stress (members may carry zero tension).

    :func:`equilibrate` refuses a state with a slack member, which is right
    for a tensegrity in general; the regular member's only equal-IF state has
    exactly zero IF tension, and it is a legitimate reference as long as K0 is
    positive definite (the IFs then act through their stiffness alone).
    """
    coords = make_coordinates(structure, parametrization)
    kin = kinematics(coords, coords.q0)
    geom = member_geometry(coords, coords.q0, kin)
    A = equilibrium_matrix(geom)
    resid = np.abs(A @ T0).max() / np.abs(A).max()
    if resid > 1e-10:
        raise NotPrestressableError(f"the given state is not a self-stress of {structure.name}: |A·T0| = {resid:.3g}")
    l = geom.lengths
    T0 = np.array(T0, dtype=float)
    load = point_vector(coords, structure.load, kin)
    probe = point_vector(coords, structure.probe, kin)
    for arr in (T0, l, load, probe):
        arr.setflags(write=False)
    # newer Cells store the continuum length L as a field; older ones derive it from the struts
    extra = {"L": float(structure.strut_lengths.mean())} if "L" in Cell.__dataclass_fields__ else {}
    return Cell(
        structure=structure, coords=coords, q0=coords.q0, lengths=l, A=A, T0=T0, load=load, probe=probe,
        self_stress_dim=self_stress_basis(A)[0].shape[1], geometry=geom, parameters=MappingProxyType(dict(parameters)),
        **extra,
    )


def regular_cell(L: float = 1.0, parametrization: str = "angles") -> Cell:
    """The regular member (α = 0, δ = arctan √2) with its IF-free self-stress.

    At the regular member the only self-stress with all 12 intermediate
    filaments equal has zero IF tension: it is the self-stress of the cell
    without intermediate filaments (all 21 actin tensions equal,
    ``1/√21`` each), padded with zeros. The IFs are kept as elastic,
    damped members at their rest length; they carry no prestress. Returns
    the 24-coordinate cell whose ``T0`` has 21 equal actin entries and 12
    zeros.

    Parameters
    ----------
    L : float
        Strut length (m).
    parametrization : {"angles", "local"}

    Returns
    -------
    Cell
    """
    L = positive_scalar("L", L, "m")
    bare = paper_cell(0.0, REGULAR_DELTA, L, intermediate_filaments=False, parametrization=parametrization)
    st = paper_structure(0.0, REGULAR_DELTA, L, intermediate_filaments=True)
    st = Structure(
        nodes=st.nodes, struts=st.struts, tendons=st.tendons, families=st.families, fixed=st.fixed, load=st.load,
        probe=st.probe, name="regular paper cell (IFs without prestress)", node_names=st.node_names,
    )
    T0 = np.concatenate([bare.T0, np.zeros(12)])
    params = {"alpha": 0.0, "delta": REGULAR_DELTA, "L": L, "intermediate_filaments": True, "IF_prestress": False}
    return _assemble_cell(st, parametrization, T0, params)


def semiflexible_structure(structure: Structure) -> Structure:
    """The same structure with each rigid strut replaced by an elastic member of family ``"strut"``.

    Every node that was on a strut becomes a point node (an anchored strut's
    tail stays fixed), and the struts are appended after the tendons, in the
    structure's strut order, so tendon indices and equal-tension groups are
    unchanged. The self-stress then gives the struts negative (compressive)
    forces; it is normalized over the cables only, so the tendons carry the
    same ``T0`` as in the rigid-strut structure.
    """
    if not structure.struts:
        raise ValueError(f"{structure.name} has no rigid struts to make elastic")
    return Structure(
        nodes=structure.nodes,
        struts=(),
        tendons=tuple(structure.tendons) + tuple(structure.struts),
        families=tuple(structure.families) + (STRUT,) * len(structure.struts),
        fixed=structure.fixed,
        load=structure.load,
        probe=structure.probe,
        equal_tension_groups=structure.equal_tension_groups,
        name=f"{structure.name} with elastic struts",
        node_names=structure.node_names,
    )


def semiflexible_paper_cell(
    alpha: float = 0.0, delta: float | None = None, L: float = 1.0, intermediate_filaments: bool = True
) -> Cell:
    """The paper cell with elastic struts (members of family ``"strut"``, the last 6 members).

    Same reference and arguments as :func:`paper_cell` (angles in rad, L in
    m). With intermediate filaments: 30 coordinates (10 point nodes) and 39
    members; without: 27 coordinates and 27 members. Give the struts their
    axial stiffness and damping through
    :func:`tenscell.studies.semiflexible.linearize_semiflexible`.
    """
    rigid = paper_cell(alpha, delta, L, intermediate_filaments)
    p = dict(rigid.parameters)
    st = semiflexible_structure(rigid.structure)
    return equilibrate(st, "angles", parameters={**p, "struts": "elastic"})


def _rotation_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


# node permutation of a +120° turn about b3: A1→A3→A2→A1, C likewise, B2→B1→B3→B2, D likewise
_TURN = {0: 2, 2: 1, 1: 0, 3: 5, 5: 4, 4: 3, 8: 6, 6: 10, 10: 8, 9: 7, 7: 11, 11: 9, 12: 12}

#: threefold-symmetric cylindrical reference found by :func:`tenscell.studies.references.find_cylindrical_reference` (L = 1):
#: (θ_C1, θ_B1, θ_D1) azimuths of C1, B1, D1 on the cylinder (rad), then the heights z_B1 and z_N (in units of L)
CYLINDRICAL_PARAMETERS = (-0.07299678835782628, 3.2753075343084035, -0.4754664633822025, 1.1394623955534753, 0.5692268252971129)


def cylindrical_nodes(params, L: float = 1.0) -> np.ndarray:
    """Node positions (m), shape (13, 3), of a threefold-symmetric cell on a right circular cylinder.

    Same nodes and tendons as the paper's cell (order :data:`PAPER_NODE_NAMES`);
    the anchors A_i are the paper's, the cylinder is the vertical one through
    them (radius ``L/√8``), and every strut end lies on it. ``params`` =
    (θ_C1, θ_B1, θ_D1, z_B1/L, z_N/L): the azimuths (rad) of C1, B1, D1, the
    height of B1 and of the centre node N (on the axis). The heights of C1
    and D1 follow from the strut length L; the other struts are turned by
    ±120° about the axis.

    Raises
    ------
    ValueError
        If a strut of length L cannot join the requested azimuths.
    """
    tc, tb, td, zb, zn = (finite_scalar("cylinder parameter", v) for v in params)
    L = positive_scalar("L", L, "m")
    A = paper_nodes(0.0, DEFAULT_DELTA, L)[:3]
    R = float(np.linalg.norm(A[0, :2]))
    x = np.zeros((13, 3))
    x[:3] = A
    on = lambda t, z: np.array([R * math.cos(t), R * math.sin(t), z])  # noqa: E731
    h1 = np.linalg.norm(on(tc, 0)[:2] - A[0, :2])
    h2 = np.linalg.norm(on(tb, 0)[:2] - on(td, 0)[:2])
    if max(h1, h2) >= L:
        raise ValueError("cylinder parameters: a strut of length L cannot join the requested azimuths")
    x[3] = on(tc, math.sqrt(L * L - h1 * h1))
    x[6] = on(tb, zb * L)
    x[7] = on(td, zb * L - math.sqrt(L * L - h2 * h2))
    x[12] = (0.0, 0.0, zn * L)
    R120 = _rotation_z(2 * math.pi / 3)
    for g in (3, 6, 7):
        x[_TURN[g]] = R120 @ x[g]
        x[_TURN[_TURN[g]]] = R120 @ x[_TURN[g]]
    return x


def cylindrical_structure(params=None, L: float = 1.0) -> Structure:
    """The cylindrical cell as a :class:`Structure` (the paper cell's topology, load and probe)."""
    params = CYLINDRICAL_PARAMETERS if params is None else params
    base = paper_structure(0.0, DEFAULT_DELTA, L, intermediate_filaments=True)
    return Structure(
        nodes=cylindrical_nodes(params, L), struts=base.struts, tendons=base.tendons, families=base.families,
        fixed=base.fixed, load=base.load, probe=base.probe, equal_tension_groups=base.equal_tension_groups,
        name="cylindrical cell", node_names=base.node_names,
    )


def cylindrical_cell(params=None, L: float = 1.0, parametrization: str = "angles") -> Cell:
    """A prestressable cell whose strut ends lie on a right circular cylinder (the paper's "cylindrical solutions").

    Parameters
    ----------
    params : sequence of 5 floats, optional
        See :func:`cylindrical_nodes`; default :data:`CYLINDRICAL_PARAMETERS`,
        the reference found by :func:`find_cylindrical_reference`.
    L : float
        Strut length (m).
    parametrization : {"angles", "local"}

    Raises
    ------
    NotPrestressableError
        If the configuration has no self-stress with equal IFs and all
        tendons in tension.
    """
    params = CYLINDRICAL_PARAMETERS if params is None else tuple(params)
    st = cylindrical_structure(params, L)
    names = ("theta_C1", "theta_B1", "theta_D1", "zB1_over_L", "zN_over_L")
    return equilibrate(st, parametrization, parameters={**dict(zip(names, map(float, params))), "L": float(L)})


# ---- the nucleus ----------------------------------------------------------------------------------------
def _nucleus_pairs() -> tuple[tuple[int, int], ...]:
    """The nucleus shell's 30 edges: the strut ends' neighbours (21 actin + 3 base + 6 strut pairs), an icosahedron."""
    struts = ((_A1, _C1), (_A2, _C2), (_A3, _C3), (_D1, _B1), (_D2, _B2), (_D3, _B3))
    return tuple(sorted(set(_actin_pairs()) | {(0, 1), (0, 2), (1, 2)} | {(min(p), max(p)) for p in struts}))


def nucleated_structure(alpha: float, delta: float, L: float, radius: float = 0.5) -> Structure:
    """The paper cell with a nucleus: a stiff shell the 12 intermediate filaments pass through.

    Each IF (strut end → centre node N) is split at the fraction ``radius``
    of its length from N by a nucleus node; the 12 nucleus nodes, on the
    IFs' lines through the centre, are joined by the 30 edges of an
    icosahedron (the strut ends' neighbour pattern) of family ``"nucleus"``.
    Members: 21 actin, 12 outer IF segments (strut end → nucleus node),
    12 inner IF segments (nucleus node → N), 30 nucleus edges, in this
    order; nodes: the paper cell's 13, then the nucleus nodes K1…K12.
    """
    paper = paper_structure(alpha, delta, L, intermediate_filaments=True)
    x = paper.nodes
    O = x[_N]
    nuc = O + radius * (x[:12] - O)  # on each IF's line, radius·|IF| from the centre
    nodes = np.vstack([x, nuc])
    k = lambda i: 13 + i  # noqa: E731  the nucleus node on strut end i's IF
    actin = list(_actin_pairs())
    outer = [(i, k(i)) for i in range(12)]
    inner = [(k(i), _N) for i in range(12)]
    shell = [(k(a), k(b)) for a, b in _nucleus_pairs()]
    tendons = actin + outer + inner + shell
    families = [ACTIN] * 21 + [INTERMEDIATE_FILAMENT] * 24 + [NUCLEUS] * len(shell)
    return Structure(
        nodes=nodes, struts=paper.struts, tendons=tuple(tendons), families=tuple(families), fixed=paper.fixed,
        load=paper.load, probe=paper.probe, name="nucleated paper cell",
        node_names=PAPER_NODE_NAMES + tuple(f"K{i + 1}" for i in range(12)),
    )


def nucleated_cell(alpha: float = 0.0, delta: float | None = None, L: float = 1.0, radius: float = 0.5,
                   parametrization: str = "angles", nucleus_load: float = 0.0) -> Cell:
    """The paper cell with a nucleus tied to its intermediate filaments (:func:`nucleated_structure`).

    The self-stress is the paper cell's: actin and IFs carry the paper's
    ``T0`` (each IF's two segments its tension), the nucleus edges carry no
    force at the reference (the IFs pass straight through the nucleus nodes,
    so each is balanced without them). The nucleus is then stress-free and
    acts through its material stiffness only: give its edges (family
    ``"nucleus"``) a stiffness with :func:`tenscell.laws.family_laws` or
    per-member arrays. Limits that hold exactly: with nucleus edges of
    vanishing stiffness and IF segments whose Voigt time ``c/k`` equals the
    whole IF's (``c_segment = c·l_IF/l_segment``), the moduli are the paper
    cell's at every frequency (a tensioned, undamped kink node condenses
    exactly; two Voigt springs of one time constant in series are one); the
    static modulus rises monotonically with the nucleus stiffness (probe =
    load, K grows in the positive-semidefinite order).

    The self-stress is normalized over the 45 cables (each IF counted twice),
    so the tensions ``P·T0`` equal the paper cell's at the prestress
    ``P·T0[0]/paper_cell().T0[0]`` (the actin tendons' ratio, 0.922 at the
    default reference).

    Parameters
    ----------
    alpha, delta, L
        As :func:`paper_cell` (rad, rad, m); δ defaults to 50°.
    radius : float
        Where the nucleus nodes sit on the IFs, as a fraction of the IF length
        from the centre, 0 < radius < 1 (the nucleus's size relative to the cell).
    parametrization : {"angles", "local"}
    nucleus_load : float
        The fraction of each IF's tension that the nucleus carries, 0 ≤ f < 1
        (dimensionless): the inner IF segments keep ``(1 − f)·T_IF`` and the
        nucleus shell balances the rest, ``f·T_IF`` pulling radially outward at
        each of its nodes (a prestressed nucleus; its shell is statically
        determinate — 30 edges, 12 nodes less 6 rigid motions — so its forces
        are unique). 0 (default): the stress-free nucleus described above.

    Returns
    -------
    Cell
        75 members (21 actin, 24 IF segments, 30 nucleus edges), 60 coordinates.
    """
    radius = finite_scalar("radius (nucleus)", radius, "a number strictly between 0 and 1 (fraction of the IF length)")
    if not 0.0 < radius < 1.0:
        raise ValueError(f"radius (nucleus) must lie strictly between 0 and 1 (fraction of the IF length), got {radius!r}")
    paper = paper_cell(alpha, delta, L, parametrization=parametrization)
    p = dict(paper.parameters)
    st = nucleated_structure(p["alpha"], p["delta"], p["L"], radius)
    frac = finite_scalar("nucleus_load", nucleus_load, "a number in [0, 1) (fraction of the IF tension)")
    if not 0.0 <= frac < 1.0:
        raise ValueError(f"nucleus_load must lie in [0, 1) (fraction of the IF tension the nucleus carries), got {frac!r}")
    ifs = paper.T0[21:]
    T0 = np.concatenate([paper.T0[:21], ifs, (1.0 - frac) * ifs, np.zeros(len(st.tendons) - 45)])
    params = {**p, "nucleus_radius": radius} | ({"nucleus_load": frac} if frac else {})
    if frac:  # the shell's forces that balance the IFs' unbalanced pull f·T_IF on its nodes (unique, see above)
        A = equilibrium_matrix(member_geometry(*_reference_geometry(st, parametrization)), sparse=False)
        x, *_ = np.linalg.lstsq(A[:, 45:], -(A[:, :45] @ T0[:45]), rcond=None)
        T0[45:] = x
    return equilibrate(st, parametrization, T0=T0, parameters=params)


def _reference_geometry(structure: Structure, parametrization: str):
    co = make_coordinates(structure, parametrization)
    return co, co.q0, kinematics(co, co.q0)

from .._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home
