"""The Markdown report of a fit of any model, rendered only from the fit's result fields.

The report is a sequence of sections; each section is a function
``(result, baseline) -> list of lines`` (``baseline`` is a baseline fit of the
same data, e.g. the homogeneous cell, or None) listed in :data:`SECTIONS` with
a name. The sections every fit has run for every model; a section named in
:data:`MODEL_SECTIONS` runs only for a model whose problem asks for it
(:attr:`tenscell.fitting.problem.Problem.report_sections`): the Voigt cell's
prestress activity, creep and stiffness bounds, a mechanism's held fields and
assignments. A new analysis adds its section function there.
"""
from __future__ import annotations

import math

import numpy as np

from ..fitting.prestress import CELL_ELASTICITY
from ..fitting.models.voigt import FitProblem
from ..fitting.records import STATUSES, noise_rms
from ..fitting.result import FitResult
from ..io.data import RheologyData
from ..io.thinning import binning_notes
from .._results import CORRELATION_THRESHOLD, correlation_text, ln_error, plus_minus
from ._format import num, table
from .fit_analysis import section_comparison, section_creep, section_identifiability, section_provenance
from .fit_structure import section_combinations, section_profile, section_structure

__all__ = ["fit_markdown", "fit_sections", "report_title", "SECTIONS", "MODEL_SECTIONS", "section_summary", "section_datasets", "section_baseline",
           "section_shape", "section_prestress", "section_stiffness", "section_parameters", "section_errors",
           "section_alternatives", "section_held", "section_assignments", "parameter_error"]


def _name(source: str) -> str:
    return source.replace("\\", "/").rsplit("/", 1)[-1]


def _parameter(result: FitResult, name: str, unit: str = "", digits: int = 4) -> str:
    """Parameter ``name`` as ``"value +/- stderr unit"`` (lmfit's convention) or with why it has no error."""
    for p, (se, note) in zip(result.parameters, result.standard_errors):
        if p.name == name:
            return plus_minus(p.value, se, unit, note, digits)
    raise ValueError(f"no parameter named {name!r}")


def _data_slopes(data: RheologyData) -> list[str]:
    """Least-squares lines of the data's G' and G'' against prestress: dG'/dP, G'(0), dG''/dP, G''(0) (Pa), each
    with its ordinary least-squares standard error (from the scatter about the line; none for 2 points).

    numpy's ``polyfit(..., cov=True)`` scales the covariance by the residual sum of squares over n − 2, as
    ``scipy.stats.linregress`` does; importing scipy.stats would cost the fit command 0.6 s."""
    assert data.prestress is not None, "a prestress sweep"
    out = []
    for G in (data.G_storage, data.G_loss):
        if data.n < 3 or np.unique(data.prestress).size < 3:
            a, b = np.polyfit(data.prestress, G, 1)
            out += [plus_minus(float(a), None, "", "(a line through 2 prestresses)", 4),
                    plus_minus(float(b), None, "", "(a line through 2 prestresses)", 4)]
            continue
        (slope, intercept), cov = np.polyfit(data.prestress, G, 1, cov=True)
        out += [plus_minus(float(slope), float(np.sqrt(cov[0, 0])), "", "", 4),
                plus_minus(float(intercept), float(np.sqrt(cov[1, 1])), "", "", 4)]
    return out


def section_summary(result: FitResult, baseline=None) -> list[str]:
    """What was fitted to what, the verdict, the search."""
    pr = result.problem
    noise = noise_rms(result.datasets)
    verdict = f"**{result.verdict}** ({STATUSES[result.status]})"
    if result.converged and not result.tolerance_met:
        # the data say how well they can be fitted: a fit inside their noise has nothing left to explain
        verdict = ("**inside the data's noise** (the optimizer's tolerance is not met, but every data set that misses "
                   "it lies within its stated noise: the data cannot tell a better fit)")
    below = [n for n in noise if n is not None and result.tolerance < n]
    if below:
        verdict += (f"; the tolerance {num(result.tolerance)} is below the data's own noise (RMS of the stated sd "
                    f"{num(max(below), 3)} decades), so the data cannot confirm it")
    each = " on every data set" if result.joint else ""
    lines = [f"- Data: {len(result.datasets)} data set(s), {sum(d.n for d in result.datasets)} points:"]
    for f in result.fits:
        at = (f", measured at {num(f.prestress_pa)} Pa (stated)" if f.prestress_pa is not None else
              f", prestress not stated: fitted {_parameter(result, f'P_data[{f.index}]', 'Pa')}"
              if f.prestress_fitted_pa is not None else "")
        what = "creep compliance J(t)" if f.axis == "time" else f"{f.axis} sweep"
        lines.append(f"  - data set {f.index}: `{f.data.source}`: {f.data.n} points, {what}{at}.")
        if f.data.provenance is not None:
            lines.append(f"    - Read: {f.data.provenance.line()}.")
        lines += [f"    - Thinned: {note}." for note in binning_notes(f.data)]
    lines += [
        f"- Model `{result.spec.name}`: {pr.describe()}; {pr.n_free} free parameters against {pr.n_residuals} "
        "residuals.",
        f"- RMS of the log10 errors: **{num(result.rms_log10_error, 4)}** decades over all points; the tolerance "
        f"{num(result.tolerance)} applies{each}: {verdict}.",
        f"- {result.message}",
        f"- Starts: {result.starts} (seed {result.seed}); time {result.elapsed_s:.1f} s"
        + (f" (the tolerance was first met after {result.time_to_tolerance_s:.2f} s)"
           if result.time_to_tolerance_s is not None else " (the tolerance was never met)")
        + f"; {result.n_evaluations} model evaluations.",
        criteria_line(result),
        "",
    ]
    return lines


def criteria_line(result: FitResult) -> str:
    """The fit's AIC and BIC, how they count σ, and lmfit's values of the same residuals beside them."""
    aic, bic = result.information_criteria()
    aic_l, bic_l = result.information_criteria_lmfit()
    k = result.problem.n_model_parameters
    counted = (f"k = {k} parameters and the noise σ, estimated from the residuals (−2 ln L = n ln(2π RSS/n) + n)"
               if not result.sigma_known else f"k = {k} parameters; σ from the data's standard deviations")
    return (f"- AIC {num(aic, 5)}, BIC {num(bic, 5)} ({counted}; n = {result.problem.n_residuals} residuals). "
            f"In lmfit's convention (n ln(χ²/n) + 2k, + k ln n; σ not counted): AIC {num(aic_l, 5)}, BIC "
            f"{num(bic_l, 5)}. Differences between models fitted to the same data are what matters; "
            + ("they agree in both conventions." if not result.sigma_known else
               "with stated standard deviations the two conventions can rank models differently."))


def section_datasets(result: FitResult, baseline=None) -> list[str]:
    """Per-data-set errors of a joint fit (one line for a single data set)."""
    if not result.joint:
        return []
    rows = [(f.index, f"`{_name(f.data.source)}`", f.data.n, num(f.rms_log10_error, 4), num(f.rms_storage, 4),
             num(f.rms_loss, 4), "yes" if f.rms_log10_error <= result.tolerance else "no") for f in result.fits]
    out = ["## Each data set", "", table(("data set", "file", "points", "RMS log10 error", "G' RMS", "G'' RMS",
                                         "within tolerance"), rows)]
    if "s" in result.problem.names:
        out.append(f"One prestress scale links the data sets: model prestress (N) = s × prestress (Pa), "
                   f"s = {_parameter(result, 's', 'm²')}.")
    unknown = [f for f in result.fits if f.prestress_fitted_pa is not None]
    for f in unknown:
        out.append(f"Data set {f.index} does not state its prestress; the fit places it at "
                   f"{_parameter(result, f'P_data[{f.index}]', 'Pa')} on the scale of the others (a fitted parameter, not a "
                   "measurement).")
    return out + [""]


def section_baseline(result: FitResult, baseline=None) -> list[str]:
    """The heterogeneous fit beside the homogeneous baseline."""
    if baseline is None:
        return []
    rows = [(name, f"`{r.spec.name}`", r.problem.n_free, num(r.rms_log10_error, 4), "yes" if r.converged else "no")
            for name, r in (("this fit", result), ("baseline", baseline))]
    return [f"## Against its baseline, `{baseline.spec.name}`", "", baseline.problem.describe() + ".", "",
            table(("fit", "model", "free parameters", "RMS log10 error", "converged"), rows)]


def section_shape(result: FitResult, baseline=None) -> list[str]:
    """Slopes of the fitted model: log-log in frequency, straight lines in prestress, each with its standard error
    (:attr:`FitResult.derived`)."""
    q = result.derived
    out = ["## Shape of the fitted model", "",
           "Each number derived from the fitted parameters carries its standard error (delta method through the "
           "parameters' covariance, `fit.json` `derived`).", ""]
    for f in result.fits:
        d = f.data
        head = f"Data set {f.index} (`{_name(d.source)}`): " if result.joint else ""
        if f.axis == "frequency":
            key = f"frequency_slopes[{f.index}]"
            line = (f"{head}local log-log slopes on 1000 frequencies from {num(d.frequency_hz.min())} to "
                    f"{num(d.frequency_hz.max())} Hz: G' {q.text(key, 0, digits=3)} to {q.text(key, 1, digits=3)}; "
                    f"G'' {q.text(key, 2, digits=3)} to {q.text(key, 3, digits=3)}.")
            if baseline is not None and not baseline.joint:
                line += (f" Homogeneous baseline: G' slope {baseline.derived.text('frequency_slopes[0]', 0, digits=3)}"
                         f" to {baseline.derived.text('frequency_slopes[0]', 1, digits=3)}.")
            out.append(line)
        elif f.axis == "time":
            key = f"creep_slopes[{f.index}]"
            out.append(f"{head}local log-log slope of the fitted creep compliance at the data's times "
                       f"{num(d.time_s.min())}–{num(d.time_s.max())} s: {q.text(key, 0, digits=3)} to "
                       f"{q.text(key, 1, digits=3)}.")
        else:
            out += _prestress_lines(result, baseline, f, head)
        out.append("")
    return out


def _prestress_lines(result: FitResult, baseline, f, head: str) -> list[str]:
    """The straight lines of G', G'' against prestress: the data's, the fitted model's (with standard errors)."""
    key = f"prestress_lines[{f.index}]"
    rows: list[tuple[str, ...]] = [("data (least squares)", *_data_slopes(f.data)),
                                   ("fitted model", *(result.derived.text(key, i) for i in range(4)))]
    if baseline is not None and not baseline.joint:
        rows.append(("homogeneous baseline", *(baseline.derived.text("prestress_lines[0]", i) for i in range(4))))
    return [f"{head}straight lines over the data's prestress range:", "",
            table(("", "dG'/dP", "G'(0) (Pa)", "dG''/dP", "G''(0) (Pa)"), rows),
            "The fitted model's lines (and its loss tangent η = G''/G' along them) restate the trend of the data "
            "it was fitted to: a check of the fit, not a prediction."]


def section_prestress(result: FitResult, baseline=None) -> list[str]:
    """Is the prestress doing anything? Elasticities and share, with the verdict in words."""
    pa = result.prestress
    q = result.derived
    out = ["## Is the prestress doing anything?", "", pa.verdict(),
           f"With standard errors: the share of the static stiffness runs from {q.text('prestress_share', 0, digits=3)}"
           f" to {q.text('prestress_share', 1, digits=3)}, ∂lnG'/∂lnP from {q.text('prestress_storage', 0, digits=3)}"
           f" to {q.text('prestress_storage', 1, digits=3)}.", ""]
    if pa.min_share_bound is not None:
        out += [f"This fit was required to keep the prestress share of the static stiffness at or above "
                f"{num(pa.min_share_bound)} (a one-sided penalty; the values below are the ones reached).", ""]
    if pa.min_elasticity_bound is not None:
        out += [f"This fit was required to keep ∂lnG'/∂lnP at {num(pa.elasticity_bound_frequency_hz)} Hz at or "
                f"above {num(pa.min_elasticity_bound)} at every prestress of the data (a one-sided penalty; the "
                "values below are the ones reached).", ""]
    rows = [(k, *(q.text(key, i, digits=d) for key, d in (("reference_prestress_N", 4), ("reference_storage", 3),
                                                           ("reference_loss", 3), ("reference_share", 3))))
            for i, k in enumerate(pa.reference_dataset)]
    out += [f"At {num(pa.reference_frequency_hz)} Hz, for each prestress of the data (model P in N at the fitted "
            "strut length):", "",
            table(("data set", "P (N)", "∂lnG'/∂lnP", "∂lnG''/∂lnP", "share of static stiffness carried by P·Kp"),
                  rows),
            f"Adherent cells show ∂lnG'/∂lnP of about {num(CELL_ELASTICITY)} (G' nearly proportional to the "
            "prestress). The share is the ω → 0 limit of ∂lnG/∂lnP. Elasticities at every data point are in "
            "`fit.json` (`prestress_activity`) and `PrestressActivity.to_dataframe()`. This section shows how the "
            "fitted model responds to a change of prestress; it does not show that the data determine that "
            "response (a fit to a frequency sweep alone does not constrain it).", ""]
    return out


def section_stiffness(result: FitResult, baseline=None) -> list[str]:
    """The spread of the fitted tendon stiffnesses (and, for the Voigt cell, the bound on it and those at a bound)."""
    q = result.derived
    unit = result.problem.units[0]
    inner = result.stiffness_spread_interior
    full = result.stiffness_spread
    extra = ("" if inner is None or inner == full else
             f"; {inner[0]:.3g} .. {inner[1]:.3g} {unit} ({inner[2]:.1f} decades) without those at bounds")
    line = (f"Tendon stiffnesses span {q.text('stiffness_spread', 0, unit, ln=True)} to "
            f"{q.text('stiffness_spread', 1, unit, ln=True)}: "
            f"{q.text('stiffness_spread', 2, 'decades', 3)}{extra}.")
    pr = result.problem
    if isinstance(pr, FitProblem):  # the Voigt cell's stiffness groups and its bound on their spread
        if any(result.parameters[g].at_bound for g in set(pr.ea_groups.tolist())):
            line += " Stiffnesses sit at their bounds: the span is set by the bound box, not measured by the data."
        if pr.max_decades is not None:
            line += (f" The fit bounded the spread to {num(pr.max_decades)} decades" +
                     (" (no constraint here: the bound is wider than the stiffness bounds)." if not pr.compact
                      else "."))
    return ["## Stiffness spread", "", line, ""]


def section_held(result: FitResult, baseline=None) -> list[str]:
    """A mechanism's law parameters held at a value (not fitted, not counted, not measured by this fit)."""
    held = [f"`{f.law_parameter}` = {num(f.value)}" for f in result.spec.fields if f.layout == "fixed"]
    if not held:
        return []
    return ["Held, not fitted (not counted among the free parameters, and not measured by this fit): "
            + ", ".join(held) + ".", ""]


def section_assignments(result: FitResult, baseline=None) -> list[str]:
    """A distributed property's assignments: how much the moduli differ between them."""
    spec = result.spec
    if not spec.heterogeneous:
        return []
    q = result.derived
    return [f"The moduli are the average over K = {spec.K} stratified assignments of the distributed property to "
            f"the tendons; between assignments G' varies by up to {q.text('assignment_spread', 0, 'decades', 3)} "
            f"and G'' by up to {q.text('assignment_spread', 1, 'decades', 3)} (standard deviation).", ""]


def parameter_error(value: float, se: float | None) -> str:
    """A fitted parameter's one standard error: ``±x %`` while it is below 50 %, else the factor ``×/÷ f`` (the
    fit works in ln-parameters, so a large error is a factor, not a difference); "" when not determined."""
    if se is None or not math.isfinite(se) or not value:
        return ""
    return ln_error(se / abs(value))


def section_parameters(result: FitResult, baseline=None) -> list[str]:
    """Every parameter with its standard error (a percentage, or a factor when large), bounds, why it has none,
    and its spread over the other starts that fit as well; the strong correlations."""
    alt = result.alternative_spread() if result.alternatives else {}
    rows: list[list[str]] = []
    why: dict[str, list[str]] = {}
    for p, (se, note) in zip(result.parameters, result.standard_errors):
        err = parameter_error(p.value, se)
        reason = note.strip("()") or ("not determined by the data" if not err else "")
        if not err:
            why.setdefault(reason, []).append(p.name)
        row = [p.name, num(p.value, 4), p.unit, err or "—", num(p.lower, 3), num(p.upper, 3)]
        if alt:
            row.append(num(alt.get(p.name), 3) if p.name in alt else "—")
        rows.append(row)
    head = ["parameter", "value", "unit", "one standard error", "lower", "upper"]
    if alt:
        head.append("spread over equally good starts (decades)")
    out = ["## Parameters", "",
           "Each value with its standard error (one σ, linearized at the optimum; see *How well the data determine "
           "the parameters*): a percentage, or a factor ×/÷ when the error exceeds 50 % (the fit works in the "
           "logarithms of the parameters).", "", table(head, rows)]
    for reason, names in why.items():
        shown = ", ".join(names[:12]) + (f" … ({len(names)} in all)" if len(names) > 12 else "")
        out.append(f"No standard error (—) for {shown}: {reason}.")
    if why:
        out.append("")
    if alt:
        out += [f"{len(result.alternatives)} other start(s) fit as well: where a parameter's spread over them exceeds "
                "its local error, the data allow several basins and the spread is the honest uncertainty.", ""]
    if result.identifiability().gauge_removed:
        out += ["The strut length L is an exact gauge of the moduli: each error is that of the combination the note "
                "names (EA/L², c/L, P/L²) at the fitted L.", ""]
    strong = result.correlations()
    if strong:
        out += [f"Correlations with |ρ| ≥ {CORRELATION_THRESHOLD:g}, strongest first ({len(strong)}; all in "
                "`fit.json`): " + ", ".join(correlation_text(strong, limit=10)) + ".", ""]
    else:
        out += [f"No correlation between determined parameters reaches |ρ| = {CORRELATION_THRESHOLD:g}.", ""]
    if result.n_at_bound:
        out += [f"{result.n_at_bound} parameter(s) sit at a bound: the data want them beyond it, so the value is a "
                "limit, not an estimate.", ""]
    if baseline is not None:
        out += [f"Baseline `{baseline.spec.name}` parameters: " + ", ".join(
            f"{p.name} = {plus_minus(p.value, se, p.unit, note, digits=4, ln=True)}"
            for p, (se, note) in zip(baseline.parameters, baseline.standard_errors)), ""]
    return out


def section_errors(result: FitResult, baseline=None) -> list[str]:
    """Data, model and log10 error at every point, per data set."""
    out = ["## Errors", ""]
    base_fits = baseline.fits if baseline is not None and len(baseline.datasets) == len(result.datasets) else None
    se = result.model_standard_errors()  # decades of log10 G' / G'' / J, per residual
    out.append("Model values with their standard errors (linearized at the optimum, from the parameters' "
               "covariance: `FitResult.model_standard_errors()`).")
    if not np.isfinite(se).any() or (baseline is not None and not np.isfinite(baseline.model_standard_errors()).any()):
        # said once here, not in every cell of the tables below
        whose = "the model values" if not np.isfinite(se).any() else "the baseline's values"
        out.append(f"Not determined for {whose} (shown without ±): the noise level σ is unknown (no standard "
                   "deviations in the data, and as many seen parameter combinations as residuals).")
    out.append("")
    for f in result.fits:
        d = f.data
        if f.axis == "time":
            if result.joint:
                out += [f"Data set {f.index} (`{_name(d.source)}`):", ""]
            e = se[result.problem.rows(f.index)]
            out.append(table(["time (s)", "J data (1/Pa)", "J model (1/Pa)", "log10 error"],
                             [[num(d.time_s[i]), num(d.compliance[i]), _model_value(f.J_model[i], e[i]),
                               f"{f.residuals[i]:+.4f}"] for i in range(d.n)]))
            continue
        xname = "prestress (Pa)" if f.axis == "prestress" else "frequency (Hz)"
        head = [xname, "G' data (Pa)", "G' model (Pa)", "log10 error", "G'' data (Pa)", "G'' model (Pa)",
                "log10 error"]
        if base_fits is not None:
            head += ["G' baseline", "G'' baseline"]
        rows = []
        e = se[result.problem.rows(f.index)]
        base_se = baseline.model_standard_errors()[baseline.problem.rows(f.index)] if base_fits is not None else None
        for i in range(d.n):
            row = [num(f.x[i]), num(d.G_storage[i]), _model_value(f.G_storage_model[i], e[i]),
                   f"{f.residuals[i]:+.4f}", num(d.G_loss[i]), _model_value(f.G_loss_model[i], e[d.n + i]),
                   f"{f.residuals[d.n + i]:+.4f}"]
            if base_fits is not None and base_se is not None:
                row += [_model_value(base_fits[f.index].G_storage_model[i], base_se[i]),
                        _model_value(base_fits[f.index].G_loss_model[i], base_se[d.n + i])]
            rows.append(row)
        if result.joint:
            out += [f"Data set {f.index} (`{_name(d.source)}`):", ""]
        out.append(table(head, rows))
    return out


def _model_value(value: float, se_decades: float) -> str:
    """A model value with its standard error, from that of its log10 (first order: value·ln10·se)."""
    if not math.isfinite(se_decades):
        return num(value, 4)  # σ unknown: said once above the table (section_errors)
    return plus_minus(value, value * math.log(10.0) * se_decades, "", "", 4)


def section_alternatives(result: FitResult, baseline=None) -> list[str]:
    """Other starts' solutions that fit almost as well (the non-uniqueness): how far each is from the best."""
    if not result.alternatives:
        return []
    best = np.log10([p.value for p in result.parameters])
    rows = []
    for a in result.alternatives:
        far = np.abs(np.log10([p.value for p in a.parameters]) - best)
        i = int(np.argmax(far))
        rows.append((a.start, num(a.rms_log10_error, 4), f"{far[i]:.2f} ({a.parameters[i].name})"))
    return ["## Other solutions that fit almost as well", "",
            table(("start", "RMS log10 error", "largest parameter difference from the best (decades)"), rows),
            "Standard errors are computed at the best fit only: these other optima are shown without them (their "
            "distance from the best fit is itself a measure of what the data leave open).", ""]


#: the report's sections, in order: (name, function); the names in MODEL_SECTIONS run only where the model asks
SECTIONS = [("summary", section_summary), ("provenance", section_provenance), ("datasets", section_datasets),
            ("combinations", section_combinations),
            ("baseline", section_baseline), ("shape", section_shape), ("held", section_held),
            ("prestress", section_prestress),
            ("structure", section_structure),
            ("identifiability", section_identifiability),
            ("profile", section_profile),
            ("comparison", section_comparison), ("creep", section_creep), ("stiffness", section_stiffness),
            ("assignments", section_assignments), ("parameters", section_parameters), ("errors", section_errors),
            ("alternatives", section_alternatives)]
#: sections that belong to one kind of model (Problem.report_sections names the ones that apply)
MODEL_SECTIONS = frozenset({"prestress", "creep", "held", "assignments"})


def section_out_of_sample(validation) -> list[str]:
    """The model and its structure-free baselines refitted on held-out splits, ranked, with the verdict."""
    if validation is None:
        return []
    rows = [(f"**{r.model}**" if r.model == validation.model else r.model,
             "tensegrity" if r.structural else "structure-free",
             "n/a" if r.n_params < 0 else r.n_params, num(r.mean, 3), num(r.worst, 3),
             *(num(x, 3) for x in r.rms)) for r in validation.rows]
    return ["## Out of sample: the model against its baselines", "",
            "Every model refitted on each split's training data (frequency sweeps trained at or below a cut-off, "
            "prestress sweeps without some prestresses) and scored by the RMS of its log10 errors on the points it "
            "did not see (decades); best first.", "",
            table(("model", "kind", "parameters", "mean held-out RMS", "worst", *validation.splits), rows),
            f"**Verdict**: {validation.verdict}.", "",
            "*What this does not show*: held-out errors on data generated from a published law measure how well a "
            "model extrapolates that law, not the cell; a model that fits the training data better can still "
            "extrapolate worse.", ""]


def fit_markdown(result: FitResult, baseline: FitResult | None = None, title: str | None = None,
                 comparison=None, validation=None) -> str:
    """A Markdown report of a fit of any model: verdict, each data set, identifiability, model comparison,
    parameters, errors, the baseline beside it, and the sections of its kind of model.

    Parameters
    ----------
    result : FitResult
        The (possibly joint) fit.
    baseline : FitResult, optional
        A baseline fit of the same data (the homogeneous cell for a Voigt fit).
    title : str, optional
    comparison : ModelComparison, optional
        From :func:`tenscell.fitting.scores.compare_models` (e.g. with held-out data); computed from ``result``
        and ``baseline`` when not given.
    validation : OutOfSampleComparison, optional
        The model and its baselines out of sample (:func:`tenscell.fitting.validation.compare_out_of_sample`).
    """
    if title is None:
        title = report_title(result)
    out = [f"# {title}", ""]
    for _, lines in fit_sections(result, baseline, comparison=comparison, validation=validation):
        out += lines
    return "\n".join(out)


def report_title(result: FitResult) -> str:
    """The report's default title: the model and the data files."""
    return f"Fit of `{result.spec.name}` to " + " and ".join(f"`{_name(d.source)}`" for d in result.datasets)


def fit_sections(result: FitResult, baseline: FitResult | None = None, comparison=None,
                 validation=None) -> list[tuple[str, list[str]]]:
    """The report's sections in order, ``(name, Markdown lines)``, as :func:`fit_markdown` joins them (the HTML
    report, :func:`tenscell.reports.html_page.fit_report_html`, renders the same sections with the figures between
    them); arguments as there. The out-of-sample comparison is the section ``"out_of_sample"``, after
    ``"comparison"``."""
    own = set(result.problem.report_sections)
    out: list[tuple[str, list[str]]] = []
    for name, section in SECTIONS:
        if name in MODEL_SECTIONS and name not in own:
            continue
        if name == "stiffness" and result.stiffness_spread is None:
            continue
        if name == "comparison":
            out += [(name, section_comparison(result, baseline, comparison=comparison)),
                    ("out_of_sample", section_out_of_sample(validation))]
        else:
            out.append((name, section(result, baseline)))
    return out
