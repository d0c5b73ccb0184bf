"""Measured moduli against fitted models (paper Figs. 4–5)."""
from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np
from matplotlib.axes import Axes

from ._style import new_axes, new_panels, styled

if TYPE_CHECKING:
    from ..io.data import RheologyData

__all__ = ["fit_figure", "data_points", "measured"]


def data_points(data: RheologyData, ax: Axes, **kw) -> Axes:
    """Measured G' (filled circles) and G'' (open circles) on ``ax`` against f or prestress."""
    x = data.prestress if data.kind == "prestress" else data.frequency_hz
    ax.plot(x, data.G_storage, "o", color="C0", label="G′ data", **kw)
    ax.plot(x, data.G_loss, "o", mfc="none", color="C3", label="G″ data", **kw)
    return ax


@styled
def measured(data: RheologyData, ax: Axes | None = None, *, title: str | None = None, **kw) -> Axes:
    """Measured G' and G'' on labelled axes: log-log against f (Hz), or linear against prestress (Pa)."""
    ax = new_axes(ax, (5.0, 3.8))
    data_points(data, ax, **kw)
    if data.kind == "prestress":
        ax.set_xlabel("prestress (Pa)")
    else:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("frequency f (Hz)")
    ax.set_ylabel("modulus (Pa)")
    ax.legend(loc="best")
    if title:
        ax.set_title(title)
    return ax


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
    prestress = data.kind == "prestress"
    ax = new_panels(axes, len(curves), (4.2 * len(curves), 3.6), title=title, sharey=True)
    for a, cv in zip(ax, curves):
        data_points(data, a)
        a.plot(cv.x, cv.G_storage, "-", color="C0", label="G′ model")
        a.plot(cv.x, cv.G_loss, "--", color="C3", label="G″ model")
        if not prestress:
            a.set_xscale("log")
            a.set_yscale("log")
            a.set_xlabel("frequency f (Hz)")
        else:
            a.set_xlabel("prestress (Pa)")
            a.set_ylim(bottom=0.0)
        a.set_title(f"{cv.label}: rms log10 error {cv.rms_log10_error:.3g}")
    ax[0].set_ylabel("modulus (Pa)")
    ax[0].legend(loc="best")
    return ax
