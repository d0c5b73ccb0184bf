"""Figures of the power-law study (:mod:`tenscell.studies.powerlaw`): moduli, the exponent map, the loss tangent,
convergence with size, the prestress.

Each function takes the study's result (a :class:`~tenscell.studies.powerlaw.PowerLawStudy`), draws on the axes
given (``ax=`` or ``axes=``) or on a new figure's, and returns them. Nothing here computes physics: the local
exponent and the loss tangent are the result's own (``PointResult.alpha``, ``.tan_delta``).
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.ticker import MaxNLocator

from ._style import colors, legend_outside, new_axes, new_panels, styled

__all__ = ["powerlaw_moduli_figure", "powerlaw_map_figure", "powerlaw_loss_tangent_figure",
           "powerlaw_convergence_figure", "powerlaw_prestress_figure", "powerlaw_fits_figure"]

_BAND = (0.1, 0.3)
_MAP_HZ = (1e-3, 1e4)
_FAMILY_COLOR = {"diluted": "#1f77b4", "hierarchical": "#d62728", "structural": "#2ca02c"}


def _in_map(f: np.ndarray) -> np.ndarray:
    return (f >= _MAP_HZ[0] * 0.999) & (f <= _MAP_HZ[1] * 1.001)


def _shade(ax: Axes) -> None:
    ax.axvspan(1e-2, 10.0, color="0.92", zorder=0)


@styled
def powerlaw_moduli_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """G' (left) and G'' (right) of each family's best structure at every prestrain (one row per family; the band
    0.01–10 Hz of goal G6 shaded)."""
    fams = study.families
    title = "Moduli of each family's best structure"
    ax = _grid(len(fams), title) if axes is None else new_panels(axes, 2 * len(fams), (9.6, 2.9 * len(fams)))
    for row, fam in enumerate(fams):
        r = study.best(fam)
        a1, a2 = ax[2 * row], ax[2 * row + 1]
        cols = colors(r.prestrain.size)
        m = _in_map(r.frequency_hz)
        for i, e in enumerate(r.prestrain):
            a1.loglog(r.frequency_hz[m], r.G_storage[i][m], color=cols[i], label=f"ε = {e:g}")
            a2.loglog(r.frequency_hz[m], r.G_loss[i][m], color=cols[i])
        for a, name in ((a1, "G′"), (a2, "G″")):
            _shade(a)
            a.set_xlim(*_MAP_HZ)
            a.set_ylabel(f"{name} (Pa)")
            a.set_xlabel("frequency f (Hz)")
        a1.set_title(f"{fam}: {r.point.label}", fontsize=8, loc="left")
        legend_outside(a2, handles=a1.get_legend_handles_labels()[0], labels=a1.get_legend_handles_labels()[1],
                       title="prestrain", fontsize=7)
    return ax


def _grid(rows: int, title: str) -> np.ndarray:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(rows, 2, figsize=(9.6, 2.9 * rows), layout="constrained", squeeze=False)
    fig.suptitle(title)
    return ax.ravel()


def _rows_of(study, fam: str):
    """The family's structures as map rows: (label, curve index nearest ε = 0.1, result), sorted by their knobs."""
    pts = list(study.family(fam))
    if fam == "diluted":  # the connectivity scan: the Voigt nets of the size most of them have
        sizes = [r.point.knob("size") for r in pts if r.point.law == "voigt"]
        main = max(set(sizes), key=sizes.count)
        pts = [r for r in pts if r.point.law == "voigt" and r.point.knob("size") == main]

    def key(r):
        return tuple(float(v) for _, v in r.point.knobs) + (r.point.damping, r.point.damping_value)

    pts.sort(key=key)
    out = []
    for r in pts:
        i = int(np.argmin(np.abs(np.log(r.prestrain / 0.1))))
        out.append((_short(fam, r), i, r))
    return out


def _short(fam: str, r) -> str:
    p = r.point
    if fam == "diluted":
        seed = p.knob("seed", 0)
        return f"z = {p.knob('connectivity'):g}" + (f" (seed {seed})" if seed else "")
    if fam == "hierarchical":
        return f"k = {p.knob('module_nodes')}, depth {p.knob('depth')}"
    where = "lattice" if p.structure == "lattice" else f"net z = {p.knob('connectivity'):g}"
    rule = {"uniform": "one c", "length": f"c ∝ l^{p.damping_value:g}",
            "tension": f"Bell, F = {p.damping_value:g}·T̄"}[p.damping]
    return f"{where}: {rule}"


@styled
def powerlaw_map_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """The local exponent α = d ln G'/d ln f over frequency (x) and each family's structures (y), at the prestrain
    nearest ε = 0.1; the band 0.1–0.3 in greens."""
    fams = study.families
    heights = [max(2.0, 0.28 * len(_rows_of(study, f)) + 1.0) for f in fams]
    if axes is None:
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(len(fams), 1, figsize=(8.4, sum(heights)), layout="constrained", squeeze=False,
                               gridspec_kw={"height_ratios": heights})
        fig.suptitle("Local exponent α = d ln G′/d ln f (prestrain ε ≈ 0.1)")
        ax = ax.ravel()
    else:
        ax = new_panels(axes, len(fams), (8.4, sum(heights)))
    cmap, norm = _alpha_colors()
    mesh = None
    for a, fam in zip(ax, fams):
        rows = _rows_of(study, fam)
        f = rows[0][2].frequency_hz
        keep = _in_map(f)
        Z = np.array([r.alpha[i][keep] for _, i, r in rows])
        y = np.arange(len(rows))
        mesh = a.pcolormesh(f[keep], y, Z, cmap=cmap, norm=norm, shading="nearest")
        a.set_xscale("log")
        a.set_yticks(y)
        a.set_yticklabels([s for s, _, _ in rows], fontsize=6)
        a.set_title(fam, fontsize=9, loc="left")
        a.set_xlabel("frequency f (Hz)")
        a.grid(False)
    if mesh is not None:
        bar = ax[0].figure.colorbar(mesh, ax=list(ax), shrink=0.8, ticks=_LEVELS)
        bar.set_label("α (greens: 0.1–0.3)")
    return ax


#: the colour levels of the exponent map: four greens for the band 0.1–0.3
_LEVELS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.7, 1.0)


def _alpha_colors():
    from matplotlib.colors import BoundaryNorm, ListedColormap

    greens = plt_cm("Greens")(np.linspace(0.35, 0.9, 4))
    low = plt_cm("Greys")(np.array([0.95, 0.6]))
    high = plt_cm("Oranges")(np.linspace(0.35, 0.9, 4))
    cmap = ListedColormap(np.vstack([low, greens, high]))
    return cmap, BoundaryNorm(_LEVELS, cmap.N)


def plt_cm(name: str):
    import matplotlib

    return matplotlib.colormaps[name]


@styled
def powerlaw_loss_tangent_figure(study, ax: Axes | None = None) -> Axes:
    """The loss tangent G''/G' against tan(απ/2) of the local exponent, every structure, prestrain and frequency of
    the map with 0.05 ≤ α ≤ 0.95 (a pure power law lies on the diagonal; dashed: ±20 %)."""
    ax = new_axes(ax, (5.6, 5.0))
    for fam in study.families:
        xs, ys = [], []
        for r in study.family(fam):
            keep = _in_map(r.frequency_hz)
            a, t = r.alpha[:, keep], r.tan_delta[:, keep]
            sel = (a >= 0.05) & (a <= 0.95)
            xs.append(np.tan(a[sel] * math.pi / 2))
            ys.append(t[sel])
        if xs:
            ax.loglog(np.concatenate(xs), np.concatenate(ys), ".", ms=2, alpha=0.5, color=_FAMILY_COLOR.get(fam),
                      label=fam)
    x = np.logspace(-1.3, 1.3, 10)
    ax.loglog(x, x, "k-", lw=0.8, label="tan δ = tan(απ/2)")
    ax.loglog(x, 1.2 * x, "k--", lw=0.6, label="±20 %")
    ax.loglog(x, 0.8 * x, "k--", lw=0.6)
    for lo in _BAND:
        ax.axvline(math.tan(lo * math.pi / 2), color="0.6", ls=":", lw=0.8,
                   label="α = 0.1, 0.3" if lo == _BAND[0] else None)
    ax.set_xlabel("tan(απ/2), α the local exponent of G′")
    ax.set_ylabel("loss tangent G″/G′")
    ax.set_title("Loss tangent against the power law's")
    legend_outside(ax, markerscale=4)
    return ax


@styled
def powerlaw_convergence_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Left: decades over which α stays in 0.1–0.3 (±0.05) against the structure's coordinates, every structure at
    its best prestrain. Right: the hierarchical nets' α (longest ±0.05 stretch) against depth, with the infinite
    net's 1 − ln k/ln(k + 2)."""
    a1, a2 = ax = new_panels(axes, 2, (10.0, 3.8), title="Convergence with size")
    marks = study.assessments
    for fam in study.families:
        pts = study.family(fam)
        n = [r.coordinates for r in pts]
        d = [max(m.band.decades for m in marks[r.point.key]) for r in pts]
        a1.semilogx(n, d, "o", ms=4, color=_FAMILY_COLOR.get(fam), label=fam)
    a1.axhline(3.0, color="k", ls=":", lw=0.8, label="3 decades")
    a1.set_xlabel("generalized coordinates")
    a1.set_ylabel("decades with α in 0.1–0.3 (±0.05)")
    legend_outside(a1, fontsize=7)
    hier = study.family("hierarchical")
    ks = sorted({int(r.point.knob("module_nodes")) for r in hier})
    cols = colors(max(len(ks), 1))
    for c, k in zip(cols, ks):
        rs = sorted((r for r in hier if int(r.point.knob("module_nodes")) == k), key=lambda r: r.point.knob("depth"))
        depth = [int(r.point.knob("depth")) for r in rs]
        alpha = [max(marks[r.point.key], key=lambda m: m.power_law.decades).power_law.alpha for r in rs]
        a2.plot(depth, alpha, "o-", color=c, label=f"k = {k}")
        a2.axhline(1.0 - math.log(k) / math.log(k + 2), color=c, ls="--", lw=0.8)
    a2.axhspan(*_BAND, color="0.93", zorder=0)
    a2.xaxis.set_major_locator(MaxNLocator(integer=True))
    a2.set_xlabel("depth (levels of modules)")
    a2.set_ylabel("α (longest ±0.05 stretch)")
    if ks:
        legend_outside(a2, fontsize=7, title="module nodes\n(dashed: 1 − ln k/ln(k+2))")
    return ax


@styled
def powerlaw_prestress_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """α(f) of each family's best structure at every prestrain: how the prestress moves the power law."""
    fams = study.families
    ax = new_panels(axes, len(fams), (4.0 * len(fams) + 1.6, 3.4), title="Local exponent against prestress")
    for a, fam in zip(ax, fams):
        r = study.best(fam)
        cols = colors(r.prestrain.size)
        m = _in_map(r.frequency_hz)
        for i, e in enumerate(r.prestrain):
            a.semilogx(r.frequency_hz[m], r.alpha[i][m], color=cols[i], label=f"ε = {e:g}")
        a.axhspan(*_BAND, color="0.92", zorder=0)
        a.set_xlim(*_MAP_HZ)
        a.set_ylim(-0.05, 1.05)
        a.set_xlabel("frequency f (Hz)")
        a.set_ylabel("α = d ln G′/d ln f")
        a.set_title(f"{fam}: {r.point.label}", fontsize=7, loc="left")
    legend_outside(ax[-1], fontsize=7, title="prestrain")
    return ax


@styled
def powerlaw_fits_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Each family's best structure fitted jointly to the Fabry sweep (left: G', G'' against f) and the Stamenović
    series (right: against the prestress), through its exact scalings; markers the data, lines the structure."""
    fits = [x for x in study.fits if len(x.fits) > 1]
    n = max(len(fits), 1)
    ax = _grid(n, "Best structures fitted to the bundled data") if axes is None else new_panels(axes, 2 * n, (9.6, 3.0 * n))
    for row, ff in enumerate(fits):
        joint = ff.fits[1]
        for col, c in enumerate(joint.curves[:2]):
            a = ax[2 * row + col]
            plot = a.semilogy if c.is_prestress else a.loglog
            plot(c.x, c.G_storage, "o", ms=3, color="C0", label="G′ data")
            plot(c.x, c.G_loss, "s", ms=3, color="C1", label="G″ data")
            plot(c.x, c.model_storage, "-", color="C0", label="G′ structure")
            plot(c.x, c.model_loss, "-", color="C1", label="G″ structure")
            a.set_xlabel("prestress (Pa)" if c.is_prestress else "frequency f (Hz)")
            a.set_ylabel("modulus (Pa)")
            a.set_title(f"{ff.family}: {c.name}, RMS {joint.rms_log10[col]:.3f} decades", fontsize=8, loc="left")
        legend_outside(ax[2 * row + 1], fontsize=7)
    return ax
