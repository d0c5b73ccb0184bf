"""Report sections of a fit's analysis: identifiability, model comparison, predicted creep, data provenance.

Each function renders Markdown lines from a result object's fields only
(:class:`~tenscell.fitting.identifiability.Identifiability`,
:class:`~tenscell.fitting.scores.ModelComparison`,
:class:`~tenscell.fitting.fitted.PredictedCreep`), in words a biologist can
read, and says what the numbers do not show.
"""
from __future__ import annotations

import math

import numpy as np

from ..fitting.identifiability import GAUGE
from .._results import ln_error
from ._format import num, pct, table

__all__ = ["identifiability_section", "comparison_section", "creep_section", "provenance_line",
           "section_provenance", "section_identifiability", "section_comparison", "section_creep"]


def _factor(se: float) -> str:
    """A standard error in ln units as '±x %' (small) or '×/÷ f' (large), as every report gives it."""
    return ln_error(se) or "not determined"


def provenance_line(data) -> str | None:
    """'These data were generated from a published fit law …' when the file's own comments say so, else None."""
    from ..io.data import generated_note

    note = generated_note(data)
    return None if note is None else f"**Note on the data.** `{data.source}`: {note}."


def identifiability_section(ident, within: float = 0.1) -> list[str]:
    """How well the data determine the parameters: rank, gauge, standard errors, combinations, correlations."""
    n_free = ident.n_analysed + len(ident.excluded)
    s = ident.singular_values
    out = ["## How well the data determine the parameters", ""]
    rel = ", ".join(num(x / s[0], 2) for x in s) if s.size and s[0] > 0 else "none"
    out.append(
        f"Linearized at the optimum, the {ident.n_residuals} residuals (decades: log10 G′ and log10 G″ of each "
        f"moduli point, log10 J of each creep point) see **{ident.rank} independent parameter combinations** of the "
        f"{ident.n_analysed} analysed parameters (singular values of the Jacobian above {ident.rtol:g} of the "
        f"largest). Singular values relative to the largest: {rel}.")
    out.append("")
    if ident.gauge_removed:
        out += [f"**The strut length L is not determined by moduli.** The map {GAUGE} leaves G′, G″ and the "
                "creep compliance exactly unchanged, so the data cannot tell L apart from a rescaling of the others. L is held at its "
                "fitted value and the other parameters stand for the combinations the data do constrain: "
                "EA/L², c/L and P/L² (s/L² for a prestress scale).", ""]
    bound = [(n, r) for n, r in ident.excluded if r != "gauge"]
    if bound:
        names = ", ".join(n for n, _ in bound[:10]) + (" …" if len(bound) > 10 else "")
        out += [f"{len(bound)} of the {n_free} free parameters sit at a bound ({names}): the data only say that "
                "they lie beyond it, so they carry no standard error and are left out.", ""]
    if ident.sigma is None:
        out += ["**Noise level unknown**: the data give no standard deviations and the fit has as many seen "
                "combinations as residuals, so the residuals cannot estimate the noise. Standard errors need data "
                "with standard deviations (columns `G_storage_sd_Pa`, `G_loss_sd_Pa`).", ""]
    elif ident.sigma_source == "residuals":
        out += [f"Noise level σ = {num(ident.sigma, 3)} decades, estimated from the residuals "
                f"({ident.dof} degrees of freedom). The data give no standard deviations, so the standard errors "
                "below measure how far the model misses the data, not measurement noise.", ""]
    else:
        red = ident.chi2 / ident.dof if ident.dof > 0 else float("nan")
        out += [f"Errors from the data's standard deviations (σ = 1 in their units); χ²/dof = {num(red, 3)} "
                f"({ident.dof} degrees of freedom): a value far above 1 means the model misses the data by more "
                "than their scatter.", ""]
    det = ident.determined(within)
    out.append(f"**{int(det.sum())} of the {ident.n_analysed} analysed parameters** are determined within "
               f"{pct(within, 0)} (one standard error); {ident.n_combinations_within(within)} independent "
               "combinations are.")
    out.append("")
    # a standard error above 1 (a factor e) is no determination: list those by name only
    shown = [i for i in range(ident.n_analysed) if ident.standard_errors[i] <= 1.0]
    if shown:
        rows = [(ident.labels[i], num(ident.values[i], 4), num(ident.standard_errors[i], 3),
                 _factor(ident.standard_errors[i])) for i in shown]
        out.append(table(["parameter", "value (SI)", "standard error of ln", "one standard error"], rows))
    rest = [ident.labels[i] for i in range(ident.n_analysed) if i not in shown]
    if rest:
        out += [f"Not determined individually (standard error above a factor e, or in a combination the data do "
                f"not see): {', '.join(rest[:12])}{' …' if len(rest) > 12 else ''} ({len(rest)} in all).", ""]
    combos = [c for c in ident.combinations if c.standard_error is not None][:5]
    if combos:
        out += ["Best-determined combinations (products of powers; the largest exponent is ±1):", ""]
        out += [f"- {c.text(max_terms=4)}: {_factor(c.standard_error)}" for c in combos]
        out.append("")
    strong = ident.strong_correlations(0.9)
    if strong:
        out += ["Strongly correlated pairs (|ρ| ≥ 0.9; the data constrain their combination, not each): "
                + "; ".join(f"{a} and {b} (ρ = {num(r, 3)})" for a, b, r in strong[:6])
                + (f"; and {len(strong) - 6} more" if len(strong) > 6 else "") + ".", ""]
    out += ["*What this does not show*: the errors are local (the Jacobian at the optimum) and assume independent "
            "Gaussian errors in log10 G. Far from the optimum, or when another start fits almost as well, the "
            "parameters can differ by much more; a parameter at a bound or in an unseen combination is not "
            "estimated at all.", ""]
    return out


def comparison_section(comparison) -> list[str]:
    """The tensegrity beside the homogeneous cell and the structural-damping law: RMS, k, AIC, BIC, held out."""
    rows = []
    held = comparison.holdout is not None
    best_aic = min(s.aic for s in comparison.scores)
    best_bic = min(s.bic for s in comparison.scores)
    for s in comparison.scores:
        row = [s.name, s.n_params, num(s.rms_log10_error, 3), num(s.aic, 5), num(s.aic - best_aic, 3),
               num(s.bic, 5), num(s.bic - best_bic, 3)]
        if held:
            row.append(num(s.holdout_rms_log10_error, 3))
        rows.append(row)
    head = ["model", "parameters k", "RMS log10 error", "AIC", "ΔAIC", "BIC", "ΔBIC"]
    if held:
        head.append("held-out RMS log10 error")
    out = ["## Against the phenomenological standard", ""]
    out.append("The same data fitted by the structural-damping (power-law) law of cell rheology, "
               "G*(ω) = G0 (ω/Φ0)^(x−1) (1 + iη) Γ(2−x) cos(π(x−1)/2) + iωμ with η = tan(π(x−1)/2), and by the "
               "homogeneous tensegrity; lower AIC/BIC is better, a difference below about 2 is no preference.")
    out.append("")
    out.append(table(head, rows))
    out.append(f"Convention: {comparison.convention}. {comparison.n_residuals} residuals.")
    out.append("")
    verdict = (f"AIC prefers **{comparison.best('aic')}**, BIC prefers **{comparison.best('bic')}**")
    if held:
        lo, hi = comparison.holdout
        verdict += (f"; on the {comparison.n_holdout} points between {num(lo)} and {num(hi)} Hz that no model was "
                    f"fitted to, **{comparison.best('holdout')}** predicts best")
    out += [verdict + ".", ""]
    out += ["*What this does not show*: AIC and BIC rank models by how well they fit per parameter, not which "
            "mechanism is right; a model with as many parameters as residuals can fit anything. A curve fitted "
            "to data generated from that same curve wins by construction.", ""]
    return out


#: largest range of the local creep exponent over the window for which a power law J ≈ A·t^α is printed
POWER_LAW_SPAN = 0.05


def creep_section(creep, frequency_slope: tuple | None = None, constrained: bool = False, derived=None) -> list[str]:
    """Predicted creep compliance of the fitted cell and its power-law exponent.

    Parameters
    ----------
    creep : PredictedCreep
    frequency_slope : (float, float), optional
        Range of the fitted G′ log-log slope over the frequencies ``1/(2πt)`` of the window.
    constrained : bool
        A frequency sweep of the fit covers those frequencies: the creep then restates what the data
        constrained and is not called a prediction.
    derived : DerivedQuantities, optional
        The fit's derived numbers with their standard errors (:attr:`tenscell.fitting.FitResult.derived`):
        every number below is then shown with its ± (``creep_*`` keys); without it, values alone.
    """
    lo, hi = creep.window
    span = float(creep.exponent.max() - creep.exponent.min())
    show = _creep_numbers(creep, frequency_slope, derived)
    # a power law is printed only for a curve that is one: a local exponent constant to within POWER_LAW_SPAN
    power = span <= POWER_LAW_SPAN
    title = "Creep of the fitted cell (restates the fitted data)" if constrained else "Predicted creep of the fitted cell"
    out = [f"## {title}", ""]
    lo_e, hi_e = int(np.argmin(creep.exponent)), int(np.argmax(creep.exponent))
    if power:
        out.append(f"After a stress step the fitted cell (prestress {show('creep_prestress_N', 0, 'N')}) creeps as "
                   f"J(t) ≈ {show('creep_A', 0, '1/Pa')}·t^**{show('creep_alpha', 0)}** (t in s) over "
                   f"{num(lo)}–{num(hi)} s; the local exponent d ln J/d ln t runs from "
                   f"{show('creep_exponent', lo_e)} to {show('creep_exponent', hi_e)} (RMS of the ln residuals of the "
                   f"straight line {num(creep.rms_log, 2)}).")
    else:
        out.append(f"After a stress step the fitted cell (prestress {show('creep_prestress_N', 0, 'N')}) creeps over "
                   f"{num(lo)}–{num(hi)} s with a local exponent d ln J/d ln t from {show('creep_exponent', lo_e)} "
                   f"to {show('creep_exponent', hi_e)}: not a power law over this window (the exponent varies by "
                   f"{span:.2g}, more than {POWER_LAW_SPAN:g}), so no single exponent is given.")
    if frequency_slope is not None:
        out.append(f"For a power-law material the creep exponent equals the frequency exponent of G′; the fitted "
                   f"G′ slope over the matching frequencies 1/(2πt) runs from {show('creep_window_slope', 0)} to "
                   f"{show('creep_window_slope', 1)}."
                   + (" That slope was fitted to a frequency sweep covering these frequencies, so this creep "
                      "restates what the data constrained: it is not a prediction." if constrained else ""))
    out.append("")
    pick = np.unique(np.linspace(0, creep.t.size - 1, 7).round().astype(int))
    out.append(table(["t (s)", "J (1/Pa)", "local exponent"],
                     [(num(creep.t[i], 3), show("creep_J", i), show("creep_exponent", i)) for i in pick]))
    out += ["*What this does not show*: the creep of the linear model (small steps); a large step can slacken "
            "tendons (`tenscell creep` simulates it).", ""]
    return out


def _creep_numbers(creep, frequency_slope, derived):
    """``show(key, i, unit="")``: a creep number as text, with its ± when ``derived`` is given."""
    plain = {"creep_A": [creep.A], "creep_alpha": [creep.alpha], "creep_J": creep.J,
             "creep_prestress_N": [creep.prestress_N],
             "creep_exponent": creep.exponent, "creep_window_slope": frequency_slope or (math.nan, math.nan)}

    def show(key: str, i: int, unit: str = "") -> str:
        if derived is not None:
            return derived.text(key, i, unit, 3)
        return num(plain[key][i], 3) + (f" {unit}" if unit else "")

    return show


# ---- the sections of tenscell.reports.fit (signature (result, baseline) -> lines) -----------------
def section_provenance(result, baseline=None) -> list[str]:
    """A note for every data set whose file says it was generated from a published law."""
    out = []
    for d in result.datasets:
        line = provenance_line(d)
        if line:
            out += [line, ""]
    return out


def section_identifiability(result, baseline=None) -> list[str]:
    """How well the data determine the parameters (:meth:`FitResult.identifiability`)."""
    return identifiability_section(result.identifiability())


def section_comparison(result, baseline=None, comparison=None) -> list[str]:
    """The model comparison: ``comparison`` if given (e.g. with held-out data), else computed here."""
    from ..fitting.scores import compare_models

    if comparison is None:
        comparison = compare_models(result, homogeneous=baseline)
    out = comparison_section(comparison)
    if not any(s.name.startswith("structural") for s in comparison.scores):
        out.insert(2, "The structural-damping law describes one frequency sweep; it has no prestress dependence "
                      "and is not fitted to prestress sweeps or joint data.")
        out.insert(3, "")
    return out


def section_creep(result, baseline=None) -> list[str]:
    """Predicted creep of the fitted cell, beside the fitted G′ slope over the matching frequencies, each number
    with its standard error (:attr:`tenscell.fitting.FitResult.derived`)."""
    creep = result.predicted_creep()
    lo, hi = creep.window
    f_lo, f_hi = 1 / (2 * math.pi * hi), 1 / (2 * math.pi * lo)
    q = result.derived
    constrained = any(f.axis == "frequency" and f.data.frequency_hz.min() <= f_hi and f.data.frequency_hz.max() >= f_lo
                      for f in result.fits)
    return creep_section(creep, tuple(q.values["creep_window_slope"]), constrained, derived=q)
