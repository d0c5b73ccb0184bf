"""Markdown of the mechanisms study, rendered only from its result fields (a mechanism fit's own report is
:func:`tenscell.reports.fit.fit_markdown`, as every fit's)."""
from __future__ import annotations


from ..fitting.models.catalog import PER_TENDON_VOIGT, mechanism, mechanism_names
from ._format import num, table

__all__ = ["mechanisms_markdown", "study_table_rows", "STUDY_COLUMNS"]


def _held(mech, where: str = "") -> str:
    """'Held, not fitted: ...' for a mechanism's fixed fields, or '' when every law parameter is fitted."""
    held = [f"`{f.law_parameter}` = {num(f.value)}" for f in mech.fields if f.layout == "fixed"]
    return (f"Held, not fitted{where} (not counted among the free parameters, and not measured by this fit): "
            + ", ".join(held) + ".") if held else ""


#: the study table's columns (CSV header; the Markdown uses the same order)
STUDY_COLUMNS = ("mechanism", "free_parameters", "stiffness_spread_decades", "rms_per_dataset_decades", "AIC", "BIC",
                 "determined_within_10pct", "at_bound", "ripple_Gstorage_slope", "Gstorage_slope_min",
                 "Gstorage_slope_max", "holdout_rms_decades", "alternatives_spread_decades", "converged",
                 "elapsed_s")


def study_table_rows(study):
    """The study table as rows of plain values (CSV)."""
    for r in study.rows:
        yield (r.name, r.n_free, r.stiffness_spread, " ".join(f"{x:.4g}" for x in r.rms), r.aic, r.bic,
               r.n_determined, " ".join(r.at_bound), r.ripple, r.slope_range[0], r.slope_range[1],
               "" if r.holdout_rms is None else r.holdout_rms, r.alternatives_spread, r.converged, r.elapsed_s)


def _md_rows(study):
    best_bic = min(r.bic for r in study.rows)
    for r in study.rows:
        name = f"**{r.name}**" if r.bic == best_bic else r.name
        yield (name, r.n_free, f"{r.stiffness_spread:.2f}", " / ".join(f"{x:.3f}" for x in r.rms), f"{r.aic:.1f}",
               f"{r.bic:.1f}", f"{r.n_determined}/{r.n_free}" + (f" ({len(r.at_bound)} at bound)" if r.at_bound else ""),
               num(r.ripple, 2), f"{num(r.slope_range[0], 2)} … {num(r.slope_range[1], 2)}",
               num(r.holdout_rms, 3))


def mechanisms_markdown(study) -> str:
    """The study: one table, the answer in words, the goals with the closest mechanism, what it does not show."""
    win = study.winner
    ref = next((r for r in study.rows if r.name == PER_TENDON_VOIGT), None)
    srcs = ", ".join(f"`{s}`" for s in study.sources)
    o = study.options
    out = ["# Which mechanism explains the cells?", "",
           f"Data: {srcs}, fitted jointly by every mechanism ({o['starts']} starts, up to {o['hops']} hops each, "
           f"seed {o['seed']}, tolerance {num(o['tolerance'])} decades on every data set). RMS values are of the "
           "log10 errors (decades), per data set in the order above.", "",
           table(("mechanism", "free", "stiffness spread (dec)", "RMS per data set", "AIC", "BIC",
                  "determined within 10 %", "G' slope ripple", "G' slope 0.01–1000 Hz", "held-out RMS"),
                 _md_rows(study)),
           "*Ripple*: the largest difference between the local slope d log G'/d log f (200 points per decade) and "
           "the model's chord slope between the two data points around it. *Held-out RMS*: the mechanism refitted "
           + (f"without the frequency sweep's points from {num(study.holdout[0], 3)} to {num(study.holdout[1], 3)} "
              "Hz and scored on them." if study.holdout else "(no frequency sweep: not measured)."), "",
           "## The answer", "",
           f"The lowest BIC is **{win.name}** ({win.description}): {win.n_free} free parameters, RMS "
           + " / ".join(f"{x:.3f}" for x in win.rms) + f", stiffness spread {win.stiffness_spread:.2f} decades, "
           f"BIC {win.bic:.1f}"
           + (f" against {ref.bic:.1f} for the per-tendon fit ({ref.n_free} parameters, spread "
              f"{ref.stiffness_spread:.1f} decades, RMS " + " / ".join(f"{x:.3f}" for x in ref.rms) + ")"
              if ref is not None and ref is not win else "") + ".", ""]
    held = _held(mechanism(win.name), f" in `{win.name}`") if win.name in mechanism_names() else ""
    if held:
        out += [held, ""]
    if win.at_bound:
        out += [f"In the winning fit {', '.join(f'`{n}`' for n in win.at_bound)} sit at a bound: "
                "the data want them beyond the box, so they are limits, not estimates.", ""]
    out += ["## The goals", "", table(("goal", "closest mechanism", "short by", "met"),
                                     [(g, n, "0" if ok else num(miss, 3), "yes" if ok else "**no**")
                                      for g, n, miss, ok in study.goals()]),
            f"The study took {study.elapsed_s:.0f} s of wall time with {o['jobs']} worker(s) (on a shared machine "
            "this includes waiting for the CPU).", "",
            "## What this does not show", "",
            "- Each mechanism had the same small search budget; a mechanism that missed a goal here might reach it "
            "with more starts, one that reached it does fit.",
            "- The frequency exponent, the prestress trend and the loss tangent are what the data constrained: "
            "the fitted curves restate them and are not predictions. Only the held-out column scores a "
            "prediction (outside the training window).",
            "- A parameter at its bound, or not determined within 10 %, is not measured by these data.", ""]
    if any("(bundled with tenscell)" in str(src) for src in study.sources):
        out.insert(-1, "- The bundled data sets are generated from published laws (Stamenović 2002's linear relations "
                       "in the prestress, Fabry 2001's structural-damping law), not raw measurements: a mechanism "
                       "that fits them reproduces those laws.")
    return "\n".join(out)
