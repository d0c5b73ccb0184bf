"""A priori predictions: dG′/dσ and dG″/dσ at 0.1 Hz of each structure, with no fitted parameter.

The tensegrity's classic parameter-free test (Stamenović et al.): how much stiffer does the structure get per
pascal of prestress? Here σ is the structure's physical prestress (:mod:`tenscell.model.prestress`: the mean normal
stress of the tendons' virial stress), so dG′/dσ is in Pa per Pa, the unit of the measured lines (bundled:
stamenovic2002, dG′/dP and dG″/dP computed from the data by least squares, :func:`data_slopes`).

Tendons and the dimensionless group
-----------------------------------
Every member is a Voigt tendon of stiffness EA (N) whose loss tangent at 0.1 Hz is φ: ``c_j = φ·EA/(ω l_j)``, so
``k*_j = (EA(1 + iφ) + T_j)/l_j`` and ``K(ω) = P·Kp + EA(1 + iφ)·Km`` (Km = Σ a aᵀ/l). G* is homogeneous of degree
one in (P, EA) at fixed φ, so ``G*/σ`` and ``dG*/dσ`` (at fixed EA) depend on the structure, φ and one group only,

``Π = EA/(σ L²)``  (dimensionless; σ in Pa, L the strut length),

invariant under the exact gauge ``(P, EA, c, L) → (λ²P, λ²EA, λc, λL)``.

The inextensible limit (Π → ∞), derived
---------------------------------------
With inextensible tendons and rigid struts the deformations left are the infinitesimal mechanisms ``N = null Aᵀ``.
Two cases, one answer for the slope:

* mechanisms that the load and the probe excite: ``K⁻¹ → N (P NᵀKpN)⁻¹ Nᵀ``, so ``G′ = σ·(0.5/L)/(σ_P·D0 N
  (NᵀKpN)⁻¹ Nᵀ b)``: G′ ∝ σ, and ``dG′/dσ = G′/σ`` is a pure number of the structure (the classic G ∝ P);
* none (the structure is kinematically determinate once the tendons are inextensible, Km positive definite — the
  paper cell with its intermediate filaments): ``G = EA(1 + iφ)·g1 + P·g0 + O(P²/EA)`` with
  ``g0 = (0.5/L)·D0 Km⁻¹ Kp Km⁻¹ b/(D0 Km⁻¹ b)²``: the intercept grows with EA (not predicted: it needs EA), the
  slope ``dG′/dσ → g0/σ_P`` is a pure number of the geometry and the self-stress.

Either way ``dG″/dσ → 0``: the mechanisms are geometric and undamped, and the tendons' dissipation (their stretch)
vanishes with 1/Π; a cytoplasm viscosity iωη does not depend on σ. The limit is evaluated from the exact
derivative at Π = 10⁶ and 10⁷ (Richardson: the error is O(1/Π)), :func:`inextensible_slopes`.

What G″ needs
-------------
At finite Π the tendons stretch and their loss shows. To first order in φ (each value below is per unit φ, taken
at φ = 10⁻⁶): ``G″/G′ = φ·q(Π)`` and ``dG″/dσ = φ·r(Π)``. φ itself is a property of the tendon material, not of
the structure: nothing here predicts dG″/dσ. What is parameter-free at a given Π is the ratio

``ρ = (dG″/dσ)/(dG′/dσ) ÷ (G″/G′) = r/(q·dG′/dσ)``,

how much of the cell's loss tangent shows up as a prestress slope; the data's ρ is computed from their lines at their
mean prestress. Π (EA/σL²) is not known a priori: the columns at finite Π are a one-parameter family, and only the
inextensible row is a prediction with no parameter at all. Nothing a fit sets enters this table.
"""
from __future__ import annotations

import math

import numpy as np

from .protocol import Table

__all__ = ["FREQUENCY_HZ", "EA_OVER_SIGMA", "a_priori_table", "structure_slopes", "inextensible_slopes",
           "data_slopes", "mechanism_count", "PHI"]

#: frequency of the slopes (Hz): the bundled prestress sweep's
FREQUENCY_HZ = 0.1
#: the values of Π = EA/(σL²) of the table (the inextensible limit is added as inf)
EA_OVER_SIGMA = (0.1, 0.3, 1.0, 3.0, 10.0, 100.0, 1000.0)
#: the tendons' loss tangent at which the first-order loss terms are taken (per unit φ)
PHI = 1e-6
#: the two Π of the Richardson extrapolation to the inextensible limit
_LIMIT_PI = (1e6, 1e7)


def mechanism_count(cell) -> int | None:
    """Infinitesimal mechanisms of the cell with inextensible members: ``n − rank A`` less the rigid-body motions
    (6 for a free-standing structure), from the self-stress dimension (``rank A = m − dim null A``); None where that
    dimension was not computed (sparse-sized cells)."""
    if cell.self_stress_dim < 0:
        return None
    rigid = 0 if cell.structure.fixed else 6
    return int(cell.n - (cell.m - cell.self_stress_dim) - rigid)


def structure_slopes(cell, ea_over_sigma: float, phi: float = PHI, frequency_hz: float = FREQUENCY_HZ) -> dict:
    """G′/σ, dG′/dσ, and per unit tendon loss tangent φ: G″/G′ and dG″/dσ, at Π = EA/(σL²) (module docstring).

    Every member (struts and nucleus included, where they are members) is a Voigt tendon of stiffness
    ``EA = Π·σ·L²`` at P = 1 N and loss tangent φ at ``frequency_hz``. ValueError where a compressed member's EA
    would not exceed its compression (a non-positive rest length).
    """
    from ..laws import Voigt
    from ..linear.assembly import modulus
    from ..linear.dynamic import dynamic_compliance
    from ..model.prestress import virial_prestress

    per = virial_prestress(cell).sigma_per_P
    P = 1.0
    sigma = per * P
    L = float(cell.strut_length)
    EA = float(ea_over_sigma) * sigma * L**2
    w = np.array([2 * math.pi * frequency_hz])
    l = np.asarray(cell.lengths, dtype=float)
    T = P * np.asarray(cell.T0, dtype=float)
    law = Voigt(EA=np.full(cell.m, EA), c=phi * EA / (w[0] * l))
    k = law.complex_stiffness(l, T, w)
    dk_dT, _ = law.complex_stiffness_derivatives(l, T, w)
    J, dJ = dynamic_compliance(cell, P, k, np.stack([k, dk_dT * T[None]]))
    PdJ = -J - dJ[0] + dJ[1]  # P ∂J/∂P at fixed EA and c: homogeneity in (P, k*) plus the tension in k*
    G = modulus(J, L)[0]
    dG = (-G * PdJ[0] / J[0]) / (P * per)  # dG*/dσ (Pa/Pa)
    return {"G_storage_over_sigma": float(G.real / sigma), "dG_storage_dsigma": float(dG.real),
            "loss_tangent_per_phi": float(G.imag / G.real / phi), "dG_loss_dsigma_per_phi": float(dG.imag / phi)}


def inextensible_slopes(cell, **kw) -> dict:
    """:func:`structure_slopes` in the limit Π → ∞ (Richardson on Π = 10⁶, 10⁷) with ``"limit_change"``: the
    relative change of dG′/dσ between the two (its convergence)."""
    a, b = (structure_slopes(cell, p, **kw) for p in _LIMIT_PI)
    ratio = _LIMIT_PI[1] / _LIMIT_PI[0]
    out = {k: (ratio * b[k] - a[k]) / (ratio - 1) for k in a}  # f(Π) = f∞ + c/Π + O(1/Π²)
    if b["G_storage_over_sigma"] > 0.5 * ratio * a["G_storage_over_sigma"]:
        out["G_storage_over_sigma"] = math.inf  # G′ grows as EA (no mechanism): its intercept needs EA
    out["limit_change"] = abs(b["dG_storage_dsigma"] - a["dG_storage_dsigma"]) / abs(b["dG_storage_dsigma"])
    return out


def data_slopes(datasets) -> dict:
    """The measured lines: dG′/dP and dG″/dP (Pa/Pa, least squares over the prestress sweep at its frequency), and
    ρ = (dG″/dP)/(dG′/dP) ÷ (G″/G′ at the mean prestress). ValueError without a prestress sweep at one frequency."""
    from .falsification import varies_with_prestress

    sweep = next((d for d in datasets if d.prestress is not None and varies_with_prestress(d)), None)
    if sweep is None:
        raise ValueError("a priori slopes need a prestress sweep (a data set whose prestress varies)")
    f = np.unique(sweep.frequency_hz)
    if f.size != 1:
        raise ValueError(f"{sweep.source}: the prestress sweep must be at one frequency, got {f.size}")
    p = np.asarray(sweep.prestress, dtype=float)
    out = {"frequency_Hz": float(f[0]), "source": sweep.source}
    pm = float(p.mean())
    fitted = {}
    for key, y in (("storage", sweep.G_storage), ("loss", sweep.G_loss)):
        y = np.asarray(y, dtype=float)
        slope = float(np.sum((p - pm) * (y - y.mean())) / np.sum((p - pm) ** 2))
        out[f"dG_{key}_dP"] = slope
        fitted[key] = float(y.mean())  # the line's value at the mean prestress
    out["loss_tangent_at_mean"] = fitted["loss"] / fitted["storage"]
    out["rho"] = out["dG_loss_dP"] / out["dG_storage_dP"] / out["loss_tangent_at_mean"]
    out["mean_prestress_Pa"] = pm
    return out


def _row(name, cell, pi, data, count) -> dict:
    from ..model.prestress import virial_prestress

    note = ""
    try:
        s = inextensible_slopes(cell) if math.isinf(pi) else structure_slopes(cell, pi)
    except ValueError as err:
        nan = math.nan
        s = {"G_storage_over_sigma": nan, "dG_storage_dsigma": nan, "loss_tangent_per_phi": nan,
             "dG_loss_dsigma_per_phi": nan}
        note = str(err).split(":")[0][:80]
    rho_den = s["loss_tangent_per_phi"] * s["dG_storage_dsigma"]
    rho = s["dG_loss_dsigma_per_phi"] / rho_den if rho_den and math.isfinite(rho_den) else math.nan
    if math.isinf(pi) and not note:
        note = ("inextensible tendons: no parameter" + (f" (limit converged to {s['limit_change']:.1g})"
                                                        if s.get("limit_change", 0) > 1e-9 else ""))
    return {"structure": name, "mechanisms": -1 if count is None else count,
            "sigma_per_P_Pa_per_N": virial_prestress(cell).sigma_per_P, "EA_over_sigma_L2": pi,
            "G_storage_over_sigma": s["G_storage_over_sigma"], "dG_storage_dsigma": s["dG_storage_dsigma"],
            "loss_tangent_per_tendon_loss_tangent": s["loss_tangent_per_phi"],
            "dG_loss_dsigma_per_tendon_loss_tangent": s["dG_loss_dsigma_per_phi"],
            "slope_ratio_over_loss_tangent": rho,
            "data_dG_storage_dP": data["dG_storage_dP"], "data_dG_loss_dP": data["dG_loss_dP"],
            "data_slope_ratio_over_loss_tangent": data["rho"],
            "dG_storage_dsigma_over_data": s["dG_storage_dsigma"] / data["dG_storage_dP"], "note": note}


def a_priori_table(datasets=None, *, structures=None, ea_over_sigma=EA_OVER_SIGMA) -> Table:
    """The a priori slopes of each structure against the data's lines (module docstring), one row per structure and
    Π (the inextensible limit, Π = inf, first).

    Parameters
    ----------
    datasets : sequence of RheologyData, optional
        Data with a prestress sweep at one frequency (default: the bundled pair; its slopes are computed, not
        typed in).
    structures : sequence of str, optional
        Keys of :data:`tenscell.studies.structures.STRUCTURES` (default all).
    ea_over_sigma : sequence of float
        The finite values of Π = EA/(σL²).
    """
    from .structures import STRUCTURES, bundled_pair, structure_cell

    data = data_slopes(bundled_pair() if datasets is None else datasets)
    names = tuple(STRUCTURES) if structures is None else tuple(structures)
    rows = []
    for name in names:
        cell = structure_cell(name)
        count = mechanism_count(cell)
        for pi in (math.inf, *ea_over_sigma):
            rows.append(_row(name, cell, float(pi), data, count))
    return Table.from_records("a_priori", rows, description=(
        f"a priori slopes at {FREQUENCY_HZ:g} Hz: dG′/dσ (Pa/Pa) with inextensible tendons (EA_over_sigma_L2 = inf: "
        "no parameter) and as a function of Π = EA/(σL²); per unit tendon loss tangent φ, G″/G′ and dG″/dσ; the "
        f"data's lines from {data['source']}"))
