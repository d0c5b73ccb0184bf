"""Spectra and time curves of the linear model: modes as stems, creep and relaxation on log-log axes."""
from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes

from ._style import legend_outside, new_axes, styled

__all__ = ["spectrum_stems", "loglog_curve", "rates_bar"]


@styled
def spectrum_stems(times, weights, ax: Axes | None = None, *, xlabel: str = "time τ (s)",
                   ylabel: str = "weight", label: str | None = None, **kw) -> Axes:
    """Modes as vertical stems: ``weights`` (any unit) at ``times`` (s) on a logarithmic time axis.

    Parameters
    ----------
    times : array_like, shape (k,)
        Characteristic times (s), > 0.
    weights : array_like, shape (k,)
        Each mode's weight, in the unit named by ``ylabel``.
    ax : Axes, optional
    xlabel, ylabel, label : str
    **kw
        Passed to :meth:`~matplotlib.axes.Axes.vlines`.

    Returns
    -------
    Axes
    """
    ax = new_axes(ax, (5.6, 3.6))
    t, w = np.asarray(times, dtype=float), np.asarray(weights, dtype=float)
    kw.setdefault("color", "C0")
    if label:
        kw["label"] = label
    ax.vlines(t, 0.0, w, **kw)
    ax.plot(t, w, "o", ms=3, color=kw["color"])
    ax.set_xscale("log")
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if label:
        legend_outside(ax)
    return ax


@styled
def loglog_curve(x, y, ax: Axes | None = None, *, xlabel: str, ylabel: str, label: str | None = None,
                 title: str | None = None, **kw) -> Axes:
    """One curve on log-log axes (e.g. J(t) in m/N, G(t) in Pa against t in s); returns the axes."""
    ax = new_axes(ax, (5.6, 4.2))
    ax.loglog(x, y, label=label, **kw)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if label:
        legend_outside(ax)
    if title:
        ax.set_title(title)
    return ax


@styled
def rates_bar(rates, ax: Axes | None = None, *, title: str | None = None) -> Axes:
    """Relaxation rates λ (1/s) of numbered modes as bars on a log scale; undamped modes (inf) omitted."""
    ax = new_axes(ax, (5.0, 3.4))
    r = np.asarray(rates, dtype=float)
    k = np.arange(1, r.size + 1)
    ok = np.isfinite(r) & (r > 0)
    ax.bar(k[ok], r[ok], color="C0")
    ax.set_yscale("log")
    ax.set_xticks(k)
    ax.set_xlabel("mode")
    ax.set_ylabel("relaxation rate λ (1/s)")
    if title:
        ax.set_title(title)
    return ax
