"""3D views of structures and of their slowest relaxation modes, coloured as the paper's Fig. 1."""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes

from ._style import new_axes, styled, wrap

if TYPE_CHECKING:
    from ..model.structure import Structure

__all__ = ["MEMBER_STYLE", "MAX_MEMBERS_DRAWN", "structure_3d", "relaxation_modes_3d"]

#: member colours and widths of the paper's Fig. 1: struts grey and thick, actin black, IFs red
MEMBER_STYLE: dict[str, dict[str, Any]] = {
    "strut": {"color": "0.55", "linewidth": 3.2, "label": "struts (microtubules)"},
    "actin": {"color": "black", "linewidth": 0.9, "label": "actin"},
    "intermediate_filament": {"color": "red", "linewidth": 0.9, "label": "intermediate filaments"},
}
_OTHER_COLORS = ("tab:green", "tab:purple", "tab:orange", "tab:cyan", "tab:brown")


def _member_pairs(structure: Structure) -> tuple[np.ndarray, np.ndarray]:
    """(struts, tendons) as integer arrays of node pairs, shapes (n_struts, 2) and (n_tendons, 2)."""
    return (np.asarray(structure.struts, dtype=np.intp).reshape(-1, 2),
            np.asarray(structure.tendons, dtype=np.intp).reshape(-1, 2))


def _draw_members(ax, structure: Structure, x: np.ndarray, alpha: float = 1.0, legend: bool = True,
                  width_scale: float = 1.0, keep: tuple[np.ndarray, np.ndarray] | None = None) -> None:
    """Struts and tendons as 3D lines, one collection per family; ``keep`` = (strut mask, tendon mask) draws only
    those."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    S, T = _member_pairs(structure)
    families = np.asarray(structure.families, dtype=object)
    if keep is not None:
        S, T, families = S[keep[0]], T[keep[1]], families[keep[1]]
    # families in order of first appearance (the legend's order), each one collection of segments
    groups = {"strut": S}
    for fam in dict.fromkeys(families.tolist()):  # elastic struts (family "strut") are drawn as the rigid ones
        groups[fam] = np.concatenate([groups.get(fam, np.zeros((0, 2), np.intp)), T[families == fam]])
    others = iter(_OTHER_COLORS * 10)
    for fam, pairs in groups.items():
        if not len(pairs):
            continue
        st = MEMBER_STYLE.get(fam) or {"color": next(others), "linewidth": 0.9, "label": fam}
        lc = Line3DCollection(x[pairs], colors=st["color"], linewidths=st["linewidth"] * width_scale, alpha=alpha,
                              label=st["label"] if legend else None)
        ax.add_collection3d(lc)
    fixed = np.asarray(structure.fixed, dtype=np.intp)
    if keep is not None:  # the anchors of the members drawn
        fixed = np.intersect1d(fixed, np.concatenate([S.ravel(), T.ravel()]))
    if fixed.size:
        ax.scatter(*x[fixed].T, marker="^", s=60 * width_scale, color="blue", depthshade=False,
                   label="anchors" if legend else None, alpha=alpha)


def _frame(ax, x: np.ndarray, pad: float = 0.08, zoom: float = 0.85) -> None:
    lo, hi = x.min(axis=0), x.max(axis=0)
    span = np.maximum(hi - lo, 1e-12 * max(1.0, float(np.abs(x).max())))
    lo, hi = lo - pad * span.max(), hi + pad * span.max()
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    # zoom < 1 leaves room inside the panel for the tick and axis labels of the box's far corners
    ax.set_box_aspect(tuple(hi - lo), zoom=zoom)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")


#: above this many members structure_3d draws a section (a slab through the middle), not every member
MAX_MEMBERS_DRAWN = 1500


def _section(structure: Structure, x: np.ndarray, most: int) -> tuple[tuple[np.ndarray, np.ndarray] | None, str]:
    """The members to draw: every one, or (above ``most``) those whose midpoints lie in the thinnest slab about the
    middle of the y extent (the axis across the default view) that holds the ``most`` nearest.

    Returns (strut mask, tendon mask) or None for every member, and what the picture shows ("" for everything).
    Drawing cost grows with the members drawn (mplot3d builds a path per segment at every draw: 61k members took
    2.4 s of CPU for the three panels of the modes figure), and beyond a few thousand the eye sees a solid block.
    """
    S, T = _member_pairs(structure)
    total = len(S) + len(T)
    if total <= most:
        return None, ""
    mid = 0.5 * (x[np.concatenate([S[:, 0], T[:, 0]]), 1] + x[np.concatenate([S[:, 1], T[:, 1]]), 1])
    centre = 0.5 * (x[:, 1].min() + x[:, 1].max())
    dist = np.abs(mid - centre)
    # a lattice's midpoints lie in a few planes: the slab takes whole planes (members as far as the `most`-th
    # nearest are all drawn), so it may hold more than `most` (2,640 of 60,984 for most=1500 in an 11x11x12 block)
    half = float(np.partition(dist, most - 1)[most - 1])
    inside = dist <= half
    shown = int(inside.sum())
    return (inside[: len(S)], inside[len(S):]), \
        f"section |y − {centre:.3g}| ≤ {half:.3g} m: {shown:,} of {total:,} members drawn"


@styled
def structure_3d(structure: Structure, title: str | None = None, x=None, load: bool = True, elev: float = 18.0,
                 azim: float = -60.0, ax: Axes | None = None, max_members: int = MAX_MEMBERS_DRAWN) -> Axes:
    """The structure in 3D, coloured as the paper's Fig. 1.

    Struts grey and thick, actin black, intermediate filaments red, other
    families in other colours, anchors (fixed nodes) as blue triangles; the
    load as a green arrow.

    Parameters
    ----------
    structure : Structure
    title : str, optional
        Axes title; default the structure's name.
    x : ndarray, shape (n_nodes, 3), optional
        Node positions to draw (m); default the structure's reference.
    load : bool
        Draw the load point and direction.
    elev, azim : float
        View angles (degrees).
    ax : Axes3D, optional
        A 3D axes (``fig.add_subplot(projection="3d")``); default a new figure.
    max_members : int
        A structure with more members is drawn as a section: the members in
        the thinnest slab through its middle (across y) that holds this many,
        thinner lines, and the title says so. Every member of a 10⁴-node
        lattice drawn at once is a solid block.

    Returns
    -------
    Axes3D
    """
    x = structure.nodes if x is None else np.asarray(x)
    ax3: Any = new_axes(ax, (6.0, 5.6), projection="3d")
    keep, note = _section(structure, x, max_members)
    shown = len(structure.struts) + len(structure.tendons) if keep is None else int(keep[0].sum() + keep[1].sum())
    _draw_members(ax3, structure, x, keep=keep, width_scale=float(min(1.0, np.sqrt(300.0 / max(shown, 1)))))
    if load:
        p = structure.load
        at = np.asarray(p.weights) @ x[list(p.nodes)]
        d = np.asarray(p.direction) * 0.3 * float(np.ptp(x, axis=0).max() or 1.0)
        ax3.quiver(*(at - d), *d, color="green", linewidth=2.5, arrow_length_ratio=0.3, label="load")
    _frame(ax3, x)
    ax3.view_init(elev=elev, azim=azim)
    ax3.legend(loc="upper left", fontsize=7)
    ax3.set_title(wrap((title or structure.name) + (f"\n{note}" if note else ""), 5.4))
    return ax3


@styled
def relaxation_modes_3d(structure: Structure, rates, displacements, title: str | None = None, max_arrows: int = 400,
                        elev: float = 18.0, azim: float = -60.0, axes: Sequence[Axes] | None = None,
                        max_members: int = MAX_MEMBERS_DRAWN) -> np.ndarray:
    """The slowest relaxation modes as arrows on the structure, one panel per mode.

    Parameters
    ----------
    structure : Structure
    rates : array_like, shape (k,)
        Relaxation rates λ (1/s) of the modes.
    displacements : array_like, shape (k, n_nodes, 3)
        Node displacement of each mode (any scale; drawn with the largest
        arrow a fifth of the structure's size).
    title : str, optional
        Figure title (only on a new figure).
    max_arrows : int
        Draw at most this many arrows per mode (the largest ones).
    axes : sequence of k Axes3D, optional
        Default a new figure with the modes side by side.
    max_members : int
        A structure with more members is drawn as the same section as
        :func:`structure_3d` (a slab through its middle, across y), with the
        arrows of the nodes in it; every panel's title says how many members
        are drawn.

    Returns
    -------
    ndarray of Axes3D, shape (k,)
    """
    disp = np.asarray(displacements)
    k = disp.shape[0]
    x = structure.nodes
    size = float(np.ptp(x, axis=0).max() or 1.0)
    keep, note = _section(structure, x, max_members)
    width = 0.7
    if keep is None:
        candidates = np.arange(len(x))
    else:  # the arrows of the nodes in the section, lines as thin as structure_3d's
        S, T = _member_pairs(structure)
        candidates = np.unique(np.concatenate([S[keep[0]].ravel(), T[keep[1]].ravel()]))
        width *= float(min(1.0, np.sqrt(300.0 / max(int(keep[0].sum() + keep[1].sum()), 1))))
    if axes is None:
        fig = plt.figure(figsize=(4.2 * k, 4.4 + 0.2 * bool(note)), layout="constrained")
        out = np.array([fig.add_subplot(1, k, i + 1, projection="3d") for i in range(k)], dtype=object)
        fig.suptitle(wrap((title or f"{structure.name}: slowest relaxation modes") + (f"\n{note}" if note else ""),
                          4.0 * k))
    else:
        out = np.asarray([new_axes(a, projection="3d") for a in np.asarray(axes, dtype=object).ravel()], dtype=object)
        if out.size != k:
            raise ValueError(f"axes: {k} modes need {k} axes, got {out.size}")
    for i, ax in enumerate(out):
        _draw_members(ax, structure, x, alpha=0.35, legend=False, width_scale=width, keep=keep)
        d = disp[i]
        mag = np.linalg.norm(d, axis=1)
        big = candidates[np.argsort(mag[candidates])[::-1][:max_arrows]]
        big = big[mag[big] > 1e-6 * max(mag.max(), 1e-300)]
        u = d[big] / max(mag.max(), 1e-300) * 0.2 * size
        ax.quiver(*x[big].T, *u.T, color="tab:orange", linewidth=1.2, arrow_length_ratio=0.25)
        _frame(ax, np.vstack([x, x[big] + u]))
        ax.view_init(elev=elev, azim=azim)
        r = float(np.asarray(rates)[i])
        head = f"mode {i + 1}: λ = {r:.4g} 1/s" if np.isfinite(r) else f"mode {i + 1}: undamped"
        ax.set_title(head if keep is None else f"{head}\n{note.rsplit(': ', 1)[1]}", fontsize=None if keep is None else 9)
    return out
