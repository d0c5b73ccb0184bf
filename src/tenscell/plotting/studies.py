"""Axes-level plots of the studies (:mod:`tenscell.studies`) and the elasticities (:mod:`tenscell.sensitivity`).

Each function draws on ``ax`` (a new figure's axes when None) and returns
the axes; the result objects' ``plot`` methods call them. Nothing here
chooses a backend or computes physics.
"""
from __future__ import annotations

import numpy as np

from ._axes import axes_or_new as _axes

__all__ = ["no_if_axes", "reference_map_axes", "references_axes", "semiflexible_axes", "stiffening_axes",
           "elasticities_axes", "monte_carlo_axes"]


def no_if_axes(study, ax=None, **kw):
    """Peak frequency of G'' without IFs against prestress (log-log), with the window's upper end."""
    ax = _axes(ax)
    P = study.without.prestress
    ax.loglog(P, [p.frequency_hz for p in study.peaks], "o-", **kw)
    ax.axhline(study.window_hz, color="0.5", ls=":", label=f"window upper end ({study.window_hz:g} Hz)")
    ax.set_xlabel("prestress P (N)")
    ax.set_ylabel("peak frequency of G″ (Hz)")
    ax.legend(loc="upper left")
    return ax


def reference_map_axes(mp, ax=None, **kw):
    """Status of each reference q0(α, δ): valid, not prestressable, K0 not positive definite."""
    from matplotlib.colors import ListedColormap

    ax = _axes(ax)
    cmap = ListedColormap(["#2a9d8f", "#f1f1f1", "#e9c46a"])
    ax.pcolormesh(np.degrees(mp.alpha), np.degrees(mp.delta), mp.status, cmap=cmap, vmin=-0.5, vmax=2.5,
                  shading="nearest", **kw)
    ax.set_xlabel("azimuth α (degrees)")
    ax.set_ylabel("declination δ (degrees)")
    ax.set_title(f"valid (green), not prestressable (grey), K0 not definite (yellow) at P = {mp.P:g} N")
    return ax


def references_axes(study, ax=None, P=None, **kw):
    """G' (solid) and G'' (dashed) of each reference against f at one prestress."""
    ax = _axes(ax)
    first = next(iter(study.responses.values()))
    P = float(first.prestress[first.prestress.size // 2]) if P is None else float(P)
    for k, (name, r) in enumerate(study.responses.items()):
        i = int(np.argmin(np.abs(r.prestress - P)))
        ax.loglog(r.frequency_hz, r.G_storage[i], color=f"C{k}", label=name, **kw)
        ax.loglog(r.frequency_hz, r.G_loss[i], color=f"C{k}", ls="--", **kw)
    ax.set_xlabel("frequency f (Hz)")
    ax.set_ylabel("G′ (solid), G″ (dashed) (Pa)")
    ax.set_title(f"P = {P:g} N")
    ax.legend(fontsize=7, loc="upper left")
    return ax


def semiflexible_axes(study, ax=None, **kw):
    """Largest relative difference from rigid struts against EA_s (log-log), with a 1/EA_s guide."""
    ax = _axes(ax)
    e = study.EA_strut
    ax.loglog(e, study.error_storage, "o-", ms=3, label="max |ΔG′/G′|", **kw)
    ax.loglog(e, study.error_loss, "s-", ms=3, label="max |ΔG″/G″|", **kw)
    ax.loglog(e, study.constant_storage / e, "k:", label="∝ 1/EA_s")
    ax.set_xlabel("strut stiffness EA_s (N)")
    ax.set_ylabel("relative difference from rigid struts")
    ax.legend(loc="best")
    return ax


def stiffening_axes(study, ax=None, **kw):
    """G'(P) at the frequency nearest 1 Hz, one curve per stiffening exponent b."""
    ax = _axes(ax)
    f = study.frequency_hz
    k = int(np.argmin(np.abs(np.log(f))))
    for i, b in enumerate(study.b):
        ax.plot(study.prestress, study.G[i, :, k].real, label=f"b = {b:g}", **kw)
    ax.set_xlabel("prestress P (N)")
    ax.set_ylabel(f"G′ at {f[k]:g} Hz (Pa)")
    ax.legend(title=f"{study.family} stiffening", loc="upper left", fontsize=7)
    return ax


def elasticities_axes(el, ax=None, which: str = "storage", **kw):
    """∂ln G'/∂ln p (or G'' with ``which="loss"``) against f for P and each parameter group's sum."""
    ax = _axes(ax)
    data = el.storage if which == "storage" else el.loss
    f = el.frequency_hz
    for name in el.names:
        if "[" not in name:
            ax.semilogx(f, data[el.index(name)], label=name, **kw)
    for g in dict.fromkeys(n.split("[")[0] for n in el.names if "[" in n):
        e = el.group_sum(g)
        ax.semilogx(f, ((el.G * e).real / el.G.real) if which == "storage" else ((el.G * e).imag / el.G.imag),
                    ls="--", label=f"all {g}", **kw)
    ax.set_xlabel("frequency f (Hz)")
    ax.set_ylabel(f"∂ln G{'′' if which == 'storage' else '″'}/∂ln p")
    ax.legend(fontsize=7, loc="best")
    return ax


def monte_carlo_axes(mc, ax=None, **kw):
    """Histogram of the largest |ΔG'/G'| and |ΔG''/G''| over frequency per valid draw (percent)."""
    ax = _axes(ax)
    v = mc.valid
    ax.hist([100 * mc.change_storage[v], 100 * mc.change_loss[v]], bins=20, label=["G′", "G″"], **kw)
    ax.set_xlabel("largest change over frequency (%)")
    ax.set_ylabel("draws")
    ax.set_title(f"{mc.label}: ±{100 * mc.spread:g}%, {int(v.sum())} valid draws")
    ax.legend(loc="best")
    return ax
