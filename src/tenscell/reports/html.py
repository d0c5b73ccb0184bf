"""HTML for notebooks: what Jupyter shows for a result (``_repr_html_``), rendered only from its fields.

A result's ``_repr_html_`` names its renderer here through :func:`tenscell._results.reporter` (results never
import ``reports/``), as its ``plot()`` names a drawing function. Each renderer gives one self-contained ``<div>``:
a title line, then small tables — for a fit the verdict, the fit quality, where each data set came from and the
parameters with their standard errors (a factor ×/÷ where the error of an ln-parameter exceeds 50 %), "not
determined" once per reason, and the correlations as lmfit lists them. Every text that comes from a file, a
user or a model is escaped (:func:`html.escape`); no script, no external style.
"""
from __future__ import annotations

import math
from html import escape
from typing import Any, Iterable, Sequence

import numpy as np

from .._results import CORRELATION_THRESHOLD, correlation_text, ln_error, span
from ..fitting.records import STATUSES
from ._format import num

__all__ = ["fit_html", "data_html", "frequency_response_html", "fitted_model_html", "comparison_html",
           "population_html", "ensemble_html", "structure_html", "html_table"]

#: the one inline style of every table (notebook themes style the rest)
_TABLE = 'style="border-collapse: collapse; margin: 0.3em 0"'
#: most rows a table shows before "... and N more"
_MAX_ROWS = 40


def html_table(header: Sequence[str], rows: Iterable[Sequence[Any]], limit: int = _MAX_ROWS) -> str:
    """An HTML table; every cell is ``str()`` of the value, escaped. Beyond ``limit`` rows: "... and N more"."""
    rows = list(rows)
    head = "".join(f'<th style="text-align: left">{escape(str(h))}</th>' for h in header)
    head = f"<thead><tr>{head}</tr></thead>" if any(header) else ""
    body = "".join("<tr>" + "".join(f'<td style="text-align: left">{escape(str(c))}</td>' for c in r) + "</tr>"
                   for r in rows[:limit])
    more = (f'<tr><td colspan="{len(header)}">... and {len(rows) - limit} more</td></tr>'
            if len(rows) > limit else "")
    return f"<table {_TABLE}>{head}<tbody>{body}{more}</tbody></table>"


def _div(title: str, *parts: str) -> str:
    """One result: its title (escaped here) and its parts (already HTML)."""
    return ('<div class="tenscell-repr">' + f"<p><strong>{escape(title)}</strong></p>" + "".join(parts) + "</div>")


def _p(text: str) -> str:
    return f"<p>{escape(text)}</p>"


def _pairs(rows: Iterable[tuple[str, Any]]) -> str:
    """A two-column table of (what, value)."""
    return html_table(("", ""), rows)


def _short(source: str) -> str:
    return str(source).replace("\\", "/").rsplit("/", 1)[-1]


# ------------------------------------------------------------------------------------------------
# fits
# ------------------------------------------------------------------------------------------------
def _fit_quality(result) -> list[tuple[str, Any]]:
    aic, bic = result.information_criteria()
    aic_l, bic_l = result.information_criteria_lmfit()
    rows: list[tuple[str, Any]] = [
        ("model", f"{result.spec.name}: {result.problem.describe()}"),
        ("verdict", result.verdict),
        ("RMS log10 error", f"{result.rms_log10_error:.4g} decades (tolerance {result.tolerance:g} on every data "
                            "set)"),
        ("free parameters", f"{result.n_free} against {result.problem.n_residuals} residuals"),
        ("status", f"{result.status}: {STATUSES[result.status]}"),
        ("AIC / BIC", f"{aic:.1f} / {bic:.1f} ({_criteria_count(result)}); lmfit's convention (n ln(χ²/n) + 2k, + k ln "
                      f"n; σ not counted): {aic_l:.1f} / {bic_l:.1f}"),
        ("search", f"{result.starts} start(s), seed {result.seed}, {result.n_evaluations} model evaluations, "
                   f"{result.elapsed_s:.1f} s"),
    ]
    if result.n_at_bound:
        rows.append(("at a bound", f"{result.n_at_bound} parameter(s): limits, not estimates"))
    return rows


def _criteria_count(result) -> str:
    """How tenscell's AIC and BIC count (:data:`tenscell.fitting.records.CRITERIA_CONVENTION`), in a few words."""
    k = result.problem.n_model_parameters
    if result.sigma_known:
        return f"k = {k}; −2 ln L from the data's standard deviations"
    return f"k = {k} + 1: the noise σ, estimated from the residuals, counts as a parameter"


def _datasets(result) -> str:
    rows = []
    for f in result.fits:
        d = f.data
        read = d.provenance.line() if d.provenance is not None else d.source
        what = "creep J(t)" if f.axis == "time" else f"{f.axis} sweep"
        noise = result.noise[f.index]
        rows.append((f.index, _short(d.source), f"{d.n} points, {what}", f"{f.rms_log10_error:.4g}",
                     "not stated" if noise is None else f"{noise:.3g}", read))
    return html_table(("data set", "file", "points", "RMS log10 error", "stated noise (decades)", "read as"), rows)


def _parameters(result) -> str:
    rows: list[tuple] = []
    why: dict[str, list[str]] = {}
    for p, (se, note) in zip(result.parameters, result.standard_errors):
        if se is None:
            why.setdefault(note.strip("()") or "not determined by the data", []).append(p.name)
            err = "—"
        else:
            err = ln_error(se / abs(p.value)) if p.value else "—"
            err += f" {note}" if note else ""
        rows.append((p.name, num(p.value, 5), p.unit, err, f"[{num(p.lower, 3)}, {num(p.upper, 3)}]",
                     "" if p.at_bound is None else f"at the {p.at_bound} bound", p.description))
    out = html_table(("parameter", "value", "unit", "one standard error", "bounds", "", "what it is"), rows)
    for reason, names in why.items():
        shown = ", ".join(names[:12]) + (f" … ({len(names)} in all)" if len(names) > 12 else "")
        out += _p(f"— not determined: {shown}: {reason}.")
    return out


def _correlations(pairs) -> str:
    if not pairs:
        return _p(f"No correlation between determined parameters reaches |ρ| = {CORRELATION_THRESHOLD:g}.")
    return _p(f"Correlations (|ρ| ≥ {CORRELATION_THRESHOLD:g}, strongest first): "
              + ", ".join(correlation_text(pairs, limit=10)) + ".")


def fit_html(result) -> str:
    """A :class:`~tenscell.fitting.FitResult`: verdict and fit quality, each data set (where it came from, its
    RMS), the parameters with their standard errors, the correlations."""
    return _div(f"FitResult: {result.label}, {len(result.datasets)} data set(s), "
                f"{sum(d.n for d in result.datasets)} points",
                _pairs(_fit_quality(result)), _datasets(result), _parameters(result),
                _correlations(result.correlations()),
                _p("Standard errors are one σ, linearized at the optimum (result.identifiability()); the full "
                   "report: result.report(), or tenscell.reports.fit.fit_markdown(result)."))


def comparison_html(comparison) -> str:
    """A :class:`~tenscell.fitting.scores.ModelComparison`: one row per model, the preferred ones named."""
    held = comparison.holdout is not None
    best_aic, best_bic = (min(getattr(s, k) for s in comparison.scores) for k in ("aic", "bic"))
    rows = []
    for s in comparison.scores:
        row = [s.name, s.n_params, f"{s.rms_log10_error:.4g}", f"{s.aic:.1f}", f"{s.aic - best_aic:.1f}",
               f"{s.bic:.1f}", f"{s.bic - best_bic:.1f}"]
        if held:
            row.append(num(s.holdout_rms_log10_error, 3))
        rows.append(row)
    head = ["model", "parameters k", "RMS log10 error", "AIC", "ΔAIC", "BIC", "ΔBIC"] + (
        ["held-out RMS log10 error"] if held else [])
    verdict = f"AIC prefers {comparison.best('aic')}, BIC prefers {comparison.best('bic')}"
    if held:
        verdict += f"; on the {comparison.n_holdout} held-out points {comparison.best('holdout')} predicts best"
    return _div(f"ModelComparison of {len(comparison.scores)} models on {comparison.n_residuals} residuals",
                html_table(head, rows), _p(verdict + ". A difference below about 2 is no preference."),
                _p(f"Convention: {comparison.convention}."))


def fitted_model_html(model) -> str:
    """A fitted model (:class:`~tenscell.fitting.models.base.FittedModel`): what it is, its values, its
    prestress."""
    rows: list[tuple[str, Any]] = [("model", model.describe())]
    values = getattr(model, "values", None)
    if isinstance(values, dict):
        rows += [(k, num(v, 5)) for k, v in values.items()]
    for name, unit in (("EA", "N"), ("c", "N·s/m")):
        v = getattr(model, name, None)
        if isinstance(v, np.ndarray):
            rows.append((name, f"{v.size} tendons, {span(v, unit)}"))
    if model.s is not None:
        rows.append(("prestress", f"model P (N) = s × prestress (Pa), s = {num(model.s, 5)} m²; the data's "
                                  f"prestresses {span(model.prestress_pa, 'Pa')}"))
    elif model.P is not None:
        rows.append(("prestress", f"P = {num(model.P, 5)} N (fitted: the data stated none)"))
    if model.viscosity:
        rows.append(("cytoplasm viscosity", f"{num(model.viscosity, 5)} Pa·s"))
    rows.append(("fitted to", model.source))
    return _div(f"{type(model).__name__}", _pairs(rows),
                _p("Standard errors belong to the fit: FitResult (fit.json) holds them."))


# ------------------------------------------------------------------------------------------------
# data and responses
# ------------------------------------------------------------------------------------------------
def _head_tail(df, n: int = 4) -> tuple[list[str], list[list[str]]]:
    """Column names and the first and last ``n`` rows (numbers with 4 significant figures)."""
    cols = [str(c) for c in df.columns]
    idx = list(range(len(df))) if len(df) <= 2 * n + 1 else [*range(n), -1, *range(len(df) - n, len(df))]
    rows = [["…"] * len(cols) if i < 0 else
            [num(v, 4) if isinstance(v, (float, np.floating)) else str(v) for v in df.iloc[i]] for i in idx]
    return cols, rows


def data_html(data) -> str:
    """Measured data (:class:`~tenscell.io.data.RheologyData`, :class:`~tenscell.io.creep_data.CreepData`):
    what they are, where they came from (the provenance), their first and last points."""
    creep = not hasattr(data, "G_storage")
    if creep:
        what = (f"CreepData: {data.n} points, t {span(data.time_s, 's')}, J {span(data.compliance, '1/Pa')}")
    else:
        sweep = (f"prestress sweep, P {span(data.prestress, 'Pa')}" if data.prestress is not None
                 else "frequency sweep")
        what = f"RheologyData: {data.n} points, {sweep}, f {span(data.frequency_hz, 'Hz')}"
    rows: list[tuple[str, Any]] = [("source", data.source)]
    if data.provenance is not None:
        rows.append(("read as", data.provenance.line()))
    rows.append(("standard deviations", "stated" if data.has_sd else "not stated"))
    counts = getattr(data, "counts", None)
    if counts is not None:
        rows.append(("binned", f"each point stands for {span(counts)} measured points"))
    rows += [("comment", c) for c in data.comments[:3]]
    cols, body = _head_tail(data.to_dataframe())
    return _div(what, _pairs(rows), html_table(cols, body))


def frequency_response_html(resp) -> str:
    """A :class:`~tenscell.response.FrequencyResponse`: the grid, and G′, G″ at its first, middle and last
    frequency for each prestress (at most :data:`_MAX_ROWS` prestresses)."""
    nP, nf = resp.J.shape
    picks = sorted({0, nf // 2, nf - 1})
    head = ["P (N)"] + [f"G′, G″ at {num(resp.frequency_hz[k], 3)} Hz (Pa)" for k in picks]
    rows = [[num(P, 4)] + [f"{num(resp.G_storage[i, k], 4)}, {num(resp.G_loss[i, k], 4)}" for k in picks]
            for i, P in enumerate(resp.prestress)]
    facts = [("frequencies", f"{nf}, {span(resp.frequency_hz, 'Hz')}"),
             ("prestresses", f"{nP}, {span(resp.prestress, 'N')}"), ("strut length L", f"{num(resp.L, 4)} m")]
    if resp.viscosity:
        facts.append(("cytoplasm viscosity", f"{num(resp.viscosity, 4)} Pa·s"))
    return _div(f"FrequencyResponse: {nP} prestress(es) × {nf} frequencies", _pairs(facts), html_table(head, rows),
                _p("Every point: .to_dataframe() (units in the column names), .to_xarray(), .plot()."))


# ------------------------------------------------------------------------------------------------
# populations
# ------------------------------------------------------------------------------------------------
def population_html(result) -> str:
    """A :class:`~tenscell.population.PopulationResult`: cells per condition (fitted, converged, failed) and
    the per-condition medians with their interquartile ranges."""
    t = result.table
    rows = []
    for cond, g in t.groupby("condition", sort=True):
        ok = g["status"] == "ok"
        med = float(np.median(g.loc[ok, "rms_log10_error"])) if ok.any() else math.nan
        rows.append((cond or "(none)", len(g), int(ok.sum()), int(g["converged"].sum()), int((~ok).sum()),
                     num(med, 3)))
    cells = html_table(("condition", "cells", "fitted", "converged", "failed", "median RMS log10"), rows)
    s = result.summary()
    summary = html_table(("condition", "quantity", "median", "interquartile range", "n"),
                         [(r.condition or "(none)", r.quantity, num(r.median), f"{num(r.q25)} – {num(r.q75)}",
                           r.n_fitted) for r in s.itertuples(index=False)])
    o = result.options
    return _div(f"PopulationResult: {result.n_cells} cells", cells, summary,
                _p(f"Each cell fitted with tendons {o.tendons}, damping {o.damping}, {o.starts} start(s); run seed "
                   f"{result.seed}; {result.elapsed_s:.1f} s on {result.n_workers or 'no'} Dask worker(s). The spread "
                   "of a parameter across cells includes its fitting uncertainty; no test of significance is made."))


def ensemble_html(result) -> str:
    """An :class:`~tenscell.population.ensemble.EnsembleResult`: the spread between assignments and how far the
    fit's own average lies from the ensemble mean."""
    nP, nf = result.reference.shape
    rs, rl = result.relative_spread()
    zs, zl = result.reference_z()
    rows = [("assignments", f"{result.K} ({result.n_failed} not a stable cell), seed {result.seed}"),
            ("grid", f"{nP} prestress(es) ({result.prestress_unit}) × {nf} frequencies, "
                     f"{span(result.frequency_hz, 'Hz')}"),
            ("spread between assignments (sd/mean, largest)", f"G′ {100 * rs:.3g} %, G″ {100 * rl:.3g} %"),
            (f"the fit's {result.reference_K}-assignment average", f"within {zs:.2g} (G′) and {zl:.2g} (G″) sampling "
                                                                   "standard errors of the ensemble mean"),
            ("run", f"{result.elapsed_s:.1f} s" + (f" on {result.workers} Dask worker(s)" if result.workers else ""))]
    return _div(f"EnsembleResult: {result.mechanism}", _pairs(rows),
                _p("One cell of this mechanism differs from the mean by about the spread; every point's mean, sd and "
                   "5–95 % band: .to_dataframe()."))


# ------------------------------------------------------------------------------------------------
# structures
# ------------------------------------------------------------------------------------------------
def structure_html(structure) -> str:
    """A :class:`~tenscell.model.Structure` or a :class:`~tenscell.model.Cell`: what its ``repr`` says, then the
    interactive 3D view (:func:`tenscell.plotting.interactive.view_html`: plotly, or the static view with the
    command that installs it)."""
    from ..plotting.interactive import view_html

    head, *lines = repr(structure).splitlines()
    facts = "<ul>" + "".join(f"<li>{escape(line.strip())}</li>" for line in lines) + "</ul>"
    return _div(head.strip("<>"), facts, view_html(structure))
