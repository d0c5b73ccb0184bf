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

This module sits after :mod:`tenscell.equilibrium` because a built-in cell
is a *prestressable* reference: building one needs the self-stress (and, for
the cell without intermediate filaments, the curve δ*(α) on which a
self-stress exists).
"""
from __future__ import annotations

import math

import numpy as np
import scipy.optimize

from ._checks import finite_scalar, positive_scalar
from .coordinates import kinematics, make_coordinates
from .equilibrium import Cell, NotPrestressableError, equilibrate, equilibrium_matrix, member_geometry
from .structure import ACTIN, INTERMEDIATE_FILAMENT, Point, Structure

__all__ = [
    "paper_cell",
    "paper_structure",
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
    names = PAPER_NODE_NAMES
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
            f"the cell without intermediate filaments has no prestressable reference at alpha={alpha:.6g} rad "
            "for declinations between 20° and 85°"
        )
    i = min(brackets, key=lambda k: abs(grid[k] - REGULAR_DELTA))
    if vals[i] == 0:
        return float(grid[i])
    return float(scipy.optimize.brentq(lambda d: _if_free_det(alpha, d), grid[i], grid[i + 1], xtol=1e-15))


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
                    f" This is the IF-free prestressable curve delta*(alpha) itself, but at alpha={alpha:.6g} rad "
                    "its self-stress puts the tendons listed above in compression; at alpha=0 (the regular member) "
                    "every actin tendon is in tension."
                )
            else:
                hint = (
                    f" Without intermediate filaments a self-stress exists only on the curve delta*(alpha); "
                    f"at alpha={alpha:.6g} rad that is delta={math.degrees(star):.6g}° (call with delta=None); "
                    f"you asked for {math.degrees(delta):.6g}°."
                )
        raise NotPrestressableError(str(err) + "." + hint) from None
