"""Markdown of the mechanisms study, rendered only from its result fields (a mechanism fit's own report is
:func:`tenscell.reports.fit.fit_markdown`, as every fit's)."""
from __future__ import annotations

import math

from ..fitting.models.catalog import MECHANISMS, PER_TENDON_VOIGT
from ._format import num, table

__all__ = ["mechanisms_markdown", "mechanisms_summary"]


def _held(mech, where: str = "") -> str:
    """'Held, not fitted: ...' for a mechanism's fixed fields, or '' when every law parameter is fitted."""
    held = [f"`{f.law_parameter}` = {num(f.value)}" for f in mech.fields if f.layout == "fixed"]
    return (f"Held, not fitted{where} (not counted among the free parameters, and not measured by this fit): "
            + ", ".join(held) + ".") if held else ""


def _rms(values, digits: int = 3) -> str:
    return " / ".join(f"{x:.{digits}f}" for x in values)


def _band(band, digits: int = 3) -> str:
    lo, hi = band
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return num(hi, digits)
    return f"{lo:.{digits}f}" if abs(hi - lo) < 0.5 * 10 ** -digits else f"{lo:.{digits}f}–{hi:.{digits}f}"


def _pct(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{100 * x:.0f} %"


def _yes(flag, no: str = "**no**") -> str:
    return "n/a" if flag is None else ("yes" if flag else no)


def _fit_rows(study):
    best_bic = min(r.bic for r in study.rows)
    for r in study.rows:
        name = f"**{r.name}**" if r.bic == best_bic else r.name
        yield (name, "tensegrity" if r.structural else "formula", r.n_free,
               "n/a" if not math.isfinite(r.stiffness_spread) else f"{r.stiffness_spread:.2f}",
               _rms(r.rms), f"{r.aic:.1f}", f"{r.bic:.1f}",
               f"{r.n_determined}/{r.n_free}" + (f" ({len(r.at_bound)} at bound)" if r.at_bound else ""),
               "yes" if r.converged else "no", f"{num(r.slope_range[0], 2)} … {num(r.slope_range[1], 2)}",
               f"{_pct(r.geometric_share[0])} / {_pct(r.geometric_share[1])}", num(r.sigma_ratio, 3))


def _not_refereed(r) -> str:
    return "not refereed" + (f" ({r.notes[0].split(':')[0]})" if r.notes else "")


def _referee_rows(study):
    for r in study.rows:
        if not r.structural:
            continue
        o = r.held_out_row
        if o is None:
            yield (r.name, _not_refereed(r), "", "", "", "", "")
            continue
        own = r.out_of_sample.get(r.formula[0]) if r.formula is not None else None
        b = r.baselines
        adds = "n/a" if own is None else ("**nothing measurable**" if r.out_of_sample.structure_adds_nothing
                                          else "better out of sample")
        yield (r.name, f"{_band(o.mean_band)} / {_band(o.worst_band)}",
               "yes" if o.converged else f"**no**: {', '.join(o.unconverged)}",
               "n/a" if own is None else f"{_band(own.mean_band)} / {_band(own.worst_band)}", adds,
               "n/a" if b is None or not b.best else f"{b.best}: {_band(b.best_mean)} / {_band(b.best_worst)}",
               "n/a" if b is None else _yes(b.better))


def _anchor_rows(study):
    from ..studies.falsification import UNLIKE_KINDS

    for r in study.rows:
        if not r.structural or r.anchored is None:
            continue
        a, e = r.anchored, r.exponent
        ratios = " / ".join(num(next((u.ratio for u in r.unlike if u.kind == k), math.nan), 3) + "×"
                            for k in UNLIKE_KINDS) if r.unlike else "n/a"
        yield (r.name, _rms(a.rms), num(a.sigma_ratio, 3), f"{a.s:.3g}", ratios,
               _yes(r.discriminates, "**does not discriminate**"), num(r.exponent_change, 2),
               "n/a" if e is None else f"{e.real:+.3f}", "n/a" if e is None else f"{e.flat:+.3f}",
               "n/a" if e is None else _rms(e.flat_rms))


def _heldout_rows(study):
    for r in study.rows:
        o = r.held_out_row
        if not r.structural or o is None:
            continue
        for s in o.scores:
            yield (r.name, s.split, f"{s.train_rms:.4f} ({num(s.reference_train_rms, 3)})",
                   "yes" if s.converged else "**no**", _band(s.band), s.n_band)


def _baseline_rows(study):
    held = {b.model: b for b in study.baselines}
    for name, (k, rms, bic) in sorted(study.baseline_fits.items(), key=lambda x: x[1][2]):
        o = held.get(name)
        yield (name, k, _rms(rms), f"{bic:.1f}",
               "not refereed" if o is None else f"{_band(o.mean_band)} / {_band(o.worst_band)}",
               "" if o is None else ("yes" if o.converged else f"**no**: {', '.join(o.unconverged)}"))


def _answer(study) -> list[str]:
    win = study.winner
    ref = next((r for r in study.rows if r.name == PER_TENDON_VOIGT), None)
    out = ["## The answer", "",
           f"The lowest BIC is **{win.name}** ({win.description}): {win.n_free} free parameters, RMS "
           + _rms(win.rms) + f", BIC {win.bic:.1f}"
           + (f" against {ref.bic:.1f} for the per-tendon fit ({ref.n_free} parameters, RMS " + _rms(ref.rms) + ")"
              if ref is not None and ref is not win else "") + "."]
    if win.out_of_sample is not None and win.structural:
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
    judged = [r for r in study.rows if r.structural and r.baselines is not None and r.held_out_row is not None]
    better = [r for r in judged if r.baselines.better]
    if judged:
        if better:
            out += ["Better out of sample than every structure-free baseline with no more free parameters, on the "
                    "mean and on every split, across the band: " + ", ".join(f"**{r.name}**" for r in better)
                    + ".", ""]
        else:
            b = min(judged, key=lambda r: r.held_out_row.mean_band[1])
            out += [f"No tensegrity is better out of sample than the best structure-free baseline with no more free "
                    f"parameters across the band. Closest on the mean: **{b.name}** ({b.baselines.detail}).", ""]
    return out


def _notes(study) -> list[str]:
    notes = [f"- `{r.name}`: {n}." for r in study.rows for n in r.notes]
    return (["Not refereed:", "", *notes, ""] if notes else [])


def _referee_section(study) -> list[str]:
    from ..fitting.validation import BAND_COST, UNCONVERGED
    from ..studies.mechanisms import REFEREE_MAX_RMS

    return [
        "## As a referee would judge them", "",
        f"Every tensegrity that describes the data in sample (worst RMS ≤ {REFEREE_MAX_RMS:g}) is refitted on each "
        "held-out split (" + ("; ".join(study.holdout) if study.holdout else "none") + ") to the main fit's standard: "
        "the same search, start 0 warm at the main fit, the others fresh. *Held out*: mean / worst held-out RMS over "
        f"the splits, each a band over the fits whose training cost lies within {100 * (BAND_COST - 1):.0f} % of "
        f"the best's; *converged*: every refit's training RMS within {UNCONVERGED:g}× the main fit's on the same "
        "points (one that is not is in no ranking or verdict). *Own formula*: its lumped terms as one element "
        "(parallel), refitted the same way; *structure adds*: whether it is at least 10 % better than that formula "
        "across the band. *Strongest baseline*: the structure-free law with no more free parameters with the lowest "
        "mean held-out RMS (P entering G′ and G″ alike, every mechanism's lumped terms in parallel and in series); "
        "*better*: better than the best of them on the mean and on every split, across the band.", "",
        table(("model", "held out mean / worst", "refits converged", "own formula held out", "structure adds",
               "strongest baseline: mean / worst", "better than the baselines"), _referee_rows(study)),
        "## At the anchor", "",
        "*Anchored*: refitted with the model's physical prestress σ (the mean normal stress of the tendons' virial "
        "stress, docs/conventions.md) held within ×/÷1.5 of the measured one (σ/measured printed; the free fit's is "
        "in the table above). *Unlike*: the anchored model's RMS on "
        "data cells do not show (stiffness independent of prestress / an exponent rising with prestress / G″ "
        "independent of prestress) over its anchored RMS on the cell data; below 2× it does not discriminate. "
        "*Δα*: the change of the local G′ slope at 0.1 Hz from the lowest to the highest measured prestress, of the "
        "free fit, the anchored fit, and the anchored fit to lines with a flat loss tangent (G′ kept): a structure "
        "whose exponent still falls there gets the fall from itself, not from the lines.", "",
        table(("model", "anchored RMS", "σ/measured", "s (m²)", "unlike ratios", "discriminates", "Δα free",
               "Δα anchored", "Δα flat loss tangent", "RMS on flat lines"), _anchor_rows(study)),
        "## Held out, split by split", "",
        "Each refit's RMS on its training points, with the main fit's RMS on the same points in brackets, and its "
        "held-out RMS (the band; fits in the band). The baselines' are in `mechanisms_heldout.csv`.", "",
        table(("model", "split", "training RMS (main fit's)", "converged", "held out", "fits in band"),
              _heldout_rows(study)),
        "## The baselines at their strongest", "",
        table(("baseline", "free", "RMS per data set", "BIC", "held out mean / worst", "refits converged"),
              _baseline_rows(study))]


def _a_priori_section(study) -> list[str]:
    """The structures' slopes with no fitted parameter (tenscell.studies.a_priori), the inextensible limit."""
    t = study.a_priori
    if t is None:
        return []
    rows = [(r["structure"], r["mechanisms"] if r["mechanisms"] >= 0 else "n/a", num(r["dG_storage_dsigma"], 3),
             num(r["data_dG_storage_dP"], 3), num(r["dG_storage_dsigma_over_data"], 3), num(r["data_dG_loss_dP"], 3))
            for r in t.records() if math.isinf(r["EA_over_sigma_L2"])]
    return ["## A priori: each structure with no fitted parameter", "",
            "dG′/dσ at 0.1 Hz of each structure with inextensible tendons (σ the structure's physical prestress; "
            "no parameter of any fit enters), against the slope of the data's line; in that limit dG″/dσ → 0 (the "
            "structure's mechanisms are undamped). At finite EA/(σL²) the slopes are a one-parameter family and "
            "dG″/dσ scales with the tendons' loss tangent: `a_priori.csv` (`tenscell.studies.a_priori`). The "
            "structures fitted with σ anchored: `tenscell.studies.structures`.", "",
            table(("structure", "mechanisms (inextensible)", "dG′/dσ", "data dG′/dP", "ratio", "data dG″/dP"), rows)]


def mechanisms_summary(study) -> str:
    """A few lines for the command line: the lowest BIC and issue 33's goals."""
    win = study.winner
    lines = [f"lowest BIC: {win.name} (RMS {_rms(win.rms)}, BIC {win.bic:.1f})"]
    lines += [f"{g.split(':')[0]}: {'met' if ok else 'not met'} (closest {n}: {how})"
              for g, n, how, ok in study.goals_issue33()]
    return "\n".join(lines)


def mechanisms_markdown(study) -> str:
    """The study: the fits, the referee's tables (out of sample across the band, the strongest baselines, the
    anchor, falsification, the exponent test), the answer in words, the goals with the closest model, what it does
    not show."""
    srcs = ", ".join(f"`{s}`" for s in study.sources)
    o = study.options
    out = ["# Which mechanism fits the cells, and does its structure explain them?", "",
           f"Data: {srcs}, fitted jointly by every model ({o['starts']} starts, up to {o['hops']} hops each, seed "
           f"{o['seed']}, tolerance {num(o['tolerance'])} decades on every data set; every refit below with the same "
           "search, warm at the main fit). RMS values are of the log10 errors (decades), per data set in the order "
           "above.", "",
           "## The fits", "",
           table(("model", "kind", "free", "stiffness spread (dec)", "RMS per data set", "AIC", "BIC",
                  "determined within 10 %", "converged", "G' slope 0.01–1000 Hz", "P·Kp share of dG′/dP / dG″/dP",
                  "σ/measured"),
                 _fit_rows(study)),
           *_a_priori_section(study), *_referee_section(study), *_notes(study), *_answer(study),
           "## The goals", "",
           table(("goal (issue 33)", "closest model", "its numbers", "met"),
                 [(g, n, how, "yes" if ok else "**no**") for g, n, how, ok in study.goals_issue33()]),
           table(("goal (issue 18)", "closest model", "short by", "met"),
                 [(g, n, "0" if ok else num(miss, 3), "yes" if ok else "**no**") for g, n, miss, ok in study.goals()]),
           f"The study took {num(study.elapsed_s, 3)} s of wall time with {o['jobs']} worker(s) (on a shared machine "
           f"this includes waiting for the CPU) and {study.cpu_s:.0f} s of CPU in its fits: {study.cpu_main_s:.0f} s "
           "in the tensegrities' main fits, the rest in the referee's refits and the baselines.", "",
           "## What this does not show", "",
           "- Each model had the same search budget; a model that missed a goal here might reach it with more "
           "starts, one that reached it does fit. A held-out band is over the starts of one search (each with its "
           "own random stream), not over every basin the training data allow.",
           "- The frequency exponent, the prestress trend and the loss tangent are what the data constrained: the "
           "fitted curves restate them and are not predictions. Only the held-out columns, the unlike data and the "
           "flat-loss-tangent lines test anything.",
           "- A parameter at its bound, or not determined within 10 %, is not measured by these data.",
           "- The unlike data keep the grids, prestresses and noise of the cell data and change one trend; a model "
           "that fits them too has not shown that the real trend comes from its mechanism.", ""]
    if any("(bundled with tenscell)" in str(src) for src in study.sources):
        out.insert(-1, "- The bundled data sets are generated from published laws (Stamenović 2002's linear relations "
                       "in the prestress, Fabry 2001's structural-damping law), not raw measurements: a model that "
                       "fits them reproduces those laws, and a held-out error measures how well it extrapolates them.")
    return "\n".join(out)

#: the columns of ``mechanisms.csv`` in 0.2.0 (:func:`study_table_rows`; deprecated: the study's tables now carry their
#: own named columns, ``tenscell.studies.mechanisms.study_tables``)
STUDY_COLUMNS = ("model", "kind", "free_parameters", "stiffness_spread_decades", "rms_per_dataset_decades", "AIC",
                 "BIC", "determined_within_10pct", "at_bound", "converged", "ripple_Gstorage_slope",
                 "Gstorage_slope_min", "Gstorage_slope_max", "alternatives_spread_decades",
                 "formula", "formula_parameters", "formula_rms_per_dataset_decades", "formula_BIC",
                 "held_out_rms_mean_decades", "held_out_rms_worst_decades", "formula_held_out_rms_mean_decades",
                 "out_of_sample_verdict", "prestress_scale_s_m2", "geometric_share_dGstorage_dP",
                 "geometric_share_dGloss_dP", "anchored_rms_per_dataset_decades", "anchored_BIC", "anchored_s_m2",
                 "anchored_L", "anchored_geometric_share_dGstorage_dP", "unlike_prestress_independent_ratio",
                 "unlike_exponent_rising_ratio", "discriminates", "elapsed_s", "cpu_s", "cpu_main_fit_s", "notes")


def study_table_rows(study):
    """Deprecated (0.3.0, removed in 0.4.0): the study's main table as rows of :data:`STUDY_COLUMNS` (blank where a
    0.2.0 column has no value in this version); use ``tenscell.studies.mechanisms.study_tables(study)[0]``, a
    table with its own named columns (``.columns``, ``.rows``, ``.records()``)."""
    import warnings

    from .._deprecated import REMOVED_IN, SINCE
    from ..studies.mechanisms import study_tables

    warnings.warn(f"tenscell.reports.mechanisms.study_table_rows is deprecated (since {SINCE}, removed in "
                  f"{REMOVED_IN}): use tenscell.studies.mechanisms.study_tables(study)[0]", DeprecationWarning,
                  stacklevel=2)
    for record in study_tables(study)[0].records():
        yield tuple(record.get(c, "") for c in STUDY_COLUMNS)


from .._deprecated import moved_away  # noqa: E402

__getattr__ = moved_away(__name__)  # the public names of 0.2.0 that moved away: a DeprecationWarning names their home
