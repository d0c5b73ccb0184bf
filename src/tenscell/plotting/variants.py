"""Figures of the variant studies and the sensitivity analysis (paper discussion and future work).

Two-panel figures take ``axes=`` (a pair of Axes), single-panel ones ``ax=``;
each draws there or on a new figure and returns the axes.
"""
from __future__ import annotations

from typing import Any, Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes

from ._style import colors, label_moduli, legend_outside, new_axes, new_panels, styled

__all__ = [
    "no_if_figure", "no_if_peaks_figure", "elasticities_figure", "monte_carlo_figure", "reference_map_figure",
    "references_figure", "semiflexible_figure", "stiffening_figure",
]

_PANELS = (9.6, 3.4)  # two panels and a legend beside them


@styled
def no_if_figure(study, title: str = "Without intermediate filaments: G'' has a peak",
                 axes: Sequence[Axes] | None = None) -> np.ndarray:
    """G', G'' against f for each prestress, without IFs (solid) and with them (dashed); peaks marked.

    ``study`` is a :class:`tenscell.studies.no_if.NoIFStudy`. Returns the
    (G', G'') axes.
    """
    w, i = study.without, study.with_ifs
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title)
    cols = colors(len(w.prestress))
    for k, P in enumerate(w.prestress):
        a1.loglog(w.frequency_hz, w.G_storage[k], color=cols[k], label=f"{P:g}")
        a1.loglog(i.frequency_hz, i.G_storage[k], color=cols[k], ls="--", lw=0.8)
        a2.loglog(w.frequency_hz, w.G_loss[k], color=cols[k], label=f"{P:g}")
        a2.loglog(i.frequency_hz, i.G_loss[k], color=cols[k], ls="--", lw=0.8)
        pk = study.peaks[k]
        if w.frequency_hz[0] <= pk.frequency_hz <= w.frequency_hz[-1]:
            a2.plot(pk.frequency_hz, pk.height, "o", color=cols[k], ms=4)
    label_moduli(ax, "frequency f (Hz)")
    for a in ax:
        a.axvspan(1e-2, 1e3, color="0.9", zorder=0)
    legend_outside(a2, title="prestress P (N)\nno IFs (solid), IFs (dashed)")
    return ax


@styled
def no_if_peaks_figure(study, title: str = "Peak of G'' without IFs against prestress",
                       axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Peak frequency and peak height of G'' against P (log-log)."""
    P = study.without.prestress
    fp = np.array([p.frequency_hz for p in study.peaks])
    hp = np.array([p.height for p in study.peaks])
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title)
    a1.loglog(P, fp, "o-")
    w = study.window_hz
    a1.axhline(w, color="0.5", ls=":", label=f"upper end of the frequency window ({w:g} Hz)")
    a1.set_xlabel("prestress P (N)")
    a1.set_ylabel("peak frequency of G″ (Hz)")
    legend_outside(a1)
    a2.loglog(P, hp, "o-")
    a2.set_xlabel("prestress P (N)")
    a2.set_ylabel("peak height of G″ (Pa)")
    return ax


def _elasticity_curves(el) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(label, storage, loss) for the groups and the largest single members of an Elasticities."""
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
    return curves


@styled
def elasticities_figure(el, title: str = "Local elasticities of G′ and G″",
                        axes: Sequence[Axes] | None = None) -> np.ndarray:
    """∂ln G'/∂ln p and ∂ln G''/∂ln p over frequency for the groups and the largest single members.

    ``el`` is a :class:`tenscell.sensitivity.Elasticities`.
    """
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title)
    curves = _elasticity_curves(el)
    cols = plt.cm.tab10(np.arange(len(curves)))
    for col, (name, s, lo) in zip(cols, curves):
        a1.semilogx(el.frequency_hz, s, color=col, label=name)
        a2.semilogx(el.frequency_hz, lo, color=col, label=name)
    a1.set_ylabel("∂ln G′/∂ln p")
    a2.set_ylabel("∂ln G″/∂ln p")
    for a in ax:
        a.set_xlabel("frequency f (Hz)")
        a.axhspan(-0.8, 0.8, color="0.9", zorder=0, label="|e| ≤ 0.8: 10% in, ≤ 8% out (first order)")
    legend_outside(a2, fontsize=7)
    return ax


@styled
def monte_carlo_figure(results, bound: float = 0.08, title: str = "Monte Carlo of simultaneous ±10% perturbations",
                       axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Histograms of the largest |ΔG'/G'| and |ΔG''/G''| per draw (one colour per result)."""
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title)
    for a, attr in ((a1, "change_storage"), (a2, "change_loss")):
        top = max(float(np.nanmax(getattr(r, attr))) for r in results)
        bins = np.linspace(0.0, 100 * top, 50)  # shared bins, so the sets compare bar for bar
        for res in results:
            v = res.valid
            a.hist(100 * getattr(res, attr)[v], bins=bins, alpha=0.6, label=f"{res.label} ({v.sum()} valid draws)")
    for a, name in ((a1, "G′"), (a2, "G″")):
        a.axvline(100 * bound, color="k", ls=":", label=f"{100 * bound:g}%")
        a.set_xlabel(f"largest |Δ{name}/{name}| over frequency (%)")
        a.set_ylabel("draws")
    legend_outside(a1, fontsize=7)
    return ax


@styled
def reference_map_figure(mp, if_free_curve=None, title: str = "Valid references q0(α, δ) of the paper cell",
                         ax: Axes | None = None) -> Axes:
    """The validity map of :func:`tenscell.studies.references.prestress_map`, with the IF-free curve δ*(α)."""
    from matplotlib.colors import ListedColormap

    own = ax is None
    ax = new_axes(ax, (5.6, 5.2))
    a, d = np.degrees(mp.alpha), np.degrees(mp.delta)
    cmap = ListedColormap(["#2a9d8f", "#f1f1f1", "#e9c46a"])
    ax.pcolormesh(a, d, mp.status, cmap=cmap, vmin=-0.5, vmax=2.5, shading="nearest")
    handles: list[Any] = [plt.Rectangle((0, 0), 1, 1, color=cmap(k)) for k in range(3)]
    labels = ["valid (T0 > 0, K0 > 0)", "not prestressable", f"K0 not positive definite (P={mp.P:g}, EA={mp.EA:g})"]
    handles += ax.plot(0, 50, "k*", ms=9)
    handles += ax.plot(0, np.degrees(np.arctan(np.sqrt(2))), "kD", ms=5)
    labels += ["default reference (0°, 50°)", "regular member"]
    if if_free_curve is not None and len(if_free_curve):
        c = np.degrees(np.asarray(if_free_curve))
        handles += ax.plot(c[:, 0], c[:, 1], "k--o", ms=3, lw=1)
        labels.append("IF-free curve δ*(α)")
    ax.set_xlabel("azimuth α (degrees)")
    ax.set_ylabel("declination δ (degrees)")
    ax.set_title(title)
    if own:
        ax.figure.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=7)
    else:
        legend_outside(ax, handles, labels, fontsize=7)
    return ax


@styled
def references_figure(responses: Mapping[str, Any], P: float, title: str | None = None,
                      axes: Sequence[Axes] | None = None) -> np.ndarray:
    """G', G'' against f for several reference cells at one prestress (dict name -> FrequencyResponse)."""
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title or f"Reference shapes compared at P = {P:g}")
    cols = plt.cm.tab10(np.arange(len(responses)))
    for col, (name, r) in zip(cols, responses.items()):
        i = int(np.argmin(np.abs(r.prestress - P)))
        a1.loglog(r.frequency_hz, r.G_storage[i], color=col, label=name)
        a2.loglog(r.frequency_hz, r.G_loss[i], color=col, label=name)
    label_moduli(ax, "frequency f (Hz)")
    legend_outside(a1, fontsize=7)
    return ax


@styled
def semiflexible_figure(study, title: str = "Semiflexible struts: convergence to rigid struts",
                        axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Left: largest relative error against EA_s (log-log) with a 1/EA_s guide; right: G'(1 Hz), G''(1 Hz) against EA_s."""
    e = study.EA_strut
    f = study.frequency_hz
    k1 = int(np.argmin(np.abs(np.log(f))))
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=title)
    a1.loglog(e, study.error_storage, "o-", ms=3, label="max |ΔG′/G′|")
    a1.loglog(e, study.error_loss, "s-", ms=3, label="max |ΔG″/G″|")
    a1.loglog(e, study.constant_storage / e, "k:", label="∝ 1/EA_s")
    a1.set_xlabel("strut stiffness EA_s (N)")
    a1.set_ylabel("relative difference from rigid struts")
    legend_outside(a1)
    a2.semilogx(e, study.G[:, k1].real / study.G_rigid[k1].real, "o-", ms=3, label=f"G′({f[k1]:.3g} Hz)")
    a2.semilogx(e, study.G[:, k1].imag / study.G_rigid[k1].imag, "s-", ms=3, label=f"G″({f[k1]:.3g} Hz)")
    a2.axhline(1.0, color="0.5", ls=":")
    a2.axvline(study.strut_compression, color="0.5", ls="--", label="strut compression P·|T0_s|")
    a2.set_xlabel("strut stiffness EA_s (N)")
    a2.set_ylabel("modulus / rigid-strut modulus")
    legend_outside(a2)
    return ax


@styled
def stiffening_figure(study, title: str = "Strain-stiffening intermediate filaments",
                      axes: Sequence[Axes] | None = None) -> np.ndarray:
    """G'(P) and G''(P) at 1 Hz (or the study's grid point nearest it) for each stiffening exponent b."""
    f = study.frequency_hz
    k = int(np.argmin(np.abs(np.log(f))))
    a1, a2 = ax = new_panels(axes, 2, _PANELS, title=f"{title} (f = {f[k]:g} Hz)")
    cols = colors(len(study.b))
    for i, b in enumerate(study.b):
        a1.plot(study.prestress, study.G[i, :, k].real, color=cols[i], label=f"b = {b:g}")
        a2.plot(study.prestress, study.G[i, :, k].imag, color=cols[i], label=f"b = {b:g}")
    label_moduli(ax, "prestress P (N, the paper's Pa)")
    legend_outside(a1, title="IF stiffening")
    return ax
