"""The structure-free formulas (the structural-damping law first), AIC/BIC and held-out error."""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.stats

from tenscell.fitting import fit
from tenscell.fitting.models.formulas import FORMULAS, Formula, lumped_formula, series_formula
from tenscell.fitting.models.catalog import MECHANISMS
from tenscell.fitting.scores import (compare_models, fit_structural_damping, information_criteria, split_holdout,
                                     structural_damping_moduli)
from tenscell.io.data import DataError, RheologyData, bundled
from tenscell.fitting import VoigtModel

F = np.logspace(-2, 2.5, 14)


def _law_data(G0=300.0, x=1.18, mu=0.05, sd=None, seed=None):
    G = structural_damping_moduli(2 * np.pi * F, G0, x, mu)
    Gs, Gl = G.real, G.imag
    if seed is not None:
        rng = np.random.default_rng(seed)
        Gs = Gs * 10 ** rng.normal(0, 0.01, F.size)
        Gl = Gl * 10 ** rng.normal(0, 0.01, F.size)
    kw = {} if sd is None else {"G_storage_sd": sd * Gs, "G_loss_sd": sd * Gl}
    return RheologyData(F, Gs, Gl, source="law", **kw)


def test_law_matches_its_definition_and_eta_is_the_loss_tangent():
    w = 2 * np.pi * F
    G = structural_damping_moduli(w, 250.0, 1.2, 0.0, phi0=3.0)
    a = 0.2
    eta = math.tan(math.pi * a / 2)
    expected = 250.0 * (w / 3.0) ** a * (1 + 1j * eta) * math.gamma(2 - 1.2) * math.cos(math.pi * a / 2)
    np.testing.assert_allclose(G, expected, rtol=1e-13)
    np.testing.assert_allclose(G.imag / G.real, eta, rtol=1e-12)


@pytest.mark.parametrize("name", sorted(FORMULAS))
def test_formula_jacobian_matches_finite_differences(name):
    d = _law_data(sd=0.05)
    data = [bundled("stamenovic2002"), d] if FORMULAS[name].uses_prestress else d
    p = FORMULAS[name].problem(data)
    theta = np.random.default_rng(1).uniform(*p.bounds)
    J = p.jacobian(theta)
    np.testing.assert_allclose(J, p.jacobian_fd(theta), rtol=1e-6, atol=1e-8 * np.abs(J).max())


@pytest.mark.parametrize("mech", ["springpot+visc", "springpot-tension+visc", "maxwell", "sls", "voigt-compact",
                                  "springpot-alpha-family+visc"])
def test_lumped_formula_jacobian_and_prestress_coupling(mech):
    """A mechanism's structure-free formula: its law's terms, the same prestress coupling, as many exponents as the
    mechanism (an exponent per family: two springpots), exact Jacobian."""
    f = lumped_formula(MECHANISMS[mech])
    assert f.uses_prestress and ("springpot_P" in f.terms) == (mech == "springpot-tension+visc")
    assert ("springpot_2" in f.terms) == (mech == "springpot-alpha-family+visc")
    assert ("newtonian" in f.terms) == ("visc" in mech or MECHANISMS[mech].law == "Voigt")
    p = f.problem([bundled("stamenovic2002"), _law_data(sd=0.05)])
    assert "P_data[1]" in p.names  # the frequency sweep states no prestress: fitted, in Pa
    theta = np.random.default_rng(2).uniform(*p.bounds)
    J = p.jacobian(theta)
    np.testing.assert_allclose(J, p.jacobian_fd(theta), rtol=1e-6, atol=1e-8 * np.abs(J).max())


@pytest.mark.parametrize("mech", ["springpot-alpha-family+visc", "voigt-compact+visc", "maxwell"])
def test_series_formula_moves_both_moduli_with_the_prestress(mech):
    """The lumped terms as a series network: the elastic terms (P enters there) in series with the law's others, the
    cytoplasm in parallel; exact Jacobian; P now moves G'' too (in the parallel network it moves G' only)."""
    par = lumped_formula(MECHANISMS[mech])
    ser = series_formula(par)
    assert ser is not None and set(ser.terms) == set(par.terms) and "aP" in ser.series[0]
    assert ("newtonian" in ser.series[1]) == (mech.startswith("voigt"))  # Voigt: the lumped element is Maxwell's
    p = ser.problem([bundled("stamenovic2002"), _law_data(sd=0.05)])
    theta = np.random.default_rng(3).uniform(*p.bounds)
    J = p.jacobian(theta)
    np.testing.assert_allclose(J, p.jacobian_fd(theta), rtol=1e-6, atol=1e-8 * np.abs(J).max())
    vals = dict(zip(p.names, p.values(theta)))
    w = np.array([0.6])
    for f in (par, ser):
        lo, hi = (f.complex_modulus(vals, w, P)[0] for P in (300.0, 3000.0))
        assert hi.real > lo.real
        assert (hi.imag != lo.imag) == (f is ser)


def test_a_spring_in_series_with_a_dashpot_is_a_maxwell_element():
    w = np.logspace(-3, 3, 30)
    ser = Formula("s", ("aP", "newtonian"), series=(("aP",), ("newtonian",)))
    E, eta = 0.2 * 500.0, 3.0
    G = ser.complex_modulus({"a": 0.2, "eta": eta}, w, 500.0)
    M = Formula("m", ("maxwell",)).complex_modulus({"E_M": E, "tau": eta / E}, w, 1.0)
    np.testing.assert_allclose(G, M, rtol=1e-13)
    with pytest.raises(ValueError, match="two disjoint"):
        Formula("bad", ("aP", "newtonian"), series=(("aP",), ("aP",)))


def test_modified_power_law_relaxes_from_its_instant_modulus_to_its_constant():
    """E0 + E_1·(iωτ)^α/(1 + (iωτ)^α): G* → E0 + E_1 at high frequency (the instant modulus), → E0 at low frequency
    (the constant it relaxes to), a power law of exponent α in between; passive."""
    f = FORMULAS["modified-power-law+constant"]
    vals = {"E0": 20.0, "E_1": 500.0, "tau_1": 1.0, "alpha_1": 0.3}
    G = f.complex_modulus(vals, np.array([1e-30, 1e30]), 1.0)
    np.testing.assert_allclose(G.real, [20.0, 520.0], rtol=1e-6)
    w = np.logspace(-10, 4, 141)
    G = f.complex_modulus(vals, w, 1.0)
    assert np.all(G.imag > 0)
    mid = (w > 1e-8) & (w < 1e-7)  # far below 1/τ: G* − E0 ≈ E_1 (iωτ)^α
    slope = np.gradient(np.log(np.abs(G - 20.0)), np.log(w))[mid]
    np.testing.assert_allclose(slope, 0.3, atol=0.02)


def test_formula_terms_are_passive_and_structural_damping_is_a_springpot():
    """G'' > 0 for every term at every ω (passivity); the structural-damping law is exactly a springpot with
    A = G0·Γ(1−α)."""
    w = np.logspace(-3, 4, 50)
    vals = {"E0": 10.0, "a": 0.2, "G0": 300.0, "g": 0.1, "alpha": 0.2, "A": 50.0, "B": 0.1, "alpha_T": 0.3,
            "E_M": 40.0, "tau": 0.1, "eta": 0.5, "A_2": 5.0, "alpha_2": 0.6}
    for term in ("structural", "structural_P", "springpot", "springpot_2", "springpot_P", "maxwell", "newtonian"):
        assert np.all(Formula("t", (term,)).complex_modulus(vals, w, 500.0).imag > 0), term
    G = Formula("t", ("structural",)).complex_modulus(vals, w, 1.0)
    S = Formula("t", ("springpot",)).complex_modulus({"A": 300.0 * math.gamma(0.8), "alpha": 0.2}, w, 1.0)
    np.testing.assert_allclose(G, S, rtol=1e-13)
    np.testing.assert_allclose(G, structural_damping_moduli(w, 300.0, 1.2, 0.0), rtol=1e-13)


def test_fit_recovers_the_law():
    r = fit_structural_damping(_law_data())
    assert r.value("G0") == pytest.approx(300.0, rel=1e-6)
    assert r.value("alpha") == pytest.approx(0.18, abs=1e-7)
    assert r.value("eta") == pytest.approx(0.05, rel=1e-5)
    assert r.rms_log10_error < 1e-8
    assert r.spec.name == "structural-damping+newtonian" and r.cell is None
    df = r.to_dataframe()
    assert {"frequency_Hz", "G_storage_model_Pa"} <= set(df.columns)
    model = r.model
    np.testing.assert_allclose(np.array(model.moduli(F)), np.array(r.moduli(F)), rtol=1e-12)
    with pytest.raises(ValueError, match="no cell"):
        model.linear()


def test_fit_of_the_bundled_data_finds_the_law_it_was_generated_from():
    r = fit_structural_damping(bundled("fabry2001"))
    assert r.value("alpha") == pytest.approx(0.20, abs=1e-4)  # the CSV comment: x − 1 = 0.20
    assert r.value("eta") == pytest.approx(0.239363, rel=1e-3)
    assert r.rms_log10_error < 1e-4


def test_prestress_sweep_is_refused():
    with pytest.raises(DataError, match="frequency sweep"):
        fit_structural_damping(bundled("stamenovic2002"))


def test_formula_with_prestress_fits_the_prestress_sweep_and_reads_it_in_pa():
    """(G0 + g·P)·Γ(1−α)(iω)^α: on the Stamenović lines G' = 0.20 P + 82 at 0.1 Hz it fits; the model's prestress
    is the data's own (Pa), so the fitted model answers at any measured prestress."""
    d = bundled("stamenovic2002")
    r = fit(d, model="structural-damping-prestress+newtonian", starts=2, seed=0, progress=False)
    assert r.rms_log10_error < 0.02
    Gs, _ = r.model.moduli([0.1], 1000.0)
    assert Gs[0] == pytest.approx(0.20 * 1000 + 82, rel=0.05)


# --- information criteria ------------------------------------------------------------------
def test_aic_bic_unknown_sigma_by_hand():
    r = np.array([0.1, -0.2, 0.05, 0.03, -0.07])
    n, k = r.size, 2
    s2 = np.sum(r**2) / n  # maximum-likelihood σ²
    loglik = scipy.stats.norm.logpdf(r, scale=math.sqrt(s2)).sum()
    aic, bic, m2 = information_criteria(r, k, sigma_known=False)
    assert m2 == pytest.approx(-2 * loglik, rel=1e-12)
    assert aic == pytest.approx(-2 * loglik + 2 * (k + 1), rel=1e-12)
    assert bic == pytest.approx(-2 * loglik + (k + 1) * math.log(n), rel=1e-12)


def test_aic_bic_known_sigma_by_hand():
    s = np.array([0.01, 0.02, 0.05, 0.01])
    raw = np.array([0.005, -0.03, 0.02, 0.0])  # decades
    loglik = scipy.stats.norm.logpdf(raw, scale=s).sum()
    aic, bic, m2 = information_criteria(raw / s, 3, sigma_known=True, weights=1 / s)
    assert m2 == pytest.approx(-2 * loglik, rel=1e-12)
    assert aic == pytest.approx(-2 * loglik + 6, rel=1e-12)
    assert bic == pytest.approx(-2 * loglik + 3 * math.log(4), rel=1e-12)
    with pytest.raises(ValueError, match="weights"):
        information_criteria(raw / s, 3, sigma_known=True)


# --- held-out data ------------------------------------------------------------------------
def test_split_holdout():
    d = _law_data(sd=0.05)
    train, held = split_holdout(d, 1.0, 30.0)
    assert train.n + held.n == d.n
    assert np.all((held.frequency_hz >= 1.0) & (held.frequency_hz <= 30.0))
    assert not np.any((train.frequency_hz >= 1.0) & (train.frequency_hz <= 30.0))
    assert held.G_storage_sd is not None
    with pytest.raises(ValueError, match="both sides"):
        split_holdout(d, 1e-6, 1e6)
    with pytest.raises(ValueError, match="FMIN must be below FMAX"):
        split_holdout(d, 10.0, 1.0)
    with pytest.raises(ValueError, match="frequency sweep"):
        split_holdout(bundled("stamenovic2002"), 0.05, 0.2)


def test_compare_models_scores_every_model_on_the_same_residuals():
    from tenscell.fitting import fit

    data = _law_data(seed=3)
    train, held = split_holdout(data, 0.3, 3.0)
    homog = fit(train, model=VoigtModel(tendons="uniform"), starts=1, hops=3, seed=0, progress=False)
    cmp_ = compare_models(homog, held_out=held, holdout=(0.3, 3.0))
    assert [s.name for s in cmp_.scores] == ["homogeneous tensegrity", "structural damping (power law)"]
    sd = fit_structural_damping(train)
    row = cmp_.score("structural damping (power law)")
    assert row.n_params == 3
    assert row.rms_log10_error == pytest.approx(sd.rms_log10_error)
    aic, bic, _ = information_criteria(sd.problem.residuals(sd.theta), 3, sigma_known=False)
    assert (row.aic, row.bic) == (pytest.approx(aic), pytest.approx(bic))
    # the tensegrity's k excludes the exact gauge: EA, c, P, L free -> 3
    assert cmp_.score("homogeneous tensegrity").n_params == 3
    # data generated by the power law with 1 % noise: the law interpolates the held-out decade
    assert row.holdout_rms_log10_error < 0.02
    assert cmp_.best("holdout") == "structural damping (power law)"
    assert cmp_.n_holdout == held.n and cmp_.to_dict()["holdout_Hz"] == [0.3, 3.0]
    assert set(cmp_.to_dataframe().columns) >= {"model", "AIC", "BIC", "holdout_rms_log10_error"}
