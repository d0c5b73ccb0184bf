"""Figures of cell populations: parameter distributions per condition, population moduli bands, ensembles, a
population fitted as one (:func:`population_fit_figure`).

Nothing here computes physics: the functions draw a population table
(:attr:`tenscell.population.PopulationResult.table`) or result.
"""
from __future__ import annotations

import math
import warnings

import matplotlib.pyplot as plt
import numpy as np

from ._style import colors, label_moduli, legend_outside, new_axes, new_panels, styled

__all__ = ["parameter_distributions", "population_moduli", "ensemble_moduli", "population_fit_figure"]

_LABELS = {
    "EA_actin_N": "EA actin (N)", "EA_intermediate_filament_N": "EA IF (N)", "c_Ns_per_m": "c (N·s/m)",
    "P_N": "P (N)", "L_m": "L (m)", "s_m2": "s (m²)", "rms_log10_error": "RMS log10 error",
    "prestress_elasticity_storage": "∂lnG′/∂lnP", "stiffness_spread_decades": "EA spread (decades)",
    "G_storage_ref_Pa": "G′(f_ref) (Pa)", "storage_slope": "∂lnG′/∂lnf",
}


def _conditions(table):
    conds = sorted(set(table["condition"]))
    return conds or [""]


@styled
def parameter_distributions(table, columns=(), ax=None, title: str | None = "Fitted parameters per condition",
                            extra=("rms_log10_error", "prestress_elasticity_storage")):
    """One panel per quantity: each fitted cell as a jittered point, with the median and quartiles per condition.

    Parameters
    ----------
    table : pandas.DataFrame
        Population table (only ``status == "ok"`` rows are drawn).
    columns : sequence of str
        Quantities to draw (default: every parameter column that varies, then ``extra``).
    ax : matplotlib Axes or array of Axes, optional
        One axes per quantity; default a new figure.
    extra : sequence of str
        Further columns drawn after the parameters.

    Returns
    -------
    ndarray of Axes
    """
    ok = table[table["status"] == "ok"]
    cols = [c for c in (*columns, *extra) if c in ok.columns]
    cols = [c for c in cols if ok[c].nunique(dropna=True) > 1] or cols[:1]
    conds = _conditions(table)
    palette = colors(max(len(conds), 1))
    if ax is None:
        n = len(cols)
        ncol = min(n, 3)
        fig, grid = plt.subplots(math.ceil(n / ncol), ncol, figsize=(3.2 * ncol, 2.8 * math.ceil(n / ncol)),
                                 layout="constrained", squeeze=False)
        for a in grid.flat[n:]:
            a.set_visible(False)
        axes = grid.ravel()[:n]
        if title:
            fig.suptitle(title)
    else:
        axes = np.atleast_1d(np.asarray(ax, dtype=object)).ravel()
    rng = np.random.default_rng(0)  # jitter only: the same picture every time
    for a, col in zip(axes, cols):
        for k, cond in enumerate(conds):
            v = ok.loc[ok["condition"] == cond, col].to_numpy(float)
            v = v[np.isfinite(v)]
            if not v.size:
                continue
            a.plot(k + 0.15 * rng.uniform(-1, 1, v.size), v, "o", ms=3, alpha=0.5, color=palette[k])
            q25, med, q75 = np.percentile(v, [25, 50, 75])
            a.errorbar(k + 0.3, med, yerr=[[med - q25], [q75 - med]], fmt="s", color="k", ms=4, capsize=3)
        vals = ok[col].to_numpy(float)
        vals = vals[np.isfinite(vals)]
        if vals.size and np.all(vals > 0) and vals.max() / vals.min() > 3:
            a.set_yscale("log")
        a.set_xticks(range(len(conds)), [c or "all" for c in conds], rotation=30 if len(conds) > 3 else 0)
        a.set_title(_LABELS.get(col, col))
    return np.asarray(axes)


@styled
def population_moduli(result, ax=None, title: str | None = "Population moduli: median and interquartile band"):
    """G′ (left) and G″ (right) against f: fitted median line and band, data median and quartiles, per condition.

    Parameters
    ----------
    result : PopulationResult
    ax : pair of Axes, optional
        G′ and G″ panels; default a new figure.

    Returns
    -------
    ndarray of two Axes
    """
    f = result.frequency_hz
    conds = _conditions(result.table)
    palette = colors(max(len(conds), 1))
    cond_of = result.table["condition"].to_numpy()
    axes = new_panels(ax, 2, (8.0, 3.4), title=title)
    for a, kind in ((axes[0], "storage"), (axes[1], "loss")):
        for k, cond in enumerate(conds):
            sel = cond_of == cond
            model, data = result.curves[f"model_{kind}"][sel], result.curves[f"data_{kind}"][sel]
            have = np.isfinite(model).sum(axis=0) >= 1
            if not have.any():
                continue
            with warnings.catch_warnings():  # all-NaN columns of one condition: a gap, not an error
                warnings.simplefilter("ignore", RuntimeWarning)
                mq = np.nanpercentile(model[:, have], [25, 50, 75], axis=0)
                dq = np.nanpercentile(data[:, have], [25, 50, 75], axis=0)
            label = cond or "all cells"
            a.fill_between(f[have], mq[0], mq[2], color=palette[k], alpha=0.25, lw=0)
            a.loglog(f[have], mq[1], color=palette[k], label=f"{label}: fit")
            a.errorbar(f[have][::2], dq[1][::2], yerr=[(dq[1] - dq[0])[::2], (dq[2] - dq[1])[::2]], fmt="o",
                       ms=3, color=palette[k], mfc="none", capsize=2, lw=0.8, label=f"{label}: data")
    label_moduli(axes, "f (Hz)")
    legend_outside(axes[0])
    return np.asarray(axes)


@styled
def ensemble_moduli(result, ax=None, title: str | None = None):
    """An ensemble's mean G′ (solid) and G″ (dashed) with their 5–95 % band, and the fit's own average (circles).

    Against frequency (one colour per prestress), or against prestress when the ensemble has one frequency.

    Parameters
    ----------
    result : tenscell.population.EnsembleResult
    ax : Axes, optional

    Returns
    -------
    Axes
    """
    ax = new_axes(ax)
    mean, (lo, hi), ref = result.mean, result.band(), result.reference
    by_prestress = result.frequency_hz.size == 1 and result.prestress.size > 1
    if by_prestress:  # one curve against prestress: transpose the (nP, nf) grids
        x, mean, lo, hi, ref = result.prestress, mean.T, lo.T, hi.T, ref.T
        labels = [f"{f:.3g} Hz" for f in result.frequency_hz]
    else:
        x = result.frequency_hz
        labels = [f"{p:.4g} {result.prestress_unit}" for p in result.prestress]
    palette = colors(max(len(labels), 1))
    for i, label in enumerate(labels):
        for part, style in ((np.real, "-"), (np.imag, "--")):
            ax.fill_between(x, part(lo[i]), part(hi[i]), color=palette[i], alpha=0.2, lw=0)
            ax.plot(x, part(mean[i]), style, color=palette[i],
                    label=f"{label}: {'G′' if part is np.real else 'G″'} mean"
                    if len(labels) < 6 or i in (0, len(labels) - 1) else None)  # many: the first and the last
            ax.plot(x, part(ref[i]), "o", ms=3, mfc="none", color=palette[i])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"prestress ({result.prestress_unit})" if by_prestress else "f (Hz)")
    ax.set_ylabel("G′, G″ (Pa)")
    ax.set_title(title if title is not None else f"{result.mechanism}: {result.K} assignments, 5–95 % band;\n"
                 f"circles: the fit's {result.reference_K}-assignment average", fontsize="small")
    ax.legend(fontsize="x-small")
    return ax


@styled
def population_fit_figure(result, cells, ax=None, title: str | None = None, n: int = 100):
    """A population fitted as one: every cell's G′ (left), G″ (middle), data (points) and fitted model (lines), the
    typical cell in black; right, each cell's exponent against its stiffness, measured (open) and fitted (filled).

    Parameters
    ----------
    result : FitResult
        Of a :class:`~tenscell.fitting.models.population.Population`.
    cells : pandas.DataFrame
        :func:`tenscell.fitting.population_scores.population_cells` of ``result``.
    ax : three Axes, optional
    n : int
        Frequencies of each model curve.

    Returns
    -------
    ndarray of three Axes
    """
    axes = new_panels(ax, 3, (11.0, 3.4), title=title)
    pb = result.problem
    order = np.argsort(np.argsort(cells["stiffness_model_Pa"].to_numpy()))
    palette = plt.get_cmap("viridis")(np.linspace(0.05, 0.95, max(pb.n_cells, 2)))
    for k, d in enumerate(result.datasets):
        c = palette[order[k]]
        f = np.logspace(math.log10(d.frequency_hz.min()), math.log10(d.frequency_hz.max()), n)
        Gs, Gl = result.moduli(f, dataset=k)
        for a, G, data in ((axes[0], Gs, d.G_storage), (axes[1], Gl, d.G_loss)):
            a.loglog(f, G, color=c, lw=0.6, alpha=0.6)
            a.loglog(d.frequency_hz, data, "o", ms=2, color=c, alpha=0.6)
    d0 = result.datasets[pb.reference_cell]
    f = np.logspace(math.log10(d0.frequency_hz.min()), math.log10(d0.frequency_hz.max()), n)
    Gs, Gl = result.moduli(f)
    axes[0].loglog(f, Gs, "k", lw=2, label="typical cell")
    axes[1].loglog(f, Gl, "k", lw=2)
    axes[0].set_title("G′: data (points), fit (lines)")
    axes[1].set_title("G″")
    label_moduli(axes[:2], "f (Hz)")
    a = axes[2]
    a.semilogx(cells["stiffness_measured_Pa"], cells["exponent_measured"], "o", mfc="none", color="0.3", ms=4,
               label="measured")
    a.semilogx(cells["stiffness_model_Pa"], cells["exponent_model"], "o", color="C1", ms=3, label="fitted cell")
    a.set_xlabel(f"G′ at {cells.attrs.get('anchor_Hz', 10):g} Hz (Pa)")
    a.set_ylabel("exponent (springpot, 1–100 Hz)")
    a.set_title("exponent against stiffness")
    a.legend(fontsize=8)
    axes[0].legend(fontsize=8, loc="lower right")
    return np.asarray(axes)
