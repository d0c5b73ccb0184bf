"""Markdown report of the sensitivity study (:class:`tenscell.studies.SensitivityStudy`).

Rendered from the study's fields only: the base point, the size of the
changes and the bound checked are the run's own.
"""
from __future__ import annotations

import math

import numpy as np

from ._format import num, pct, table

__all__ = ["sensitivity_markdown"]


def _uniform(x, unit: str) -> str:
    x = np.asarray(x, dtype=float)
    return f"{num(x[0])} {unit}" if np.ptp(x) == 0 else f"{num(x.min())}–{num(x.max())} {unit} (per tendon)"


def sensitivity_markdown(study) -> str:
    """The sensitivity study as a short Markdown report with its numbers."""
    el, s = study.elasticities, study
    f = el.frequency_hz
    ch, da, b = s.change, s.alpha_change, s.bound
    geo = "; ".join(f"{n}: {m}, error estimate {e:.1e}" for n, m, e in zip(el.names, el.methods, el.errors)
                    if n in ("L", "alpha", "delta"))
    lines = [
        "# Sensitivity of G' and G'' to the parameters",
        "",
        f"{s.describe}: α = {s.alpha:g} rad, δ = {math.degrees(s.delta):.4g}°, L = {num(s.L)} m, P = {num(s.P)} N, "
        f"EA = {_uniform(s.EA, 'N')}, c = {_uniform(s.c, 'N·s/m')}, f = {num(f[0])}–{num(f[-1])} Hz ({f.size} points). "
        "Elasticities of the tendon-law parameters and P are analytic (derivatives of J through (K0 + iωC0)⁻¹); "
        f"L, α and δ by finite differences through paper_cell ({geo}). "
        f"For α the semi-elasticity ∂ln G/∂α is per rad and the finite change is ±{num(da)} rad. "
        f"The angles are also changed by half as much (rows marked 'half': ±{num(da / 2)} rad, ±{num(100 * ch / 2)}%), "
        "since the valid band of references is narrow.",
        "",
    ]
    head = ["parameter group", "n", "max abs ∂lnG'/∂ln p", "max abs ∂lnG''/∂ln p", f"max ΔG'/G' (±{num(100 * ch)}%)",
            f"max ΔG''/G'' (±{num(100 * ch)}%)", f"≤ {num(100 * b)}%?"]
    verdict = {True: "yes", False: "**no**", None: "partly"}
    rows = []
    for g in s.summary:
        both_invalid = math.isnan(g.max_change_storage) and math.isnan(g.max_change_loss)
        rows.append([g.group, g.n, f"{g.max_elasticity_storage:.4f}", f"{g.max_elasticity_loss:.4f}",
                     pct(g.max_change_storage), pct(g.max_change_loss),
                     ("n/a" if both_invalid else verdict[g.holds]) + (f" ({g.note})" if g.note else "")])
    lines.append(table(head, rows))
    ok = [g.group for g in s.summary if g.holds]
    bad = [g.group for g in s.summary if g.holds is False]
    na = [g.group for g in s.summary if math.isnan(g.max_change_storage) and math.isnan(g.max_change_loss)]
    part = [g.group for g in s.summary if g.holds is None and g.group not in na]
    lines += [f"**{num(100 * ch)}% in, at most {num(100 * b)}% out** holds for: {', '.join(ok) or 'none'}.",
              f"It fails for: {', '.join(bad) or 'none'}."
              + (f" Within {num(100 * b)}% where valid, but part of the perturbations are not valid references: "
                 f"{', '.join(part)}." if part else "")
              + (f" Not applicable (both perturbations leave the valid region): {', '.join(na)}." if na else ""),
              ""]
    forcelike = [k for k, n in enumerate(el.names) if n.split("[")[0] in ("EA", "c", "P")]
    tot = el.complex[forcelike].sum(axis=0)
    lines += [f"Sum rule e_P + Σe_EA + Σe_c = 1: largest deviation {np.max(np.abs(tot - 1)):.2e}.", ""]
    for mc in s.monte_carlo:
        lines += _monte_carlo(mc, b)
    lines += ["Not shown: changes larger than the ones above (the elasticities are local), other reference shapes, "
              "and correlations between parameters beyond independent uniform draws.", ""]
    return "\n".join(lines)


def _monte_carlo(mc, bound) -> list[str]:
    p = mc.percentiles()
    n = mc.factors.shape[0]
    nv = int(mc.valid.sum())
    reasons = sorted(set(mc.reasons) - {""})
    return [
        f"## Monte Carlo, {mc.label}",
        "",
        f"{n} draws (seed {mc.seed}), each factor uniform in ±{num(100 * mc.spread)}%"
        + (f", α shifted uniformly in ±{num(mc.alpha_spread)} rad" if mc.alpha_spread else "")
        + f"; {n - nv} draws were not valid references"
        + (" (" + ", ".join(f"{r}: {mc.reasons.count(r)}" for r in reasons) + ")" if reasons else "") + ".",
        f"- largest |ΔG'/G'| over f: median {pct(p['storage'][0])}, 95th percentile {pct(p['storage'][1])}, "
        f"max {pct(p['storage'][2])}",
        f"- largest |ΔG''/G''| over f: median {pct(p['loss'][0])}, 95th percentile {pct(p['loss'][1])}, "
        f"max {pct(p['loss'][2])}",
        f"- draws with both moduli within {num(100 * bound)}% at every frequency: {100 * mc.fraction_within(bound):.1f}%",
        "",
    ]
