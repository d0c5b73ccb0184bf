"""Markdown reports of the studies: no IFs, other references, semiflexible struts, stiffening IFs.

Each function renders one study result from its fields only: every number
printed comes from the run's own inputs and outputs, and each report says
what the study does not show.
"""
from __future__ import annotations

import math

import numpy as np

from ._format import num, table

__all__ = ["no_if_markdown", "references_markdown", "semiflexible_markdown", "stiffening_markdown"]


def _nearest(values, x) -> int:
    """Index of the entry of a positive grid nearest ``x`` in log scale."""
    return int(np.argmin(np.abs(np.log(np.asarray(values) / x))))


def _span(x) -> str:
    """``min–max`` of an array, or the one value when they agree to the digits shown."""
    x = np.asarray(x, dtype=float).ravel()
    lo, hi = num(x.min()), num(x.max())
    return lo if lo == hi else f"{lo}–{hi}"


# ---- no intermediate filaments -----------------------------------------------------------------------
def no_if_markdown(s) -> str:
    """The :class:`~tenscell.studies.no_if.NoIFStudy` as Markdown."""
    cell = s.cell
    Ps = s.without.prestress
    lam = s.c0_eigenvalues
    T0 = cell.T0
    fams = sorted(set(cell.structure.families))
    equal = "all tensions equal" if np.ptp(T0) <= 1e-9 * np.abs(T0).max() else "tensions unequal"
    lines = [
        "# The cell without intermediate filaments",
        "",
        f"{cell.describe()}: {cell.n} coordinates, {cell.m} tendons ({', '.join(fams)}), self-stress dimension "
        f"{cell.self_stress_dim} ({equal}, T0 = {_span(T0)}). Uniform EA = {num(s.EA)} N, c = {num(s.c)} N·s/m.",
        "",
        "## C0 is singular",
        "",
        f"Eigenvalues of C0 at c = {num(s.c)} N·s/m: smallest {lam[0]:.2e}, next {num(lam[1])}, largest "
        f"{num(lam[-1])} N·s/m. The null vector v of C0 is an infinitesimal mechanism (|Aᵀv|/|A| = "
        f"{s.mechanism_residual:.1e}): no tendon length changes along it, so no damping acts on it and only the "
        "prestress (P·Kp) holds it. compliance() therefore uses direct solves; the relaxation spectrum does not exist.",
        f"As f → ∞ the damped coordinates freeze and the mechanism alone moves: G' → {num(s.storage_limit_per_P, 5)}·P Pa "
        "(exact, from vᵀKp v), while G'' → 0. So G'' rises, then falls: a peak.",
        "",
        "## The G'' peak against prestress",
        "",
        table(["P (N)", "f_peak (Hz)", "G''_peak (Pa)", "G' at the peak (Pa)", "f_peak/P (Hz/N)", "G''_peak/P"],
              [(num(P), num(p.frequency_hz, 5), num(p.height, 5), num(p.storage, 5), num(p.frequency_hz / P, 5),
                num(p.height / P, 5)) for P, p in zip(Ps, s.peaks)]),
    ]
    a, b = s.peak_exponents
    fp = np.array([p.frequency_hz for p in s.peaks])
    inside = fp <= s.window_hz
    if Ps.size > 1:
        lines.append(f"Fitted power laws over P = {_span(Ps)} N: f_peak ∝ P^{a:.3f}, G''_peak ∝ P^{b:.3f}.")
    if math.isfinite(s.window_prestress):
        lines.append(
            f"With c = {num(s.c)} N·s/m the peak lies inside the window f ≤ {num(s.window_hz)} Hz for P below about "
            f"{num(s.window_prestress)} N (since f_peak ∝ 1/c, for P/c below {num(s.window_prestress / s.c)} in general)."
        )
    if inside.all():
        lines.append(f"At every prestress of this run the peak is inside the window (f_peak = {_span(fp)} Hz).")
    elif not inside.any():
        lines.append(
            f"**At none of this run's prestresses ({_span(Ps)} N) is the peak inside the window**: it sits at "
            f"{_span(fp)} Hz, so over f ≤ {num(s.window_hz)} Hz G'' only rises."
        )
    else:
        lines.append(f"It is inside the window at P = {', '.join(num(P) for P in Ps[inside])} N and above it at "
                     f"P = {', '.join(num(P) for P in Ps[~inside])} N.")
    lines += ["", _no_if_scans(s), "", "## Is anything else much affected by removing the IFs? (the paper: no)", ""]
    lines += _no_if_comparison(s)
    lines += [
        "",
        "Not shown: the peak's shape in the time domain (the massless equations of motion need a positive definite "
        "C0, which this cell lacks), nor any other reference than this one.",
        "",
    ]
    return "\n".join(lines)


def _no_if_scans(s) -> str:
    fe = np.array([p.frequency_hz for _, p in s.peaks_EA])
    fc = np.array([p.frequency_hz for _, p in s.peaks_c])
    cs = np.array([x for x, _ in s.peaks_c])
    text = (f"At P = {num(s.reference_P)} N: f_peak against uniform EA: "
            + ", ".join(f"EA={num(e)}: {num(p.frequency_hz)} Hz ({num(p.height)} Pa)" for e, p in s.peaks_EA)
            + "; against uniform c: "
            + ", ".join(f"c={num(x)}: {num(p.frequency_hz)} Hz ({num(p.height)} Pa)" for x, p in s.peaks_c) + ".")
    if fc.size > 1:
        dev = float(np.max(np.abs(fc * cs / (fc[0] * cs[0]) - 1)))
        text += f" f_peak·c is constant to {dev:.1e} (the scaling c → s·c maps G(f) to G(s·f))"
    if fe.size > 1:
        text += (f"; over EA = {_span([e for e, _ in s.peaks_EA])} N, f_peak changes by a factor "
                 f"{num(fe.max() / fe.min())}")
    ok = [num(x) for x, p in s.peaks_c if p.frequency_hz <= s.window_hz]
    text += (f". Of the damping values scanned, c = {', '.join(ok)} N·s/m bring the peak inside f ≤ "
             f"{num(s.window_hz)} Hz at this prestress." if ok else
             f". None of the damping values scanned brings the peak inside f ≤ {num(s.window_hz)} Hz at this prestress.")
    return text


def _no_if_comparison(s) -> list[str]:
    Ps, f = s.without.prestress, s.without.frequency_hz
    out = []
    for f0 in sorted({float(f[_nearest(f, 1.0)]), float(f[_nearest(f, 10.0)])}):
        k = _nearest(f, f0)
        gw, gi = s.without.G_storage[:, k], s.with_ifs.G_storage[:, k]
        lw, li = s.without.G_loss[:, k], s.with_ifs.G_loss[:, k]
        out.append(f"- at {num(f[k], 3)} Hz over P = {_span(Ps)} N: G' rises ×{num(gw[-1] / gw[0], 3)} without IFs, "
                   f"×{num(gi[-1] / gi[0], 3)} with; G'' rises ×{num(lw[-1] / lw[0], 3)} without, "
                   f"×{num(li[-1] / li[0], 3)} with")
    i = int(np.argmin(np.abs(Ps - s.reference_P)))
    hi = _nearest(f, s.window_hz)
    w, c = s.without.G_storage[i], s.with_ifs.G_storage[i]
    out.append(f"- at P = {num(Ps[i])} N, G'({num(f[hi], 3)} Hz)/G'({num(f[0], 3)} Hz): {num(w[hi] / w[0], 3)} without IFs, "
               f"{num(c[hi] / c[0], 3)} with; G'({num(f[0], 3)} Hz) = {num(w[0])} Pa without, {num(c[0])} Pa with")
    return out


# ---- other references ------------------------------------------------------------------------------------
def references_markdown(s) -> str:
    """The :class:`~tenscell.studies.references.ReferencesStudy` as Markdown."""
    from ..studies.references import NOT_PRESTRESSABLE, NOT_STABLE, VALID

    mp = s.map
    lo, hi = mp.delta_band(0.0)
    names = {VALID: "valid", NOT_PRESTRESSABLE: "not prestressable", NOT_STABLE: "K0 not positive definite"}
    counts = ", ".join(f"{names[k]}: {int(np.sum(mp.status == k))}" for k in (VALID, NOT_PRESTRESSABLE, NOT_STABLE))
    a0 = mp.alpha[int(np.argmin(np.abs(mp.alpha)))]
    lines = [
        "# Other references",
        "",
        "## Which q0(α, δ) are valid (paper cell with IFs)",
        "",
        f"Grid α = {math.degrees(mp.alpha[0]):g}°…{math.degrees(mp.alpha[-1]):g}° ({mp.alpha.size} values), "
        f"δ = {math.degrees(mp.delta[0]):g}°…{math.degrees(mp.delta[-1]):g}° ({mp.delta.size} values); stability checked at "
        f"P = {num(mp.P)} N, EA = {num(mp.EA)} N. {counts} ({100 * mp.fraction_valid:.1f}% valid).",
        f"At α = {math.degrees(a0):g}° the valid grid points span δ = {math.degrees(lo):.4g}°–{math.degrees(hi):.4g}° "
        f"(resolution {math.degrees(np.min(np.diff(mp.delta))) if mp.delta.size > 1 else float('nan'):.3g}°). Outside the "
        "valid region `paper_cell` raises NotPrestressableError (with the reason: which tendons go slack) and "
        "`linearize` raises NotPositiveDefiniteError.",
    ]
    if len(s.if_free_curve):
        lines.append("IF-free prestressable curve δ*(α): " + ", ".join(
            f"α = {math.degrees(a):g}°: δ* = {math.degrees(d):.4f}°" for a, d in s.if_free_curve) + ".")
    roles = s.roles
    reg = s.cells[roles["regular"]]
    fam = np.array(reg.structure.families)
    tensed = reg.T0 > 1e-12 * np.abs(reg.T0).max()
    regular_delta = math.degrees(reg.parameters["delta"]) if "delta" in reg.parameters else float("nan")
    lines += [
        "",
        "## The references compared",
        "",
        f"Regular member: δ = {regular_delta:.4f}°, with its IF-free self-stress: "
        + "; ".join(f"{int(np.sum((fam == g) & tensed))} {g} tendons at T0 = {_span(reg.T0[(fam == g) & tensed])}"
                    for g in sorted(set(fam[tensed])))
        + "; " + "; ".join(f"{int(np.sum((fam == g) & ~tensed))} {g} tendons at zero tension (springs and dashpots)"
                           for g in sorted(set(fam[~tensed]))) + ". "
        "Cylindrical: every strut end on a vertical circular cylinder through the anchors, threefold symmetric, found "
        "by form-finding (`find_cylindrical_reference`; parameters "
        f"{', '.join(f'{k} = {v:.6g}' for k, v in s.cells[roles['cylindrical']].parameters.items())}).",
        "",
        f"Uniform EA = {num(s.EA)} N, c = {num(s.c)} N·s/m.",
        "",
    ]
    first = next(iter(s.responses.values()))
    f = first.frequency_hz
    idx = sorted({_nearest(f, x) for x in (f[0], 1.0, f[-1])})
    head = ["reference", "coords", "min T0", "P (N)"] + [f"G'({num(f[k], 3)} Hz)" for k in idx] \
        + [f"G''({num(f[k], 3)} Hz)" for k in idx]
    rows = []
    for name, resp in s.responses.items():
        cell = s.cells[name]
        for i, P in enumerate(resp.prestress):
            rows.append([name, cell.n, f"{cell.T0.min():.4f}", num(P)] + [num(resp.G_storage[i, k]) for k in idx]
                        + [num(resp.G_loss[i, k]) for k in idx])
    lines.append(table(head, rows))
    sph, cyl = s.responses[roles["spherical"]], s.responses[roles["cylindrical"]]
    rs, rl = cyl.G_storage / sph.G_storage, cyl.G_loss / sph.G_loss
    lines.append(f"Cylindrical / spherical over all P and f: G' ratio {_span(rs)}, G'' ratio {_span(rl)}.")
    for name in (roles["spherical"], roles["cylindrical"]):
        r = s.responses[name]
        i = r.prestress.size // 2
        slope = np.diff(np.log(r.G_loss[i])) / np.diff(np.log(r.frequency_hz))
        lines.append(f"- {name} at P = {num(r.prestress[i])} N: G'({num(f[-1], 3)} Hz)/G'({num(f[0], 3)} Hz) = "
                     f"{num(r.G_storage[i, -1] / r.G_storage[i, 0], 3)}; log-log slope of G'' {_span(slope)}")
    lines += ["", "Not shown: references off the (α, δ) family other than the two named ones, and the stability of "
              "each reference at prestresses other than the one of the map.", ""]
    return "\n".join(lines)


# ---- semiflexible struts -------------------------------------------------------------------------------
def semiflexible_markdown(s) -> str:
    """The :class:`~tenscell.studies.semiflexible.SemiflexibleStudy` as Markdown."""
    f = s.frequency_hz
    k1 = _nearest(f, 1.0)
    f1 = num(f[k1], 3)
    gr = s.G_rigid[k1]
    first_order = abs(s.rate_storage + 1) < 0.05 and abs(s.rate_loss + 1) < 0.05
    lines = [
        "# Semiflexible struts",
        "",
        f"Each of the {s.n_struts} struts is an elastic Voigt member of axial stiffness EA_s (damping c_s = "
        f"{num(s.c_strut)} N·s/m); tendons EA = {num(s.EA)} N, c = {num(s.c)} N·s/m; P = {num(s.P)} N. The self-stress "
        f"is the rigid cell's (tendon T0 identical; strut force {s.strut_compression:.6g} N of compression at this P).",
        "",
        f"- Convergence to the rigid-strut moduli (max over {num(f[0])}–{num(f[-1])} Hz): |ΔG'/G'| ∝ "
        f"EA_s^{s.rate_storage:.4f}, |ΔG''/G''| ∝ EA_s^{s.rate_loss:.4f} on the stiff end"
        + (f" — first order, error ≈ {num(s.constant_storage)}/EA_s for G' and {num(s.constant_loss)}/EA_s for G'' "
           "(EA_s in N)." if first_order else "."),
    ]
    if abs(s.critical_EA / s.strut_compression - 1) < 1e-6:
        soft = s.G_softest[k1]
        lines.append(
            f"- Softening: K0 stays positive definite for every EA_s above the strut compression P·|T0_s| = "
            f"{s.strut_compression:.6g} N, the least stiffness the Voigt strut law allows (a positive rest length); in "
            f"that limit the struts' tangent stiffness vanishes and the prestressed tendons alone hold the cell: "
            f"G'({f1} Hz) = {num(soft.real, 5)} Pa, G''({f1} Hz) = {num(soft.imag, 5)} Pa "
            f"({100 * (soft.real / gr.real - 1):+.1f}% and {100 * (soft.imag / gr.imag - 1):+.1f}% from rigid).")
    elif math.isfinite(s.critical_EA):
        lines.append(f"- Softening: the cell is stable (K0 positive definite) down to EA_s ≈ {s.critical_EA:.6g} N "
                     f"({s.critical_EA / s.strut_compression:.4g}× the strut compression).")
    else:
        lines.append("- Softening: no strut stiffness in the search range gave a positive definite K0.")
    lines += [
        f"- Euler buckling (pinned struts of length L): the struts reach π²EI/L² when P > EI/{s.euler_EI_per_P:.6g} "
        "(EI in N·m², P in N); `linearize_semiflexible(..., EI=...)` raises BucklingError beyond it.",
        "",
    ]
    rows = []
    if not np.isnan(s.G_softest[k1].real):
        rows.append([f"{s.critical_EA:.6g} (softest)", num(s.G_softest[k1].real, 6), num(s.G_softest[k1].imag, 6), "", ""])
    for e, g, a, b in zip(s.EA_strut, s.G[:, k1], s.error_storage, s.error_loss):
        rows.append([num(e), "unstable", "", "", ""] if np.isnan(g.real)
                    else [num(e), num(g.real, 6), num(g.imag, 6), f"{a:.3e}", f"{b:.3e}"])
    rows.append(["rigid", num(gr.real, 6), num(gr.imag, 6), "0", "0"])
    lines.append(table(["EA_s (N)", f"G'({f1} Hz) (Pa)", f"G''({f1} Hz) (Pa)", "max ΔG'/G'", "max ΔG''/G''"], rows))
    lines += ["Not shown: buckled struts (the linear model stops at the Euler load) and strut bending modes.", ""]
    return "\n".join(lines)


# ---- strain-stiffening filaments ---------------------------------------------------------------------------
def stiffening_markdown(s) -> str:
    """The :class:`~tenscell.studies.stiffening.StiffeningStudy` as Markdown."""
    P = s.prestress
    ex = s.exponent()
    i1 = _nearest(s.frequency_hz, 1.0)
    f1 = num(s.frequency_hz[i1], 3)
    idx = s.stiffening_indices
    T0 = s.cell.T0[idx]
    lines = [
        "# Strain-stiffening filaments",
        "",
        f"The {idx.size} {s.family} tendons follow T = (EA/b)(exp(bε) − 1) + c·l', ε = l/l0 − 1 (b = 0 is the paper's "
        f"linear law); the other tendons are Voigt. Uniform EA = {num(s.EA)} N, c = {num(s.c)} N·s/m. Each stiffening "
        f"tendon's rest length gives the reference tension P·T0 (T0 = {_span(T0)}), and the cell is linearized through "
        "the law with the tangent stiffness (EA + b·T)(1 + ε)/l, which grows with the tension.",
        "",
        table(["b", f"tangent at P={num(P[0])} (N/m)", f"at P={num(P[-1])}", f"G'({f1} Hz) at P={num(P[0])} (Pa)",
               f"at P={num(P[-1])}", "ratio", "exponent of G' in P", f"G''({f1} Hz) ratio"],
              [(num(b), num(s.if_tangent[i, 0]), num(s.if_tangent[i, -1]), num(s.G[i, 0, i1].real, 5),
                num(s.G[i, -1, i1].real, 5), num(s.G[i, -1, i1].real / s.G[i, 0, i1].real),
                f"{ex[i, i1]:.4f}", num(s.G[i, -1, i1].imag / s.G[i, 0, i1].imag)) for i, b in enumerate(s.b)]),
    ]
    k = P.size // 2
    lines.append(f"At P = {num(P[k])} N, G'({f1} Hz) is " + ", ".join(
        f"{num(s.G[i, k, i1].real, 5)} Pa (b={num(b)})" for i, b in enumerate(s.b)) + ".")
    imax = int(np.argmax(ex[:, i1]))
    text = (f"Over P = {num(P[0])}–{num(P[-1])} N the exponent of G' in P ranges over {ex[:, i1].min():.3f}–"
            f"{ex[:, i1].max():.3f}, largest at b = {num(s.b[imax])}")
    if imax < s.b.size - 1:
        text += f"; at the largest b = {num(s.b[-1])} it is {ex[-1, i1]:.3f}"
    lines.append(text + ".")
    ratios = s.G[:, -1, i1].imag / s.G[:, 0, i1].imag
    falls = [num(b) for b, r in zip(s.b, ratios) if r < 1]
    lines.append(f"G''({f1} Hz) from P = {num(P[0])} to {num(P[-1])} N: " + ", ".join(
        f"b={num(b)}: ×{num(r, 3)}" for b, r in zip(s.b, ratios)) + "."
        + (f" For b = {', '.join(falls)} G'' falls with prestress, against the paper's report that G'' increases "
           "with P." if falls else " G'' increases with prestress for every b."))
    lines += ["", "Not shown: finite-amplitude behaviour (see the time-domain simulation with the same law), nor "
              "stiffening of any family but the one named.", ""]
    return "\n".join(lines)
