"""Every tendon law through every consumer, each analytic derivative against finite differences.

Laws: Voigt, power-law dashpot (β = 1 linearizes like Voigt; β = 2 has C0 = 0),
strain-stiffening filaments (alone, and on the IFs of a composite law), the
linear spring of ``linearize_tangent``, and a law written in this file (a
cubic spring) to show that a user's law — one class — works everywhere,
with derivatives from the base class's finite differences.

Consumers: the law's tangent and its derivatives (in T and in every
parameter), ``linearize_law`` (K0 is the Jacobian of the exact nonlinear
forces), ``analytic_elasticities`` (against central differences of ln G
through the same law) and ``simulate`` (small amplitude = the linear model).
The finite differences are central with steps chosen so their error is far
below the tolerances, and the tolerances are far below the size of the terms
a wrong formula would drop.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

import tenscell
from tenscell import compliance, laws, paper_cell
from tenscell.dynamics import oscillatory_response
from tenscell.laws import (
    CompositeLaw,
    LinearSpring,
    Maxwell,
    Parameter,
    PowerDashpot,
    Springpot,
    StandardLinearSolid,
    StiffeningFilament,
    TendonLaw,
    TensionSpringpot,
    Voigt,
    family_laws,
    stiffening_law,
)
from tenscell.linear.linearize import linearize_law
from tenscell.laws.filaments import _dlog1p_over_b_db
from tenscell.model.equilibrium import generalized_forces
from tenscell.model.structure import INTERMEDIATE_FILAMENT
from tenscell.sensitivity import analytic_elasticities

P0 = 1000.0
F = np.array([0.01, 1.0, 100.0])


@dataclass(frozen=True, eq=False)
class CubicSpring(TendonLaw):
    """A user's law: ``T = EA(ε + a·ε³) + c·l'`` — only tension, derivatives and the inverse are written."""

    EA: object
    c: object
    a: object = 1.0
    l0: object = None
    parameters: ClassVar = (Parameter("EA", "N"), Parameter("c", "N·s/m", True), Parameter("a", "", True))

    def __post_init__(self):
        self._validate()

    def tension(self, l, ldot):
        e = np.asarray(l) / self._l0() - 1.0
        return self.EA * (e + self.a * e ** 3) + self.c * ldot

    def derivatives(self, l, ldot):
        e = np.asarray(l) / self._l0() - 1.0
        return self.tension(l, ldot), self.EA * (1 + 3 * self.a * e ** 2) / self._l0(), np.broadcast_to(self.c, e.shape)

    def rest_lengths(self, l, T):
        # solve ε + a ε³ = T/EA by Newton from ε = T/EA (monotone for a ≥ 0)
        y = np.asarray(T, dtype=float) / self.EA
        e = y.copy()
        for _ in range(50):
            e = e - (e + self.a * e ** 3 - y) / (1 + 3 * self.a * e ** 2)
        return np.asarray(l, dtype=float) / (1.0 + e)


def _cell():
    return paper_cell()


CELL = _cell()
IFS = CELL.structure.family_indices(INTERMEDIATE_FILAMENT)
RNG = np.random.default_rng(5)
EA = RNG.uniform(0.5, 2.0, CELL.m)
C = RNG.uniform(0.5, 2.0, CELL.m)

LAWS = {
    "voigt": Voigt(EA=EA, c=C),
    "dashpot-beta1": PowerDashpot(EA=EA, c=C, beta=1.0),
    "dashpot-beta2": PowerDashpot(EA=EA, c=C, beta=2.0),
    "stiffening-all": StiffeningFilament(EA=EA, c=C, b=RNG.uniform(0.2, 1.0, CELL.m)),
    "stiffening-IF": stiffening_law(CELL, None, EA, C, b=0.3),
    "linear-spring": LinearSpring(k=(EA + P0 * CELL.T0) / CELL.lengths, c=C),
    "composite-by-family": family_laws(CELL, {
        "actin": Voigt(EA=1.5, c=0.7),
        INTERMEDIATE_FILAMENT: CubicSpring(EA=0.8, c=1.2, a=2.0),
    }),
    "user-cubic": CubicSpring(EA=EA, c=C, a=RNG.uniform(0.5, 3.0, CELL.m)),
}


#: laws with a frequency-dependent tangent (no constant (k, c)): the consumers below either realize them
#: with internal variables or refuse them in one line (tests at the end of this file)
DYNAMIC_LAWS = {
    "maxwell": Maxwell(EA=EA, c=C),
    "sls": StandardLinearSolid(EA=EA, EA_arm=RNG.uniform(0.5, 5.0, CELL.m), c=C),
    "springpot": Springpot(EA=EA, kappa=RNG.uniform(0.1, 2.0, CELL.m), alpha=RNG.uniform(0.1, 0.9, CELL.m)),
    "tension-springpot": TensionSpringpot(EA=EA, kappa=RNG.uniform(0.1, 2.0, CELL.m), alpha=0.3, beta=5e-3,
                                          alpha_T=RNG.uniform(0.1, 0.9, CELL.m)),
    "dynamic-by-family": family_laws(CELL, {"actin": Maxwell(EA=1.5, c=0.3)},
                                     default=Springpot(EA=0.8, kappa=0.5, alpha=0.25)),
}


def test_every_law_class_is_run_through_every_consumer():
    """A new law class in tenscell.laws must join LAWS or DYNAMIC_LAWS (and so every test below)."""
    classes = {obj for obj in vars(laws).values()
               if isinstance(obj, type) and issubclass(obj, TendonLaw) and obj is not TendonLaw
               and not obj.__name__.startswith("_")}
    covered = set()
    for law in list(LAWS.values()) + list(DYNAMIC_LAWS.values()):
        covered.add(type(law))
        if isinstance(law, CompositeLaw):
            covered |= {type(part) for part in law.laws}
    assert classes <= covered, f"laws not covered by tests/test_laws.py: {sorted(c.__name__ for c in classes - covered)}"


def _lnG(law, P, f=F):
    lin = linearize_law(CELL, law, P)
    return np.log((0.5 / CELL.strut_length) / compliance(lin, f))


def _replace(law, name, j, factor, m=None):
    """The law with parameter ``name`` of tendon ``j`` (of ``m``) multiplied by ``factor``."""
    m = CELL.m if m is None else m
    if isinstance(law, CompositeLaw):
        parts = list(law.laws)
        for p, (sub, idx) in enumerate(zip(law.laws, law.indices)):
            if j in idx and name in sub.names:
                parts[p] = _replace(sub, name, int(np.flatnonzero(idx == j)[0]), factor, idx.size)
        return CompositeLaw(tuple(parts), law.indices)
    v = np.array(np.broadcast_to(getattr(law, name), (m,)), dtype=float)
    v[j] *= factor
    return dataclasses.replace(law, **{name: v})


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# ---- 1. the law itself -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(LAWS))
def test_tangent_is_the_derivative_of_the_placed_law(name):
    """k and c of tangent_at_rest are ∂T/∂l and ∂T/∂l' of the law placed at that tension; it carries T."""
    law = LAWS[name].at_prestress(CELL, P0)
    l, T = CELL.lengths, P0 * CELL.T0
    assert _rel(law.elastic(l), T) < 1e-12
    k, c = LAWS[name].tangent_at_rest(l, T)
    h = 1e-7 * l
    fd_k = (law.elastic(l + h) - law.elastic(l - h)) / (2 * h)
    assert _rel(k, fd_k) < 1e-6
    if name != "dashpot-beta2":  # the smoothed dashpot's slope at 0 is not the exact law's (tested in test_dynamics)
        v = 1e-6 * np.ones_like(l)
        fd_c = (law.tension(l, v) - law.tension(l, -v)) / (2 * v)
        assert _rel(c, fd_c) < 1e-6


@pytest.mark.parametrize("name", list(LAWS))
def test_tangent_derivatives_match_central_differences(name):
    law = LAWS[name]
    l, T = CELL.lengths, P0 * CELL.T0
    tan = law.tangent(l, T)
    k, c = law.tangent_at_rest(l, T)
    assert np.array_equal(tan.k, k) or _rel(tan.k, k) < 1e-12
    h = 1e-4 * T
    kp, cp = law.tangent_at_rest(l, T + h)
    km, cm = law.tangent_at_rest(l, T - h)
    fd = (kp - km) / (2 * h)
    assert _rel(tan.dk_dT, fd) < 1e-6, "dk/dT"
    assert np.allclose(tan.dc_dT, (cp - cm) / (2 * h), atol=1e-9)
    # a formula missing the rest length's dependence on T would be off by O(1) here
    for i, pname in enumerate(tan.names):
        for j in np.flatnonzero(tan.present[i])[[0, -1]]:
            v = tan.values[i, j]
            s = 1e-5 if v != 0 else 0.0
            if s == 0.0:  # b = 0 etc.: one-sided second order in absolute steps
                continue
            up, dn = _replace(law, pname, j, 1 + s), _replace(law, pname, j, 1 - s)
            ku, cu = up.tangent_at_rest(l, T)
            kd, cd = dn.tangent_at_rest(l, T)
            dk = (ku[j] - kd[j]) / (2 * s * v)
            dc = (cu[j] - cd[j]) / (2 * s * v)
            scale_k = abs(tan.k[j]) / v
            assert abs(tan.dk[i, j] - dk) <= 1e-6 * max(abs(dk), scale_k), (pname, j)
            assert abs(tan.dc[i, j] - dc) <= 1e-6 * max(abs(dc), abs(tan.c[j]) / v, 1e-12), (pname, j)
            # a tendon's tangent depends on its own parameters only
            others = np.delete(np.arange(CELL.m), j)
            assert np.array_equal(ku[others], k[others])


def test_stiffening_series_matches_the_closed_form_across_its_switch():
    """∂ε/∂b: the series used for small b·y and the closed form agree where both are accurate."""
    y = np.array([0.3, 1.0, 3.0])
    for x in (0.0199, 0.0201):
        b = x / y
        series = sum((-1) ** n * n / (n + 1) * b ** (n - 1) * y ** (n + 1) for n in range(1, 12))
        assert np.allclose(_dlog1p_over_b_db(b, y), series, rtol=1e-10)
    assert np.allclose(_dlog1p_over_b_db(0.0, y), -y ** 2 / 2, rtol=1e-15)


# ---- 2. linearization ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(LAWS))
def test_K0_is_the_jacobian_of_the_nonlinear_forces(name):
    lin = linearize_law(CELL, LAWS[name], P0)
    placed = lin.law
    n = CELL.n
    Jac = np.zeros((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1e-6
        fp, _ = generalized_forces(CELL, CELL.q0 + e, placed.elastic)
        fm, _ = generalized_forces(CELL, CELL.q0 - e, placed.elastic)
        Jac[:, i] = (fp - fm) / 2e-6
    assert np.abs(Jac - lin.K0).max() < 1e-6 * np.abs(lin.K0).max()
    f0, _ = generalized_forces(CELL, CELL.q0, placed.elastic)
    assert np.abs(f0).max() < 1e-9 * P0  # the rest lengths hold the reference in equilibrium
    # and the law placed by the linearization linearizes back to the same model
    again = linearize_law(CELL, placed)
    assert again.P == pytest.approx(P0, rel=1e-12)
    assert np.abs(again.K0 - lin.K0).max() < 1e-9 * np.abs(lin.K0).max()


def test_linearize_is_linearize_law_with_voigt():
    a = tenscell.linearize(CELL, P0, EA, C)
    b = linearize_law(CELL, Voigt(EA=EA, c=C), P0)
    assert np.abs(a.K0 - b.K0).max() < 1e-13 * np.abs(a.K0).max()
    assert np.array_equal(a.C0, b.C0) and np.allclose(a.l0, b.l0, rtol=1e-15)
    assert isinstance(a.law, Voigt) and np.array_equal(a.law.EA, EA)


# ---- 3. sensitivity --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(LAWS))
def test_elasticities_match_finite_differences_through_the_law(name):
    law = LAWS[name]
    el = analytic_elasticities(linearize_law(CELL, law, P0), F)
    h = 1e-5
    fd_P = (_lnG(law, P0 * math.exp(h)) - _lnG(law, P0 * math.exp(-h))) / (2 * h)
    an_P = el.complex[el.index("P")]
    assert _rel(an_P, fd_P) < 1e-6, ("P", an_P, fd_P)
    tan = law.tangent(CELL.lengths, P0 * CELL.T0)
    for i, pname in enumerate(tan.names):
        for j in np.flatnonzero(tan.present[i])[[0, -1]]:
            if tan.values[i, j] == 0:
                continue
            fd = (_lnG(_replace(law, pname, j, math.exp(h)), P0) - _lnG(_replace(law, pname, j, math.exp(-h)), P0)) / (2 * h)
            an = el.complex[el.index(f"{pname}[{j}]")]
            assert np.abs(an - fd).max() < 1e-6 * max(np.abs(fd).max(), 1e-3), (pname, j, an, fd)
    # scaling P and every force-like parameter (EA, c, k) by s scales G by s: the sum rule holds for any law
    # whose tangent is homogeneous of degree 1 in (T, EA, c); b, a are dimensionless and stay out
    if all(n in ("EA", "c", "k") or n in ("b", "a") for n in tan.names):
        rows = [r for r, n in enumerate(el.names) if n.split("[")[0] in ("EA", "c", "k", "P")]
        assert np.allclose(el.complex[rows].sum(axis=0), 1.0, atol=1e-9)


def test_stiffening_prestress_elasticity_is_fixed():
    """The issue's case: IFs with b = 1 at P = 1000. The Voigt formula gave ∂lnG'/∂lnP = 0.67; FD gives 1.06."""
    from tenscell.studies.stiffening import linearize_stiffening

    lin = linearize_stiffening(CELL, P0, b=1.0)
    el = analytic_elasticities(lin, [1.0])
    h = 1e-5
    G = lambda P: ((0.5 / CELL.strut_length) / compliance(linearize_stiffening(CELL, P, b=1.0), [1.0])).real  # noqa: E731
    fd = (np.log(G(P0 * math.exp(h))) - np.log(G(P0 * math.exp(-h)))) / (2 * h)
    assert el.storage[el.index("P")][0] == pytest.approx(fd[0], rel=1e-7)
    assert fd[0] == pytest.approx(1.06, abs=0.01)
    voigt_reading = analytic_elasticities(dataclasses.replace(lin, law=None), [1.0])
    assert abs(voigt_reading.storage[voigt_reading.index("P")][0] - fd[0]) > 0.3


# ---- 4. time domain --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["voigt", "dashpot-beta1", "stiffening-all", "stiffening-IF", "linear-spring",
                                  "composite-by-family", "user-cubic"])
def test_small_amplitude_simulation_is_the_linear_model(name):
    """simulate with the law, at 0.1 N, reproduces the law's linear moduli (nonlinear correction ~1e-7)."""
    law = LAWS[name].at_prestress(CELL, P0)
    r = oscillatory_response(CELL, law, 0.1, 1.0)
    assert r.linear is not None and r.linear.law is law
    assert abs(r.G_storage / r.G_storage_linear - 1) < 1e-4
    assert abs(r.G_loss / r.G_loss_linear - 1) < 1e-4
    # and the linear model it compares with is the law's, not Voigt's (unless the law is Voigt at the reference)
    G_lin = (0.5 / CELL.strut_length) / compliance(linearize_law(CELL, LAWS[name], P0), [1.0])[0]
    assert r.G_storage_linear == pytest.approx(G_lin.real, rel=1e-10)


def test_a_law_without_rest_lengths_is_refused_by_simulate_with_advice():
    with pytest.raises(ValueError, match="at_prestress"):
        tenscell.dynamics.simulate(CELL, Voigt(EA=1.0, c=1.0), tenscell.dynamics.SineForce(1.0, 1.0), 1.0)


# ---- 5. laws with dynamics of their own, through every consumer -----------------------------------------
# moduli: the exact kernel; creep/relaxation: the internal-variable realization; elasticities: exact from the
# dynamic tangent; the nonlinear time domain and constant (k, c) consumers: a one-line refusal naming the way.
@pytest.mark.parametrize("name", list(DYNAMIC_LAWS))
def test_dynamic_law_moduli_through_linearize_law_equal_the_kernel(name):
    from tenscell.linear.dynamic import dynamic_moduli

    lin = linearize_law(CELL, DYNAMIC_LAWS[name], P0)
    assert lin.realization is not None and lin.K0.shape[0] == CELL.n + lin.realization.r
    Gs, Gl = tenscell.moduli(lin, F)
    Ks, Kl = dynamic_moduli(CELL, DYNAMIC_LAWS[name], P0, F)
    assert _rel(Gs, Ks) < 1e-12 and _rel(Gl, Kl) < 1e-12


@pytest.mark.parametrize("name", list(DYNAMIC_LAWS))
def test_dynamic_law_creep_and_relaxation_from_the_realization(name):
    """Creep and relaxation run on the realized pencil; J(t) rises to the exact static compliance (probe = load)."""
    from tenscell.linear.dynamic import dynamic_stiffness_static

    law = DYNAMIC_LAWS[name]
    lin = linearize_law(CELL, law, P0)
    spec = tenscell.timedomain.creep_spectrum(lin)
    K0 = dynamic_stiffness_static(CELL, law, P0)
    assert spec.static == pytest.approx(CELL.probe @ np.linalg.solve(K0, CELL.load), rel=1e-9)
    t = np.logspace(-4, 3, 15)
    if lin.realization.band_hz is None:  # exact realizations (Maxwell, SLS) hold at every time
        J = spec.compliance(t)
    else:  # a band-limited one (springpots) says where it stops; creep_compliance inverts exactly there
        with pytest.warns(tenscell.timedomain.RealizationWarning, match="outside"):
            J = spec.compliance(t)
    assert np.all(np.diff(J) >= -1e-12 * spec.static)
    R = tenscell.stress_relaxation(lin)
    assert R.equilibrium == pytest.approx(1.0 / spec.static, rel=1e-9)


@pytest.mark.parametrize("name", list(DYNAMIC_LAWS))
def test_dynamic_law_elasticities_match_finite_differences(name):
    """analytic_elasticities of a dynamic law (exact, from complex_stiffness_derivatives) against central
    differences of ln G through the same law, for P and for the first and last tendon of every parameter."""
    law = DYNAMIC_LAWS[name]
    el = analytic_elasticities(linearize_law(CELL, law, P0), F)
    h = 1e-5
    fd_P = (_lnG(law, P0 * math.exp(h)) - _lnG(law, P0 * math.exp(-h))) / (2 * h)
    assert _rel(el.complex[el.index("P")], fd_P) < 1e-6
    vals = law.parameter_values(CELL.m)
    for i, pname in enumerate(law.names):
        for j in np.flatnonzero(~np.isnan(vals[i]))[[0, -1]]:
            fd = (_lnG(_replace(law, pname, j, math.exp(h)), P0) - _lnG(_replace(law, pname, j, math.exp(-h)), P0)) / (2 * h)
            an = el.complex[el.index(f"{pname}[{j}]")]
            assert np.abs(an - fd).max() < 1e-6 * max(np.abs(fd).max(), 1e-3), (pname, j)


@pytest.mark.parametrize("name", list(DYNAMIC_LAWS))
def test_dynamic_laws_are_refused_in_one_line_where_they_have_no_meaning(name):
    from tenscell.laws import DynamicLawError
    from tenscell.summary import relaxation_modes

    law = DYNAMIC_LAWS[name]
    placed = law.at_prestress(CELL, P0)
    for call in (lambda: law.tangent_at_rest(CELL.lengths, P0 * CELL.T0),
                 lambda: oscillatory_response(CELL, placed, 0.1, 1.0),
                 lambda: tenscell.dynamics.simulate(CELL, placed, tenscell.dynamics.SineForce(1.0, 1.0), 1.0),
                 lambda: linearize_law(CELL, placed)):
        with pytest.raises(DynamicLawError) as err:
            call()
        assert "\n" not in str(err.value) and ("dynamic" in str(err.value) or "internal" in str(err.value))
    lin = linearize_law(CELL, law, P0)
    with pytest.raises(ValueError, match="internal variables"):
        relaxation_modes(lin)
    with pytest.raises(ValueError, match="internal dynamics"):
        tenscell.response.viscosity_limit(lin)


def test_dynamic_laws_on_a_sparse_lattice():
    """Sparse cells: the kernel solves one sparse LU per frequency (= the Lanczos path for Voigt); a realized
    SLS lattice creeps through the sparse pencil and its compliance equals the kernel's."""
    from tenscell.io.structure_files import member_values
    from tenscell.linear.dynamic import dynamic_moduli
    from tenscell.linear.spectrum import modal_compliance
    from tenscell.model.lattices import lattice_cell
    from tenscell.linear.modal import NotPositiveDefiniteError

    cell = lattice_cell(9, 9, 1)
    assert cell.sparse
    f = np.logspace(-2, 3, 4)
    voigt = Voigt(EA=member_values(cell.structure, {"strut": 1e3, "default": 1.0}), c=1.0)
    G0 = tenscell.moduli(linearize_law(cell, voigt, P0), f)
    G1 = dynamic_moduli(cell, voigt, P0, f)
    assert _rel(G1[0], G0[0]) < 1e-9 and _rel(G1[1], G0[1]) < 1e-9  # the Lanczos path is converged to 1e-12
    law = family_laws(cell, {"strut": Voigt(EA=1e3, c=1.0)}, default=StandardLinearSolid(EA=1.0, EA_arm=1.0, c=1.0))
    lin = linearize_law(cell, law, P0)
    assert lin.pencil.sparse
    tau, rho, err = lin.pencil.retardation()
    J = tenscell.compliance(lin, f)
    assert _rel(modal_compliance(tau, rho, 2 * np.pi * f), J) < 1e-8
    # a cytoplasm on the sparse realized pencil: its retardation spectrum gives G* + iωη of the kernel
    visc = linearize_law(cell, law, P0, viscosity=0.3)
    tau, rho, err = visc.pencil.retardation()
    Gv = (0.5 / cell.strut_length) / modal_compliance(tau, rho, 2 * np.pi * f)
    G = (0.5 / cell.strut_length) / J + 2j * np.pi * f * 0.3
    assert _rel(Gv, G) < 1e-8
    # Maxwell tendons everywhere relax the material stiffness the lattice's stability needs: refused in one line
    with pytest.raises(NotPositiveDefiniteError, match="not a stable equilibrium"):
        dynamic_moduli(cell, family_laws(cell, {"strut": Voigt(EA=1e3, c=1.0)}, default=Maxwell(EA=1.0, c=1.0)), P0, f)
