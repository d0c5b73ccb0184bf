"""Publication-quality figures. Nothing here computes physics: every function
takes results computed elsewhere and returns a matplotlib Figure.

Use :func:`save` to write a figure atomically.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # files, not windows: tenscell runs on headless machines
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..io.outputs import atomic_path  # noqa: E402
from ..response import FrequencyResponse  # noqa: E402

__all__ = [
    "fig2_prestress",
    "fig3_frequency",
    "moduli_panels",
    "save",
    "STYLE",
    "no_if_figure",
    "no_if_peaks_figure",
    "elasticities_figure",
    "monte_carlo_figure",
    "reference_map_figure",
    "references_figure",
    "semiflexible_figure",
    "stiffening_figure",
    "fit_figure",
    "structure_3d",
    "relaxation_modes_3d",
    "MEMBER_STYLE",
]

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


# ---- variants and sensitivity (issue 5) --------------------------------------------------------
def no_if_figure(study, title: str = "Without intermediate filaments: G'' has a peak"):
    """G', G'' against f for each prestress, without IFs (solid) and with them (dashed); peaks marked.

    ``study`` is a :class:`tenscell.studies.no_if.NoIFStudy`.
    """
    w, i = study.without, study.with_ifs
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title)
        cols = _colors(len(w.prestress))
        for k, P in enumerate(w.prestress):
            a1.loglog(w.frequency_hz, w.G_storage[k], color=cols[k], label=f"P = {P:g}")
            a1.loglog(i.frequency_hz, i.G_storage[k], color=cols[k], ls="--", lw=0.8)
            a2.loglog(w.frequency_hz, w.G_loss[k], color=cols[k], label=f"P = {P:g}")
            a2.loglog(i.frequency_hz, i.G_loss[k], color=cols[k], ls="--", lw=0.8)
            pk = study.peaks[k]
            if w.frequency_hz[0] <= pk.frequency_hz <= w.frequency_hz[-1]:
                a2.plot(pk.frequency_hz, pk.height, "o", color=cols[k], ms=4)
        for ax, name in ((a1, "G′"), (a2, "G″")):
            ax.set_xlabel("frequency f (Hz)")
            ax.set_ylabel(f"{name} (Pa)")
            ax.axvspan(1e-2, 1e3, color="0.9", zorder=0)
        a1.legend(title="no IFs (solid), IFs (dashed)", ncol=2, loc="upper left")
    return fig


def no_if_peaks_figure(study, title: str = "Peak of G'' without IFs against prestress"):
    """Peak frequency and peak height of G'' against P (log-log)."""
    P = study.without.prestress
    fp = np.array([p.frequency_hz for p in study.peaks])
    hp = np.array([p.height for p in study.peaks])
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title)
        a1.loglog(P, fp, "o-")
        a1.axhline(1e3, color="0.5", ls=":", label="upper end of the paper's window (1000 Hz)")
        a1.set_xlabel("prestress P (N)")
        a1.set_ylabel("peak frequency of G″ (Hz)")
        a1.legend(loc="upper left")
        a2.loglog(P, hp, "o-")
        a2.set_xlabel("prestress P (N)")
        a2.set_ylabel("peak height of G″ (Pa)")
    return fig


def elasticities_figure(el, title: str = "Local elasticities of G′ and G″"):
    """∂ln G'/∂ln p and ∂ln G''/∂ln p over frequency for the groups and the largest single members.

    ``el`` is a :class:`tenscell.sensitivity.Elasticities`.
    """
    f = el.frequency_hz
    curves = []
    for g in ("P", "L", "alpha", "delta"):
        if g in el.names:
            k = el.index(g)
            curves.append((g + (" (per rad)" if g == "alpha" else ""), el.storage[k], el.loss[k]))
    for key in ("EA", "c"):
        e = el.group_sum(key)
        curves.append((f"all {key} together", (el.G * e).real / el.G.real, (el.G * e).imag / el.G.imag))
        rows = [k for k, g in enumerate(el.groups) if g.startswith(key + " ")]
        ks = rows[int(np.argmax(np.abs(el.storage[rows]).max(axis=1)))]
        curves.append((f"largest single {el.names[ks]}", el.storage[ks], el.loss[ks]))
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title)
        cols = plt.cm.tab10(np.arange(len(curves)))
        for col, (name, s, lo) in zip(cols, curves):
            a1.semilogx(f, s, color=col, label=name)
            a2.semilogx(f, lo, color=col, label=name)
        a1.set_ylabel("∂ln G′/∂ln p")
        a2.set_ylabel("∂ln G″/∂ln p")
        for ax in (a1, a2):
            ax.set_xlabel("frequency f (Hz)")
            ax.axhspan(-0.8, 0.8, color="0.9", zorder=0, label="|e| ≤ 0.8: 10% in, ≤ 8% out (first order)")
        a2.legend(loc="best", fontsize=7)
    return fig


def monte_carlo_figure(results, bound: float = 0.08, title: str = "Monte Carlo of simultaneous ±10% perturbations"):
    """Histograms of the largest |ΔG'/G'| and |ΔG''/G''| per draw (one colour per result)."""
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title)
        for ax, attr in ((a1, "change_storage"), (a2, "change_loss")):
            top = max(float(np.nanmax(getattr(r, attr))) for r in results)
            bins = np.linspace(0.0, 100 * top, 50)  # shared bins, so the sets compare bar for bar
            for res in results:
                v = res.valid
                ax.hist(100 * getattr(res, attr)[v], bins=bins, alpha=0.6, label=f"{res.label} ({v.sum()} valid draws)")
        for ax, name in ((a1, "G′"), (a2, "G″")):
            ax.axvline(100 * bound, color="k", ls=":", label=f"{100 * bound:g}%")
            ax.set_xlabel(f"largest |Δ{name}/{name}| over frequency (%)")
            ax.set_ylabel("draws")
        a1.legend(fontsize=7)
    return fig


def reference_map_figure(mp, if_free_curve=None, title: str = "Valid references q0(α, δ) of the paper cell"):
    """The validity map of :func:`tenscell.studies.references.prestress_map`, with the IF-free curve δ*(α)."""
    from matplotlib.colors import ListedColormap

    a, d = np.degrees(mp.alpha), np.degrees(mp.delta)
    with plt.rc_context(STYLE):
        fig, ax = plt.subplots(figsize=(5.6, 5.2), constrained_layout=True)
        cmap = ListedColormap(["#2a9d8f", "#f1f1f1", "#e9c46a"])
        ax.pcolormesh(a, d, mp.status, cmap=cmap, vmin=-0.5, vmax=2.5, shading="nearest")
        handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(k)) for k in range(3)]
        labels = ["valid (T0 > 0, K0 > 0)", "not prestressable", f"K0 not positive definite (P={mp.P:g}, EA={mp.EA:g})"]
        ax.plot(0, 50, "k*", ms=9)
        ax.plot(0, np.degrees(np.arctan(np.sqrt(2))), "kD", ms=5)
        handles += ax.lines[-2:]
        labels += ["default reference (0°, 50°)", "regular member"]
        if if_free_curve is not None and len(if_free_curve):
            c = np.degrees(np.asarray(if_free_curve))
            (h,) = ax.plot(c[:, 0], c[:, 1], "k--o", ms=3, lw=1)
            handles.append(h)
            labels.append("IF-free curve δ*(α)")
        ax.set_xlabel("azimuth α (degrees)")
        ax.set_ylabel("declination δ (degrees)")
        ax.set_title(title)
        fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=7)
    return fig


def references_figure(responses: dict, P: float, title: str | None = None):
    """G', G'' against f for several reference cells at one prestress (dict name -> FrequencyResponse)."""
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title or f"Reference shapes compared at P = {P:g}")
        cols = plt.cm.tab10(np.arange(len(responses)))
        for col, (name, r) in zip(cols, responses.items()):
            i = int(np.argmin(np.abs(r.prestress - P)))
            a1.loglog(r.frequency_hz, r.G_storage[i], color=col, label=name)
            a2.loglog(r.frequency_hz, r.G_loss[i], color=col, label=name)
        for ax, name in ((a1, "G′"), (a2, "G″")):
            ax.set_xlabel("frequency f (Hz)")
            ax.set_ylabel(f"{name} (Pa)")
        a1.legend(fontsize=7, loc="upper left")
    return fig


def semiflexible_figure(study, title: str = "Semiflexible struts: convergence to rigid struts"):
    """Left: largest relative error against EA_s (log-log) with a 1/EA_s guide; right: G'(1 Hz), G''(1 Hz) against EA_s."""
    e = study.EA_strut
    f = study.frequency_hz
    k1 = int(np.argmin(np.abs(np.log(f))))
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(title)
        a1.loglog(e, study.error_storage, "o-", ms=3, label="max |ΔG′/G′|")
        a1.loglog(e, study.error_loss, "s-", ms=3, label="max |ΔG″/G″|")
        a1.loglog(e, study.constant_storage / e, "k:", label="∝ 1/EA_s")
        a1.set_xlabel("strut stiffness EA_s (N)")
        a1.set_ylabel("relative difference from rigid struts")
        a1.legend()
        a2.semilogx(e, study.G[:, k1].real / study.G_rigid[k1].real, "o-", ms=3, label=f"G′({f[k1]:.3g} Hz)")
        a2.semilogx(e, study.G[:, k1].imag / study.G_rigid[k1].imag, "s-", ms=3, label=f"G″({f[k1]:.3g} Hz)")
        a2.axhline(1.0, color="0.5", ls=":")
        a2.axvline(study.strut_compression, color="0.5", ls="--", label="strut compression P·|T0_s|")
        a2.set_xlabel("strut stiffness EA_s (N)")
        a2.set_ylabel("modulus / rigid-strut modulus")
        a2.legend()
    return fig


def stiffening_figure(study, title: str = "Strain-stiffening intermediate filaments"):
    """G'(P) and G''(P) at 1 Hz (or the study's first frequency) for each stiffening exponent b."""
    f = study.frequency_hz
    k = int(np.argmin(np.abs(np.log(f))))
    with plt.rc_context(STYLE):
        fig, (a1, a2) = moduli_panels(f"{title} (f = {f[k]:g} Hz)")
        cols = _colors(len(study.b))
        for i, b in enumerate(study.b):
            a1.plot(study.prestress, study.G[i, :, k].real, color=cols[i], label=f"b = {b:g}")
            a2.plot(study.prestress, study.G[i, :, k].imag, color=cols[i], label=f"b = {b:g}")
        for ax, name in ((a1, "G′"), (a2, "G″")):
            ax.set_xlabel("prestress P (N, the paper's Pa)")
            ax.set_ylabel(f"{name} (Pa)")
        a1.legend(title="IF stiffening", loc="upper left")
    return fig


def fit_figure(data, curves, title: str | None = None):
    """Measured moduli as circles and fitted models as lines, one panel per model (paper Figs. 4–5).

    Parameters
    ----------
    data : tenscell.io.data.RheologyData
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


# ---- 3D structure views (issue 6) ---------------------------------------------------------
#: member colours and widths of the paper's Fig. 1: struts grey and thick, actin black, IFs red
MEMBER_STYLE = {
    "strut": {"color": "0.55", "linewidth": 3.2, "label": "struts (microtubules)"},
    "actin": {"color": "black", "linewidth": 0.9, "label": "actin"},
    "intermediate_filament": {"color": "red", "linewidth": 0.9, "label": "intermediate filaments"},
}
_OTHER_COLORS = ("tab:green", "tab:purple", "tab:orange", "tab:cyan", "tab:brown")


def _draw_members(ax, structure, x, alpha=1.0, legend=True, width_scale=1.0):
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    groups = {"strut": [tuple(p) for p in structure.struts]}
    for (a, b), fam in zip(structure.tendons, structure.families):
        groups.setdefault(fam, []).append((a, b))
    others = iter(_OTHER_COLORS * 10)
    for fam, pairs in groups.items():
        if not pairs:
            continue
        st = MEMBER_STYLE.get(fam) or {"color": next(others), "linewidth": 0.9, "label": fam}
        seg = np.stack([x[[a for a, _ in pairs]], x[[b for _, b in pairs]]], axis=1)
        lc = Line3DCollection(seg, colors=st["color"], linewidths=st["linewidth"] * width_scale, alpha=alpha,
                              label=st["label"] if legend else None)
        ax.add_collection3d(lc)
    fixed = list(structure.fixed)
    if fixed:
        ax.scatter(*x[fixed].T, marker="^", s=60 * width_scale, color="blue", depthshade=False,
                   label="anchors" if legend else None, alpha=alpha)


def _frame(ax, x, pad=0.08):
    lo, hi = x.min(axis=0), x.max(axis=0)
    span = np.maximum(hi - lo, 1e-12 * max(1.0, float(np.abs(x).max())))
    lo, hi = lo - pad * span.max(), hi + pad * span.max()
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")


def structure_3d(structure, title: str | None = None, x=None, load=True, elev: float = 18.0, azim: float = -60.0):
    """The structure in 3D, coloured as the paper's Fig. 1.

    Struts grey and thick, actin black, intermediate filaments red, other
    families in other colours, anchors (fixed nodes) as blue triangles; the
    load as a green arrow.

    Parameters
    ----------
    structure : Structure
    title : str, optional
    x : ndarray, shape (n_nodes, 3), optional
        Node positions to draw (m); default the structure's reference.
    load : bool
        Draw the load point and direction.
    """
    x = structure.nodes if x is None else np.asarray(x)
    with plt.rc_context(STYLE):
        fig = plt.figure(figsize=(6.0, 5.6), constrained_layout=True)
        ax = fig.add_subplot(projection="3d")
        _draw_members(ax, structure, x)
        if load:
            p = structure.load
            at = np.asarray(p.weights) @ x[list(p.nodes)]
            d = np.asarray(p.direction) * 0.3 * float(np.ptp(x, axis=0).max() or 1.0)
            ax.quiver(*(at - d), *d, color="green", linewidth=2.5, arrow_length_ratio=0.3, label="load")
        _frame(ax, x)
        ax.view_init(elev=elev, azim=azim)
        ax.legend(loc="upper left", fontsize=7)
        ax.set_title(title or structure.name)
    return fig


def relaxation_modes_3d(structure, rates, displacements, title: str | None = None, max_arrows: int = 400,
                        elev: float = 18.0, azim: float = -60.0):
    """The slowest relaxation modes as arrows on the structure, one panel per mode.

    Parameters
    ----------
    structure : Structure
    rates : array_like, shape (k,)
        Relaxation rates λ (1/s) of the modes.
    displacements : array_like, shape (k, n_nodes, 3)
        Node displacement of each mode (any scale; drawn with the largest
        arrow a fifth of the structure's size).
    max_arrows : int
        Draw at most this many arrows per mode (the largest ones).
    """
    disp = np.asarray(displacements)
    k = disp.shape[0]
    x = structure.nodes
    size = float(np.ptp(x, axis=0).max() or 1.0)
    with plt.rc_context(STYLE):
        fig = plt.figure(figsize=(4.2 * k, 4.4), constrained_layout=True)
        for i in range(k):
            ax = fig.add_subplot(1, k, i + 1, projection="3d")
            _draw_members(ax, structure, x, alpha=0.35, legend=False, width_scale=0.7)
            d = disp[i]
            mag = np.linalg.norm(d, axis=1)
            keep = np.argsort(mag)[::-1][:max_arrows]
            keep = keep[mag[keep] > 1e-6 * max(mag.max(), 1e-300)]
            u = d[keep] / max(mag.max(), 1e-300) * 0.2 * size
            ax.quiver(*x[keep].T, *u.T, color="tab:orange", linewidth=1.2, arrow_length_ratio=0.25)
            _frame(ax, np.vstack([x, x[keep] + u]))
            ax.view_init(elev=elev, azim=azim)
            r = float(np.asarray(rates)[i])
            ax.set_title(f"mode {i + 1}: λ = {r:.4g} 1/s" if np.isfinite(r) else f"mode {i + 1}: undamped")
        fig.suptitle(title or f"{structure.name}: slowest relaxation modes")
    return fig
