"""Markdown of the mechanisms study, rendered only from its result fields (a mechanism fit's own report is
:func:`tenscell.reports.fit.fit_markdown`, as every fit's)."""
from __future__ import annotations

import math

from ..fitting.models.catalog import MECHANISMS, PER_TENDON_VOIGT
from ._format import num, table

__all__ = ["mechanisms_markdown", "study_table_rows", "STUDY_COLUMNS"]


def _held(mech, where: str = "") -> str:
    """'Held, not fitted: ...' for a mechanism's fixed fields, or '' when every law parameter is fitted."""
    held = [f"`{f.law_parameter}` = {num(f.value)}" for f in mech.fields if f.layout == "fixed"]
    return (f"Held, not fitted{where} (not counted among the free parameters, and not measured by this fit): "
            + ", ".join(held) + ".") if held else ""


#: the study table's columns (CSV header; the Markdown's two tables take them in the same order)
STUDY_COLUMNS = ("model", "kind", "free_parameters", "stiffness_spread_decades", "rms_per_dataset_decades", "AIC",
                 "BIC", "determined_within_10pct", "at_bound", "converged", "ripple_Gstorage_slope",
                 "Gstorage_slope_min", "Gstorage_slope_max", "alternatives_spread_decades",
                 "formula", "formula_parameters", "formula_rms_per_dataset_decades", "formula_BIC",
                 "held_out_rms_mean_decades", "held_out_rms_worst_decades", "formula_held_out_rms_mean_decades",
                 "out_of_sample_verdict", "prestress_scale_s_m2", "geometric_share_dGstorage_dP",
                 "geometric_share_dGloss_dP", "anchored_rms_per_dataset_decades", "anchored_BIC", "anchored_s_m2",
                 "anchored_L", "anchored_geometric_share_dGstorage_dP", "unlike_prestress_independent_ratio",
                 "unlike_exponent_rising_ratio", "discriminates", "elapsed_s", "cpu_s", "cpu_main_fit_s", "notes")


def _rms(values) -> str:
    return " ".join(f"{x:.4g}" for x in values)


def _unlike_ratio(r, kind: str):
    return next((u.ratio for u in r.unlike if u.kind == kind), "")


def study_table_rows(study):
    """The study table as rows of plain values (CSV); empty where a column does not apply or was not run."""
    for r in study.rows:
        f = r.formula
        mean, worst = r.held_out
        oos = r.out_of_sample
        f_mean = "" if oos is None or r.formula is None else oos.row(r.formula[0]).mean
        a = r.anchored
        yield (r.name, "tensegrity" if r.structural else "structure-free", r.n_free, r.stiffness_spread, _rms(r.rms),
               r.aic, r.bic, r.n_determined, " ".join(r.at_bound), r.converged, r.ripple, r.slope_range[0],
               r.slope_range[1], r.alternatives_spread,
               "" if f is None else f[0], "" if f is None else f[1], "" if f is None else _rms(f[2]),
               "" if f is None else f[3], mean, worst, f_mean, "" if oos is None else oos.verdict, r.s,
               r.geometric_share[0], r.geometric_share[1],
               "" if a is None else _rms(a.rms), "" if a is None else a.bic, "" if a is None else a.s,
               "" if a is None else a.L, "" if a is None else a.geometric_share[0],
               _unlike_ratio(r, "prestress-independent"), _unlike_ratio(r, "exponent-rising"),
               "" if r.discriminates is None else r.discriminates, r.elapsed_s, r.cpu_s, r.cpu_main_s, "; ".join(r.notes))


def _pct(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{100 * x:.0f} %"


def _fit_rows(study):
    best_bic = min(r.bic for r in study.rows)
    for r in study.rows:
        name = f"**{r.name}**" if r.bic == best_bic else r.name
        yield (name, "tensegrity" if r.structural else "formula", r.n_free,
               "n/a" if not math.isfinite(r.stiffness_spread) else f"{r.stiffness_spread:.2f}",
               " / ".join(f"{x:.3f}" for x in r.rms), f"{r.aic:.1f}", f"{r.bic:.1f}",
               f"{r.n_determined}/{r.n_free}" + (f" ({len(r.at_bound)} at bound)" if r.at_bound else ""),
               "yes" if r.converged else "no", f"{num(r.slope_range[0], 2)} … {num(r.slope_range[1], 2)}")


def _referee_rows(study):
    for r in study.rows:
        f = r.formula
        mean, worst = r.held_out
        oos = r.out_of_sample
        f_mean = math.nan if oos is None or f is None else oos.row(f[0]).mean
        a = r.anchored
        unlike = " / ".join(f"{u.ratio:.2f}×" for u in r.unlike) if r.unlike else "n/a"
        disc = "n/a" if r.discriminates is None else ("yes" if r.discriminates else "**does not discriminate**")
        adds = "n/a" if oos is None or f is None else ("**nothing measurable**" if oos.structure_adds_nothing
                                                        else "better out of sample")
        yield (r.name,
               "n/a" if f is None else f"{' / '.join(f'{x:.3f}' for x in f[2])} ({f[1]})",
               "n/a" if not math.isfinite(mean) else f"{mean:.3f} / {worst:.3f}",
               "n/a" if not math.isfinite(f_mean) else f"{f_mean:.3f}", adds,
               "n/a" if a is None else f"{' / '.join(f'{x:.3f}' for x in a.rms)} (L = {a.L:.2g})",
               f"{_pct(r.geometric_share[0])} / {_pct(r.geometric_share[1])}", unlike, disc)


def _answer(study) -> list[str]:
    win = study.winner
    ref = next((r for r in study.rows if r.name == PER_TENDON_VOIGT), None)
    out = ["## The answer", "",
           f"The lowest BIC is **{win.name}** ({win.description}): {win.n_free} free parameters, RMS "
           + " / ".join(f"{x:.3f}" for x in win.rms) + f", BIC {win.bic:.1f}"
           + (f" against {ref.bic:.1f} for the per-tendon fit ({ref.n_free} parameters, RMS "
              + " / ".join(f"{x:.3f}" for x in ref.rms) + ")" if ref is not None and ref is not win else "") + "."]
    if win.out_of_sample is not None:
        out.append(f"Out of sample: {win.out_of_sample.verdict}.")
    if not win.structural:
        out.append("A structure-free formula has the lowest BIC: on these data no tensegrity earns its parameters.")
    out.append("")
    held = _held(MECHANISMS[win.name], f" in `{win.name}`") if win.name in MECHANISMS else ""
    if held:
        out += [held, ""]
    if win.at_bound:
        out += [f"In the winning fit {', '.join(f'`{n}`' for n in win.at_bound)} sit at a bound: "
                "the data want them beyond the box, so they are limits, not estimates.", ""]
    best_oos = [r for r in study.rows if r.structural and r.out_of_sample is not None]
    if best_oos:
        b = min(best_oos, key=lambda r: r.held_out[0])
        out += [f"The tensegrity that predicts best out of sample is **{b.name}** (mean held-out RMS "
                f"{b.held_out[0]:.3f}, worst {b.held_out[1]:.3f}); {b.out_of_sample.verdict}.", ""]
    return out


def _notes(study) -> list[str]:
    notes = [f"- `{r.name}`: {n}." for r in study.rows for n in r.notes]
    return (["Not run:", "", *notes, ""] if notes else [])


def mechanisms_markdown(study) -> str:
    """The study: the fits, the referee's table (baselines, out of sample, anchors, what the structure carries,
    falsification), the answer in words, the goals with the closest model, what it does not show."""
    srcs = ", ".join(f"`{s}`" for s in study.sources)
    o = study.options
    refit = o.get("refit", {})
    out = ["# Which mechanism explains the cells?", "",
           f"Data: {srcs}, fitted jointly by every model ({o['starts']} starts, up to {o['hops']} hops each, seed "
           f"{o['seed']}, tolerance {num(o['tolerance'])} decades on every data set; the refits below with "
           f"{refit.get('starts', '?')} starts and up to {refit.get('hops', '?')} hops). RMS values are of the "
           "log10 errors (decades), per data set in the order above.", "",
           "## The fits", "",
           table(("model", "kind", "free", "stiffness spread (dec)", "RMS per data set", "AIC", "BIC",
                  "determined within 10 %", "converged", "G' slope 0.01–1000 Hz"), _fit_rows(study)),
           "## As a referee would judge them", "",
           "*Formula*: the model's own structure-free formula (its tendon law's terms as one lumped element with the "
           "same prestress coupling; parameters in brackets), fitted to the same data. *Held out*: the model refitted "
           "on each split's training data and scored on the rest (mean / worst over the splits"
           + (f": {'; '.join(study.holdout)}" if study.holdout else "") + "); *structure adds*: whether the tensegrity "
           "is at least 10 % better out of sample than its formula. *Anchored*: the prestress gauge held to the "
           "paper's convention (model prestress = measured prestress, strut length L = s^(−1/2) within 0.1–10). "
           "*Geometric share*: the share of dG′/dP and dG″/dP over the data's prestresses carried by the geometric "
           "prestress stiffness P·Kp (the rest: the tendon law's tension terms). *Unlike*: the model's RMS on data "
           "cells do not show (stiffness independent of prestress / an exponent rising with prestress) over its RMS "
           "on the cell data; below 2× it does not discriminate.", "",
           table(("model", "formula RMS (k)", "held out mean / worst", "formula held out", "structure adds",
                  "anchored RMS (L)", "geometric share dG′/dP / dG″/dP", "unlike ratios", "discriminates"),
                 _referee_rows(study)),
           *_notes(study), *_answer(study),
           "## The goals", "",
           table(("goal (issue 26)", "closest model", "by how much", "met"),
                 [(g, n, how, "yes" if ok else "**no**") for g, n, how, ok in study.goals_issue26()]),
           table(("goal (issue 18)", "closest model", "short by", "met"),
                 [(g, n, "0" if ok else num(miss, 3), "yes" if ok else "**no**") for g, n, miss, ok in study.goals()]),
           f"The study took {study.elapsed_s:.0f} s of wall time with {o['jobs']} worker(s) (on a shared machine "
           f"this includes waiting for the CPU) and {study.cpu_s:.0f} s of CPU in its fits: {study.cpu_main_s:.0f} s "
           "in the main fits, the rest in the referee's refits.", "",
           "## What this does not show", "",
           "- Each model had the same small search budget; a model that missed a goal here might reach it with more "
           "starts, one that reached it does fit.",
           "- The frequency exponent, the prestress trend and the loss tangent are what the data constrained: the "
           "fitted curves restate them and are not predictions. Only the held-out columns score predictions.",
           "- A parameter at its bound, or not determined within 10 %, is not measured by these data.",
           "- The unlike data keep the grids, prestresses and noise of the cell data and change one trend; a model "
           "that fits them too has not shown that the real trend comes from its mechanism.", ""]
    if any("(bundled with tenscell)" in str(src) for src in study.sources):
        out.insert(-1, "- The bundled data sets are generated from published laws (Stamenović 2002's linear relations "
                       "in the prestress, Fabry 2001's structural-damping law), not raw measurements: a model that "
                       "fits them reproduces those laws, and a held-out error measures how well it extrapolates them.")
    return "\n".join(out)

from .._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home
