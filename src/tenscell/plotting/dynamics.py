"""Axes-level plots of the time-domain results (:mod:`tenscell.dynamics`).

Each function draws on ``ax`` (a new figure's axes when None) and returns
the axes; the result objects' ``plot`` methods call them. Nothing here
chooses a backend or computes physics.
"""
from __future__ import annotations

import numpy as np

from ._axes import axes_or_new as _axes

__all__ = ["simulation_axes", "harmonics_axes", "loop_axes", "amplitude_sweep_axes", "creep_axes"]


def simulation_axes(sim, ax=None, **kw):
    """Probe displacement z (mm) against time (s), intervals with a slack tendon shaded."""
    ax = _axes(ax)
    ax.plot(sim.t, 1e3 * sim.z, **{"color": "C1", **kw})
    slack = ~np.all(sim.taut, axis=1)
    if slack.any():
        ax.fill_between(sim.t, 0, 1, where=slack, transform=ax.get_xaxis_transform(), color="0.5", alpha=0.2,
                        label="some tendon slack")
        ax.legend(loc="best")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("probe displacement z (mm)")
    return ax


def harmonics_axes(harm, ax=None, **kw):
    """Response harmonics relative to the fundamental, log scale."""
    ax = _axes(ax)
    h = harm.harmonic_numbers[1:]
    amp = np.abs(harm.response[1:])
    rel = np.maximum(amp / amp[0], 1e-300)
    ax.bar(h, rel, **{"color": "C0", **kw})
    ax.set_yscale("log")
    ax.set_ylim(max(rel.min(), 1e-12) / 3, 2.0)
    ax.set_xlabel(f"harmonic of {harm.frequency_hz:g} Hz")
    ax.set_ylabel("|z_h| / |z_1|")
    ax.set_title(f"THD = {100 * harm.thd:.3g} %")
    return ax


def loop_axes(resp, ax=None, **kw):
    """Force (N) against probe displacement (mm) over the analysed cycles, with the linear model's loop."""
    ax = _axes(ax)
    _, z, F = resp.cycle()
    zl, Fl = resp.linear_cycle()
    ax.plot(1e3 * z, F, **{"color": "C0", "label": "nonlinear", **kw})
    if np.all(np.isfinite(zl)) and np.all(np.isfinite(Fl)):
        ax.plot(1e3 * zl, Fl, color="k", lw=0.8, ls="--", label="linear model")
    ax.set_xlabel("probe displacement z (mm)")
    ax.set_ylabel("load F (N)")
    ax.legend(loc="upper left")
    return ax


def amplitude_sweep_axes(sweep, ax=None, **kw):
    """Departures of G', G'' from the linear moduli and the THD against the load amplitude (log-log)."""
    ax = _axes(ax)
    a = sweep.amplitudes
    ax.loglog(a, np.maximum(sweep.storage_departure, 1e-16), "o-", label="|G'/G'_lin − 1|", **kw)
    ax.loglog(a, np.maximum(sweep.loss_departure, 1e-16), "s-", label="|G''/G''_lin − 1|", **kw)
    ax.loglog(a, np.maximum(sweep.thd, 1e-16), "^-", label="THD", **kw)
    ax.set_xlabel("force amplitude (N)")
    ax.set_ylabel("relative size")
    ax.set_title(f"{sweep.frequency_hz:g} Hz")
    ax.legend(loc="best")
    return ax


def creep_axes(creep, ax=None, **kw):
    """Creep compliance z(t)/F (m/N) against time on log-log axes, simulated and linear."""
    ax = _axes(ax)
    ax.loglog(creep.t, creep.compliance, **{"color": "C0", "label": f"simulated, F = {creep.amplitude:g} N", **kw})
    if creep.linear is not None:
        ax.loglog(creep.t, creep.linear, color="k", lw=0.8, ls="--", label="linear model")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("J(t) = z/F (m/N)")
    ax.legend(loc="best")
    return ax
