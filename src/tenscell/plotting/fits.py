"""Figures of fits: data against the fitted model per data set, the compactness front, the stiffness histogram.

Nothing here computes physics beyond evaluating a fitted model on a grid
(:func:`tenscell.fitting.model_curve`); every function draws on ``ax`` when
given and returns it, or makes a figure and returns it.
"""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from . import STYLE

__all__ = ["plot_fit", "fit_panels", "compactness_front", "stiffness_histogram"]


def _short(source: str) -> str:
    return source.replace("\\", "/").rsplit("/", 1)[-1]


def plot_fit(result, ax=None, *, dataset: int | None = None, baseline=None, n: int = 200):
    """Data (circles) and fitted model (lines) of one data set on ``ax``.

    With ``ax`` None and ``dataset`` None, every data set gets a panel of a
    new figure and the array of axes is returned; otherwise the given (or a
    new) axes. ``baseline`` (a fit of the same data sets) is drawn dotted.
    Frequency sweeps on log-log axes against f (Hz); prestress sweeps on
    linear axes against prestress (Pa), as in the paper.
    """
    from ..fitting.result import model_curve

    if ax is None and dataset is None and len(result.datasets) > 1:
        return fit_panels(result, baseline=baseline, n=n).axes
    if ax is None:
        with plt.rc_context(STYLE):
            _, ax = plt.subplots(figsize=(4.4, 3.6), constrained_layout=True)
    k = 0 if dataset is None else int(dataset)
    fit = result.fits[k]
    d = fit.data
    cv = model_curve(result, n=n, dataset=k)
    ax.plot(fit.x, d.G_storage, "o", color="C0", label="G′ data")
    ax.plot(fit.x, d.G_loss, "o", mfc="none", color="C3", label="G″ data")
    ax.plot(cv.x, cv.G_storage, "-", color="C0", label=f"G′ {cv.label}")
    ax.plot(cv.x, cv.G_loss, "--", color="C3", label=f"G″ {cv.label}")
    if baseline is not None:
        bv = model_curve(baseline, n=n, dataset=k, label="homogeneous")
        ax.plot(bv.x, bv.G_storage, ":", color="C0", label="G′ homogeneous")
        ax.plot(bv.x, bv.G_loss, ":", color="C3", label="G″ homogeneous")
    if fit.axis == "frequency":
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("frequency f (Hz)")
    else:
        ax.set_xlabel("prestress (Pa)")
        ax.set_ylim(bottom=0.0)
    ax.set_ylabel("modulus (Pa)")
    at = (f" at {fit.prestress_pa:.4g} Pa" if fit.prestress_pa is not None else
          f" at {fit.prestress_fitted_pa:.4g} Pa (fitted)" if fit.prestress_fitted_pa is not None else "")
    ax.set_title(f"{_short(d.source)}{at}\nrms log10 error {fit.rms_log10_error:.3g}")
    return ax


def fit_panels(result, baseline=None, title: str | None = None, n: int = 200):
    """A figure with one panel per data set of ``result`` (the combined figure of a joint fit)."""
    k = len(result.datasets)
    with plt.rc_context(STYLE):
        fig, axes = plt.subplots(1, k, figsize=(4.4 * k, 3.8), constrained_layout=True, squeeze=False)
        for i, ax in enumerate(axes[0]):
            plot_fit(result, ax=ax, dataset=i, baseline=baseline, n=n)
        axes[0][0].legend(loc="best")
        if title:
            fig.suptitle(title)
    return fig


def compactness_front(decades, rms, tolerance: float | None = None, knee: float | None = None, ax=None,
                      title: str | None = None):
    """Best RMS log10 error reached against the bound on the stiffness spread (decades).

    ``knee`` (decades) is marked if given; ``tolerance`` drawn as a line.
    Returns the axes.
    """
    if ax is None:
        with plt.rc_context(STYLE):
            _, ax = plt.subplots(figsize=(4.8, 3.6), constrained_layout=True)
    ax.semilogy(decades, rms, "o-", color="C0", label="best RMS reached")
    if tolerance is not None:
        ax.axhline(tolerance, color="0.4", ls="--", lw=1, label=f"tolerance {tolerance:g}")
    if knee is not None:
        ax.axvline(knee, color="C3", ls=":", lw=1.2, label=f"narrowest within tolerance: {knee:g}")
    ax.set_xlabel("bound on the stiffness spread, log10(max EA / min EA) (decades)")
    ax.set_ylabel("RMS log10 error (decades)")
    ax.legend(loc="best")
    if title:
        ax.set_title(title)
    return ax


def stiffness_histogram(EA, ax=None, title: str | None = None, families=None):
    """Histogram of log10 tendon stiffness (N), by family when ``families`` (one label per tendon) is given."""
    if ax is None:
        with plt.rc_context(STYLE):
            _, ax = plt.subplots(figsize=(4.8, 3.6), constrained_layout=True)
    x = np.log10(np.asarray(EA, dtype=float))
    bins = np.linspace(np.floor(x.min()), np.ceil(x.max()) + 1e-9, max(4, int(np.ceil(x.max()) - np.floor(x.min())) * 2
                                                                      + 1))
    if families is None:
        ax.hist(x, bins=bins, color="C0")
    else:
        fams = list(dict.fromkeys(families))
        ax.hist([x[np.array(families) == f] for f in fams], bins=bins, stacked=True, label=fams)
        ax.legend(loc="best")
    ax.set_xlabel("log10 EA (EA in N)")
    ax.set_ylabel("tendons")
    if title:
        ax.set_title(title)
    return ax
