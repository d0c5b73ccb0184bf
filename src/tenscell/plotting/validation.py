"""Figures of the validation against measured cells (``tenscell study real-cells``, docs/validation.md).

Each function takes plain arrays (what a study computed; nothing is fitted here) and draws on the axes it is given:

* :func:`heldout_bands`: each model's held-out error as a band (the fits the training data cannot tell apart) per
  cell line, beside the goal's limit;
* :func:`population_cells`: a population's cells against the model, exponent against stiffness, measured and
  modelled (and the model with the measurement's scatter added), each with its least-squares slope;
* :func:`slope_scatter`: each cell's measured G' slope against the slope of a model fitted to it (one panel per
  model and line: :func:`cell_slopes_figure`).

:func:`validation_figures` draws all three from a :class:`~tenscell.studies.real_cells_study.RealCellsStudy`.
"""
from __future__ import annotations

import textwrap
from typing import Any, Mapping, Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ._style import figure_of, legend_below, new_axes, new_panels, styled, wrap

__all__ = ["validation_figure", "heldout_bands", "heldout_bands_figure", "population_cells", "population_cells_figure", "slope_scatter",
           "cell_slopes_figure", "validation_figures", "LINE_COLORS"]

#: one colour per cell line, the same in every figure (colour-blind safe: blue, orange, then the rest of tab10)
LINE_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b")


@styled
def heldout_bands(models: Sequence[str], low, high, best=None, *, columns: Sequence[str] = ("held out",),
                  limit: float | None = None, reference: str | None = None, ax: Axes | None = None,
                  xlabel: str = "held-out RMS of the log10 errors (decades)") -> Axes:
    """Each model's held-out error as a band per column (a cell line, a split), models top to bottom.

    Parameters
    ----------
    models : sequence of str
        One row each, drawn top to bottom.
    low, high : array_like, shape (n_models, n_columns)
        The band's ends (decades): the held-out RMS over the fits the training data cannot tell apart. Equal ends
        draw a point; NaN draws nothing (no score).
    best : array_like, shape (n_models, n_columns), optional
        The best fit's own held-out RMS, marked on its band.
    columns : sequence of str
        What each column is (legend), e.g. the cell lines.
    limit : float, optional
        The goal's limit (decades), a vertical dashed line.
    reference : str, optional
        A model whose row is shaded (e.g. the strongest structure-free baseline).
    ax : Axes, optional
    xlabel : str

    Returns
    -------
    Axes
    """
    lo = np.atleast_2d(np.asarray(low, dtype=float))
    hi = np.atleast_2d(np.asarray(high, dtype=float))
    if lo.shape != hi.shape or lo.shape != (len(models), len(columns)):
        raise ValueError(f"low and high: expected shape ({len(models)}, {len(columns)}) (models × columns), got "
                         f"{lo.shape} and {hi.shape}")
    mid = None if best is None else np.atleast_2d(np.asarray(best, dtype=float))
    ax = new_axes(ax, (6.2, 0.5 * len(models) + 1.4))
    n = len(columns)
    offsets = (np.arange(n) - (n - 1) / 2) * min(0.28, 0.8 / max(n, 1))
    y = np.arange(len(models))[::-1].astype(float)
    for j, name in enumerate(columns):
        color = LINE_COLORS[j % len(LINE_COLORS)]
        yy = y + offsets[j]
        ok = np.isfinite(lo[:, j]) & np.isfinite(hi[:, j])
        ax.hlines(yy[ok], lo[ok, j], hi[ok, j], color=color, lw=5, alpha=0.55, label=name)
        ax.plot(lo[ok, j], yy[ok], "|", color=color, ms=9, mew=1.5)
        ax.plot(hi[ok, j], yy[ok], "|", color=color, ms=9, mew=1.5)
        if mid is not None:
            m = ok & np.isfinite(mid[:, j])
            ax.plot(mid[m, j], yy[m], "o", color=color, mec="white", ms=6, zorder=4)
    if mid is not None:  # one entry for the markers of every column
        ax.plot([], [], "o", color="0.35", mec="white", ms=6, label="the best training fit")
    if reference is not None and reference in models:
        k = list(models).index(reference)
        ax.axhspan(y[k] - 0.45, y[k] + 0.45, color="0.92", zorder=0)
    if limit is not None:
        ax.axvline(limit, color="0.25", ls="--", lw=1.0, label=f"limit {limit:g}")
    ax.set_yticks(y, [textwrap.fill(str(m), 30, break_on_hyphens=False) for m in models])
    ax.set_ylim(-0.6, len(models) - 0.4)
    ax.set_xlabel(xlabel)
    ax.grid(axis="y", visible=False)
    return ax


@styled
def heldout_bands_figure(models: Sequence[str], low, high, best=None, *, columns: Sequence[str] = ("held out",),
                         limit: float | None = None, reference: str | None = None, title: str | None = None) -> Axes:
    """:func:`heldout_bands` on a new figure, its legend below (arguments as there)."""
    ax = heldout_bands(models, low, high, best, columns=columns, limit=limit, reference=reference)
    fig = figure_of(ax)
    if title:
        fig.suptitle(wrap(title, 0.95 * fig.get_figwidth()), fontsize="medium")
    legend_below([ax])
    return ax


def _line_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float] | None:
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3 or np.ptp(x[ok]) == 0:
        return None
    slope, intercept = np.polyfit(x[ok], y[ok], 1)
    return float(slope), float(intercept)


@styled
def population_cells(measured_stiffness, measured_exponent, model_stiffness, model_exponent, *,
                     simulated_stiffness=None, simulated_exponent=None, title: str | None = None,
                     ax: Axes | None = None) -> Axes:
    """A population's cells against the model: each cell's exponent against its stiffness (log axis), measured
    (grey) and as the population model fits it (colour), each cloud with its least-squares line; the title gives
    each line's slope dα/dlog10 k.

    Parameters
    ----------
    measured_stiffness, measured_exponent : array_like, shape (n_cells,)
        Each cell's measured stiffness (Pa) and exponent.
    model_stiffness, model_exponent : array_like, shape (n_cells,)
        The same of each cell as the population model fitted it.
    simulated_stiffness, simulated_exponent : array_like, optional
        The model population with the measurement's scatter added (a simulated measurement), drawn as open
        circles with its own line.
    title : str, optional
        The panel's first title line (the slopes follow it).
    ax : Axes, optional

    Returns
    -------
    Axes
    """
    ax = new_axes(ax, (4.8, 4.2))
    sets: list[tuple[str, Any, Any, dict[str, Any]]] = [
        ("measured", measured_stiffness, measured_exponent, {"color": "0.45", "marker": "o", "ms": 4.5,
                                                             "alpha": 0.75}),
        ("model", model_stiffness, model_exponent, {"color": LINE_COLORS[0], "marker": "o", "ms": 4.0,
                                                    "alpha": 0.85})]
    if simulated_stiffness is not None and simulated_exponent is not None:
        sets.append(("model + measured scatter", simulated_stiffness, simulated_exponent,
                     {"color": LINE_COLORS[1], "marker": "o", "ms": 4.5, "mfc": "none", "alpha": 0.85}))
    slopes = []
    for name, k, a, style in sets:
        k = np.asarray(k, dtype=float)
        a = np.asarray(a, dtype=float)
        lk = np.log10(np.where(k > 0, k, np.nan))
        fitted = _line_fit(lk, a)
        ax.plot(k, a, ls="none", label="measured cells" if name == "measured" else
                "population model" if name == "model" else name, **style)
        if fitted is not None:
            xs = np.linspace(np.nanmin(lk), np.nanmax(lk), 20)
            ax.plot(10.0 ** xs, fitted[1] + fitted[0] * xs, "-", color=style["color"], lw=1.3)
            slopes.append(f"{name} {fitted[0]:+.3f}")
    ax.set_xscale("log")
    # 1-2-5 ticks in plain numbers: a population spans about a decade, where 10^n ticks alone say little and
    # matplotlib's minor labels overlap
    ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("stiffness k (Pa)")
    ax.set_ylabel("exponent α")
    head = f"{title}\n" if title else ""
    ax.set_title(head + "dα/dlog10 k: " + (", ".join(slopes) or "too few cells"), fontsize="medium")
    return ax


@styled
def population_cells_figure(lines: Mapping[str, Mapping[str, Sequence[float]]], title: str | None = None,
                            axes: Sequence[Axes] | None = None) -> np.ndarray:
    """:func:`population_cells` for each cell line, one panel each, one legend below them.

    Parameters
    ----------
    lines : mapping of str to mapping
        Per line, its cells' arrays under the names of
        :attr:`tenscell.fitting.population_scores.PopulationScores.cells`: ``stiffness_measured_Pa``,
        ``exponent_measured``, ``stiffness_model_Pa``, ``exponent_model``, and optionally
        ``stiffness_simulated_Pa``, ``exponent_simulated`` (the model with the measurement's scatter added).
    title : str, optional
    axes : sequence of Axes, optional

    Returns
    -------
    ndarray of Axes
    """
    names = list(lines)
    ax = new_panels(axes, max(1, len(names)), (4.3 * max(1, len(names)) + 0.6, 4.6), title=title, sharey=True)
    for a, name in zip(ax, names):
        c = lines[name]
        population_cells(c["stiffness_measured_Pa"], c["exponent_measured"], c["stiffness_model_Pa"],
                         c["exponent_model"], simulated_stiffness=c.get("stiffness_simulated_Pa"),
                         simulated_exponent=c.get("exponent_simulated"),
                         title=f"{name} ({len(c['exponent_measured'])} cells)", ax=a)
    for a in ax[1:]:
        a.set_ylabel("")
    if axes is None:
        legend_below(ax)
    return ax


def _correlation(x: np.ndarray, y: np.ndarray) -> float:
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3 or np.std(x[ok]) == 0 or np.std(y[ok]) == 0:
        return float("nan")
    return float(np.corrcoef(x[ok], y[ok])[0, 1])


@styled
def slope_scatter(measured, modelled, *, title: str | None = None, color: str = "C0",
                  limits: tuple[float, float] | None = None, ax: Axes | None = None) -> Axes:
    """Each cell's measured G' slope against the slope of a model fitted to it, with the line model = measured;
    the title gives their correlation r and the RMS of model − measured.

    Parameters
    ----------
    measured, modelled : array_like, shape (n_cells,)
        The cells' measured slopes and the model's (NaN: not fitted, not drawn).
    title : str, optional
        The panel's first title line (the model, the line).
    color : str
    limits : (float, float), optional
        Both axes' range (default the points' own).
    ax : Axes, optional

    Returns
    -------
    Axes
    """
    ax = new_axes(ax, (4.0, 4.0))
    meas = np.asarray(measured, dtype=float)
    mod = np.asarray(modelled, dtype=float)
    ok = np.isfinite(meas) & np.isfinite(mod)
    ax.plot(meas[ok], mod[ok], "o", ms=3.5, alpha=0.75, color=color, label="cells")
    if limits is None:
        v = np.r_[meas[ok], mod[ok]]
        lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 1.0)
        pad = 0.05 * (hi - lo or 1.0)
        limits = (lo - pad, hi + pad)
    ax.plot(limits, limits, color="0.4", lw=0.9, ls="--", label="model = measured", zorder=0)
    ax.set_xlim(*limits)
    ax.set_ylim(*limits)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("measured G′ slope")
    ax.set_ylabel("model's G′ slope")
    rms = float(np.sqrt(np.mean((mod[ok] - meas[ok]) ** 2))) if ok.any() else float("nan")
    head = f"{title}\n" if title else ""
    ax.set_title(f"{head}r = {_correlation(meas, mod):.2f}, RMS difference {rms:.3f} ({int(ok.sum())} cells)",
                 fontsize="small")
    return ax


@styled
def cell_slopes_figure(lines: Mapping[str, tuple], title: str | None = None,
                       axes: Sequence[Axes] | None = None) -> np.ndarray:
    """:func:`slope_scatter` for every model (rows) and cell line (columns), on shared axes.

    Parameters
    ----------
    lines : mapping of str to (measured, modelled)
        Per line: the measured slopes (one array, or a mapping model -> array when the models' cells differ) and a
        mapping model -> the model's slopes at those cells.
    title : str, optional
    axes : sequence of Axes, optional
        One per (model, line), row by row.

    Returns
    -------
    ndarray of Axes, shape (n_models * n_lines,)
    """
    names = list(lines)
    models = list(dict.fromkeys(m for _, modelled in lines.values() for m in modelled))
    if not models:
        ax = new_panels(axes, 1, (4.6, 2.4), title=title)
        ax[0].text(0.5, 0.5, "no per-cell fits in this run", ha="center", va="center", transform=ax[0].transAxes)
        ax[0].set_axis_off()
        return ax
    cells = [(m, ln) for m in models for ln in names]
    every = np.concatenate([np.r_[np.ravel(meas[m] if isinstance(meas, Mapping) else meas), np.ravel(mod[m])]
                            for ln, (meas, mod) in lines.items() for m in mod] or [np.zeros(1)])
    every = every[np.isfinite(every)]
    lo, hi = (float(every.min()), float(every.max())) if every.size else (0.0, 1.0)
    pad = 0.05 * (hi - lo or 1.0)
    if axes is None:
        import matplotlib.pyplot as plt

        fig, grid = plt.subplots(len(models), len(names), figsize=(3.3 * len(names) + 0.6, 3.0 * len(models) + 0.7),
                                 layout="constrained", squeeze=False, sharex=True, sharey=True)
        if title:
            fig.suptitle(wrap(title, 3.2 * len(names)), fontsize="medium")
        ax = grid.ravel()
    else:
        ax = new_panels(axes, len(cells), (1.0, 1.0))
    for k, (a, (model, line)) in enumerate(zip(ax, cells)):
        meas, mod = lines[line]
        if model not in mod:
            a.set_visible(False)
            continue
        slope_scatter(meas[model] if isinstance(meas, Mapping) else meas, mod[model], title=f"{model}: {line}",
                      color=LINE_COLORS[names.index(line) % len(LINE_COLORS)], limits=(lo - pad, hi + pad), ax=a)
        if axes is None:  # the outer panels carry the labels
            if k % len(names):
                a.set_ylabel("")
            if k < len(cells) - len(names):
                a.set_xlabel("")
    return ax


def _heldout_figure(study):
    lines = list(study.medians)
    split = study.g3.split
    models = list(dict.fromkeys(s.model for s in study.scores))
    if not models:
        return None
    held = np.full((len(models), len(lines)), np.nan)
    low, high = held.copy(), held.copy()
    for s in study.scores:
        i, j = models.index(s.model), lines.index(s.line)
        held[i, j] = s.held(split)
        low[i, j], high[i, j] = s.band(split)  # over the fits the training data cannot tell apart
    order = np.argsort(np.nanmax(high, axis=1), kind="stable")
    return heldout_bands_figure(
        [models[i] for i in order], low[order], high[order], held[order], columns=lines, limit=study.g3.limit,
        reference="structural-damping+newtonian", title=f"Every model on the medians, held out ({split})")


def _population_figure(study):
    populations: dict = {}
    for line, scores, _ in study.populations:
        populations.setdefault(line, scores)
    if not populations:
        return None
    name = next(iter(populations.values())).population.name
    return population_cells_figure({line: sc.cells for line, sc in populations.items()},
                                   title=f"Each cell's exponent against its stiffness: measured, and fitted by {name}")


def _slopes_figure(study):
    per_line: dict = {}
    for c in study.cells:
        meas, mod = per_line.setdefault(c.line, ({}, {}))
        meas[c.model] = c.measured
        mod[c.model] = c.modelled
    return cell_slopes_figure(per_line, title="Per cell: the fitted model's G′ slope (3–30 Hz) against the measured one")


#: the validation page's figures by file stem
_FIGURES = {"validation_heldout": _heldout_figure, "validation_population": _population_figure,
            "validation_slopes": _slopes_figure}


def validation_figure(study, name: str):
    """One of :func:`validation_figures` by its file stem (None when the run has nothing to draw there): what a
    study's :class:`~tenscell.studies.protocol.Figure` names."""
    return _FIGURES[name](study)


def validation_figures(study) -> dict:
    """The validation page's figures from a :class:`~tenscell.studies.real_cells_study.RealCellsResult`, by file
    stem: ``"validation_heldout"`` (every model on the medians, the first split, per line, with G3's limit and the
    held-out bands), ``"validation_slopes"`` (the per-cell slopes; a panel saying so when the run fitted no cell)
    and, when the run scored populations, ``"validation_population"`` (each line's first population model: the
    mechanism's)."""
    out = {name: draw(study) for name, draw in _FIGURES.items()}
    return {name: fig for name, fig in out.items() if fig is not None}
