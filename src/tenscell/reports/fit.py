"""The Markdown report of a fit, rendered only from the fit's result fields."""
from __future__ import annotations

import math

import numpy as np

from ..fitting.result import FitResult, frequency_slopes, prestress_slopes
from ..io.data import RheologyData

__all__ = ["fit_markdown"]


def _data_slopes(data: RheologyData):
    a1, b1 = np.polyfit(data.prestress, data.G_storage, 1)
    a2, b2 = np.polyfit(data.prestress, data.G_loss, 1)
    return float(a1), float(b1), float(a2), float(b2)


def fit_markdown(result: FitResult, baseline: FitResult | None = None, title: str | None = None) -> str:
    """A markdown report: verdict, parameters (bounds hit), error table, the homogeneous baseline beside it.

    Parameters
    ----------
    result : FitResult
        The (heterogeneous) fit.
    baseline : FitResult, optional
        The homogeneous fit (``tendons="uniform"``) of the same data.
    """
    d = result.data
    title = title or f"Fit of the tensegrity model to {d.source}"
    lo, hi, dec = result.stiffness_spread
    out = [f"# {title}", ""]
    verdict = "**converged**" if result.converged else "**NOT converged**"
    out += [
        f"- Data: `{d.source}`: {d.n} points, {d.kind} sweep.",
        f"- Model: {result.cell.describe()}; stiffness {result.tendons}, damping {result.damping}; "
        f"{result.problem.n_free} free parameters against {result.problem.n_residuals} residuals.",
        f"- RMS of the log10 errors: **{result.rms_log10_error:.5f}** decades "
        f"(tolerance {result.tolerance:g}): {verdict}.",
        f"- {result.message}",
        f"- Starts: {result.starts} (seed {result.seed}); time {result.elapsed_s:.1f} s; "
        f"{result.n_evaluations} model evaluations.",
        f"- Tendon stiffness spread: {lo:.3g} to {hi:.3g} N ({dec:.1f} decades){result._interior_text()}.",
        "",
    ]
    if baseline is not None:
        out += ["## Heterogeneous fit versus the homogeneous baseline", "",
                "| model | stiffness | free parameters | RMS log10 error | converged |", "|---|---|---|---|---|"]
        for name, r in (("heterogeneous", result), ("homogeneous baseline", baseline)):
            out.append(f"| {name} | {r.tendons} | {r.problem.n_free} | {r.rms_log10_error:.5f} | "
                       f"{'yes' if r.converged else 'no'} |")
        out.append("")
    # shape checks
    out += ["## Shape of the fitted model", ""]
    if d.kind == "frequency":
        f_lo, f_hi = float(d.frequency_hz.min()), float(d.frequency_hz.max())
        _, s1, s2 = frequency_slopes(result, f_lo, f_hi, 1000)
        out.append(f"Local log-log slopes on 1000 frequencies from {f_lo:g} to {f_hi:g} Hz: "
                   f"G' {s1.min():.3f} to {s1.max():.3f}; G'' {s2.min():.3f} to {s2.max():.3f}.")
        if f_lo <= 0.01 and f_hi >= 100:
            _, s1, _ = frequency_slopes(result, 0.01, 100, 1000)
            out.append(f"G' slope from 0.01 to 100 Hz: {s1.min():.3f} to {s1.max():.3f}.")
        if baseline is not None:
            _, b1, _ = frequency_slopes(baseline, f_lo, f_hi, 1000)
            out.append(f"Homogeneous baseline: G' slope {b1.min():.3f} to {b1.max():.3f}.")
    else:
        a1, b1, a2, b2 = prestress_slopes(result)
        da1, db1, da2, db2 = _data_slopes(d)
        out += ["| straight line over the data's prestress range | dG'/dP | G'(0) (Pa) | dG''/dP | G''(0) (Pa) |",
                "|---|---|---|---|---|",
                f"| data | {da1:.4f} | {db1:.2f} | {da2:.4f} | {db2:.2f} |",
                f"| fitted model | {a1:.4f} | {b1:.2f} | {a2:.4f} | {b2:.2f} |"]
        if baseline is not None:
            c1, e1, c2, e2 = prestress_slopes(baseline)
            out.append(f"| homogeneous baseline | {c1:.4f} | {e1:.2f} | {c2:.4f} | {e2:.2f} |")
    out.append("")
    # parameters
    out += ["## Parameters", "", "| parameter | value | unit | lower | upper | note |", "|---|---|---|---|---|---|"]
    for p in result.parameters:
        note = ("fixed" if not p.vary else "") + (f"at {p.at_bound} bound" if p.at_bound else "")
        out.append(f"| {p.name} | {p.value:.6g} | {p.unit} | {p.lower:.3g} | {p.upper:.3g} | {note} |")
    out.append("")
    if result.n_at_bound:
        out += [f"{result.n_at_bound} parameter(s) sit at a bound: a stiffness at its lower bound is a tendon "
                "the fit switched off, one at its upper bound a tendon it made rigid.", ""]
    if baseline is not None:
        out += ["Homogeneous baseline parameters: " + ", ".join(
            f"{p.name} = {p.value:.4g} {p.unit}" + (f" ({p.at_bound} bound)" if p.at_bound else "")
            for p in baseline.parameters), ""]
    # error table
    x = d.prestress if d.kind == "prestress" else d.frequency_hz
    xname = "prestress (Pa)" if d.kind == "prestress" else "frequency (Hz)"
    Gs, Gl = result.problem.moduli(result.theta)
    head = f"| {xname} | G' data (Pa) | G' model (Pa) | log10 error | G'' data (Pa) | G'' model (Pa) | log10 error |"
    sep = "|---|---|---|---|---|---|---|"
    if baseline is not None:
        head += " G' baseline | G'' baseline |"
        sep += "---|---|"
        Bs, Bl = baseline.problem.moduli(baseline.theta)
    out += ["## Errors", "", head, sep]
    for i in range(d.n):
        row = (f"| {x[i]:.4g} | {d.G_storage[i]:.4g} | {Gs[i]:.4g} | {result.residuals[i]:+.4f} | "
               f"{d.G_loss[i]:.4g} | {Gl[i]:.4g} | {result.residuals[d.n + i]:+.4f} |")
        if baseline is not None:
            row += f" {Bs[i]:.4g} | {Bl[i]:.4g} |"
        out.append(row)
    out.append("")
    if result.alternatives:
        out += ["## Other solutions that fit almost as well", "",
                "| start | RMS log10 error | c (N·s/m) | stiffness spread (decades) |", "|---|---|---|---|"]
        for a in result.alternatives:
            vals = {p.name: p.value for p in a.parameters}
            ea = np.array([p.value for p in a.parameters if p.name.startswith("EA")])
            cs = ", ".join(f"{v:.4g}" for k, v in vals.items() if k == "c" or k.startswith("c_"))
            out.append(f"| {a.start} | {a.rms_log10_error:.5f} | {cs} | {math.log10(ea.max() / ea.min()):.1f} |")
        out.append("")
    return "\n".join(out)
