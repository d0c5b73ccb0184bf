"""The paper's figures of the homogeneous cell: moduli against prestress (Fig. 2) and frequency (Fig. 3).

Each function draws on the two axes it is given (``axes=[ax_storage, ax_loss]``)
or on a new figure's, and returns the axes as an array.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np
from matplotlib.axes import Axes

from ._style import colors, label_moduli, new_panels, styled

if TYPE_CHECKING:
    from ..response import FrequencyResponse

__all__ = ["fig2_prestress", "fig3_frequency", "moduli_vs_frequency", "moduli_vs_prestress", "linear_model_moduli"]

_PANELS = (8.0, 3.4)


@styled
def moduli_vs_prestress(resp: FrequencyResponse, axes: Sequence[Axes] | None = None, *, title: str | None = None,
                        legend: bool = True, **line_kw) -> np.ndarray:
    """G' (left) and G'' (right) against prestress on linear axes, one curve per frequency.

    Parameters
    ----------
    resp : FrequencyResponse
        Prestresses as rows, the curve frequencies as columns.
    axes : pair of Axes, optional
        Where to draw G' and G''; default a new figure.
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
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title)
    cols = colors(len(resp.frequency_hz))
    for k, f in enumerate(resp.frequency_hz):
        kw = {"color": cols[k], "label": f"{f:g} Hz", **line_kw}
        a1.plot(resp.prestress, resp.G_storage[:, k], **kw)
        a2.plot(resp.prestress, resp.G_loss[:, k], **kw)
    label_moduli(ax, "prestress P (N, the paper's Pa)")
    if legend:
        a2.legend(title="frequency", ncol=2, loc="lower right")
    return ax


@styled
def moduli_vs_frequency(resp: FrequencyResponse, axes: Sequence[Axes] | None = None, *, title: str | None = None,
                        legend: bool = True, **line_kw) -> np.ndarray:
    """G' (left) and G'' (right) against frequency on log-log axes, one curve per prestress.

    Parameters and return as :func:`moduli_vs_prestress`.
    """
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title)
    cols = colors(len(resp.prestress))
    for i, P in enumerate(resp.prestress):
        kw = {"color": cols[i], "label": f"P = {P:g}", **line_kw}
        a1.loglog(resp.frequency_hz, resp.G_storage[i], **kw)
        a2.loglog(resp.frequency_hz, resp.G_loss[i], **kw)
    label_moduli(ax, "frequency f (Hz)")
    if legend:
        a1.legend(title="prestress", ncol=2, loc="upper left")
    return ax


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
                   axes: Sequence[Axes] | None = None) -> np.ndarray:
    """The paper's Fig. 2: :func:`moduli_vs_prestress` with the paper's title."""
    return moduli_vs_prestress(resp, axes, title=title)


def fig3_frequency(resp: FrequencyResponse, title: str = "Homogeneous cell: moduli versus frequency (paper Fig. 3)",
                   axes: Sequence[Axes] | None = None) -> np.ndarray:
    """The paper's Fig. 3: :func:`moduli_vs_frequency` with the paper's title."""
    return moduli_vs_frequency(resp, axes, title=title)
