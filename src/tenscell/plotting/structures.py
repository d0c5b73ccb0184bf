"""3D views of structures and of their slowest relaxation modes, coloured as the paper's Fig. 1."""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes

from ._style import new_axes, styled

if TYPE_CHECKING:
    from ..model.structure import Structure

__all__ = ["MEMBER_STYLE", "structure_3d", "relaxation_modes_3d"]

#: member colours and widths of the paper's Fig. 1: struts grey and thick, actin black, IFs red
MEMBER_STYLE: dict[str, dict[str, Any]] = {
    "strut": {"color": "0.55", "linewidth": 3.2, "label": "struts (microtubules)"},
    "actin": {"color": "black", "linewidth": 0.9, "label": "actin"},
    "intermediate_filament": {"color": "red", "linewidth": 0.9, "label": "intermediate filaments"},
}
_OTHER_COLORS = ("tab:green", "tab:purple", "tab:orange", "tab:cyan", "tab:brown")


def _draw_members(ax, structure: Structure, x: np.ndarray, alpha: float = 1.0, legend: bool = True,
                  width_scale: float = 1.0) -> None:
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    groups = {"strut": [tuple(p) for p in structure.struts]}
    for (a, b), fam in zip(structure.tendons, structure.families):
        groups.setdefault(fam, []).append((a, b))
    others = iter(_OTHER_COLORS * 10)
    for fam, pairs in groups.items():
        if not pairs:
            continue
        st = MEMBER_STYLE.get(fam) or {"color": next(others), "linewidth": 0.9, "label": fam}
        seg = np.stack([x[[a for a, _ in pairs]], x[[b for _, b in pairs]]], axis=1)
        lc = Line3DCollection(seg, colors=st["color"], linewidths=st["linewidth"] * width_scale, alpha=alpha,
                              label=st["label"] if legend else None)
        ax.add_collection3d(lc)
    fixed = list(structure.fixed)
    if fixed:
        ax.scatter(*x[fixed].T, marker="^", s=60 * width_scale, color="blue", depthshade=False,
                   label="anchors" if legend else None, alpha=alpha)


def _frame(ax, x: np.ndarray, pad: float = 0.08) -> None:
    lo, hi = x.min(axis=0), x.max(axis=0)
    span = np.maximum(hi - lo, 1e-12 * max(1.0, float(np.abs(x).max())))
    lo, hi = lo - pad * span.max(), hi + pad * span.max()
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")


@styled
def structure_3d(structure: Structure, title: str | None = None, x=None, load: bool = True, elev: float = 18.0,
                 azim: float = -60.0, ax: Axes | None = None) -> Axes:
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

    Returns
    -------
    Axes3D
    """
    x = structure.nodes if x is None else np.asarray(x)
    ax3: Any = new_axes(ax, (6.0, 5.6), projection="3d")
    _draw_members(ax3, structure, x)
    if load:
        p = structure.load
        at = np.asarray(p.weights) @ x[list(p.nodes)]
        d = np.asarray(p.direction) * 0.3 * float(np.ptp(x, axis=0).max() or 1.0)
        ax3.quiver(*(at - d), *d, color="green", linewidth=2.5, arrow_length_ratio=0.3, label="load")
    _frame(ax3, x)
    ax3.view_init(elev=elev, azim=azim)
    ax3.legend(loc="upper left", fontsize=7)
    ax3.set_title(title or structure.name)
    return ax3


@styled
def relaxation_modes_3d(structure: Structure, rates, displacements, title: str | None = None, max_arrows: int = 400,
                        elev: float = 18.0, azim: float = -60.0, axes: Sequence[Axes] | None = None) -> np.ndarray:
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

    Returns
    -------
    ndarray of Axes3D, shape (k,)
    """
    disp = np.asarray(displacements)
    k = disp.shape[0]
    x = structure.nodes
    size = float(np.ptp(x, axis=0).max() or 1.0)
    if axes is None:
        fig = plt.figure(figsize=(4.2 * k, 4.4), layout="constrained")
        out = np.array([fig.add_subplot(1, k, i + 1, projection="3d") for i in range(k)], dtype=object)
        fig.suptitle(title or f"{structure.name}: slowest relaxation modes")
    else:
        out = np.asarray([new_axes(a, projection="3d") for a in np.asarray(axes, dtype=object).ravel()], dtype=object)
        if out.size != k:
            raise ValueError(f"axes: {k} modes need {k} axes, got {out.size}")
    for i, ax in enumerate(out):
        _draw_members(ax, structure, x, alpha=0.35, legend=False, width_scale=0.7)
        d = disp[i]
        mag = np.linalg.norm(d, axis=1)
        keep = np.argsort(mag)[::-1][:max_arrows]
        keep = keep[mag[keep] > 1e-6 * max(mag.max(), 1e-300)]
        u = d[keep] / max(mag.max(), 1e-300) * 0.2 * size
        ax.quiver(*x[keep].T, *u.T, color="tab:orange", linewidth=1.2, arrow_length_ratio=0.25)
        _frame(ax, np.vstack([x, x[keep] + u]))
        ax.view_init(elev=elev, azim=azim)
        r = float(np.asarray(rates)[i])
        ax.set_title(f"mode {i + 1}: λ = {r:.4g} 1/s" if np.isfinite(r) else f"mode {i + 1}: undamped")
    return out
