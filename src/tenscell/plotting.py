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

__all__ = ["fig2_prestress", "fig3_frequency", "moduli_panels", "save", "STYLE", "fit_figure"]

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


def fit_figure(data, curves, title: str | None = None):
    """Measured moduli as circles and fitted models as lines, one panel per model (paper Figs. 4–5).

    Parameters
    ----------
    data : tenscell.data.RheologyData
        The measurements: G' filled circles, G'' open circles.
    curves : sequence of tenscell.fitting.FitCurve
        One panel each (e.g. the heterogeneous fit, then the homogeneous
        baseline); G' solid line, G'' dashed.
    title : str, optional

    Frequency sweeps are drawn on log-log axes against f (Hz); prestress
    sweeps on linear axes against prestress (Pa), as in the paper.
    """
    prestress = data.kind == "prestress"
    x = data.prestress if prestress else data.frequency_hz
    with plt.rc_context(STYLE):
        fig, axes = plt.subplots(1, len(curves), figsize=(4.2 * len(curves), 3.6), constrained_layout=True,
                                 sharey=True, squeeze=False)
        if title:
            fig.suptitle(title)
        for ax, cv in zip(axes[0], curves):
            ax.plot(x, data.G_storage, "o", color="C0", label="G′ data")
            ax.plot(x, data.G_loss, "o", mfc="none", color="C3", label="G″ data")
            ax.plot(cv.x, cv.G_storage, "-", color="C0", label="G′ model")
            ax.plot(cv.x, cv.G_loss, "--", color="C3", label="G″ model")
            if not prestress:
                ax.set_xscale("log")
                ax.set_yscale("log")
                ax.set_xlabel("frequency f (Hz)")
            else:
                ax.set_xlabel("prestress (Pa)")
                ax.set_ylim(bottom=0.0)
            ax.set_title(f"{cv.label}: rms log10 error {cv.rms_log10_error:.3g}")
        axes[0][0].set_ylabel("modulus (Pa)")
        axes[0][0].legend(loc="best")
    return fig
