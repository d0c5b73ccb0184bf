"""Creep compliance, stress relaxation and power-law analysis of the linear model.

Every check compares with something computed independently of the spectral
formulas: the transfer function by direct complex solves, the inverse
Laplace transform by numerical Fourier integration, the static and
high-frequency limits from response.py, and the nonlinear simulation.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

import tenscell
from _tolerances import EPS, modal_rtol, solve_rtol
from tenscell.laws import voigt_law
from tenscell.dynamics import creep_response
from tenscell.timedomain import (
    creep_compliance,
    creep_spectrum,
    fit_power_law,
    local_exponent,
    relaxation_modulus,
    stress_relaxation,
)


@pytest.fixture(scope="module")
def cell():
    return tenscell.paper_cell()


@pytest.fixture(scope="module")
def lin(cell):
    return tenscell.linearize(cell, P=1000.0, EA=1.0, c=1.0)


@pytest.fixture(scope="module")
def lin_noif():
    return tenscell.linearize(tenscell.paper_cell(intermediate_filaments=False), P=1000.0)


def _J_direct(lin, s):
    """D0 (K0 + s C0)⁻¹ (−H0) by a dense complex solve, no eigen-decomposition."""
    return complex(lin.D0 @ np.linalg.solve(lin.K0 + s * lin.C0, (-lin.H0).astype(complex)))


def _inverse_laplace_creep(lin, t):
    """Step response from the frequency response by Fourier-sine integration (QUADPACK QAWF).

    For a causal impulse response with transfer J(s), the step response is
    J(t) = J(0) − (2/π) ∫₀^∞ (J(0) − Re J(iω))/ω · sin(ωt) dω  (the J(0)
    term uses ∫₀^∞ sin(ωt)/ω dω = π/2; the remaining integrand is regular at 0).
    """
    J0 = _J_direct(lin, 0.0).real
    val, err = scipy.integrate.quad(lambda w: (J0 - _J_direct(lin, 1j * w).real) / w, 0.0, np.inf,
                                    weight="sin", wvar=t, limlst=200)
    assert err < 2e-5 * J0
    return J0 - 2.0 / math.pi * val


@pytest.mark.parametrize("t", [1e-4, 1e-3, 1e-2, 0.1])
def test_creep_equals_inverse_laplace_by_numerical_integration(lin, t):
    J_num = _inverse_laplace_creep(lin, t)
    assert creep_compliance(lin, t) == pytest.approx(J_num, rel=1e-6)


def test_creep_inverse_laplace_without_intermediate_filaments(lin_noif):
    # singular C0: an instantaneous jump J(0+) > 0 that the integral must reproduce
    spec = creep_spectrum(lin_noif)
    assert spec.instantaneous > 0
    for t in (1e-3, 3e-2):
        assert spec.compliance(t) == pytest.approx(_inverse_laplace_creep(lin_noif, t), rel=1e-5)


def test_creep_limits(lin, lin_noif):
    spec = creep_spectrum(lin)
    K0, C0 = np.asarray(lin.K0), np.asarray(lin.C0)
    # J(0) = 0 with positive definite C0; J(∞) = static compliance = (0.5/L)/G'(0): Σ ρ_k against a Cholesky
    # solve, both accurate to κ(K0) (tolerances: tests/_tolerances.py)
    assert spec.instantaneous == 0.0
    assert spec.compliance(0.0) == 0.0
    assert spec.compliance(1e3) == pytest.approx((0.5 / lin.L) / tenscell.response.static_modulus(lin), rel=solve_rtol(K0))
    # initial creep rate = Σ r_k = D0 C0⁻¹ (−H0) (pure dashpot response), so G''/ω → (0.5/L)/rate;
    # checked against a direct Cholesky solve with C0 (viscosity_limit itself sums the same spectrum)
    direct_rate = float(lin.D0 @ scipy.linalg.cho_solve(scipy.linalg.cho_factor(C0), -lin.H0))
    rate_tol = modal_rtol(lin) + solve_rtol(C0)  # Σ ρ_k/τ_k: each τ_k to eps·τ_max/τ_k
    assert spec.rate(0.0) == pytest.approx(direct_rate, rel=rate_tol)
    assert (0.5 / lin.L) / tenscell.response.viscosity_limit(lin) == pytest.approx(direct_rate, rel=rate_tol)
    # monotone creep: weights are non-negative (probe = load)
    assert np.all(spec.weights >= -1e-15 * spec.static)
    J = spec.compliance(np.logspace(-6, 1, 200))
    assert np.all(np.diff(J) >= 0)


def test_instantaneous_compliance_is_the_high_frequency_limit(lin_noif):
    """J(0+) without IFs is lim_{s→∞} D0 (K0 + s C0)⁻¹ (−H0) = D0 N (NᵀK0N)⁻¹ Nᵀ (−H0), N spanning null(C0).

    The limit is taken exactly, not by a solve at a huge s: (K0 + sC0) at s = 1e13 has a condition number
    ~ s·‖C0‖/λ_min(K0) ~ 1e15, and its answer differs in the 6th digit between BLAS kernels.
    """
    spec = creep_spectrum(lin_noif)
    K0, C0 = np.asarray(lin_noif.K0), np.asarray(lin_noif.C0)
    c = np.linalg.eigvalsh(C0)
    N = scipy.linalg.null_space(C0)
    assert 0 < N.shape[1] < C0.shape[0]
    # the null space is well separated: the smallest non-zero eigenvalue of C0 sets how accurately N is known
    gap = float(c[N.shape[1]])
    assert gap > 1e3 * C0.shape[0] * EPS * c[-1]
    KN = N.T @ K0 @ N
    limit = float(lin_noif.D0 @ N @ np.linalg.solve(KN, N.T @ -lin_noif.H0))
    n = K0.shape[0]
    spread = float(spec.times.max() / spec.times.min())
    # spectral side: the undamped subspace of the whitened pencil is known to eps·(κ(K0) + τ_max/τ_min); its
    # error leaks a share of the whole static compliance into J(0+), hence the factor J(∞)/J(0+) (here ~30).
    # reference side: N to eps·‖C0‖/gap, and the solve with NᵀK0N.
    tol = (4 * n * EPS * (np.linalg.cond(K0) + spread) * spec.static / spec.instantaneous
           + 4 * n * EPS * c[-1] / gap + solve_rtol(KN))
    assert spec.instantaneous > 0
    assert spec.instantaneous == pytest.approx(limit, rel=tol)


def test_spectrum_matches_linear_relaxation_spectrum(lin):
    spec = creep_spectrum(lin)
    rel = tenscell.linear.relaxation_spectrum(lin)
    assert np.allclose(np.sort(spec.times), np.sort(rel.times), rtol=1e-9)
    assert spec.static == pytest.approx(rel.weights.sum(), rel=1e-10)
    times, weights = spec.significant(rtol=1e-3)
    assert 0 < times.size < spec.times.size
    assert weights.sum() == pytest.approx(spec.static, rel=24e-3)


def test_transfer_function_matches_direct_solve(lin):
    spec = creep_spectrum(lin)
    for s in (0.5 + 3j, 200.0, 1e4j, 30 - 700j):
        assert spec.transfer(s) == pytest.approx(_J_direct(lin, s), rel=1e-10)


@pytest.mark.parametrize("which", ["with_if", "no_if"])
def test_relaxation_is_the_laplace_inverse_of_creep(which, lin, lin_noif):
    """s·J(s)·R(s) = 1: the relaxation function is the convolution inverse of the creep compliance."""
    model = lin if which == "with_if" else lin_noif
    rel = stress_relaxation(model)
    for s in (0.7 + 2j, 50.0, 3e3j, 40 - 900j):
        assert s * _J_direct(model, s) * rel.laplace(s) == pytest.approx(1.0, rel=1e-8)
    assert np.all(rel.times > 0) and np.all(np.diff(rel.times) > 0)


def test_relaxation_limits(lin, lin_noif):
    rel = stress_relaxation(lin)
    assert rel.modulus(1e3) == pytest.approx(tenscell.response.static_modulus(lin), rel=1e-10)
    assert rel.viscosity == pytest.approx(tenscell.response.viscosity_limit(lin), rel=1e-10)
    assert relaxation_modulus(lin, 1e3) == pytest.approx(tenscell.response.static_modulus(lin), rel=1e-10)
    # relaxation modulus decreases monotonically to G'(0)
    G = rel.modulus(np.logspace(-6, 0, 100))
    assert np.all(np.diff(G) <= 1e-12 * G[0])
    # without IFs: no impulse, finite jump R(0+) = 1/J(0+)
    r2 = stress_relaxation(lin_noif)
    assert r2.impulse == 0.0
    assert r2.initial == pytest.approx(1.0 / creep_spectrum(lin_noif).instantaneous, rel=1e-8)


def test_local_exponent_analytic_and_numeric(lin):
    spec = creep_spectrum(lin)
    t = np.logspace(-6, 0, 400)
    a = spec.exponent(t)
    num = local_exponent(t, spec.compliance(t))
    assert np.allclose(a[5:-5], num[5:-5], atol=2e-3)
    # Voigt network: exponent 1 at short times (viscous), 0 at long times (elastic plateau)
    assert spec.exponent(1e-7) == pytest.approx(1.0, abs=1e-3)
    assert spec.exponent(10.0) < 1e-10
    # J concave with J(0) = 0 and increasing  =>  0 <= t·J'/J <= 1
    assert np.all((a >= 0) & (a <= 1))


def test_power_law_fit_recovers_exact_power_law():
    t = np.logspace(-3, 2, 40)
    fit = fit_power_law(t, 2.5e-3 * t ** 0.2, 1e-2, 10.0)
    assert fit.alpha == pytest.approx(0.2, abs=1e-12)
    assert fit.A == pytest.approx(2.5e-3, rel=1e-12)
    assert fit.rms_log < 1e-12 and fit.n == sum((t >= 1e-2) & (t <= 10.0))
    assert fit(10.0) == pytest.approx(2.5e-3 * 10 ** 0.2)


def test_power_law_fit_of_tensegrity_creep_is_poor(lin):
    # the Voigt network's creep is not a power law: its local exponent sweeps from 1 to 0
    spec = creep_spectrum(lin)
    t = np.logspace(-4, -1, 60)
    fit = fit_power_law(t, spec.compliance(t))
    ex = spec.exponent(t)
    assert ex.min() < fit.alpha < ex.max()
    assert fit.max_rel > 0.05


def test_bad_input():
    t = np.logspace(-3, 0, 10)
    with pytest.raises(ValueError, match="window"):
        fit_power_law(t, t ** 0.3, 1.0, 0.1)
    with pytest.raises(ValueError, match="at least 2"):
        fit_power_law(t, t ** 0.3, 0.5, 0.6)
    with pytest.raises(ValueError, match="J"):
        fit_power_law(t, -t)
    with pytest.raises(ValueError, match="t"):
        creep_compliance(tenscell.linearize(tenscell.paper_cell()), -1.0)
    with pytest.raises(ValueError, match="increasing"):
        local_exponent(t[::-1], t)


def test_small_step_simulation_matches_linear_creep(cell, lin):
    t = np.logspace(-4, -0.5, 30)
    cr = creep_response(cell, voigt_law(cell, P=1000.0, EA=1.0, c=1.0), 0.01, t)
    J = creep_compliance(lin, t)
    assert np.allclose(cr.compliance, J, rtol=2e-4)
    assert np.allclose(cr.linear, J, rtol=1e-12)
    # the nonlinear departure is first order in the step: ten times the force, ~ten times the error
    cr10 = creep_response(cell, voigt_law(cell, P=1000.0), 0.1, t)
    e1 = np.abs(cr.compliance / J - 1).max()
    e10 = np.abs(cr10.compliance / J - 1).max()
    assert 7 < e10 / e1 < 13
