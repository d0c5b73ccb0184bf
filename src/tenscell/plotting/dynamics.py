"""Time-domain figures: simulated traces, force–displacement loops, harmonics, creep curves."""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.ticker import MaxNLocator

from ._style import colors, legend_outside, new_axes, new_panels, styled

if TYPE_CHECKING:
    from ..timedomain import PowerLawFit

__all__ = ["time_traces", "force_displacement_loop", "harmonic_spectrum", "creep_loglog",
           "simulation_axes", "harmonics_axes", "loop_axes", "amplitude_sweep_axes", "creep_axes"]


@styled
def time_traces(sim, title: str | None = None, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Force, probe displacement and tendon tensions against time, slack intervals shaded.

    ``sim`` is a :class:`tenscell.dynamics.Simulation`. Draws on three axes
    (stacked, shared time axis on a new figure) and returns them.
    """
    a1, a2, a3 = ax = new_panels(axes, 3, (7.0, 6.4), title=title, vertical=True, sharex=True)
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
    legend_outside(a3)
    return ax


@styled
def force_displacement_loop(z, force, z_linear=None, force_linear=None, title: str | None = None,
                            ax: Axes | None = None) -> Axes:
    """Force against probe displacement over whole cycles (m, N), with the linear ellipse if given."""
    ax = new_axes(ax, (4.8, 4.2))
    ax.plot(1e3 * np.asarray(z), force, color="C0", label="nonlinear")
    if z_linear is not None:
        ax.plot(1e3 * np.asarray(z_linear), force if force_linear is None else force_linear, color="k", lw=0.8,
                ls="--", label="linear model")
    ax.set_xlabel("probe displacement z (mm)")
    ax.set_ylabel("load F (N)")
    legend_outside(ax)
    if title:
        ax.set_title(title)
    return ax


@styled
def harmonic_spectrum(harm, title: str | None = None, ax: Axes | None = None) -> Axes:
    """Amplitudes of the response harmonics relative to the fundamental (log scale).

    ``harm`` is a :class:`tenscell.dynamics.Harmonics`.
    """
    h = harm.harmonic_numbers[1:]
    amp = np.abs(harm.response[1:])
    ax = new_axes(ax, (5.4, 3.6))
    rel = np.maximum(amp / amp[0], 1e-300)
    ax.bar(h, rel, color="C0")
    ax.set_yscale("log")
    ax.set_ylim(max(rel.min(), 1e-12) / 3, 2.0)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel(f"harmonic of {harm.frequency_hz:g} Hz")
    ax.set_ylabel("|z_h| / |z_1|")
    ax.set_title(title or f"THD = {100 * harm.thd:.3g} %")
    return ax


@styled
def creep_loglog(t, curves: Mapping[str, np.ndarray], exponent: Mapping[str, np.ndarray] | None = None,
                 fit: PowerLawFit | None = None, title: str | None = None, axes=None):
    """Creep compliance J(t) on log-log axes, optionally with the local exponent below.

    Parameters
    ----------
    t : array_like
        Times (s).
    curves : dict
        Label -> J(t) (m/N) on the times ``t``.
    exponent : dict, optional
        Label -> local exponent d ln J/d ln t on ``t``; drawn on a second axes.
    fit : PowerLawFit, optional
        Drawn over its window.
    title : str, optional
        Figure title (only on a new figure).
    axes : Axes, or pair of Axes when ``exponent`` is given, optional

    Returns
    -------
    Axes, or ndarray of two Axes when ``exponent`` is given
    """
    ax: Any
    if exponent:
        a1, a2 = ax = new_panels(axes, 2, (5.6, 6.0), title=title, vertical=True, sharex=True,
                                 gridspec_kw={"height_ratios": [2, 1]})
    else:
        a1 = ax = new_axes(axes, (5.6, 4.2))
        if title and axes is None:
            a1.figure.suptitle(title)
    cols = colors(len(curves))
    for (label, J), col in zip(curves.items(), cols):
        a1.loglog(t, J, color=col, label=label, ls="--" if label.startswith("linear") else "-")
    if fit is not None:
        tt = np.logspace(np.log10(fit.t_min), np.log10(fit.t_max), 50)
        a1.loglog(tt, fit(tt), color="C3", lw=2, alpha=0.6, label=f"power law A·t^α, α = {fit.alpha:.3f}")
    a1.set_ylabel("creep compliance J(t) (m/N)")
    legend_outside(a1)
    if exponent:
        for (label, e), col in zip(exponent.items(), cols):
            a2.semilogx(t, e, color=col, label=label)
        a2.set_ylabel("d ln J / d ln t")
        a2.set_xlabel("time after the step t (s)")
        a2.set_ylim(-0.05, 1.05)
    else:
        a1.set_xlabel("time after the step t (s)")
    return ax


# Axes-level views used by the dynamics result objects' plot() methods.

def simulation_axes(sim, ax=None, **kw):
    """Probe displacement z (mm) against time (s), intervals with a slack tendon shaded."""
    ax = new_axes(ax)
    ax.plot(sim.t, 1e3 * sim.z, **{"color": "C1", **kw})
    slack = ~np.all(sim.taut, axis=1)
    if slack.any():
        ax.fill_between(sim.t, 0, 1, where=slack, transform=ax.get_xaxis_transform(), color="0.5", alpha=0.2,
                        label="some tendon slack")
        legend_outside(ax)
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("probe displacement z (mm)")
    return ax


def harmonics_axes(harm, ax=None, **kw):
    """Response harmonics relative to the fundamental, log scale (:func:`harmonic_spectrum` on ``ax``)."""
    return harmonic_spectrum(harm, ax=ax)


def loop_axes(resp, ax=None, **kw):
    """Force (N) against probe displacement (mm) over the analysed cycles, with the linear model's loop."""
    _, z, F = resp.cycle()
    zl, Fl = resp.linear_cycle()
    finite = bool(np.all(np.isfinite(zl)) and np.all(np.isfinite(Fl)))
    return force_displacement_loop(z, F, zl if finite else None, Fl if finite else None, ax=ax)


def amplitude_sweep_axes(sweep, ax=None, **kw):
    """Departures of G', G'' from the linear moduli and the THD against the load amplitude (log-log)."""
    ax = new_axes(ax)
    a = sweep.amplitudes
    ax.loglog(a, np.maximum(sweep.storage_departure, 1e-16), "o-", label="|G'/G'_lin − 1|", **kw)
    ax.loglog(a, np.maximum(sweep.loss_departure, 1e-16), "s-", label="|G''/G''_lin − 1|", **kw)
    ax.loglog(a, np.maximum(sweep.thd, 1e-16), "^-", label="THD", **kw)
    ax.set_xlabel("force amplitude (N)")
    ax.set_ylabel("relative size")
    ax.set_title(f"{sweep.frequency_hz:g} Hz")
    legend_outside(ax)
    return ax


def creep_axes(creep, ax=None, **kw):
    """Creep compliance z(t)/F (m/N) against time on log-log axes, simulated and linear."""
    ax = new_axes(ax)
    ax.loglog(creep.t, creep.compliance, **{"color": "C0", "label": f"simulated, F = {creep.amplitude:g} N", **kw})
    if creep.linear is not None:
        ax.loglog(creep.t, creep.linear, color="k", lw=0.8, ls="--", label="linear model")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("J(t) = z/F (m/N)")
    legend_outside(ax)
    return ax
