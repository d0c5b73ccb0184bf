"""The paper's figures of the homogeneous cell: moduli against prestress (Fig. 2) and frequency (Fig. 3).

Each function draws on the two axes it is given (``ax=[ax_storage, ax_loss]``)
or on a new figure's, and returns the axes as an array. The legend (with its
unit) sits to the right of the G″ panel, off the curves.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np
from matplotlib.axes import Axes

from ._style import colors, label_moduli, legend_outside, new_panels, styled

if TYPE_CHECKING:
    from ..response import FrequencyResponse

__all__ = ["fig2_prestress", "fig3_frequency", "moduli_vs_frequency", "moduli_vs_prestress", "linear_model_moduli"]

_PANELS = (9.0, 3.4)  # two panels and the legend beside them


@styled
def moduli_vs_prestress(resp: FrequencyResponse, ax: Sequence[Axes] | None = None, *, title: str | None = None,
                        legend: bool = True, axes: Sequence[Axes] | None = None, **line_kw) -> np.ndarray:
    """G' (left) and G'' (right) against prestress on linear axes, one curve per frequency.

    Parameters
    ----------
    resp : FrequencyResponse
        Prestresses as rows, the curve frequencies as columns.
    ax : pair of Axes, optional
        Where to draw G' and G''; default a new figure. ``axes=`` is the
        same (the older spelling).
    title : str, optional
        Figure title (only on a new figure).
    legend : bool
        Label the frequencies.
    **line_kw
        Passed to :meth:`~matplotlib.axes.Axes.plot` (e.g. ``lw``, ``ls``).

    Returns
    -------
    ndarray of Axes, shape (2,)
    """
    a1, a2 = out = new_panels(ax if ax is not None else axes, 2, _PANELS, title=title)
    cols = colors(len(resp.frequency_hz))
    for k, f in enumerate(resp.frequency_hz):
        kw = {"color": cols[k], "label": f"{f:g}", **line_kw}
        a1.plot(resp.prestress, resp.G_storage[:, k], **kw)
        a2.plot(resp.prestress, resp.G_loss[:, k], **kw)
    label_moduli(out, "prestress P (N, the paper's Pa)")
    if legend:
        legend_outside(a2, title="frequency f (Hz)", ncol=1 if len(cols) <= 12 else 2)
    return out


@styled
def moduli_vs_frequency(resp: FrequencyResponse, ax: Sequence[Axes] | None = None, *, title: str | None = None,
                        legend: bool = True, axes: Sequence[Axes] | None = None, **line_kw) -> np.ndarray:
    """G' (left) and G'' (right) against frequency on log-log axes, one curve per prestress.

    Parameters and return as :func:`moduli_vs_prestress`.
    """
    a1, a2 = out = new_panels(ax if ax is not None else axes, 2, _PANELS, title=title)
    cols = colors(len(resp.prestress))
    for i, P in enumerate(resp.prestress):
        kw = {"color": cols[i], "label": f"{P:g}", **line_kw}
        a1.loglog(resp.frequency_hz, resp.G_storage[i], **kw)
        a2.loglog(resp.frequency_hz, resp.G_loss[i], **kw)
    label_moduli(out, "frequency f (Hz)")
    if legend:
        legend_outside(a2, title="prestress P (N)", ncol=1 if len(cols) <= 12 else 2)
    return out


def linear_model_moduli(lin, axes: Sequence[Axes] | None = None, f_hz=None, **kw) -> np.ndarray:
    """G' and G'' of one :class:`~tenscell.linear.linearize.LinearModel` against frequency (``LinearModel.plot``).

    ``f_hz`` defaults to 61 frequencies from 0.01 to 1000 Hz (the paper's
    window); ``kw`` as :func:`moduli_vs_frequency`.
    """
    from ..response import FrequencyResponse, compliance

    f = np.logspace(-2, 3, 61) if f_hz is None else np.atleast_1d(np.asarray(f_hz, dtype=float))
    resp = FrequencyResponse(frequency_hz=f, prestress=np.array([lin.P]), J=compliance(lin, f)[None, :], L=lin.L)
    return moduli_vs_frequency(resp, axes, **kw)


def fig2_prestress(resp: FrequencyResponse, title: str = "Homogeneous cell: moduli versus prestress (paper Fig. 2)",
                   ax: Sequence[Axes] | None = None, *, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """The paper's Fig. 2: :func:`moduli_vs_prestress` with the paper's title."""
    return moduli_vs_prestress(resp, ax if ax is not None else axes, title=title)


def fig3_frequency(resp: FrequencyResponse, title: str = "Homogeneous cell: moduli versus frequency (paper Fig. 3)",
                   ax: Sequence[Axes] | None = None, *, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """The paper's Fig. 3: :func:`moduli_vs_frequency` with the paper's title."""
    return moduli_vs_frequency(resp, ax if ax is not None else axes, title=title)
