"""Figures of ``tenscell study real-cells``: the medians with every model trained on 1–30 Hz, and the per-cell
G' slopes, model against measurement."""
from __future__ import annotations

from typing import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.ticker import NullFormatter

from ._style import legend_outside, new_panels, styled

__all__ = ["real_cells_medians_figure", "real_cells_slopes_figure", "real_cells_time_figure"]


@styled
def real_cells_medians_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Per line, G' (top) and G'' (bottom) of the median (error bars: bootstrap standard errors of the median) and
    every model refitted on the first split's training band (shaded: the held-out band, white)."""
    lines = list(study.medians)
    if axes is None:
        import matplotlib.pyplot as plt

        fig, grid = plt.subplots(2, len(lines), figsize=(5.0 * len(lines) + 3.5, 7.0), layout="constrained",
                                 squeeze=False)
        fig.suptitle("Xie et al. 2024 medians: models trained on the shaded band (1–30 Hz), scored outside it")
        ax = grid.T.ravel()  # per line: G', then G''
    else:
        ax = new_panels(axes, 2 * len(lines), (1.0, 1.0))
    split = study.scores[0].splits[0] if study.scores else ""
    for j, line in enumerate(lines):
        d = study.medians[line]
        rows = [s for s in study.scores if s.line == line]
        for i, (part, y, sd, name) in enumerate(((np.real, d.G_storage, d.G_storage_sd, "G′"),
                                                 (np.imag, d.G_loss, d.G_loss_sd, "G″"))):
            a = ax[2 * j + i]
            a.axvspan(1.0, 30.0, color="0.92", zorder=0)
            for k, s in enumerate(rows):
                if s.curve.size:
                    a.plot(s.curve_hz, part(s.curve), color=f"C{k % 10}", lw=1.2,
                           ls="-" if s.role == "mechanism" else "--",
                           label=f"{s.model} ({s.held_out[0]:.3f})")
            a.errorbar(d.frequency_hz, y, yerr=sd, fmt="o", color="k", ms=4, capsize=2, label="median", zorder=5)
            a.set_xscale("log")
            a.set_yscale("log")
            a.set_xlabel("frequency f (Hz)")
            a.set_ylabel(f"{name} (Pa)")
            a.set_title(f"{line}: {name}", fontsize="medium")
    legend_outside(ax[-1], fontsize="x-small", title=f"held-out RMS [{split}]")
    return ax


@styled
def real_cells_slopes_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """Per line: each cell's measured G' slope (3–30 Hz) against the slope of each model fitted to it."""
    lines = list(dict.fromkeys(c.line for c in study.cells))
    ax = new_panels(axes, max(1, len(lines)), (4.6 * max(1, len(lines)) + 2.5, 4.2),
                    title="Per cell: the fitted model's G′ slope against the cell's measured slope (3–30 Hz)")
    if not lines:
        ax[0].text(0.5, 0.5, "no per-cell fits in this run", ha="center", transform=ax[0].transAxes)
        return ax
    for j, line in enumerate(lines):
        a = ax[j]
        sets = [c for c in study.cells if c.line == line]
        lo = min(float(np.nanmin(np.r_[c.measured, c.modelled])) for c in sets)
        hi = max(float(np.nanmax(np.r_[c.measured, c.modelled])) for c in sets)
        a.plot([lo, hi], [lo, hi], color="0.6", lw=0.8, label="model = measured")
        for k, c in enumerate(sets):
            a.plot(c.measured, c.modelled, "o", ms=3, alpha=0.7, color=f"C{k % 10}",
                   label=f"{c.model} (r = {c.pearson:.2f})")
        a.set_xlabel("measured G′ slope")
        a.set_ylabel("model's G′ slope")
        a.set_title(line, fontsize="medium")
    legend_outside(ax[len(lines) - 1], fontsize="x-small")
    return ax


@styled
def real_cells_time_figure(study, axes: Sequence[Axes] | None = None) -> np.ndarray:
    """The HL60 creep compliance J(t) and the oocyte's relaxation shape F(t)/F(t_ref), each with every model fitted
    to it in the time domain."""
    series = list(dict.fromkeys(f.data for f in study.time_domain))
    ax = new_panels(axes, max(1, len(series)), (5.0 * max(1, len(series)) + 3.0, 4.2),
                    title="Measured cells in the time domain: every model fitted to each curve")
    if not series:
        ax[0].text(0.5, 0.5, "no time-domain fits in this run", ha="center", transform=ax[0].transAxes)
        return ax
    data = {ts.name: ts for ts in study.time_series}
    for j, name in enumerate(series):
        a = ax[j]
        fits = [f for f in study.time_domain if f.data == name]
        if name in data:
            a.plot(data[name].time_s, data[name].values, "o", color="k", ms=3, label="measured", zorder=5)
        for k, f in enumerate(fits):
            if f.curve:
                a.plot(*f.curve, color=f"C{k % 10}", lw=1.2, ls="-" if f.structural else "--",
                       label=f"{f.model} ({f.rms:.3f})")
        a.set_xscale("log")
        a.set_yscale("log")
        a.set_xlabel("time t (s)")
        a.xaxis.set_minor_formatter(NullFormatter())
        a.set_ylabel("J(t) (1/Pa)" if "creep" in name else "F(t) / F(t_ref)")
        a.set_title(name, fontsize="medium")
        a.legend(fontsize="x-small", title="RMS (decades)", title_fontsize="x-small")
    return ax
