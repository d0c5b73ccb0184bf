"""A priori slopes (tenscell.studies.a_priori): the inextensible limit derived two ways, homogeneity, the gauge."""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

from tenscell.io.data import bundled
from tenscell.model import paper_cell
from tenscell.model.prestress import virial_prestress
from tenscell.studies.a_priori import (a_priori_table, data_slopes, inextensible_slopes, mechanism_count,
                                       structure_slopes)


def _dense(M):
    return M.toarray() if hasattr(M, "toarray") else np.asarray(M, dtype=float)


def test_the_mechanism_limit_is_the_prestress_stiffness_on_the_mechanisms():
    """Without IFs the cell has one mechanism: G′ → σ·(0.5/L)/(σ_P·D0 N (NᵀKpN)⁻¹ Nᵀ b), G′ ∝ σ, G″ → 0."""
    cell = paper_cell(intermediate_filaments=False)
    assert mechanism_count(cell) == 1
    N = scipy.linalg.null_space(_dense(cell.A).T)
    assert N.shape[1] == 1
    Kp = _dense(cell.Kp)
    J = cell.probe @ N @ np.linalg.solve(N.T @ Kp @ N, N.T @ cell.load)  # per unit P
    per = virial_prestress(cell).sigma_per_P
    expected = (0.5 / cell.strut_length) / J / per
    lim = inextensible_slopes(cell)
    assert lim["dG_storage_dsigma"] == pytest.approx(expected, rel=1e-6)
    assert lim["G_storage_over_sigma"] == pytest.approx(expected, rel=1e-6)
    assert abs(lim["dG_loss_dsigma_per_phi"]) < 1e-4 * expected


def test_the_kinematically_determinate_limit_is_the_first_order_prestress_term():
    """With IFs rank A = n: G = EA·g1 + P·g0 + …, dG′/dσ → g0/σ_P with g0 = (0.5/L) D Km⁻¹KpKm⁻¹b/(D Km⁻¹b)²."""
    cell = paper_cell()
    assert mechanism_count(cell) == 0
    A = _dense(cell.A)
    Km = (A / cell.lengths) @ A.T
    x, y = np.linalg.solve(Km, cell.load), np.linalg.solve(Km.T, cell.probe)
    g0 = (0.5 / cell.strut_length) * (y @ _dense(cell.Kp) @ x) / (cell.probe @ x) ** 2
    lim = inextensible_slopes(cell)
    assert lim["dG_storage_dsigma"] == pytest.approx(g0 / virial_prestress(cell).sigma_per_P, rel=1e-6)
    assert math.isinf(lim["G_storage_over_sigma"])  # the intercept grows with EA: not predicted
    assert abs(lim["dG_loss_dsigma_per_phi"]) < 1e-4


@pytest.mark.parametrize("pi", [0.3, 3.0, 30.0])
def test_slopes_follow_from_homogeneity(pi):
    """G* = σ·h(Π) with Π = EA/(σL²) at fixed EA: dG/dσ = h − Π h′ (storage, and the loss per unit φ)."""
    cell = paper_cell()
    eps = 1e-4
    lo, mid, hi = (structure_slopes(cell, pi * f) for f in (1 - eps, 1.0, 1 + eps))
    h = lambda s: s["G_storage_over_sigma"]  # noqa: E731
    h2 = lambda s: s["G_storage_over_sigma"] * s["loss_tangent_per_phi"]  # G″/(σφ)  # noqa: E731
    dh = (h(hi) - h(lo)) / (2 * eps * pi)
    dh2 = (h2(hi) - h2(lo)) / (2 * eps * pi)
    assert mid["dG_storage_dsigma"] == pytest.approx(h(mid) - pi * dh, rel=1e-6)
    assert mid["dG_loss_dsigma_per_phi"] == pytest.approx(h2(mid) - pi * dh2, rel=1e-5, abs=1e-9)
    assert mid["loss_tangent_per_phi"] > 0  # passive: the tendons' loss shows as G″ > 0


def test_slopes_are_invariant_under_the_strut_length_gauge():
    a, b = structure_slopes(paper_cell(), 2.0), structure_slopes(paper_cell(L=3.0), 2.0)
    for k in a:
        assert b[k] == pytest.approx(a[k], rel=1e-9), k


def test_the_data_slopes_are_the_published_lines():
    """Computed from the bundled sweep (G′ = 0.20 P + 82, G″ = 0.05 P + 32 Pa), not typed in."""
    d = data_slopes([bundled("stamenovic2002")])
    assert d["dG_storage_dP"] == pytest.approx(0.20, abs=2e-4)
    assert d["dG_loss_dP"] == pytest.approx(0.05, abs=2e-4)
    assert d["frequency_Hz"] == pytest.approx(0.1)
    with pytest.raises(ValueError, match="prestress sweep"):
        data_slopes([bundled("fabry2001")])


def test_the_table():
    t = a_priori_table(structures=["6-strut paper cell", "6-strut, elastic struts"], ea_over_sigma=(0.1, 1.0))
    rows = t.records()
    assert [r["EA_over_sigma_L2"] for r in rows] == [math.inf, 0.1, 1.0] * 2
    assert all(r["data_dG_storage_dP"] == pytest.approx(0.2, abs=2e-4) for r in rows)
    # an elastic strut as soft as Π = 0.1 buckles under its own compression: not computed, and said so
    soft = next(r for r in rows if r["structure"] == "6-strut, elastic struts" and r["EA_over_sigma_L2"] == 0.1)
    assert math.isnan(soft["dG_storage_dsigma"]) and "compression" in soft["note"]
    assert rows[0]["note"].startswith("inextensible")
