"""The structures study's page (:mod:`tenscell.studies.structures`): rendered from its tables only."""
from __future__ import annotations

import math

from ._format import num, table

__all__ = ["structures_markdown"]


def _n(x, digits: int = 4) -> str:
    return "—" if x is None or (isinstance(x, float) and not math.isfinite(x)) else num(x, digits)


def _band(r) -> str:
    lo, hi = r["band_worst_rms_lo_decades"], r["band_worst_rms_hi_decades"]
    return "—" if not math.isfinite(lo) else f"{lo:.4f}–{hi:.4f}"


def structures_markdown(study) -> str:
    """The page: G1, the ranking of structures at each anchor, then every structure × mechanism × anchor."""
    t, rk, check = study.table, study.ranking, study.check
    rms_cols = [c for c in t.columns if c.startswith("rms_") and c.endswith("_decades")]
    out = ["# Structures compared at the anchor", "",
           f"Data: {', '.join(study.sources)}. Each mechanism is fitted on each structure free, with the model's "
           "physical prestress σ (the tendons' virial stress Σ T·l/(3V), V the hull of the nodes; "
           "docs/conventions.md) within ×/÷1.5 of the measured prestress, and with σ equal to it. The free fit runs "
           "from several seeds, each anchored fit from the best free fit (warm) and from a fresh seed (the 30-strut "
           "sphere and the lattice, whose fits cost 10–50 times the paper cell's: one free seed, anchored fits warm "
           "only); the band is the worse of the two RMS over every fit whose cost lies within 10 % of the best.", "",
           f"**{check.label}: {'met' if check.met else 'not met'}.** {check.detail}", ""]
    out += ["## Structures ranked", "",
            "Each structure's best mechanism with at most 8 free parameters (all of them when none has so few), "
            "ranked by the worse of its two RMS (decades).", ""]
    for anchor in dict.fromkeys(r["anchor"] for r in rk.records()):
        rows = [(r["rank"], r["structure"], r["best_mechanism"], r["n_free"], _n(r["worst_rms_decades"]), _band(r),
                 _n(r["sigma_over_measured"], 3), _n(r["bic"], 4)) for r in rk.records() if r["anchor"] == anchor]
        out += [f"### σ {anchor}" if anchor != "free" else "### free", "",
                table(("rank", "structure", "best mechanism", "free", "worse RMS", "band", "σ/measured", "BIC"), rows),
                ""]
    out += ["## Every fit", ""]
    rows = []
    for r in t.records():
        rows.append((r["structure"], r["mechanism"], r["anchor"], r["n_free"], *(_n(r[c]) for c in rms_cols),
                     _band(r), f"{r['fits_in_band']}/{r['fits']}", _n(r["sigma_over_measured"], 3), _n(r["bic"], 4),
                     r["at_bound"] or "", r["errors"] or ""))
    head = ("structure", "mechanism", "σ", "free", *(f"RMS {c[4:-8]}" for c in rms_cols), "band (worse RMS)",
            "in band", "σ/measured", "BIC", "at a bound", "failed")
    out += [table(head, rows), ""]
    out += [f"CPU: {study.cpu_s:.0f} s over {len(study.records)} fits (each measured in its worker).", "",
            "*What this does not show*: σ is one continuum reading of the structure's member forces, compared with a "
            "traction-based prestress that sees only the stress the substrate balances; a structure that fits at the "
            "anchor is consistent with the measured prestress, not shown to carry it. Where members carry "
            "compression (elastic struts) the mechanism's spring is laid out per family and bounded below by twice "
            "the struts' largest compression, and their free fit keeps s in the gauge window 0.01–100 m².", ""]
    return "\n".join(out)
