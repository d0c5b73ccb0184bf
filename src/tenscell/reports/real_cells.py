"""Markdown and CSV rows of ``tenscell study real-cells`` (:mod:`tenscell.studies.real_cells_study`), rendered only
from the study's fields: every number is one the run computed."""
from __future__ import annotations

import math

from ._format import num, table

__all__ = ["population_rows", "POPULATION_COLUMNS", "time_rows", "TIME_COLUMNS", "real_cells_markdown", "validation_tables", "median_rows", "MEDIAN_COLUMNS", "cell_rows", "CELL_COLUMNS",
           "g3_rows", "G3_COLUMNS"]

MEDIAN_COLUMNS = ("line", "model", "role", "formula", "free_parameters", "rms_decades", "AIC", "BIC", "fit",
                  "at_bound", "split", "train_rms_decades", "held_out_rms_decades", "cpu_s")
G3_COLUMNS = ("mechanism", "free_parameters", "formula", "formula_free_parameters", "line", "held_out_rms_decades",
              "formula_held_out_rms_decades", "within_limit_both_lines", "beats_formula", "no_more_parameters", "met")
CELL_COLUMNS = ("line", "model", "cell", "measured_Gstorage_slope", "model_Gstorage_slope", "rms_decades")
POPULATION_COLUMNS = ("line", "population", "model", "kind", "free_parameters", "rms_decades", "BIC",
                      "held_out_train_le_30Hz_decades", "held_out_train_3_100Hz_decades", "held_out_cells_decades")
TIME_COLUMNS = ("series", "model", "structural", "free_parameters", "rms_decades", "rms_late_decades",
                "local_exponent", "at_bound", "message", "cpu_s")

#: what the data cannot tell, next to the numbers it qualifies (the texts are real_cells.FACTS')
_QUALIFY = {
    "held_high": "The 100 and 200 Hz points scored here carry the undocumented hydrodynamic-drag correction: part of "
                 "the rise of G'' there may be instrumental, so a model that misses it is not necessarily wrong.",
    "held_low": "The 1 Hz point held out by the second split is the least reliable of the spectrum (in the per-cell "
                "data 11 rows have G' ≤ 0 and 22 have G'' ≤ 0 there).",
    "selection": "Every spectrum is the authors' pick of a monotone curve per cell: the cells and curves whose G', G'' "
                 "do not rise with frequency are absent, so these data cannot show a model failing on them.",
}


def median_rows(study):
    """One row per line × model × split (the in-sample numbers repeated on each split's row)."""
    for s in study.scores:
        for k, name in enumerate(s.splits):
            yield (s.line, s.model, s.role, s.formula, s.n_params, s.rms, s.aic, s.bic, s.verdict,
                   " ".join(s.at_bound), name, s.train_rms[k], s.held_out[k], round(s.cpu_s, 2))


def g3_rows(study):
    for r in study.g3.rows:
        for line, h in r.held.items():
            yield (r.model, r.n_params, r.formula, r.formula_n_params, line, h, r.formula_held.get(line, math.nan),
                   r.within_limit, r.beats_formula, r.no_more_parameters, r.met)


def cell_rows(study):
    for c in study.cells:
        for i, idx in enumerate(c.cells):
            yield (c.line, c.model, idx, c.measured[i], c.modelled[i], c.rms[i])


def time_rows(study):
    for f in study.time_domain:
        yield (f.data, f.model, f.structural, f.n_params, f.rms, f.rms_late, f.local_exponent, " ".join(f.at_bound),
               f.message, round(f.cpu_s, 2))


def population_rows(study):
    for line, sc, _ in study.populations:
        for r in sc.rows:
            yield (line, sc.population.name, r.model, r.kind, r.n_params, r.rms_log10_error, r.bic,
                   *r.heldout_frequencies, r.heldout_cells)


def _population_section(study) -> list:
    out = ["### Populations: shared material, one parameter per cell (G4)\n"]
    for line, sc, cpu in study.populations:
        head = ["model", "kind", "free", "RMS", "BIC",
                *[f"held out: train {lo:g}–{hi:g} Hz" for lo, hi in sc.splits], f"held-out cells ({sc.folds}-fold)"]
        rows = [[f"`{r.model}`", r.kind, r.n_params, num(r.rms_log10_error, 3), num(r.bic, 5),
                 *[num(x, 3) for x in r.heldout_frequencies], num(r.heldout_cells, 3)] for r in sc.rows]
        out += [f"**{line}** ({sc.n_cells} of its {study.n_cells[line]} cells: those with 4 frequencies or more in "
                f"both training windows; {cpu:.0f} s of CPU): `{sc.population.name}`\n", table(head, rows)]
        corr = [[c.x, c.y, num(c.measured, 2), num(c.model, 2), c.n_cells] for c in sc.correlations]
        out += [table(["Spearman of", "with", "measured", "population model", "cells"], corr)]
        out += ["\n".join(f"- {n}" for n in sc.notes) + "\n"]
    if study.g4:
        head = ["line", "population", "BIC", "per-cell laws' BIC", "held-out cells", "per-cell laws'",
                "Spearman exponent–stiffness model (measured)", "G4"]
        rows = [[g.line, f"`{g.model}`", num(g.bic, 5), ", ".join(num(b, 5) for b in g.baseline_bic.values()),
                 num(g.heldout_cells, 3), ", ".join(num(b, 3) for b in g.baseline_heldout_cells.values()),
                 f"{g.spearman_model:+.2f} ({g.spearman_measured:+.2f})", "met" if g.met else "missed"]
                for g in study.g4]
        out += ["**G4** (the mechanism's population beats the independent per-cell power laws on BIC and on held-out "
                f"cells, and its exponent–stiffness Spearman correlation is within ±{study.g4[0].tol:g} of the "
                "measured one):\n", table(head, rows)]
        out += ["\n".join(f"- {g.line}: " + (g.why_not() or "met") for g in study.g4) + "\n"]
    return out


def _time_table(study) -> str:
    from ..studies.real_cells_time import LATE_S

    head = ["series", "model", "free", "RMS (decades)", f"RMS t ≥ {LATE_S:g} s", "local exponent (mid-range)",
            "at bound", "CPU s"]
    rows = [[f.data, f"`{f.model}`", f.n_params, num(f.rms, 3), num(f.rms_late, 3), num(f.local_exponent, 3),
             ", ".join(f.at_bound) or "—", f"{f.cpu_s:.1f}"] for f in study.time_domain]
    return table(head, rows)


def _g3_table(study) -> str:
    g = study.g3
    lines = list(g.reference)
    head = ["mechanism", "free", *[f"held out {ln}" for ln in lines], "its formula (free)",
            *[f"formula {ln}" for ln in lines], f"≤ {g.limit:g} both", "as good as its formula",
            "no more free than its formula", "G3"]
    rows = [[f"`{r.model}`", r.n_params, *[num(r.held.get(ln), 3) for ln in lines],
             f"{r.formula} ({r.formula_n_params})", *[num(r.formula_held.get(ln), 3) for ln in lines],
             _yes(r.within_limit), _yes(r.beats_formula), _yes(r.no_more_parameters), "met" if r.met else "missed"]
            for r in g.rows]
    ref = [["power law + Newtonian (reference)", 3, *[num(g.reference[ln], 3) for ln in lines], "—",
            *["—" for _ in lines], _yes(all(v <= g.limit for v in g.reference.values())), "—", "—", "—"]]
    return table(head, rows + ref)


def _yes(b: bool) -> str:
    return "yes" if b else "no"


def _median_table(study, line: str) -> str:
    splits = study.scores[0].splits if study.scores else ()
    head = ["model", "role", "free", "RMS (all 6 f)", "AIC", "BIC", "fit", "at bound",
            *[h for name in splits for h in (f"train RMS [{name}]", f"held out [{name}]")], "CPU s"]
    rows = []
    for s in sorted((s for s in study.scores if s.line == line), key=lambda s: s.held_out[0]):
        rows.append([f"`{s.model}`", s.role + (f" ({s.formula})" if s.role == "formula" else ""), s.n_params,
                     num(s.rms, 3), num(s.aic, 4), num(s.bic, 4), s.verdict, ", ".join(s.at_bound) or "—",
                     *[num(x, 3) for k in range(len(splits)) for x in (s.train_rms[k], s.held_out[k])],
                     f"{s.cpu_s:.1f}"])
    return table(head, rows)


def _cells_table(study) -> str:
    head = ["line", "model", "cells", "slope correlation (Pearson)", "Spearman", "RMS model − measured slope",
            "median fit RMS", "fits ≤ tolerance"]
    rows = [[c.line, f"`{c.model}`", len(c.cells), num(c.pearson, 3), num(c.spearman, 3), num(c.slope_rms, 3),
             num(float(_nanmedian(c.rms)), 3), f"{c.converged}/{len(c.cells)}"] for c in study.cells]
    return table(head, rows)


def _fit_column(study) -> str:
    """Why the medians' fits say what they say: their tolerance against the medians' own standard errors."""
    import numpy as np

    noise = []
    for line, d in study.medians.items():
        if d.G_storage_sd is not None and d.G_loss_sd is not None:
            rel = np.r_[d.G_storage_sd / d.G_storage, d.G_loss_sd / d.G_loss] / np.log(10.0)
            noise.append(f"{line} {float(np.sqrt(np.mean(rel ** 2))):.3f}")
    return ("The fit column compares each fit with a tolerance of 0.01 decades or, where it is larger, the data's "
            "stated noise: here the medians' bootstrap standard errors, in decades (RMS over the six frequencies): "
            + ", ".join(noise) + ". A fit whose misfit exceeds both says \"tolerance not met at an optimum\" when the "
            "search stopped at an optimum it could not improve (the model does not fit to that tolerance; not a failed "
            "search), or \"NOT converged: stopped by its budget\" when its starts ran all their hops still improving.")


def _nanmedian(x) -> float:
    import numpy as np

    x = np.asarray(x, float)
    return float(np.median(x[np.isfinite(x)])) if np.isfinite(x).any() else math.nan


def validation_tables(study) -> str:
    """The tables of the validation page (docs/validation.md): G3, every model on each median, the per-cell slopes,
    and the run's cost."""
    b, cb = study.budgets["medians"], study.budgets["cells"]
    out = [f"### G3: held out {study.g3.split} on the medians\n", _g3_table(study), study.g3.text() + ".\n"]
    for line in study.medians:
        out += [f"### {line} median: every model\n", _median_table(study, line)]
    out.append(_fit_column(study) + "\n")
    out.append(_QUALIFY["held_high"] + " " + _QUALIFY["held_low"] + "\n")
    if study.cells:
        out += ["### Per cell: the model's G' slope (3–30 Hz) against the cell's\n", _cells_table(study),
                "A cell's fit has no stated noise, so its tolerance (0.01 decades) is a target of the search, not a "
                "verdict: the per-cell spectra scatter more than that (the median fit RMS column). "
                + _QUALIFY["selection"] + "\n"]
    else:
        out.append("Per-cell fits: not run in this run.\n")
    if study.populations:
        out += _population_section(study)
    else:
        out.append("Populations and G4: not run in this run (`--populations`).\n")
    if study.time_domain:
        out += ["### Time domain: the HL60 creep curve and the oocyte relaxation's shape\n", _time_table(study),
                "One cell each, other cell types than the Xie lines. The oocyte's force has no modulus scale (the probe "
                "radius is unknown): only its shape, force over the force at the first bin, is fitted, and one "
                "combination of a mechanism's parameters is not determined by it (not counted among the free "
                "parameters). Its first second includes the end of the approach ramp: the late RMS is beside the "
                "whole one. The HL60 compliance depends on the optical stress model used to compute it. The power law (and "
                "for creep the power law + Newtonian) is the only structure-free baseline fitted here: a mechanism's "
                "own formula is not fitted in the time domain, so a mechanism that beats the power law is not shown "
                "to need its structure.\n"]
    else:
        out.append("Time domain (HL60 creep, oocyte relaxation): not run in this run (`--time-domain`).\n")
    cells = (f"; per cell: {cb.starts} starts × up to {cb.hops} hops, cells per line: "
             + ", ".join(f"{k} {v}" for k, v in study.n_cells.items())) if cb is not None else ""
    out.append(f"Cost: {study.cpu_s:.0f} s of CPU, {study.wall_s:.0f} s wall (load average {study.load[0]:.1f} at "
               f"the start, {study.load[1]:.1f} at the end, on {_cpus()} CPUs); medians: {b.starts} starts × up to "
               f"{b.hops} hops per fit, seed {b.seed}{cells}.\n")
    return "\n".join(out)


def _cpus() -> int:
    import os

    return os.cpu_count() or 1


def real_cells_markdown(study) -> str:
    """The study's report (real_cells.md)."""
    facts = "\n".join(f"- {f}" for f in study.facts)
    return "\n".join([
        "# The mechanisms against measured cells (`tenscell study real-cells`)\n",
        f"Data: the Xie et al. 2024 AFM spectra in `{study.directory}` (read at run time, never shipped): the median "
        "spectrum of each line (weighted by its bootstrap standard errors of the median) and each cell's own "
        "spectrum. Each model is fitted to all six frequencies (in sample) and refitted on each split's training "
        "frequencies and scored, unweighted, on the held-out ones (RMS of the log10 errors of G' and G'', "
        "decades). The prestress of these cells is not measured: every mechanism's prestress is fitted, so the "
        "mechanisms here are free-gauge fits, not anchored ones.\n",
        "G3 asks of a mechanism: held-out RMS (train 1–30 Hz → 100, 200 Hz) ≤ 0.08 decades on both lines, at least "
        "as good as its own structure-free formula on each line, with no more free parameters than that formula.\n",
        validation_tables(study),
        "## What these data cannot tell\n", facts + "\n",
        *(["## Not done in this run\n",
           "- the population models and G4 (`--populations`): not evaluated here, and no number in this report speaks "
           "for them.\n"] if not study.populations else []),
    ])
