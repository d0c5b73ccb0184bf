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

__all__ = ["fig2_prestress", "fig3_frequency", "moduli_panels", "save", "STYLE"]

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


# ---- time domain (tenscell.dynamics, tenscell.timedomain) ---------------------------------
__all__ += ["time_traces", "force_displacement_loop", "harmonic_spectrum", "creep_loglog"]


def time_traces(sim, title: str | None = None):
    """Force, probe displacement and tendon tensions against time, slack intervals shaded.

    ``sim`` is a :class:`tenscell.dynamics.Simulation`.
    """
    with plt.rc_context(STYLE):
        fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(7.0, 6.4), sharex=True, constrained_layout=True)
        a1.plot(sim.t, sim.force, color="C0")
        a1.set_ylabel("load F (N)")
        a2.plot(sim.t, 1e3 * sim.z, color="C1")
        a2.set_ylabel("probe z (mm)")
        fam = sim.cell.structure.families
        for j in range(sim.tensions.shape[1]):
            a3.plot(sim.t, sim.tensions[:, j], lw=0.6, color="C2" if fam[j] == "intermediate_filament" else "C3",
                    alpha=0.7)
        a3.plot([], [], color="C3", label="actin")
        a3.plot([], [], color="C2", label="intermediate filament")
        slack = ~np.all(sim.taut, axis=1)
        if slack.any():
            a3.fill_between(sim.t, 0, 1, where=slack, transform=a3.get_xaxis_transform(), color="0.5", alpha=0.2,
                            label="some tendon slack")
        a3.set_ylabel("tension (N)")
        a3.set_xlabel("time t (s)")
        a3.legend(loc="upper right", ncol=3)
        if title:
            fig.suptitle(title)
    return fig


def force_displacement_loop(z, force, z_linear=None, force_linear=None, title: str | None = None):
    """Force against probe displacement over whole cycles (m, N), with the linear ellipse if given."""
    with plt.rc_context(STYLE):
        fig, ax = plt.subplots(figsize=(4.8, 4.2), constrained_layout=True)
        ax.plot(1e3 * np.asarray(z), force, color="C0", label="nonlinear")
        if z_linear is not None:
            ax.plot(1e3 * np.asarray(z_linear), force if force_linear is None else force_linear, color="k", lw=0.8,
                    ls="--", label="linear model")
        ax.set_xlabel("probe displacement z (mm)")
        ax.set_ylabel("load F (N)")
        ax.legend(loc="upper left")
        if title:
            ax.set_title(title)
    return fig


def harmonic_spectrum(harm, title: str | None = None):
    """Amplitudes of the response harmonics relative to the fundamental (log scale).

    ``harm`` is a :class:`tenscell.dynamics.Harmonics`.
    """
    h = harm.harmonic_numbers[1:]
    amp = np.abs(harm.response[1:])
    with plt.rc_context(STYLE):
        fig, ax = plt.subplots(figsize=(5.4, 3.6), constrained_layout=True)
        rel = np.maximum(amp / amp[0], 1e-300)
        ax.bar(h, rel, color="C0")
        ax.set_yscale("log")
        ax.set_ylim(max(rel.min(), 1e-12) / 3, 2.0)
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
        ax.set_xlabel(f"harmonic of {harm.frequency_hz:g} Hz")
        ax.set_ylabel("|z_h| / |z_1|")
        ax.set_title(title or f"THD = {100 * harm.thd:.3g} %")
    return fig


def creep_loglog(t, curves, exponent=None, fit=None, title: str | None = None):
    """Creep compliance J(t) on log-log axes, optionally with the local exponent below.

    Parameters
    ----------
    t : array_like
        Times (s).
    curves : dict
        Label -> J(t) (m/N) on the times ``t``.
    exponent : dict, optional
        Label -> local exponent d ln J/d ln t on ``t``.
    fit : PowerLawFit, optional
        Drawn over its window.
    """
    with plt.rc_context(STYLE):
        if exponent:
            fig, (a1, a2) = plt.subplots(2, 1, figsize=(5.6, 6.0), sharex=True, constrained_layout=True,
                                         gridspec_kw={"height_ratios": [2, 1]})
        else:
            fig, a1 = plt.subplots(figsize=(5.6, 4.2), constrained_layout=True)
        cols = _colors(len(curves))
        for (label, J), col in zip(curves.items(), cols):
            a1.loglog(t, J, color=col, label=label, ls="--" if label.startswith("linear") else "-")
        if fit is not None:
            tt = np.logspace(np.log10(fit.t_min), np.log10(fit.t_max), 50)
            a1.loglog(tt, fit(tt), color="C3", lw=2, alpha=0.6,
                      label=f"power law A·t^α, α = {fit.alpha:.3f}")
        a1.set_ylabel("creep compliance J(t) (m/N)")
        a1.legend(loc="lower right")
        if exponent:
            for (label, e), col in zip(exponent.items(), cols):
                a2.semilogx(t, e, color=col, label=label)
            a2.set_ylabel("d ln J / d ln t")
            a2.set_xlabel("time after the step t (s)")
            a2.set_ylim(-0.05, 1.05)
        else:
            a1.set_xlabel("time after the step t (s)")
        if title:
            fig.suptitle(title)
    return fig
