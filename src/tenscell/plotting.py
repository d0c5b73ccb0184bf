"""Publication-quality figures. Nothing here computes physics: every function
takes results computed elsewhere and returns a matplotlib Figure.

Use :func:`save` to write a figure atomically.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # files, not windows: tenscell runs on headless machines
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ._io import atomic_path  # noqa: E402
from .response import FrequencyResponse  # noqa: E402

__all__ = ["fig2_prestress", "fig3_frequency", "moduli_panels", "save", "STYLE", "structure_3d", "relaxation_modes_3d", "MEMBER_STYLE"]

STYLE = {
    "font.size": 10,
    "axes.labelsize": 10,
    "axes.titlesize": 10,
    "legend.fontsize": 8,
    "figure.dpi": 150,
    "savefig.dpi": 200,
    "axes.grid": True,
    "grid.alpha": 0.3,
}


def _colors(n):
    return plt.cm.viridis(np.linspace(0.0, 0.9, n))


def moduli_panels(title: str | None = None, figsize=(8.0, 3.4)):
    """A figure with two side-by-side axes for G' (left) and G'' (right)."""
    with plt.rc_context(STYLE):
        fig, axes = plt.subplots(1, 2, figsize=figsize, constrained_layout=True)
    if title:
        fig.suptitle(title)
    return fig, axes


def fig2_prestress(resp: FrequencyResponse, title: str = "Homogeneous cell: moduli versus prestress (paper Fig. 2)"):
    """G' and G'' against prestress, one curve per frequency (linear axes, as in the paper).

    ``resp`` has prestresses as rows and the curve frequencies as columns.
    """
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title)
        cols = _colors(len(resp.frequency_hz))
        for k, f in enumerate(resp.frequency_hz):
            a1.plot(resp.prestress, resp.G_storage[:, k], color=cols[k], label=f"{f:g} Hz")
            a2.plot(resp.prestress, resp.G_loss[:, k], color=cols[k], label=f"{f:g} Hz")
        for ax, name in ((a1, "G′"), (a2, "G″")):
            ax.set_xlabel("prestress P (N, the paper's Pa)")
            ax.set_ylabel(f"{name} (Pa)")
        a2.legend(title="frequency", ncol=2, loc="lower right")
    return fig


def fig3_frequency(resp: FrequencyResponse, title: str = "Homogeneous cell: moduli versus frequency (paper Fig. 3)"):
    """G' and G'' against frequency on log-log axes, one curve per prestress."""
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title)
        cols = _colors(len(resp.prestress))
        for i, P in enumerate(resp.prestress):
            a1.loglog(resp.frequency_hz, resp.G_storage[i], color=cols[i], label=f"P = {P:g}")
            a2.loglog(resp.frequency_hz, resp.G_loss[i], color=cols[i], label=f"P = {P:g}")
        for ax, name in ((a1, "G′"), (a2, "G″")):
            ax.set_xlabel("frequency f (Hz)")
            ax.set_ylabel(f"{name} (Pa)")
        a1.legend(title="prestress", ncol=2, loc="upper left")
    return fig


def save(fig, path) -> None:
    """Save a figure atomically (PNG, PDF or SVG by extension) and close it."""
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=str(path).rsplit(".", 1)[-1])
    finally:
        plt.close(fig)


# ---- 3D structure views (issue 6) ---------------------------------------------------------
#: member colours and widths of the paper's Fig. 1: struts grey and thick, actin black, IFs red
MEMBER_STYLE = {
    "strut": {"color": "0.55", "linewidth": 3.2, "label": "struts (microtubules)"},
    "actin": {"color": "black", "linewidth": 0.9, "label": "actin"},
    "intermediate_filament": {"color": "red", "linewidth": 0.9, "label": "intermediate filaments"},
}
_OTHER_COLORS = ("tab:green", "tab:purple", "tab:orange", "tab:cyan", "tab:brown")


def _draw_members(ax, structure, x, alpha=1.0, legend=True, width_scale=1.0):
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


def _frame(ax, x, pad=0.08):
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


def structure_3d(structure, title: str | None = None, x=None, load=True, elev: float = 18.0, azim: float = -60.0):
    """The structure in 3D, coloured as the paper's Fig. 1.

    Struts grey and thick, actin black, intermediate filaments red, other
    families in other colours, anchors (fixed nodes) as blue triangles; the
    load as a green arrow.

    Parameters
    ----------
    structure : Structure
    title : str, optional
    x : ndarray, shape (n_nodes, 3), optional
        Node positions to draw (m); default the structure's reference.
    load : bool
        Draw the load point and direction.
    """
    x = structure.nodes if x is None else np.asarray(x)
    with plt.rc_context(STYLE):
        fig = plt.figure(figsize=(6.0, 5.6), constrained_layout=True)
        ax = fig.add_subplot(projection="3d")
        _draw_members(ax, structure, x)
        if load:
            p = structure.load
            at = np.asarray(p.weights) @ x[list(p.nodes)]
            d = np.asarray(p.direction) * 0.3 * float(np.ptp(x, axis=0).max() or 1.0)
            ax.quiver(*(at - d), *d, color="green", linewidth=2.5, arrow_length_ratio=0.3, label="load")
        _frame(ax, x)
        ax.view_init(elev=elev, azim=azim)
        ax.legend(loc="upper left", fontsize=7)
        ax.set_title(title or structure.name)
    return fig


def relaxation_modes_3d(structure, rates, displacements, title: str | None = None, max_arrows: int = 400,
                        elev: float = 18.0, azim: float = -60.0):
    """The slowest relaxation modes as arrows on the structure, one panel per mode.

    Parameters
    ----------
    structure : Structure
    rates : array_like, shape (k,)
        Relaxation rates λ (1/s) of the modes.
    displacements : array_like, shape (k, n_nodes, 3)
        Node displacement of each mode (any scale; drawn with the largest
        arrow a fifth of the structure's size).
    max_arrows : int
        Draw at most this many arrows per mode (the largest ones).
    """
    disp = np.asarray(displacements)
    k = disp.shape[0]
    x = structure.nodes
    size = float(np.ptp(x, axis=0).max() or 1.0)
    with plt.rc_context(STYLE):
        fig = plt.figure(figsize=(4.2 * k, 4.4), constrained_layout=True)
        for i in range(k):
            ax = fig.add_subplot(1, k, i + 1, projection="3d")
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
        fig.suptitle(title or f"{structure.name}: slowest relaxation modes")
    return fig
