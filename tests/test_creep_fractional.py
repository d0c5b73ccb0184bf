"""Creep and relaxation of fractional (springpot) tendons at every requested time (issue 26, item 6; goal G5).

References, each independent of the code under test:

* a single springpot element: ``J(t) = t^α/(κ·Γ(1+α))`` (closed form), and a Kelvin element ``1 − e^{−t/τ}``;
* a cell whose tendons all share one springpot (EA, κ, α): ``K(s) = A + κ s^α B`` with ``A = P·ΣT0∇²l +
  Σ(EA + T)/l aaᵀ``, ``B = Σ aaᵀ/l``; with ``A v = λ B v`` (``vᵀBv = 1``), ``J(s) = Σ ρ_k/(λ_k + κ s^α)``, so
  ``J(t) = Σ (ρ_k/λ_k)(1 − E_α(−λ_k t^α/κ))`` (Mittag-Leffler), E_α from its integral representation by
  quadrature — an exact inverse transform computed without any contour;
* laws realized exactly (Voigt, Maxwell, standard linear solid): the inversion equals the retardation spectrum.

Plus the invariants: time scaling (κ → λ^α κ, c → λc gives J(t) → J(t/λ)), creep nondecreasing and concave
(a Bernstein function for passive laws), a local exponent in [0, 1], and the warning where a realized spectrum
is asked for a time outside its band.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

from tenscell import paper_cell
from tenscell.laws import Maxwell, Springpot, StandardLinearSolid, TensionSpringpot, Voigt, family_laws
from tenscell.linear import linearize_law
from tenscell.linear.dynamic import exact_compliance, laplace_compliance
from tenscell.timedomain import (RealizationWarning, creep_compliance, creep_spectrum, invert_laplace,
                                 relaxation_modulus, stress_relaxation)

CELL = paper_cell()
P0 = 1000.0
#: the G5 window (s)
T_G5 = np.logspace(-3, 3, 25)
#: Talbot with 32 nodes in float64: rounding amplified by e^(2M/5) ≈ 3.6e5 on values of order 1, so ~1e-10;
#: the tests ask 1e-8 of smooth transforms (a wrong branch, sign or node formula is off by O(1))
TALBOT_RTOL = 1e-8


def _mittag_leffler_neg(alpha: float, x: float) -> float:
    """``E_α(−x)`` for 0 < α < 1, x ≥ 0: ``∫_0^∞ e^{−r y} K_α(r) dr`` with ``y = x^{1/α}``, ``K_α`` the spectral density
    ``r^{α−1} sin(απ) / (π (r^{2α} + 2 r^α cos(απ) + 1))`` (Gorenflo & Mainardi), by quadrature in ln r."""
    if x == 0.0:
        return 1.0
    y = x ** (1.0 / alpha)
    sa, ca = math.sin(alpha * math.pi), math.cos(alpha * math.pi)

    def integrand(u):  # r = e^u, dr = r du
        r = math.exp(u)
        ra = r ** alpha
        return math.exp(-r * y) * ra * sa / (math.pi * (ra * ra + 2 * ra * ca + 1.0))

    hi = math.log(60.0 / y)  # e^{-r y} < e^{-60} beyond
    lo = math.log(1e-17 * alpha) / alpha  # below, the integrand ~ r^α sin(απ)/π integrates to < 1e-17
    val, err = scipy.integrate.quad(integrand, lo, hi, limit=400, epsabs=0.0, epsrel=1e-12)
    return val


def _uniform_springpot_creep(EA, kappa, alpha, t, P=P0):
    """Exact J(t) (m/N) of the paper cell with one springpot law on every tendon at prestress P (module docstring)."""
    A_ = np.asarray(CELL.A)
    l, T = CELL.lengths, P * CELL.T0
    H = np.asarray(CELL.prestress_hessian)
    A = P * 0.5 * (H + H.T) + (A_ * ((EA + T) / l)) @ A_.T
    B = (A_ / l) @ A_.T
    lam, V = scipy.linalg.eigh(A, B)
    b, d = np.asarray(CELL.load), np.asarray(CELL.probe)
    rho = (V.T @ d) * (V.T @ b)
    return np.array([sum(r / lk * (1.0 - _mittag_leffler_neg(alpha, lk * tt ** alpha / kappa))
                         for r, lk in zip(rho, lam)) for tt in np.atleast_1d(t)])


# ---- the inverter ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("alpha", [0.1, 0.17, 0.5, 0.9])
def test_talbot_inverts_a_springpot_element_exactly(alpha):
    kappa = 3.0
    J = invert_laplace(lambda s: 1.0 / (kappa * s ** (alpha + 1.0)), T_G5)
    exact = T_G5 ** alpha / (kappa * math.gamma(1.0 + alpha))
    assert np.max(np.abs(J / exact - 1.0)) < TALBOT_RTOL


def test_talbot_inverts_a_kelvin_element_and_keeps_the_shape_of_t():
    t = np.logspace(-3, 3, 12).reshape(3, 4)
    J = invert_laplace(lambda s: 1.0 / (s * (1.0 + 2.0 * s)), t)
    assert J.shape == (3, 4)
    assert np.max(np.abs(J - (-np.expm1(-t / 2.0)))) < TALBOT_RTOL


def test_talbot_refuses_too_few_nodes_and_bad_times():
    with pytest.raises(ValueError, match="nodes"):
        invert_laplace(lambda s: 1 / s, [1.0], nodes=4)
    with pytest.raises(ValueError, match="time"):
        invert_laplace(lambda s: 1 / s, [-1.0])


# ---- the law's k*(s) -------------------------------------------------------------------------------------
@pytest.mark.parametrize("law", [
    Voigt(EA=1.3, c=0.7), Maxwell(EA=1.3, c=0.7), StandardLinearSolid(EA=1.0, EA_arm=2.0, c=0.4),
    Springpot(EA=1.0, kappa=2.0, alpha=0.3), TensionSpringpot(EA=1.0, kappa=2.0, alpha=0.3, beta=5.0, alpha_T=0.2),
    family_laws(CELL, {"actin": Maxwell(EA=1.5, c=0.3)}, default=Springpot(EA=0.8, kappa=0.5, alpha=0.25)),
], ids=lambda law: type(law).__name__)
def test_laplace_stiffness_continues_the_dynamic_tangent(law):
    """k*(s) at s = iω is k*(ω) (every law), and K(s) of a passive law is real on the positive real axis."""
    l, T = CELL.lengths, P0 * CELL.T0
    w = np.array([1e-3, 0.3, 20.0, 4e3])
    a, b = law.complex_stiffness(l, T, w), law.laplace_stiffness(l, T, 1j * w)
    assert np.max(np.abs(a - b) / np.abs(a)) < 1e-14
    r = law.laplace_stiffness(l, T, np.array([0.5, 7.0]))
    assert np.max(np.abs(r.imag)) <= 1e-14 * np.max(np.abs(r))


def test_laplace_compliance_on_the_imaginary_axis_is_the_exact_compliance():
    lin = linearize_law(CELL, Springpot(EA=0.5, kappa=2.0, alpha=0.2), P0, viscosity=0.3)
    f = np.array([0.01, 1.0, 300.0])
    assert np.max(np.abs(laplace_compliance(lin, 2j * np.pi * f) / exact_compliance(lin, f) - 1)) < 1e-12


# ---- G5: a springpot cell's creep at every time -------------------------------------------------------------
@pytest.mark.parametrize("EA, kappa, alpha, P", [(1e-3, 100.0, 0.17, 1.0), (1.0, 2.0, 0.17, P0), (0.05, 2.0, 0.5, P0)])
def test_springpot_cell_creep_is_the_exact_inverse_transform_from_1ms_to_1000s(EA, kappa, alpha, P):
    """G5: within 1e-3 of the Mittag-Leffler sum over the cell's modes at every time from 1e-3 to 1e3 s.

    The first case is springpot-dominated, as issue 26's fitted cell was (its creep still rises as t^0.17 at
    1000 s, where the default realization's spectrum has levelled off: 35 % too high there, next test). The
    bound met is far tighter than G5's (about 1e-8: quadrature and Talbot rule both near double precision; the
    modal sum of the reference adds κ(A) rounding).
    """
    lin = linearize_law(CELL, Springpot(EA=EA, kappa=kappa, alpha=alpha), P)
    J = creep_compliance(lin, T_G5)
    exact = _uniform_springpot_creep(EA, kappa, alpha, T_G5, P)
    err = np.max(np.abs(J / exact - 1.0))
    assert err < 1e-7, err  # G5 asks 1e-3


def test_the_realized_spectrum_misses_long_times_and_warns():
    """The default Prony band (1e-2–1e3 Hz) covers 1.6e-4–16 s: beyond, the spectrum's creep is wrong and says so."""
    lin = linearize_law(CELL, Springpot(EA=1e-3, kappa=100.0, alpha=0.17), 1.0)
    exact = creep_compliance(lin, [1e3])[0]
    with pytest.warns(RealizationWarning, match="outside"):
        spectral = creep_compliance(lin, [1e3], method="spectrum")[0]
    assert spectral / exact - 1.0 > 0.2  # issue 26: 37 % too high at 1000 s (here 35 %)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RealizationWarning)
        inside = creep_spectrum(lin).compliance([1e-2, 1.0])  # inside the band: no warning
    assert np.max(np.abs(inside / creep_compliance(lin, [1e-2, 1.0]) - 1.0)) < 1e-2


@pytest.mark.parametrize("law", [Voigt(EA=1.3, c=0.7), Maxwell(EA=1.3, c=0.7),
                                 StandardLinearSolid(EA=1.0, EA_arm=2.0, c=0.4)], ids=lambda law: type(law).__name__)
def test_inversion_equals_the_exact_spectrum_of_exactly_realized_laws(law):
    lin = linearize_law(CELL, law, P0, viscosity=0.2)
    t = np.logspace(-3, 3, 13)
    a, b = creep_compliance(lin, t, method="inversion"), creep_compliance(lin, t, method="spectrum")
    assert np.max(np.abs(a / b - 1.0)) < 1e-7
    if isinstance(law, Voigt):  # its dashpots give the relaxation an impulse the inversion does not separate
        with pytest.raises(ValueError, match="dashpot"):
            relaxation_modulus(lin, t, method="inversion")
        return
    ra, rb = relaxation_modulus(lin, t, method="inversion"), relaxation_modulus(lin, t, method="spectrum")
    assert np.max(np.abs(ra / rb - 1.0)) < 1e-7


def test_creep_time_scaling():
    """κ → λ^α κ (and the cytoplasm η → λη) maps k*(ω) to k*(λω): J_λ(t) = J_1(t/λ) exactly."""
    lam, alpha = 7.0, 0.3
    a = linearize_law(CELL, Springpot(EA=0.1, kappa=1.0, alpha=alpha), P0, viscosity=0.2)
    b = linearize_law(CELL, Springpot(EA=0.1, kappa=lam ** alpha, alpha=alpha), P0, viscosity=0.2 * lam)
    t = np.logspace(-2, 2, 9)
    assert np.max(np.abs(creep_compliance(b, t) / creep_compliance(a, t / lam) - 1.0)) < 1e-8


def test_fractional_creep_is_monotone_concave_and_its_exponent_is_between_0_and_1():
    lin = linearize_law(CELL, TensionSpringpot(EA=0.05, kappa=1.0, alpha=0.3, beta=1e-3, alpha_T=0.15), P0,
                        viscosity=0.1)
    t = np.logspace(-3, 3, 61)
    J = creep_compliance(lin, t)
    assert np.all(J > 0) and np.all(np.diff(J) > 0)
    rate = np.diff(J) / np.diff(t)
    assert np.all(np.diff(rate) < 0)  # concave: the creep rate falls (a Bernstein function)
    expo = np.gradient(np.log(J), np.log(t))
    assert np.all((expo > 0) & (expo < 1))


def test_fractional_relaxation_agrees_with_the_realized_spectrum_inside_its_band():
    """Inside 0.01–100 s of the (1e-3–1e3 Hz) realization, the realized relaxation is accurate to its tol 1e-3."""
    law = Springpot(EA=0.5, kappa=2.0, alpha=0.2)
    lin = linearize_law(CELL, law, P0, viscosity=0.05)
    wide = linearize_law(CELL, law, P0, viscosity=0.05, band_hz=(1e-5, 1e5))
    t = np.logspace(-2, 2, 9)
    exact = relaxation_modulus(lin, t)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RealizationWarning)
        realized = stress_relaxation(wide).modulus(t)
    assert np.max(np.abs(realized / exact - 1.0)) < 5e-3
    assert np.all(np.diff(exact) < 0) and np.all(exact > 0)  # relaxes, towards the static stiffness


def test_relaxation_inversion_refuses_a_dashpot_like_structure():
    lin = linearize_law(CELL, Springpot(EA=0.5, kappa=2.0, alpha=1.0), P0)  # α = 1: a Voigt dashpot
    with pytest.raises(ValueError, match="dashpot"):
        relaxation_modulus(lin, [1.0], method="inversion")


def test_method_is_checked():
    lin = linearize_law(CELL, Springpot(EA=0.5, kappa=2.0, alpha=0.2), P0)
    with pytest.raises(ValueError, match="method"):
        creep_compliance(lin, [1.0], method="talbot")
