"""Report sections of what a fit determines and what its structure carries.

Three sections of :data:`tenscell.reports.fit.SECTIONS`, each rendered from result fields only:

* :func:`section_combinations` — in front: the products of parameters the data determine although their factors are
  not (``beta·s``; ``EA/L²`` under the strut-length gauge), each with its value and error, in words;
* :func:`section_structure` — what the structure carries: a mechanism's share of dG′/dP and dG″/dP due to the
  geometric prestress stiffness P·Kp against the tendon law's tension terms, and for every model with a cell the
  fitted prestress against the measured one (:attr:`tenscell.fitting.FitResult.structure`);
* :func:`section_profile` — profile-likelihood intervals of the parameters the local analysis cannot bound
  (:attr:`tenscell.fitting.FitResult.profile`), with what they cost.
"""
from __future__ import annotations

import math

import numpy as np

from .._results import ln_error, plus_minus
from ..fitting.shares import GAUGE_WINDOW_L, SHARE_PARTS, TENSION_TERMS
from ..model.prestress import PRESTRESS_CONVENTION
from ._format import num, table

__all__ = ["section_combinations", "section_structure", "section_profile", "combination_lines", "structure_lines",
           "profile_lines"]

#: frequencies of the shares' table at most (the first, the last and evenly between)
_SHOWN_FREQUENCIES = 6


def _pct(x: float) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{100 * x:.3g} %"


# ---- what the data determine, in front -----------------------------------------------------------------------
def combination_lines(ident, profile=None) -> list[str]:
    """The determined products whose factors are not, in words, each with its value and error (Markdown lines)."""
    out = []
    if ident.gauge_removed:
        out.append("- **The strut length L is an exact gauge of the moduli**: the data determine EA/L², c/L and P/L² "
                   "(s/L²), never EA, c, P or L alone; every error in this report is of those combinations at the "
                   "fitted L.")
    for c in ident.identified():
        factors = ", ".join(f"{n} {ln_error(se) or 'not determined'}" for n, se in c.factor_errors)
        out.append(f"- **{c.words()} = {num(c.value, 4)} {ln_error(c.standard_error)}**: determined; its factors are "
                   f"not separately determined (alone: {factors}).")
    for p in profile or ():
        iv = p.interval(0.95)
        for comp in p.compensations:
            where = (f"held at {num(p.value)} by the mechanism" if p.held else f"fitted at {num(p.value)}")
            out.append(f"- **{comp.words} = {num(comp.value, 4)}**, constant within ×/÷ "
                       f"{math.exp(comp.spread_ln / 2):.3g} while {p.name} runs over the values the data accept "
                       f"({iv.text(p.unit)}): the data determine {comp.words}, not {p.name} ({where}) nor "
                       f"{comp.other} alone.")
    return out


def section_combinations(result, baseline=None) -> list[str]:
    """In front: the products of parameters the data determine although their factors are not."""
    ident = result.identifiability()
    lines = combination_lines(ident, result.profile)
    loose = [ident.labels[i] for i in range(ident.n_analysed) if not ident.standard_errors[i] <= 1.0]
    bound = [n for n, r in ident.excluded if r != "gauge"]
    out = ["## What the data determine", ""]
    if lines:
        out += ["Combinations the data determine although their factors are not (the value, then one standard "
                "error):", "", *lines, ""]
    else:
        out += ["Each parameter the data determine is determined on its own: no product of two parameters is "
                "determined while its factors are not.", ""]
    if loose or bound:
        what = "; ".join(t for t in (_names(loose), _names(bound) + " (at a bound)" if bound else "") if t)
        out += [f"Not determined by the local analysis: {what}; see *Profile likelihood* below.", ""]
    return out


# ---- what the structure carries -----------------------------------------------------------------------------
def _shown(n: int) -> list[int]:
    return sorted(set(np.linspace(0, n - 1, min(n, _SHOWN_FREQUENCIES)).round().astype(int).tolist()))


def _share_table(st) -> list[str]:
    q, f = st.quantities, st.shares.frequency_hz
    rows = []
    for i in _shown(f.size):
        cells = [num(f[i], 3), q.text("change_storage", i, "Pa", 3), q.text("change_loss", i, "Pa", 3)]
        cells += [st.share_text(part, "storage", i) for part in SHARE_PARTS]
        cells.append(st.share_text("geometric", "loss", i))
        rows.append(cells)
    terms = TENSION_TERMS.get(st.law or "", "the law's tension terms")
    return [table(("frequency (Hz)", "ΔG′ over the range", "ΔG″ over the range", "P·Kp share of ΔG′",
                   "transverse (P·ΣT0∇²l)", "axial (T/l)", f"tension terms ({terms})", "P·Kp share of ΔG″"), rows)]


def _scale_lines(sc) -> list[str]:
    """The fitted prestress against the measured one, and the strut length it means."""
    if sc.s is None:
        P = "" if sc.P_N is None else f" P = {num(sc.P_N)} N"
        return [f"No data set states its prestress: the model prestress{P} is fitted, with no measured counterpart "
                "(give the prestress of a data set, `--prestress FILE=PA`, to compare them).", ""]
    err = plus_minus(sc.s, None if sc.s_error_ln is None else sc.s * sc.s_error_ln, "m²", sc.s_note, 4, ln=True)
    L_err = ln_error(sc.L_paper_error_ln)
    inside = "inside" if sc.in_gauge_window else "**outside**"
    lo, hi = min(sc.measured_pa), max(sc.measured_pa)
    s_range = (f"s ∈ [{GAUGE_WINDOW_L[1] ** -2:g}, {GAUGE_WINDOW_L[0] ** -2:g}] m²" if sc.L_cell == 1.0 else
               f"s/L_cell² ∈ [{GAUGE_WINDOW_L[1] ** -2:g}, {GAUGE_WINDOW_L[0] ** -2:g}]")
    out = [f"**The fitted prestress against the measured one.** The data state {num(lo)}–{num(hi)} Pa; the model "
           f"prestress P (N) on the fit's cell (strut length {num(sc.L_cell, 4)} m) is s × the measured one with "
           f"s = {err}.", "", _sigma_line(sc), "",
           f"P/L_cell² is {_pct(sc.ratio)} of the measured prestress: in the paper's convention (the model "
           f"prestress in N equal to the measured prestress in Pa, moved along the exact gauge) the cell's strut "
           f"length is L = L_cell/√s = {num(sc.L_paper, 3)} m{' ' + L_err if L_err else ''}, {inside} the "
           f"gauge window {GAUGE_WINDOW_L[0]:g}–{GAUGE_WINDOW_L[1]:g} m ({s_range}; a window on the gauge, not an "
           "anchor)."
           + (f" s sits at its {sc.s_at_bound} bound: this L is a limit, not an estimate." if sc.s_at_bound else "")]
    if sc.profile_L is not None:
        short, long_ = sc.profile_L
        if short is None and long_ is None:
            span = "is not bounded within the bounds of s"
        elif short is None:
            span = f"is at most {num(long_, 3)} m (not bounded below within the bounds of s)"
        elif long_ is None:
            span = f"is at least {num(short, 3)} m (not bounded above within the bounds of s)"
        else:
            span = f"lies between {num(short, 3)} and {num(long_, 3)} m"
        out.append(f"At 95 % (the profile of s) the strut length {span}.")
    for k, v, e in sc.fitted_pa:
        out.append(f"Data set {k} states no prestress; the fit places it at {plus_minus(v, e, 'Pa', '', 4)} (a fitted "
                   "parameter, not a measurement).")
    return out + [""]


def _sigma_line(sc) -> str:
    """σ / measured in words: the physical comparison, and the anchor the fit was held to."""
    if sc.sigma_ratio is None:
        return ("σ / measured: not defined (the cell's nodes span no volume, so its tendons' virial stress per unit "
                "volume is not).")
    held = ("a free fit: nothing held σ" if sc.anchor is None else
            f"the fit held {sc.anchor.words} (anchored)")
    err = ln_error(sc.s_error_ln) if sc.anchor is None or not sc.anchor.is_exact else ""
    return (f"**σ / measured = {num(sc.sigma_ratio, 3)}**{' ' + err if err else ''}: the model's physical prestress "
            f"({PRESTRESS_CONVENTION}; {num(sc.sigma_per_P, 4)} Pa per N of P on this cell) over the measured one, "
            f"at every prestress the data state; {held}.")


def structure_lines(st, profile=None) -> list[str]:
    """What the structure carries (:class:`~tenscell.fitting.shares.StructureSummary`) as Markdown lines."""
    out = ["## What the structure carries", ""]
    if st.shares is None:  # the Voigt cell: no tension terms
        out += ["The Voigt tendons have no tension terms: every change of G′ and G″ with the prestress goes through "
                "the geometric prestress stiffness P·Kp (how much G responds is in *Is the prestress doing "
                "anything?* above).", ""]
    else:
        sh = st.shares
        over = (f"{num(sh.prestress_pa[0])}–{num(sh.prestress_pa[-1])} Pa (model P {num(sh.prestress_n[0], 3)}–"
                f"{num(sh.prestress_n[-1], 3)} N)" if np.all(np.isfinite(sh.prestress_pa))
                else f"the fitted P = {num(sh.prestress_n[0])} N (a local derivative: no prestress range is stated)")
        out += [st.share_verdict(), "",
                f"The change of G′ and G″ over {over}, split exactly into the paper's geometric prestress stiffness "
                "P·Kp (a taut tendon resists rotation: transverse; the rest lengths follow the tension: axial) and "
                "the tendon law's own tension terms; shares with their standard errors (delta method):", ""]
        out += _share_table(st)
        for p in profile or ():
            rng = p.share_range(0.95)
            if rng is not None and p.held:
                out.append(f"These errors hold {p.name} at its held value. Over the values of {p.name} the data "
                           f"accept at 95 % ({p.interval(0.95).text(p.unit)}), the P·Kp share of ΔG′ runs from "
                           f"{_pct(rng[0])} to {_pct(rng[1])}.")
            elif rng is not None:
                out.append(f"Over the values of {p.name} the data accept at 95 %, the P·Kp share of ΔG′ runs from "
                           f"{_pct(rng[0])} to {_pct(rng[1])}.")
        out.append(f"Integration check: the parts add up to the direct change within {sh.closure:.1g} of G.")
        out.append("")
    out += _scale_lines(st.scale)
    out += ["*What this does not show*: the shares say how the fitted model responds to the prestress, not that the "
            "data determine that response; a tendon law that writes G ∝ P in fits the same data with the structure "
            "as a passenger. σ is a continuum reading of the structure's member forces (docs/conventions.md, "
            "\"Physical prestress\"), compared with a traction-based measurement that sees only the stress the "
            "substrate balances; the gauge window is a convention of the paper's cell, not a measurement.", ""]
    return out


def section_structure(result, baseline=None) -> list[str]:
    """What the structure carries (models with a cell; :attr:`tenscell.fitting.FitResult.structure`)."""
    st = result.structure
    return [] if st is None else structure_lines(st, result.profile)


# ---- profile intervals ----------------------------------------------------------------------------------------
def _needed_text(needed) -> str:
    """``"EA, c (not determined locally); P (at its lower bound)"``: names grouped by reason, at most 8 per reason."""
    by: dict[str, list[str]] = {}
    for name, reason in needed:
        key = "not determined locally" if reason.startswith("not determined locally") else reason
        by.setdefault(key, []).append(name)
    return "; ".join(_names(names) + f" ({reason})" for reason, names in by.items())


def _names(names, limit: int = 8) -> str:
    return ", ".join(names[:limit]) + (f" … ({len(names)} in all)" if len(names) > limit else "")


def profile_lines(profile, needed=()) -> list[str]:
    """Profile-likelihood intervals (:class:`~tenscell.fitting.profile.ProfileSet`) as Markdown lines."""
    out = ["## Profile likelihood: what the data say where the local analysis cannot", ""]
    if profile is None:
        return out + [f"Parameters the local analysis cannot bound: {_needed_text(needed)}. Their profile intervals "
                      "were not computed (`FitResult.compute_profile()`, `tenscell fit --profile yes`).", ""]
    if profile.not_run:
        if not profile.needed:
            return []
        return out + [f"Profile intervals {profile.not_run}. Parameters the local analysis cannot bound: "
                      f"{_needed_text(profile.needed)}.", ""]
    rows = [(p.name, p.reason, f"{num(p.value, 4)} {p.unit}".strip(), p.interval(0.6827).text(p.unit),
             p.interval(0.95).text(p.unit), p.refits) for p in profile]
    out += ["Each parameter below was held at values over its bounds (log-spaced, each crossing refined by "
            "bisection) while every other parameter was refitted; the interval is where −2 ln L rises by at most 1 "
            "(68 %) or 3.84 (95 %) above its minimum, open on a side where it stays below that up to the bound. "
            f"Likelihood: {profile.convention()}.", "",
            table(("parameter", "why", "fitted / held", "68 %", "95 %", "refits"), rows)]
    for p in profile:
        if p.improved > 0.05:
            best = p.values[int(np.argmin(p.delta))]
            out.append(f"A refit with {p.name} = {num(best)} fits better than the fit itself by Δ(−2 ln L) = "
                       f"{num(p.improved, 3)}: the {'held value' if p.held else 'search'} is not the data's best.")
    held = sorted({n for p in profile for n in p.held_others})
    if held:
        out.append(f"Every profile holds {', '.join(held)} at the fitted value: an exact gauge of the moduli, which "
                   "the data do not see.")
    out += ["", f"Cost: {profile.refits} refits in {profile.cpu_s:.1f} s of CPU (each the other parameters refitted "
            "from the neighbouring point's values: one start and a short basin-hopping budget).", "",
            "*What this does not show*: a refit with a short budget can stop above the best fit at its value, which "
            "raises −2 ln L there and narrows the interval; the thresholds 1 and 3.84 are the large-sample (Wilks) "
            "ones; an open side is open within the bounds scanned only.", ""]
    return out


def section_profile(result, baseline=None) -> list[str]:
    """Profile intervals of the parameters the local analysis cannot bound (when computed; else which need one)."""
    profile = result.profile
    if profile is not None:
        return profile_lines(profile)
    from ..fitting.profile import needs_profile

    needed = needs_profile(result) if not getattr(result.problem, "sparse_jacobian", False) else ()
    return profile_lines(None, needed) if needed else []
