"""The text report of a fit (lmfit's ``fit_report``): statistics, parameters with ±, correlations, residuals."""
from __future__ import annotations

from .._results import CORRELATION_THRESHOLD, correlation_text, plus_minus

__all__ = ["fit_text"]


def fit_text(result) -> str:
    """A fit as plain text, in the spirit of lmfit's ``fit_report`` (:meth:`tenscell.fitting.FitResult.report`)."""
    lines = [
        "[[Fit statistics]]",
        *(f"    data {f.index}:             {f.data.source} ({f.data.n} points, {f.axis}): "
          f"rms {f.rms_log10_error:.5f}" for f in result.fits),
        f"    model:              {result.spec.name}: {result.problem.describe()}",
        f"    free parameters:    {result.problem.n_free} (residuals: {result.problem.n_residuals})",
        f"    rms log10 error:    {result.rms_log10_error:.5f} (tolerance {result.tolerance:g}): " + result.verdict,
        f"    starts:             {result.starts} (seed {result.seed}), {result.n_evaluations} model evaluations, "
        f"{result.elapsed_s:.1f} s",
        f"    message:            {result.message}",
    ]
    if result.stiffness_spread is not None:
        q, u = result.derived, result.problem.units[0]
        lines.append(f"    stiffness spread:   {q.text('stiffness_spread', 0, u, 3, ln=True)} .. "
                     f"{q.text('stiffness_spread', 1, u, 3, ln=True)} ({q.text('stiffness_spread', 2, 'decades', 3)})")
    lines.append("[[Parameters]] (value +/- standard error, in the unit shown: a factor ×/÷ when it exceeds 50 %, "
                 "as the fit works in ln-parameters; see identifiability())")
    width = max(len(p.name) for p in result.parameters)
    if result.identifiability().gauge_removed:
        lines.append("    (L is an exact gauge of the moduli: the errors are those of EA/L², c/L, P/L² at the "
                     "fitted L)")
    why: dict[str, list[str]] = {}  # "not determined" once per reason, under the table
    for p, (se, note) in zip(result.parameters, result.standard_errors):
        if se is None:
            why.setdefault(note.strip("()") or "not determined by the data", []).append(p.name)
            shown = f"{p.value:.6g}" + (f" {p.unit}" if p.unit else "") + "  (—)"
        else:
            shown = plus_minus(p.value, se, p.unit, note, ln=True)
        lines.append(f"    {p.name + ':':<{width + 1}} {shown}  [{p.lower:.3g}, {p.upper:.3g}]  {p.description}")
    for reason, names in why.items():
        listed = ", ".join(names[:12]) + (f" ... ({len(names)} in all)" if len(names) > 12 else "")
        lines.append(f"    (—) not determined: {listed}: {reason}")
    strong = result.correlations()
    lines.append(f"[[Correlations]] (unreported correlations are < {CORRELATION_THRESHOLD:.3f}; strongest first)")
    lines += ["    " + c for c in correlation_text(strong)]
    if not strong:
        lines.append("    none")
    for f in result.fits:
        lines += _residual_lines(f)
    if result.alternatives:
        lines.append(f"[[Alternatives]] {len(result.alternatives)} other start(s) fit almost as well:")
        lines += [f"    start {a.start}: rms {a.rms_log10_error:.5f}" for a in result.alternatives]
    return "\n".join(lines) + "\n"


def _residual_lines(f) -> list[str]:
    """The text report's residual table of one data set (moduli: G' and G''; creep: J)."""
    d = f.data
    out = [f"[[Residuals log10(model/data): data {f.index}]]"]
    if f.axis == "time":
        out.append(f"    {'t (s)':>10}  {f.symbol:>10}")
        out += [f"    {d.time_s[i]:>10.4g}  {f.residuals[i]:>+10.5f}" for i in range(d.n)]
        return out
    xname = "P (Pa)" if f.axis == "prestress" else "f (Hz)"
    out.append(f"    {xname:>10}  {'G_storage':>10}  {'G_loss':>10}")
    out += [f"    {f.x[i]:>10.4g}  {f.residuals[i]:>+10.5f}  {f.residuals[d.n + i]:>+10.5f}" for i in range(d.n)]
    return out
