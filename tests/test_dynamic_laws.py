"""Tendon laws with dynamics of their own (Maxwell, standard linear solid, springpot), the dynamic kernel,
their internal-variable realizations and the cytoplasm: invariants a wrong law fails.

- every analytic derivative of k*(ω) (in T and in each parameter) against central differences through the law;
- passivity: Im k* ≥ 0 and G'' ≥ 0 at all ω for random parameter draws (a sign error in a dashpot fails);
- static and high-frequency limits against their closed forms;
- Kramers–Kronig: G' − G'(0) from G'' on a wide log grid, tolerance from the quadrature's truncation;
- time scaling (c → λc, kappa → λ^α·kappa, η → λη at f → f/λ) and strut-length scaling
  (P, EA, EA_arm, kappa, c, L) → (λ²P, λ²EA, λ²EA_arm, λ²kappa, λc, λL);
- Voigt limits (Maxwell and SLS as τ → ∞, SLS as EA_arm → ∞ at fixed c, springpot α → 1);
- the realizations: exact for Maxwell and SLS; the springpot's Prony series within its stated tolerance.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import tenscell
from tenscell.laws import Maxwell, Springpot, StandardLinearSolid, TensionSpringpot, Voigt, family_laws
from tenscell.laws.viscoelastic import springpot_prony
from tenscell.linear.dynamic import (
    dynamic_complex_modulus, dynamic_compliance, dynamic_moduli, dynamic_stiffness_static,
)
from tenscell.linear.linearize import linearize_law
from tenscell.linear.modal import NotPositiveDefiniteError, modal_compliance, modulus
from tenscell.timedomain import creep_spectrum

CELL = tenscell.paper_cell()
P0 = 1000.0
RNG = np.random.default_rng(18)
EA = RNG.uniform(0.5, 2.0, CELL.m)
C = RNG.uniform(0.5, 2.0, CELL.m)
W = 2 * np.pi * np.logspace(-3, 4, 15)
L_, T_ = CELL.lengths, P0 * CELL.T0

DYNAMIC = {
    "maxwell": Maxwell(EA=EA, c=C),
    "sls": StandardLinearSolid(EA=EA, EA_arm=RNG.uniform(0.5, 5.0, CELL.m), c=C),
    "springpot": Springpot(EA=EA, kappa=RNG.uniform(0.1, 2.0, CELL.m), alpha=RNG.uniform(0.1, 0.9, CELL.m)),
    "mixed": family_laws(CELL, {"actin": Maxwell(EA=1.5, c=0.3)}, default=Springpot(EA=0.8, kappa=0.5, alpha=0.25)),
    # beta·T ~ 0.2 at P0: the active part comparable to the passive one (the derivative in T is not swamped)
    "tension-springpot": TensionSpringpot(EA=EA, kappa=RNG.uniform(0.1, 2.0, CELL.m), alpha=RNG.uniform(0.1, 0.9, CELL.m),
                                          beta=RNG.uniform(1e-3, 1e-2, CELL.m), alpha_T=RNG.uniform(0.1, 0.9, CELL.m)),
}


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _draw(kind, rng, m=CELL.m):
    """A random law of a kind: parameters log-uniform over 3 decades (exponents uniform in (0, 1))."""
    lu = lambda lo, hi: 10 ** rng.uniform(lo, hi, m)  # noqa: E731
    if kind == "maxwell":
        return Maxwell(EA=lu(-1, 2), c=lu(-2, 1))
    if kind == "sls":
        return StandardLinearSolid(EA=lu(-1, 2), EA_arm=lu(-1, 2), c=lu(-2, 1))
    if kind == "tension-springpot":
        return TensionSpringpot(EA=lu(-1, 2), kappa=lu(-2, 1), alpha=rng.uniform(0.02, 0.98, m), beta=lu(-5, -2),
                                alpha_T=rng.uniform(0.02, 0.98, m))
    return Springpot(EA=lu(-1, 2), kappa=lu(-2, 1), alpha=rng.uniform(0.02, 0.98, m))


# ---- the kernel --------------------------------------------------------------------------------------
def test_kernel_is_the_pencil_for_a_voigt_law():
    """For k* = k + iωc the kernel's direct solves equal the modal sum of linearize_law (round-off, ~1e-15)."""
    f = np.logspace(-2, 3, 11)
    law = Voigt(EA=EA, c=C)
    Gs, Gl = dynamic_moduli(CELL, law, P0, f)
    Gs0, Gl0 = tenscell.moduli(linearize_law(CELL, law, P0), f)
    assert _rel(Gs, Gs0) < 1e-11 and _rel(Gl, Gl0) < 1e-11


@pytest.mark.parametrize("name", list(DYNAMIC))
def test_kernel_derivatives_match_central_differences(name):
    """dynamic_compliance's exact ∂J/∂θ against differences of J in one tendon's parameters and in T."""
    law = DYNAMIC[name]
    kstar = law.complex_stiffness(L_, T_, W)
    dT, dk = law.complex_stiffness_derivatives(L_, T_, W)
    J, dJ = dynamic_compliance(CELL, P0, kstar, dk)
    for i in range(dk.shape[0]):
        # a step along the derivative's direction, 1e-6 of |k*| at each frequency: truncation ~1e-12 relative
        scale = np.maximum(np.abs(dk[i]).max(axis=1), 1e-300)
        h = 1e-6 * np.abs(kstar).max(axis=1) / scale
        d = dk[i] * h[:, None]
        fd = (dynamic_compliance(CELL, P0, kstar + d) - dynamic_compliance(CELL, P0, kstar - d)) / (2 * h)
        assert _rel(dJ[i], fd) < 1e-6


# ---- 1. derivatives of the law -----------------------------------------------------------------------
@pytest.mark.parametrize("name", list(DYNAMIC))
def test_complex_stiffness_derivative_in_tension(name):
    """∂k*/∂T against central differences (step 1e-6·T: truncation ~1e-12, round-off ~1e-10 relative)."""
    law = DYNAMIC[name]
    dT, _ = law.complex_stiffness_derivatives(L_, T_, W)
    h = 1e-6 * T_
    fd = (law.complex_stiffness(L_, T_ + h, W) - law.complex_stiffness(L_, T_ - h, W)) / (2 * h)
    assert _rel(dT, fd) < 1e-7


@pytest.mark.parametrize("name", ["maxwell", "sls", "springpot", "tension-springpot"])
def test_complex_stiffness_derivatives_in_every_parameter(name):
    """∂k*/∂θ_j for every parameter and two tendons, against central differences with relative step 1e-5.

    Truncation is O(1e-10) relative; a missing chain-rule factor (1/l, log(iω)) is O(1) off. A tendon's k*
    depends on its own parameters only.
    """
    law = DYNAMIC[name]
    _, dk = law.complex_stiffness_derivatives(L_, T_, W)
    k0 = law.complex_stiffness(L_, T_, W)
    for i, pname in enumerate(law.names):
        v = np.array(getattr(law, pname), dtype=float)
        for j in (0, CELL.m - 1):
            s = 1e-5 * v[j]
            up, dn = v.copy(), v.copy()
            up[j] += s
            dn[j] -= s
            import dataclasses
            ku = dataclasses.replace(law, **{pname: up}).complex_stiffness(L_, T_, W)
            kd = dataclasses.replace(law, **{pname: dn}).complex_stiffness(L_, T_, W)
            fd = (ku[:, j] - kd[:, j]) / (2 * s)
            assert _rel(dk[i][:, j], fd) < 1e-7, (pname, j)
            others = np.delete(np.arange(CELL.m), j)
            assert np.array_equal(ku[:, others], k0[:, others])


# ---- 2. passivity ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["maxwell", "sls", "springpot", "tension-springpot"])
def test_passivity_for_random_draws(kind):
    """Im k* ≥ 0, Re k* non-decreasing in ω for every tendon, and the cell's G'' ≥ 0, at all ω, for 8 draws.

    A dashpot of the wrong sign or a Prony weight < 0 fails; the tolerance −1e-12·|G| is round-off.
    """
    rng = np.random.default_rng(7)
    w = 2 * np.pi * np.logspace(-6, 8, 141)
    for _ in range(8):
        law = _draw(kind, rng)
        k = law.complex_stiffness(L_, T_, w)
        assert np.all(k.imag >= -1e-12 * np.abs(k))
        assert np.all(np.diff(k.real, axis=0) >= -1e-12 * np.abs(k[1:]))
        try:
            G = dynamic_complex_modulus(CELL, law, P0, w / (2 * np.pi))
        except NotPositiveDefiniteError:
            continue  # a draw whose relaxed static state is unstable has no moduli (refused, not negative)
        assert np.all(G.imag >= -1e-12 * np.abs(G))


# ---- 3. limits ---------------------------------------------------------------------------------------------
def _static_modulus(k):
    """(0.5/L)/(D0 K⁻¹ b) for K = P·Σ T0∇²l + Σ k_j a_j a_jᵀ with real tangents k (N/m)."""
    K = P0 * np.asarray(CELL.prestress_hessian) + (CELL.A * k) @ CELL.A.T
    return float(modulus(CELL.probe @ np.linalg.solve(K, CELL.load), CELL.strut_length))


def test_maxwell_limits_are_the_prestress_and_the_voigt_spring():
    """ω → 0: G = (0.5/L)/(D0 (P·Kp)⁻¹ b), independent of EA and c and ∝ P; ω → ∞: the Voigt spring (EA, c = 0)."""
    law = DYNAMIC["maxwell"]
    G0 = dynamic_complex_modulus(CELL, law, P0, [1e-9])[0]
    Kp_static = float(modulus(CELL.probe @ np.linalg.solve(P0 * np.asarray(CELL.Kp), CELL.load), CELL.strut_length))
    assert G0.real == pytest.approx(Kp_static, rel=1e-8)  # O(ωτ)² = 1e-17 away
    other = dynamic_complex_modulus(CELL, Maxwell(EA=3 * EA, c=0.1 * C), 2 * P0, [1e-9])[0]
    assert other.real == pytest.approx(2 * Kp_static, rel=1e-8)
    Ginf = dynamic_complex_modulus(CELL, law, P0, [1e9])[0]
    assert Ginf.real == pytest.approx(_static_modulus((EA + T_) / L_), rel=1e-8)
    assert 0 <= Ginf.imag < 1e-6 * Ginf.real  # the dashpot is locked: G'' ~ 1/(ωτ)


def test_sls_and_springpot_limits():
    """SLS: ω → 0 the spring EA, ω → ∞ the spring EA + EA_arm. Springpot: ω → 0 the spring EA; ω → ∞ G''/G' → tan(απ/2)."""
    sls = DYNAMIC["sls"]
    assert dynamic_complex_modulus(CELL, sls, P0, [1e-9])[0].real == pytest.approx(_static_modulus((EA + T_) / L_), rel=1e-8)
    assert dynamic_complex_modulus(CELL, sls, P0, [1e9])[0].real == pytest.approx(
        _static_modulus((EA + sls.EA_arm + T_) / L_), rel=1e-8)
    pot = Springpot(EA=EA, kappa=1.0, alpha=0.5)
    assert dynamic_complex_modulus(CELL, pot, P0, [1e-14])[0].real == pytest.approx(_static_modulus((EA + T_) / L_), rel=1e-5)
    G = dynamic_complex_modulus(CELL, pot, P0, [1e14])[0]
    # k* = (EA+T)/l + (κ/l)(iω)^½ with (EA+T)/l ~ 1e3 N/m against κ/l·ω^½ ~ 3e7: relative 4e-5 from the spring
    assert G.imag / G.real == pytest.approx(math.tan(0.25 * math.pi), rel=2e-4)


# ---- 4. Kramers–Kronig ------------------------------------------------------------------------------------
def _kk_storage(wg, G2, w, G2w):
    """G'(ω) − G'(0) from G'' by the once-subtracted Kramers–Kronig relation, on a uniform grid in u = ln ω'.

    G'(ω) − G'(0) = (2ω²/π) P∫ G''(ω') / (ω'(ω² − ω'²)) dω', with ``G''(ω)·ω'/ω`` subtracted so the integrand
    is regular at ω' = ω (P∫ dω'/(ω'² − ω²) = 0); ``G2w`` is G'' at ``w`` exactly (an interpolated value would
    leave a pole). Returns the value and a bound on the truncated tails.
    """
    u = np.log(wg)
    h = u[1] - u[0]
    out, tails = [], []
    for wk, g2k in zip(w, G2w):
        num = G2 - g2k * wg / wk
        den = wk ** 2 - wg ** 2
        f = np.divide(num, den, out=np.zeros_like(num), where=np.abs(den) > 1e-12 * wk ** 2)
        out.append(2 * wk ** 2 / math.pi * h * (f.sum() - 0.5 * (f[0] + f[-1])))
        # tails: |f| decays at least as e^{αu} below the grid and e^{-u} above: ∫ tail ≤ |f_end|/rate
        tails.append(2 * wk ** 2 / math.pi * (abs(f[0]) / 0.1 + abs(f[-1]) / 1.0))
    return np.array(out), np.array(tails)


@pytest.mark.parametrize("name,eta", [("maxwell", 0.0), ("sls", 0.0), ("springpot", 0.0), ("mixed", 0.0),
                                      ("tension-springpot", 0.0), ("maxwell", 0.3), ("springpot", 0.3)])
def test_kramers_kronig(name, eta):
    """G' of the cell (with a cytoplasm η, whose iωη is KK-neutral) from its G'' to the quadrature's accuracy.

    Grid 10⁻⁶⁰…10³⁰ rad/s at 10 points per decade: the integrand is analytic in a strip |Im u| < π/2, so the
    trapezoid rule's discretization error is ~exp(−π²/h) ≈ 1e-19; the truncated tails are bounded from the
    integrand at the grid's ends (springpot exponents here are ≥ 0.1). Tolerance: that bound + 1e-8·G'
    (the solves' round-off summed over 900 points).
    """
    law = DYNAMIC[name]
    wg = np.logspace(-60, 30, 901)
    G = dynamic_complex_modulus(CELL, law, P0, wg / (2 * np.pi), viscosity=eta)
    G0 = dynamic_complex_modulus(CELL, law, P0, [1e-70])[0].real
    w = 2 * np.pi * np.logspace(-2, 3, 6)
    Gw = dynamic_complex_modulus(CELL, law, P0, w / (2 * np.pi), viscosity=eta)
    kk, tail = _kk_storage(wg, G.imag, w, Gw.imag)
    Gs = Gw.real
    assert np.all(np.abs(kk - (Gs - G0)) <= tail + 1e-8 * Gs), (kk, Gs - G0, tail)
    assert np.max(np.abs(Gs - G0)) > 1e3 * np.max(tail + 1e-8 * Gs)  # the check has something to check


def test_kramers_kronig_fails_for_an_acausal_response():
    """The check is not vacuous: flipping the sign of G'' (an acausal, 'active' response) fails it."""
    law = DYNAMIC["maxwell"]
    wg = np.logspace(-60, 30, 901)
    G = dynamic_complex_modulus(CELL, law, P0, wg / (2 * np.pi))
    G0 = dynamic_complex_modulus(CELL, law, P0, [1e-70])[0].real
    w = 2 * np.pi * np.logspace(-1, 1, 3)
    Gw = dynamic_complex_modulus(CELL, law, P0, w / (2 * np.pi))
    kk, tail = _kk_storage(wg, -G.imag, w, -Gw.imag)
    Gs = Gw.real
    assert np.all(np.abs(kk - (Gs - G0)) > 100 * (tail + 1e-8 * Gs))


# ---- 5. scaling -------------------------------------------------------------------------------------------
def _scaled(law, lam, time):
    """The law under time scaling (time=True: c → λc, kappa → λ^α kappa) or strut-length scaling (force-like ×λ²)."""
    import dataclasses

    if isinstance(law, tenscell.laws.CompositeLaw):
        return tenscell.laws.CompositeLaw(tuple(_scaled(p, lam, time) for p in law.laws), law.indices)
    kw = {}
    for n in law.names:
        v = np.asarray(getattr(law, n), dtype=float)
        if n == "c":
            kw[n] = lam * v
        elif n == "kappa":
            kw[n] = v * lam ** np.asarray(law.alpha) if time else lam ** 2 * v
        elif n == "beta" and time:  # a modulus per unit tension: unchanged by the strut-length scaling
            kw[n] = v * lam ** np.asarray(law.alpha_T)
        elif n in ("EA", "EA_arm") and not time:
            kw[n] = lam ** 2 * v
    return dataclasses.replace(law, **kw)


@pytest.mark.parametrize("name", list(DYNAMIC))
def test_time_scaling(name):
    """c → λc (kappa → λ^α·kappa, η → λη) at f → f/λ leaves G unchanged (round-off)."""
    lam, f = 7.3, np.logspace(-2, 3, 6)
    G = dynamic_complex_modulus(CELL, DYNAMIC[name], P0, f, viscosity=0.2)
    Gl = dynamic_complex_modulus(CELL, _scaled(DYNAMIC[name], lam, True), P0, f / lam, viscosity=0.2 * lam)
    assert _rel(Gl, G) < 1e-11


@pytest.mark.parametrize("name", list(DYNAMIC))
def test_strut_length_scaling(name):
    """(P, EA, EA_arm, kappa, c, L) → (λ²P, λ²EA, λ²EA_arm, λ²kappa, λc, λL) leaves G unchanged (η too)."""
    lam, f = 2.9, np.logspace(-2, 3, 6)
    G = dynamic_complex_modulus(CELL, DYNAMIC[name], P0, f, viscosity=0.2)
    big = tenscell.paper_cell(L=lam)
    Gl = dynamic_complex_modulus(big, _scaled(DYNAMIC[name], lam, False), lam ** 2 * P0, f, viscosity=0.2)
    assert _rel(Gl, G) < 1e-10


# ---- 6. Voigt limits ----------------------------------------------------------------------------------------
def test_maxwell_and_sls_tend_to_voigt_springs_as_tau_grows():
    """τ → ∞: Maxwell → Voigt(EA, 0), SLS → Voigt(EA + EA_arm, 0); the error falls as 1/c (first order)."""
    f = np.logspace(-2, 3, 6)
    sls = DYNAMIC["sls"]
    for law, target in ((Maxwell(EA=EA, c=C), Voigt(EA=EA, c=0.0)),
                        (StandardLinearSolid(EA=EA, EA_arm=sls.EA_arm, c=C), Voigt(EA=EA + sls.EA_arm, c=0.0))):
        Gv = dynamic_complex_modulus(CELL, target, P0, f)
        errs = [_rel(dynamic_complex_modulus(CELL, _with_c(law, C * s), P0, f), Gv) for s in (1e6, 1e7)]
        assert errs[1] < 1e-4 and errs[0] / errs[1] == pytest.approx(10, rel=0.05)


def _with_c(law, c):
    import dataclasses

    return dataclasses.replace(law, c=c)


def test_sls_tends_to_voigt_as_the_arm_stiffens():
    """EA_arm → ∞ at fixed c: SLS → Voigt(EA, c) with error O(ωc·l/EA_arm) (first order)."""
    f = np.logspace(-2, 3, 6)
    Gv = dynamic_complex_modulus(CELL, Voigt(EA=EA, c=C), P0, f)
    errs = [_rel(dynamic_complex_modulus(CELL, StandardLinearSolid(EA=EA, EA_arm=s * EA, c=C), P0, f), Gv)
            for s in (1e8, 1e9)]
    assert errs[1] < 1e-4 and errs[0] / errs[1] == pytest.approx(10, rel=0.05)


def test_sls_without_its_spring_is_maxwell():
    """EA → 0 (the parallel spring gone, the prestress term T/l kept): SLS → Maxwell(EA_arm, c), error O(EA)."""
    f = np.logspace(-2, 3, 6)
    Gm = dynamic_complex_modulus(CELL, Maxwell(EA=EA, c=C), P0, f)
    errs = [_rel(dynamic_complex_modulus(CELL, StandardLinearSolid(EA=s * EA, EA_arm=EA, c=C), P0, f), Gm)
            for s in (1e-6, 1e-7)]
    assert errs[1] < 1e-5 and errs[0] / errs[1] == pytest.approx(10, rel=0.05)


def test_springpot_tends_to_voigt_as_alpha_tends_to_one():
    """α = 1 is exactly Voigt with c = kappa·t1/l; α = 1 − ε differs by O(ε·|log ω|)."""
    f = np.logspace(-2, 3, 6)
    kappa = RNG.uniform(0.1, 2.0, CELL.m)
    Gv = dynamic_complex_modulus(CELL, Voigt(EA=EA, c=kappa / L_), P0, f)
    assert _rel(dynamic_complex_modulus(CELL, Springpot(EA=EA, kappa=kappa, alpha=1.0), P0, f), Gv) < 1e-12
    errs = [_rel(dynamic_complex_modulus(CELL, Springpot(EA=EA, kappa=kappa, alpha=1 - e), P0, f), Gv)
            for e in (1e-4, 1e-5)]
    assert errs[1] < 1e-3 and errs[0] / errs[1] == pytest.approx(10, rel=0.05)


def test_tension_springpot_identities():
    """beta = 0 is the Springpot (EA, kappa, α); α_T = α is the Springpot (EA, kappa + beta·T, α): exact (round-off).
    A wrong T in the active term, or its exponent swapped with the passive one, fails either."""
    law = DYNAMIC["tension-springpot"]
    import dataclasses

    k = dataclasses.replace(law, beta=0.0).complex_stiffness(L_, T_, W)
    assert _rel(k, Springpot(EA=EA, kappa=law.kappa, alpha=law.alpha).complex_stiffness(L_, T_, W)) < 1e-14
    same = dataclasses.replace(law, alpha_T=law.alpha)
    pot = Springpot(EA=EA, kappa=law.kappa + law.beta * T_, alpha=law.alpha)
    assert _rel(same.complex_stiffness(L_, T_, W), pot.complex_stiffness(L_, T_, W)) < 1e-14
    assert _rel(dynamic_complex_modulus(CELL, same, P0, [0.1, 10.0]), dynamic_complex_modulus(CELL, pot, P0, [0.1, 10.0])) < 1e-12


def test_tension_springpot_exponent_falls_with_the_prestress():
    """With α_T < α the cell's loss tangent at 1 Hz falls as P rises (the active part takes over), and tends to
    tan(α_T·π/2) when the active springpot dominates every other term (beta·T ≫ EA, kappa, T)."""
    law = TensionSpringpot(EA=1e-3, kappa=1.0, alpha=0.3, beta=1e4, alpha_T=0.15)
    tan = [float(G.imag / G.real) for G in (dynamic_complex_modulus(CELL, law, P, [1 / (2 * math.pi)])[0]
                                            for P in (1e-7, 1e-3, 1e-1, 1e1, 1e5))]
    assert np.all(np.diff(tan) < 0)
    # P = 1e-7: beta·T ≤ 2.3e-4, EA = 1e-3 beside kappa = 1; P = 1e5: T/l, kappa/l ≤ 1e-4 of beta·T/l
    assert tan[0] == pytest.approx(math.tan(0.15 * math.pi), rel=5e-3)
    assert tan[-1] == pytest.approx(math.tan(0.075 * math.pi), rel=5e-3)


# ---- 7. realizations ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["maxwell", "sls"])
def test_maxwell_and_sls_realizations_are_exact(name):
    """The realized pencil's modal compliance equals the exact kernel at every frequency (round-off)."""
    lin = linearize_law(CELL, DYNAMIC[name], P0)
    assert lin.realization.r == CELL.m and lin.realization.error == 0.0
    tau, rho, _ = lin.pencil.retardation()
    w = 2 * np.pi * np.logspace(-5, 6, 23)
    J = modal_compliance(tau, rho, w)
    assert _rel(J, dynamic_compliance(CELL, P0, DYNAMIC[name].complex_stiffness(L_, T_, w))) < 1e-11


def test_maxwell_creep_limits():
    """Maxwell creep: J(0+) is the Voigt springs' (EA + T)/l compliance (no damping on the nodes), J(∞) the prestress's."""
    spec = creep_spectrum(linearize_law(CELL, DYNAMIC["maxwell"], P0))
    K_inst = P0 * np.asarray(CELL.prestress_hessian) + (CELL.A * ((EA + T_) / L_)) @ CELL.A.T
    assert spec.instantaneous == pytest.approx(CELL.probe @ np.linalg.solve(K_inst, CELL.load), rel=1e-9)
    assert spec.static == pytest.approx(CELL.probe @ np.linalg.solve(P0 * np.asarray(CELL.Kp), CELL.load), rel=1e-9)
    assert np.all(spec.weights >= -1e-12 * spec.static)  # probe = load: a passive creep is non-decreasing


@pytest.mark.parametrize("alpha", [0.05, 0.2, 0.5, 0.9])
@pytest.mark.parametrize("tol", [1e-2, 1e-3, 1e-4])
def test_springpot_prony_series_meets_its_tolerance(alpha, tol):
    """(iω)^α by the Prony series within tol across the band, checked at 500 points per decade (10× the grid the
    series was verified on): between the verification points the error is smooth on the arms' spacing ≥ 1/8 decade.
    Non-negative weights (passive); exact static limit (no spring term)."""
    band = (1e-2, 1e3)
    g_d, tau, g, err = springpot_prony(alpha, band, tol)
    assert err <= tol and g_d >= 0 and np.all(g > 0)
    w = 2 * np.pi * np.logspace(-2, 3, 2501)
    z = 1j * np.multiply.outer(w, tau)
    series = g_d * 1j * w + (z / (1 + z)) @ g
    exact = (1j * w) ** alpha
    assert np.max(np.abs(series - exact) / np.abs(exact)) <= 1.05 * tol


@pytest.mark.parametrize("name", ["springpot", "tension-springpot"])
def test_springpot_realization_within_tolerance_and_statically_exact(name):
    """Realized tendons within tol of k* over the band; the realized pencil's J within tol of the exact J;
    the static compliance exact (the series has no spring term)."""
    law, tol = DYNAMIC[name], 1e-3
    R = law.realization(L_, T_, (1e-2, 1e3), tol)
    w = 2 * np.pi * np.logspace(-2, 3, 501)
    k = law.complex_stiffness(L_, T_, w)
    assert np.max(np.abs(R.complex_stiffness(w) - k) / np.abs(k)) <= 1.05 * tol
    lin = linearize_law(CELL, law, P0, band_hz=(1e-2, 1e3), tol=tol)
    tau, rho, _ = lin.pencil.retardation()
    J = dynamic_compliance(CELL, P0, k)
    assert np.max(np.abs(modal_compliance(tau, rho, w) - J) / np.abs(J)) <= tol
    K0 = dynamic_stiffness_static(CELL, law, P0)
    assert rho.sum() == pytest.approx(CELL.probe @ np.linalg.solve(K0, CELL.load), rel=1e-10)


# ---- 8. the cytoplasm ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("law", [Voigt(EA=EA, c=C), DYNAMIC["maxwell"], DYNAMIC["springpot"]], ids=["voigt", "maxwell", "springpot"])
def test_cytoplasm_adds_i_omega_eta(law):
    """The linear model's cytoplasm (a dashpot 2Lη on the probe, in C0) adds exactly iωη to G* (probe = load):
    through the pencil's modal sum for Voigt, the realized pencil for the dynamic laws, and the kernel."""
    eta, f = 0.37, np.logspace(-2, 3, 6)
    w = 2 * np.pi * f
    G = dynamic_complex_modulus(CELL, law, P0, f)
    assert _rel(dynamic_complex_modulus(CELL, law, P0, f, viscosity=eta) - G, 1j * w * eta) < 1e-12
    lin = linearize_law(CELL, law, P0, viscosity=eta, band_hz=(1e-2, 1e3) if law.dynamic else None)
    tau, rho, _ = lin.pencil.retardation()
    Gp = modulus(modal_compliance(tau, rho, w), CELL.strut_length)
    tol = lin.realization.error * 2 if lin.realization is not None else 1e-10
    assert _rel(Gp, G + 1j * w * eta) <= max(tol, 1e-10)
    Gs, Gl = tenscell.moduli(lin, f)
    assert _rel(Gs + 1j * Gl, G + 1j * w * eta) < 1e-10


def test_cytoplasm_in_the_high_frequency_viscosity_and_creep():
    """Voigt cell: G''/ω → η_structure + η; creep with the cytoplasm starts slower (J(t) smaller at every t)."""
    lin0 = linearize_law(CELL, Voigt(EA=EA, c=C), P0)
    lin = linearize_law(CELL, Voigt(EA=EA, c=C), P0, viscosity=0.5)
    assert tenscell.response.viscosity_limit(lin) == pytest.approx(tenscell.response.viscosity_limit(lin0) + 0.5, rel=1e-10)
    t = np.logspace(-3, 1, 9)
    Jv, J0 = creep_spectrum(lin).compliance(t), creep_spectrum(lin0).compliance(t)
    assert np.all(Jv <= J0 * (1 + 1e-10)) and Jv[0] < 0.9 * J0[0]  # equal (round-off) once both have crept
    assert creep_spectrum(lin).static == pytest.approx(creep_spectrum(lin0).static, rel=1e-10)


def test_negative_viscosity_is_refused():
    with pytest.raises(ValueError, match="viscosity"):
        dynamic_moduli(CELL, Voigt(EA=1.0, c=1.0), P0, [1.0], viscosity=-1.0)


def test_frequency_response_with_a_law_and_a_cytoplasm():
    """frequency_response(law=, viscosity=) = the kernel per prestress; Voigt with η = linearize(viscosity=)."""
    f, Ps = np.logspace(-2, 3, 5), np.array([300.0, 1000.0])
    law = DYNAMIC["springpot"]
    r = tenscell.frequency_response(CELL, f, Ps, law=law, viscosity=0.1)
    for i, p in enumerate(Ps):
        assert _rel(r.G[i], dynamic_complex_modulus(CELL, law, p, f, viscosity=0.1)) < 1e-12
    v = tenscell.frequency_response(CELL, f, Ps, EA, C, viscosity=0.1)
    for i, p in enumerate(Ps):
        Gs, Gl = tenscell.moduli(tenscell.linearize(CELL, p, EA, C, viscosity=0.1), f)
        assert _rel(v.G[i], Gs + 1j * Gl) < 1e-10
    assert v.viscosity == 0.1 and r.to_dataframe().shape[0] == Ps.size * f.size


def test_cytoplasm_in_the_linear_model_needs_probe_at_the_load():
    """A dashpot on the probe is 'in parallel' with the measured modulus only when the probe is the load: refused
    otherwise in one line (dynamic_moduli, which adds iωη to G*, still works)."""
    import dataclasses

    from tenscell.model.equilibrium import equilibrate
    from tenscell.model.structure import Point

    st = dataclasses.replace(CELL.structure, probe=Point(nodes=(6,), weights=(1.0,), direction=(0.0, 0.0, 1.0)))
    cell = equilibrate(st, parameters=dict(CELL.parameters))
    with pytest.raises(ValueError, match="probe to be the load") as err:
        linearize_law(cell, Voigt(EA=EA, c=C), P0, viscosity=0.1)
    assert "\n" not in str(err.value)
    G = dynamic_complex_modulus(cell, Voigt(EA=EA, c=C), P0, [1.0], viscosity=0.1)
    assert _rel(G - dynamic_complex_modulus(cell, Voigt(EA=EA, c=C), P0, [1.0]), np.array([2j * np.pi * 0.1])) < 1e-12


@pytest.mark.parametrize("alpha", [0.2, 0.5])
def test_springpot_creep_within_tolerance_inside_the_band_time_window(alpha):
    """The realization's tolerance is stated in frequency; its creep J(t) for 1/(2π f_high) ≤ t ≤ 1/(2π f_low)
    stays within it too, against a realization of 10× finer tolerance over a band 2 decades wider each side
    (measured 2.1e-4 at α = 0.2 and 7.5e-4 at α = 0.5 for tol = 1e-3)."""
    law = Springpot(EA=1.0, kappa=5.0, alpha=alpha)
    t = np.logspace(np.log10(1 / (2 * np.pi * 1e3)), np.log10(1 / (2 * np.pi * 1e-2)), 41)
    J = creep_spectrum(linearize_law(CELL, law, P0, band_hz=(1e-2, 1e3), tol=1e-3)).compliance(t)
    ref = creep_spectrum(linearize_law(CELL, law, P0, band_hz=(1e-4, 1e5), tol=1e-4)).compliance(t)
    assert np.max(np.abs(J / ref - 1)) <= 1e-3
