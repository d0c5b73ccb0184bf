"""Measured moduli against fitted models (paper Figs. 4–5, joint fits), the compactness front, stiffness histograms.

Nothing here computes physics beyond evaluating a fitted model on a grid
(:func:`tenscell.fitting.model_curve`).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np
from matplotlib.axes import Axes

from ._style import figure_of, legend_below, legend_outside, new_axes, new_panels, styled, wrap

if TYPE_CHECKING:
    from ..io.data import RheologyData

__all__ = ["fit_figure", "data_points", "plot_fit", "fit_panels", "compactness_front", "stiffness_histogram",
           "measured", "plot_profile", "plot_residuals", "residual_panels", "profile_panels"]


def _x_axis(data: RheologyData) -> str:
    """``"prestress"`` for a sweep over prestress at one frequency, else ``"frequency"``."""
    from ..fitting.records import data_axis

    return data_axis(data)


def data_points(data: RheologyData, ax: Axes, **kw) -> Axes:
    """Measured G' (filled circles) and G'' (open circles) on ``ax`` against f or prestress."""
    from ..io.data import generated_note

    x = data.prestress if _x_axis(data) == "prestress" and data.prestress is not None else data.frequency_hz
    # data generated from a published law (the bundled sets) say so in the legend
    what = "data (published law, not raw)" if generated_note(data) else "data"
    ax.plot(x, data.G_storage, "o", color="C0", label=f"G′ {what}", **kw)
    ax.plot(x, data.G_loss, "o", mfc="none", color="C3", label=f"G″ {what}", **kw)
    return ax


def _axis_labels(ax: Axes, kind: str) -> None:
    if kind == "frequency":
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("frequency f (Hz)")
    else:
        ax.set_xlabel("prestress (Pa)")
        ax.set_ylim(bottom=0.0)


@styled
def measured(data: RheologyData, ax: Axes | None = None, *, title: str | None = None, **kw) -> Axes:
    """Measured G' and G'' on labelled axes: log-log against f (Hz), or linear against prestress (Pa)."""
    ax = new_axes(ax, (6.2, 3.8))
    data_points(data, ax, **kw)
    _axis_labels(ax, _x_axis(data))
    ax.set_ylabel("modulus (Pa)")
    legend_outside(ax)
    if title:
        ax.set_title(wrap(title, _width_in(ax)))
    return ax


def _width_in(ax: Axes) -> float:
    """About how wide (inches) a panel is: its figure's width over the columns of its grid."""
    spec = ax.get_subplotspec()
    cols = spec.get_gridspec().ncols if spec is not None else 1
    return 0.9 * figure_of(ax).get_figwidth() / cols


@styled
def fit_figure(data: RheologyData, curves: Sequence, title: str | None = None,
               axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Measured moduli as circles and fitted models as lines, one panel per model (paper Figs. 4–5).

    Parameters
    ----------
    data : tenscell.io.data.RheologyData
        The measurements: G' filled circles, G'' open circles.
    curves : sequence of tenscell.fitting.FitCurve
        One panel each (e.g. the heterogeneous fit, then the homogeneous
        baseline); G' solid line, G'' dashed.
    title : str, optional
        Figure title (only on a new figure).
    axes : sequence of Axes, optional
        One per curve; default a new figure with the panels side by side.

    Returns
    -------
    ndarray of Axes, shape (len(curves),)

    Frequency sweeps are drawn on log-log axes against f (Hz); prestress
    sweeps on linear axes against prestress (Pa), as in the paper.
    """
    ax = new_panels(axes, len(curves), (4.2 * len(curves) + 1.8, 3.6), title=title, sharey=True)
    for a, cv in zip(ax, curves):
        data_points(data, a)
        a.plot(cv.x, cv.G_storage, "-", color="C0", label="G′ model")
        a.plot(cv.x, cv.G_loss, "--", color="C3", label="G″ model")
        _axis_labels(a, _x_axis(data))
        a.set_title(wrap(f"{cv.label}: rms log10 error {cv.rms_log10_error:.3g}", 3.8))
    ax[0].set_ylabel("modulus (Pa)")
    legend_outside(ax[-1])
    return ax


def _short(source: str) -> str:
    return source.replace("\\", "/").rsplit("/", 1)[-1]


@styled
def plot_fit(result, ax: Axes | None = None, *, dataset: int | None = None, baseline=None, n: int = 200):
    """Data (circles) and fitted model (lines) of one data set of a fit on ``ax``.

    With ``ax`` and ``dataset`` both None and several data sets, every data
    set gets a panel of a new figure (:func:`fit_panels`) and the array of
    axes is returned; otherwise the given (or a new) axes. ``baseline`` (a
    fit of the same data sets, e.g. the homogeneous one) is drawn dotted.
    Frequency sweeps on log-log axes against f (Hz); prestress sweeps on
    linear axes against prestress (Pa), as in the paper.
    """
    from ..fitting.curves import model_curve

    if ax is None and dataset is None and len(result.datasets) > 1:
        return fit_panels(result, baseline=baseline, n=n)
    ax = new_axes(ax, (4.4, 3.6))
    k = 0 if dataset is None else int(dataset)
    fit = result.fits[k]
    if fit.axis == "time":
        return _plot_creep_fit(result, fit, ax, baseline)
    cv = model_curve(result, n=n, dataset=k)
    data_points(fit.data, ax)
    ax.plot(cv.x, cv.G_storage, "-", color="C0", label=f"G′ {cv.label}")
    ax.plot(cv.x, cv.G_loss, "--", color="C3", label=f"G″ {cv.label}")
    if baseline is not None:
        bv = model_curve(baseline, n=n, dataset=k)
        ax.plot(bv.x, bv.G_storage, ":", color="C0", label=f"G′ {bv.label}")
        ax.plot(bv.x, bv.G_loss, ":", color="C3", label=f"G″ {bv.label}")
    _axis_labels(ax, fit.axis)
    ax.set_ylabel("modulus (Pa)")
    at = (f" at {fit.prestress_pa:.4g} Pa" if fit.prestress_pa is not None else
          f" at {fit.prestress_fitted_pa:.4g} Pa (fitted)" if fit.prestress_fitted_pa is not None else "")
    ax.set_title(wrap(f"{_short(fit.data.source)}{at}\nrms log10 error {fit.rms_log10_error:.3g}", _width_in(ax)))
    return ax


def _plot_creep_fit(result, fit, ax, baseline=None):
    """Creep data (circles) and the fitted model's J(t) (line) on log-log axes."""
    from ..io.data import generated_note

    d = fit.data
    what = "J data (published law, not raw)" if generated_note(d) else "J data"
    ax.loglog(d.time_s, d.compliance, "o", color="C2", label=what)
    ax.loglog(d.time_s, fit.J_model, "-", color="C2", label=f"J {result.label}")
    if baseline is not None:
        ax.loglog(d.time_s, baseline.fits[fit.index].J_model, ":", color="C2", label=f"J {baseline.label}")
    ax.set_xlabel("time after the step (s)")
    ax.set_ylabel("creep compliance (1/Pa)")
    at = (f" at {fit.prestress_pa:.4g} Pa" if fit.prestress_pa is not None else
          f" at {fit.prestress_fitted_pa:.4g} Pa (fitted)" if fit.prestress_fitted_pa is not None else "")
    ax.set_title(wrap(f"{_short(d.source)}{at}\nrms log10 error {fit.rms_log10_error:.3g}", _width_in(ax)))
    return ax


@styled
def fit_panels(result, baseline=None, title: str | None = None, n: int = 200,
               axes: Sequence[Axes] | None = None) -> np.ndarray:
    """One panel per data set of ``result`` (the combined figure of a joint fit); returns the axes.

    On a new figure one legend below the panels names every line once (the panels keep their full width); on
    axes you pass, the legend goes beside the last panel."""
    k = len(result.datasets)
    ax = new_panels(axes, k, (4.0 * k + 1.2, 4.4), title=title)
    for i, a in enumerate(ax):
        plot_fit(result, ax=a, dataset=i, baseline=baseline, n=n)
    if axes is None:
        legend_below(ax)
    else:
        legend_outside(ax[-1])
    return ax



@styled
def compactness_front(decades, rms, tolerance: float | None = None, knee: float | None = None,
                      ax: Axes | None = None, title: str | None = None) -> Axes:
    """Best RMS log10 error reached against the bound on the stiffness spread (decades).

    ``knee`` (decades) is marked if given; ``tolerance`` drawn as a line.
    """
    ax = new_axes(ax, (6.4, 3.6))
    ax.semilogy(decades, rms, "o-", color="C0", label="best RMS reached")
    if tolerance is not None:
        ax.axhline(tolerance, color="0.4", ls="--", lw=1, label=f"tolerance {tolerance:g}")
    if knee is not None:
        ax.axvline(knee, color="C3", ls=":", lw=1.2, label=f"narrowest within tolerance: {knee:g}")
    ax.set_xlabel("bound on the stiffness spread (decades)")
    ax.set_ylabel("RMS log10 error (decades)")
    legend_outside(ax)
    if title:
        ax.set_title(wrap(title, _width_in(ax)))
    return ax


@styled
def stiffness_histogram(EA, ax: Axes | None = None, title: str | None = None, families=None) -> Axes:
    """Histogram of log10 tendon stiffness (N), stacked by family when ``families`` (one label per tendon) is given."""
    ax = new_axes(ax, (4.8, 3.6))
    x = np.log10(np.asarray(EA, dtype=float))
    lo, hi = np.floor(x.min()), np.ceil(x.max())
    bins = np.arange(lo, max(hi, lo + 1) + 0.5, 0.5).tolist()
    if families is None:
        ax.hist(x, bins=bins, color="C0")
    else:
        fams = list(dict.fromkeys(families))
        ax.hist([x[np.array(families) == f] for f in fams], bins=bins, stacked=True, label=fams)
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, title="family")
    ax.set_xlabel("log10 EA (EA in N)")
    ax.set_ylabel("tendons")
    if title:
        ax.set_title(wrap(title, _width_in(ax)))
    return ax


@styled
def plot_profile(profile, ax: Axes | None = None, title: str | None = None, legend: bool = True) -> Axes:
    """The profile likelihood of one parameter (:class:`tenscell.fitting.profile.ParameterProfile`): Δ(−2 ln L)
    against the held value (log axis), the 68 % and 95 % thresholds, the fit's own value and the intervals' ends
    (``legend=False``: no legend on the axes, for a figure that has one for all its panels)."""
    ax = new_axes(ax, (6.4, 3.8))
    d = np.clip(profile.delta, 1e-3, None)  # the minimum (0) on a log axis
    ax.semilogx(profile.values, d, "o-", color="C0", ms=4, label="refit at each value")
    ax.set_yscale("symlog", linthresh=1.0)
    for iv, ls in zip(profile.intervals, (":", "--")):
        ax.axhline(iv.threshold, color="0.4", ls=ls, lw=1, label=f"{100 * iv.level:.0f} % threshold")
        for end in (iv.lower, iv.upper):
            if end is not None:
                ax.axvline(end, color="C3", ls=ls, lw=1)
    ax.axvline(profile.value, color="C2", lw=1.2, label=("held value" if profile.held else "fitted value"))
    unit = f" ({profile.unit})" if profile.unit else ""
    ax.set_xlabel(f"{profile.name}{unit}, held")
    ax.set_ylabel("Δ(−2 ln L), others refitted")
    if legend:
        legend_outside(ax)
    ax.set_title(wrap(title or f"Profile likelihood of {profile.name}: {profile.interval(0.95).text(profile.unit)}",
                      _width_in(ax)))
    return ax


def _residual_axis(fit) -> tuple[np.ndarray, str, bool]:
    """(x of each point, x label, log axis) of a data set's residuals."""
    d = fit.data
    if fit.axis == "time":
        return np.asarray(d.time_s, float), "time after the step (s)", True
    if fit.axis == "prestress":
        return np.asarray(fit.x, float), "prestress (Pa)", False
    return np.asarray(fit.x, float), "frequency f (Hz)", True


@styled
def plot_residuals(result, ax: Axes | None = None, *, dataset: int = 0, baseline=None) -> Axes:
    """The log10 errors (``log10 model − log10 data``, decades) of one data set of a fit, point by point.

    G' filled circles, G'' open circles (creep: J), against f, prestress or time as the data vary; the shaded band is
    ± the fit's tolerance, the dashed lines ± the RMS of the data's stated standard deviations (where they state
    them); a ``baseline`` fit of the same data sets (e.g. the structure-free formula) as small grey crosses.
    """
    ax = new_axes(ax, (4.4, 3.2))
    fit = result.fits[int(dataset)]
    x, xlabel, log = _residual_axis(fit)
    ax.axhspan(-result.tolerance, result.tolerance, color="0.88", zorder=0,
               label=f"± tolerance {result.tolerance:g}")
    ax.axhline(0.0, color="0.3", lw=0.8, zorder=1)
    noise = result.noise[fit.index]
    if noise is not None:
        for sign in (-1.0, 1.0):
            ax.axhline(sign * noise, color="0.4", ls="--", lw=0.9, label="± stated noise (RMS of sd)" if sign > 0
                       else None)
    r = np.asarray(fit.residuals, float)
    if fit.axis == "time":
        ax.plot(x, r, "o", color="C2", ms=4, label="J", zorder=3)
    else:
        n = x.size
        ax.plot(x, r[:n], "o", color="C0", ms=4, label="G′", zorder=3)
        ax.plot(x, r[n:], "o", mfc="none", color="C3", ms=4, label="G″", zorder=3)
    if baseline is not None and baseline is not result and len(baseline.fits) == len(result.fits):
        rb = np.asarray(baseline.fits[fit.index].residuals, float)
        ax.plot(np.tile(x, rb.size // max(x.size, 1)), rb, "x", color="0.55", ms=3.5, zorder=2,
                label=f"{baseline.label} (baseline)")
    if log:
        ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("log10 model − log10 data")
    ax.set_title(wrap(f"{_short(fit.data.source)}: RMS {fit.rms_log10_error:.3g} decades", _width_in(ax)))
    return ax


@styled
def residual_panels(result, baseline=None, title: str | None = None,
                    axes: Sequence[Axes] | None = None) -> np.ndarray:
    """The residuals of every data set of a fit (:func:`plot_residuals`), one panel each, one legend below them;
    returns the axes."""
    k = len(result.datasets)
    ax = new_panels(axes, k, (4.0 * k + 1.2, 3.6), title=title)
    for i, a in enumerate(ax):
        plot_residuals(result, ax=a, dataset=i, baseline=baseline)
    if axes is None:
        legend_below(ax)
    else:
        legend_outside(ax[-1])
    return ax


@styled
def profile_panels(profiles, title: str | None = None, axes: Sequence[Axes] | None = None,
                   ncols: int = 3) -> np.ndarray:
    """Every profile of a :class:`~tenscell.fitting.profile.ProfileSet` (or a sequence of
    :class:`~tenscell.fitting.profile.ParameterProfile`), one panel each (:func:`plot_profile`), ``ncols`` to a row,
    one legend below them; returns the axes."""
    items = list(getattr(profiles, "profiles", profiles))
    if not items:
        raise ValueError("profiles: nothing was profiled (ProfileSet.not_run says why)")
    cols = min(ncols, len(items))
    rows = -(-len(items) // cols)
    if axes is None:
        import matplotlib.pyplot as plt

        fig, grid = plt.subplots(rows, cols, figsize=(3.9 * cols + 0.6, 3.2 * rows + 0.9), layout="constrained",
                                 squeeze=False)
        if title:
            fig.suptitle(wrap(title, 3.7 * cols))
        for extra in grid.ravel()[len(items):]:
            extra.set_visible(False)
        ax = grid.ravel()[: len(items)]
    else:
        ax = new_panels(axes, len(items), (1.0, 1.0))
    for a, p in zip(ax, items):
        plot_profile(p, ax=a, legend=False)
    if axes is None:
        legend_below(ax)
    else:
        legend_outside(ax[-1])
    return ax
