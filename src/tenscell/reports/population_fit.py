"""The Markdown report of a population fitted as one (shared and per-cell parameters), and of its scores.

Rendered only from the result objects: the :class:`~tenscell.fitting.FitResult` of a
:class:`~tenscell.fitting.models.population.Population`, its per-cell table
(:func:`tenscell.fitting.population_scores.population_cells`) and, optionally, its
:class:`~tenscell.fitting.population_scores.PopulationScores`.
"""
from __future__ import annotations

import numpy as np

from ._format import num, table
from .fit import parameter_error
from .fit_analysis import identifiability_section

__all__ = ["population_fit_markdown", "population_scores_markdown"]

#: cells listed one by one in the report (more: the worst ones, and cells.csv)
_MAX_ROWS = 60


def _spread(values) -> str:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return "—"
    q25, med, q75 = np.percentile(v, [25, 50, 75])
    return f"{num(med, 4)} (quartiles {num(q25, 3)}–{num(q75, 3)}; range {num(v.min(), 3)}–{num(v.max(), 3)})"


def _summary(result, cells) -> list[str]:
    pb = result.problem
    f = np.concatenate([d.frequency_hz for d in result.datasets])
    rms = np.asarray(result.dataset_rms)
    worst = int(np.argmax(rms))
    return [
        f"- Data: {pb.n_cells} cells, {pb.n_points} points ({num(f.min())}–{num(f.max())} Hz).",
        f"- Model `{result.spec.name}`: {pb.describe()}.",
        f"- Parameters: {pb.n_shared} shared ({', '.join(pb.shared_names)}) and {pb.n_own} per cell "
        f"({', '.join(pb.own_names)}): {pb.n_free} free against {pb.n_residuals} residuals.",
        f"- RMS of the log10 errors: **{num(result.rms_log10_error, 4)}** decades over all cells; per cell "
        f"{_spread(rms)}; worst cell {worst} (`{cells['source'][worst]}`) {num(rms[worst], 3)}. Tolerance "
        f"{num(result.tolerance)} on every cell: **{result.verdict}**.",
        f"- Search: {result.starts} start(s) (seed {result.seed}), {result.n_evaluations} evaluations of every "
        f"cell, {result.elapsed_s:.1f} s; stopped: {result.stop_reason}.",
        "",
    ]


def _shared(result) -> list[str]:
    pb = result.problem
    rows = []
    for p, (se, note) in list(zip(result.parameters, result.standard_errors))[: pb.n_shared]:
        err = parameter_error(p.value, se) or (note.strip("()") or "not determined")
        rows.append((p.name, num(p.value, 4), p.unit, err, num(p.lower, 3), num(p.upper, 3), p.at_bound or ""))
    return ["## Shared parameters", "",
            "One value for every cell, with its standard error (one σ; every cell's own parameters profiled out).", "",
            table(("parameter", "value", "unit", "one standard error", "lower", "upper", "at bound"), rows), ""]


def _per_cell(result, cells) -> list[str]:
    pb = result.problem
    out = ["## Per-cell parameters", ""]
    for name in pb.own_names:
        unit = next(p.unit for p in result.parameters[pb.n_shared:] if p.name.startswith(f"{name}["))
        value = next(c for c in cells.columns if c.startswith(f"{name}_") and "_stderr_" not in c
                     and not c.endswith("_at_bound"))
        stderr = next(c for c in cells.columns if c.startswith(f"{name}_stderr_"))
        rel = cells[stderr].to_numpy(float) / cells[value].to_numpy(float)
        at = int((cells[f"{name}_at_bound"] != "").sum())
        undetermined = int((~np.isfinite(rel)).sum()) - at
        out.append(f"- `{name}` ({unit}): median {_spread(cells[value])}; relative standard error per cell "
                   f"{_spread(rel)}; {at} cell(s) at a bound, {undetermined} not determined.")
    out.append("")
    return out


def _cells_table(cells, title: str) -> list[str]:
    shown = cells
    note = ""
    if len(cells) > _MAX_ROWS:
        shown = cells.sort_values("rms_log10_error", ascending=False).head(_MAX_ROWS // 3)
        note = f"The {len(shown)} cells with the largest RMS of {len(cells)}; every cell is in `cells.csv`."
    cols = [c for c in shown.columns if c not in ("source",)]
    rows = [[num(v, 4) if isinstance(v, (float, np.floating)) else str(v) for v in r]
            for r in shown[cols].itertuples(index=False)]
    return [f"## {title}", "", table(cols, rows)] + ([note] if note else []) + [""]


def population_fit_markdown(result, cells, scores=None, title: str | None = None) -> str:
    """A Markdown report of a population fit: verdict, shared parameters, per-cell parameters, what the data
    determine (the shared parameters with the cells' own profiled out), each cell, and the scores if given.

    Parameters
    ----------
    result : FitResult
        Of a :class:`~tenscell.fitting.models.population.Population`.
    cells : pandas.DataFrame
        Its per-cell table (:func:`tenscell.fitting.population_scores.population_cells`).
    scores : PopulationScores, optional
    title : str, optional
    """
    out = [f"# {title or 'Population fitted as one: ' + result.spec.name}", ""]
    out += _summary(result, cells)
    out += _shared(result)
    out += _per_cell(result, cells)
    out += identifiability_section(result.identifiability())
    out += ["Each cell's own parameters carry their marginal standard errors (the shared parameters' uncertainty "
            "included) in `cells.csv` and `fit.json` (`identifiability.per_cell`).", ""]
    out += _cells_table(cells, "Each cell")
    if scores is not None:
        out += population_scores_markdown(scores)
    out += ["## What this does not show", "",
            "- The per-cell parameters are fitted to each cell's own data: the spread of the cells' stiffness, and "
            "its correlation with anything measured beside it, restate the data.",
            "- The standard errors are local (linearized at the optimum) and assume independent Gaussian errors in "
            "log10 G; the data give no standard deviations unless the files have sd columns.",
            "- A fit to frequency sweeps does not test the prestress dependence the model writes in.", ""]
    return "\n".join(out)


def population_scores_markdown(scores) -> list[str]:
    """The scores of a population model (:class:`~tenscell.fitting.population_scores.PopulationScores`) as lines."""
    splits = [f"train {num(lo)}–{num(hi)} Hz" if lo > 0 else f"train ≤ {num(hi)} Hz" for lo, hi in scores.splits]
    head = ["model", "fitted", "parameters k", "RMS log10 error", "BIC", "ΔBIC"] + \
        [f"held out ({s}): RMS" for s in splits] + [f"held-out cells ({scores.folds}-fold): RMS"]
    best = min(r.bic for r in scores.rows)
    rows = [[f"`{r.model}`", r.kind, r.n_params, num(r.rms_log10_error, 3), num(r.bic, 5), num(r.bic - best, 3)]
            + [num(x, 3) for x in r.heldout_frequencies] + [num(r.heldout_cells, 3)] for r in scores.rows]
    corr = [[f"{c.x} – {c.y}", c.n_cells, num(c.measured, 2), num(c.model, 2), num(c.model_vs_measured, 2)]
            for c in scores.correlations]
    return ["## Against independent per-cell formulas", "",
            f"{scores.label or 'The cells'}: the population model and per-cell structure-free formulas fitted "
            "cell by cell, on the same residuals (BIC), at each cell's frequencies outside each training window, and "
            f"on held-out cells whose own parameter{'s are' if len(scores.population.per_cell) > 1 else ' is'} set "
            f"by their measured {'G′ and G″' if len(scores.population.per_cell) > 1 else 'G′'} at "
            f"{num(scores.anchor_hz)} Hz (the formulas: their other parameters at the training cells' median).", "",
            table(head, rows), "",
            "Spearman rank correlations across cells (exponent: a springpot fitted to G′, G″ over 1–100 Hz; "
            f"stiffness: G′ at {num(scores.anchor_hz)} Hz):", "",
            table(["correlation", "cells", "measured", "population model", "model x with measured y"], corr), ""] + \
        [f"- {n}" for n in scores.notes] + [""]
