"""Physics invariants of the core pipeline: structure -> equilibrium -> linearization -> response.

Each test states an invariant that a wrong model fails.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tenscell
from tenscell.model.equilibrium import generalized_forces, member_geometry, tangent_stiffness

F_WIDE = np.logspace(-3, 5, 161)  # Hz


def _direct(lin, w):
    """Independent reference: one dense complex solve of (K0 + iωC0) x = −H0 per frequency."""
    K0, C0 = (M.toarray() if hasattr(M, "toarray") else M for M in (lin.K0, lin.C0))
    return np.array([lin.D0 @ np.linalg.solve(K0 + 1j * wk * C0, -lin.H0) for wk in np.atleast_1d(w)])


@pytest.fixture(scope="module")
def cell():
    return tenscell.paper_cell()


@pytest.fixture(scope="module")
def lin(cell):
    return tenscell.linearize(cell, P=1000.0, EA=1.0, c=1.0)


# ---- structure and reference ----------------------------------------------------------
def test_paper_cell_counts(cell):
    s = cell.structure
    assert cell.n == 24 and cell.m == 33
    assert len(s.family_indices("actin")) == 21 and len(s.family_indices("intermediate_filament")) == 12
    assert len(s.struts) == 6 and sum(s.is_anchored(k) for k in range(6)) == 3
    np.testing.assert_allclose(s.strut_lengths, 1.0, rtol=1e-14)


def test_reference_matches_appendix():
    """q0 reproduces the appendix's X10, Y10, X20, Y20, X30 and the angle pattern."""
    a, d, L = 0.07, math.radians(49.0), 1.3
    q = tenscell.paper_cell(alpha=a, delta=d, L=L).q0
    sd, sa, ca = math.sin(d), math.sin(a), math.cos(a)
    X10 = -L * math.sqrt(6) / 8 + L / 4 * sd * ca + L * math.sqrt(3) / 4 * sd * sa
    Y10 = L * math.sqrt(2) / 8 + L / 4 * sa * sd - L * math.sqrt(3) / 4 * sd * ca
    X20 = L * math.sqrt(6) / 8 - L / 2 * sd * ca
    Y20 = L * math.sqrt(2) / 8 - L / 2 * sa * sd
    X30 = L / 4 * sd * ca - L * math.sqrt(3) / 4 * sa * sd
    np.testing.assert_allclose([q[6], q[7], q[11], q[12], q[16]], [X10, Y10, X20, Y20, X30], atol=1e-14)
    deg = math.radians
    angles = np.mod([q[1], q[3], q[5], q[10], q[15], q[20]], 2 * math.pi)
    expect = np.mod([a, a + deg(240), a + deg(120), a + deg(120), a, a + deg(240)], 2 * math.pi)
    np.testing.assert_allclose(angles, expect, atol=1e-12)
    np.testing.assert_allclose(q[[0, 2, 4, 9, 14, 19]], d, atol=1e-12)


def test_all_strut_ends_on_one_sphere(cell):
    x = cell.structure.nodes
    r = np.linalg.norm(x[:12] - x[12], axis=1)
    np.testing.assert_allclose(r, r[0], rtol=1e-13)


def test_regular_member_geometry():
    """At the regular member every actin tendon has length L·√(3/8) and the sphere radius is √5·L/4."""
    c = tenscell.paper_cell(delta=tenscell.model.REGULAR_DELTA, intermediate_filaments=False)
    np.testing.assert_allclose(c.lengths, math.sqrt(3 / 8), rtol=1e-13)
    x = tenscell.model.paper_structure(0.0, tenscell.model.REGULAR_DELTA, 1.0).nodes
    np.testing.assert_allclose(np.linalg.norm(x[:12] - x[12], axis=1), math.sqrt(5) / 4, rtol=1e-13)
    np.testing.assert_allclose(x[12, 2], math.sqrt(3) / 4, rtol=1e-13)


# ---- statics -----------------------------------------------------------------------------
def test_self_stress_equilibrium_and_rank(cell):
    A = cell.A
    assert np.linalg.matrix_rank(A) == 24 and cell.self_stress_dim == 9
    assert np.linalg.norm(A @ cell.T0) <= 1e-12 * np.linalg.norm(A) * np.linalg.norm(cell.T0)
    assert np.all(cell.T0 > 0)
    np.testing.assert_allclose(np.linalg.norm(cell.T0), 1.0, rtol=1e-14)
    T_if = cell.T0[cell.structure.family_indices("intermediate_filament")]
    np.testing.assert_allclose(T_if, T_if[0], rtol=1e-12)


@pytest.mark.parametrize("delta_deg", [46.0, 48.0, 52.0, 54.0])
def test_equal_if_state_positive_inside_band(delta_deg):
    c = tenscell.paper_cell(delta=math.radians(delta_deg))
    assert np.all(c.T0 > 0) and np.linalg.norm(c.A @ c.T0) < 1e-12


def test_regular_member_with_ifs_is_not_prestressable():
    with pytest.raises(tenscell.model.NotPrestressableError, match="intermediate_filament"):
        tenscell.paper_cell(delta=tenscell.model.REGULAR_DELTA)
    with pytest.raises(tenscell.model.NotPrestressableError):
        tenscell.paper_cell(delta=math.radians(56.0))


def test_if_free_cell_lives_on_its_curve():
    c = tenscell.paper_cell(intermediate_filaments=False)
    assert c.n == 21 and c.m == 21 and c.self_stress_dim == 1
    assert math.isclose(c.parameters["delta"], tenscell.model.REGULAR_DELTA, rel_tol=1e-12)
    np.testing.assert_allclose(c.T0, 1 / math.sqrt(21), rtol=1e-10)  # regular member: all actin equal
    with pytest.raises(tenscell.model.NotPrestressableError, match="curve"):
        tenscell.paper_cell(delta=math.radians(50.0), intermediate_filaments=False)


def test_rest_lengths_reproduce_prestress(cell):
    """Tendons with l0 from Eq. (11) carry exactly P·T0 at q0, and A(q0)·T = 0 (equilibrium)."""
    P, EA = 2500.0, np.linspace(0.5, 3.0, 33)
    l0 = tenscell.laws.rest_lengths(cell, P, EA)
    f, geom = generalized_forces(cell, cell.q0, lambda l: EA * (l / l0 - 1))
    np.testing.assert_allclose(EA * (geom.lengths / l0 - 1), P * cell.T0, rtol=1e-12)
    assert np.linalg.norm(f) < 1e-9 * P


# ---- exact derivatives ------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["angles", "local"])
def test_equilibrium_matrix_and_hessians_match_finite_differences(kind):
    c = tenscell.paper_cell(parametrization=kind)
    rng = np.random.default_rng(1)
    q = c.q0 + 1e-2 * rng.standard_normal(c.n)
    g = member_geometry(c.coords, q)
    h = 1e-6
    for i in range(c.n):
        e = np.zeros(c.n)
        e[i] = h
        gp, gm = member_geometry(c.coords, q + e), member_geometry(c.coords, q - e)
        dl = (gp.lengths - gm.lengths) / (2 * h)
        a_i = np.array([g.grad[j][g.index[j] == i].sum() for j in range(c.m)])
        np.testing.assert_allclose(a_i, dl, atol=1e-8)
        # Hessian column i: d(grad)/dq_i
        for j in range(0, c.m, 4):
            gp_full = np.zeros(c.n + 1)
            gm_full = np.zeros(c.n + 1)
            np.add.at(gp_full, gp.index[j], gp.grad[j])
            np.add.at(gm_full, gm.index[j], gm.grad[j])
            H = np.zeros((c.n + 1, c.n + 1))
            np.add.at(H, (g.index[j][:, None], g.index[j][None, :]), g.hess[j])
            np.testing.assert_allclose(H[:-1, i], (gp_full - gm_full)[:-1] / (2 * h), atol=1e-7)


def test_K0_symmetric_positive_definite(lin):
    K = lin.K0
    assert np.abs(K - K.T).max() <= 1e-12 * np.abs(K).max()
    assert np.linalg.eigvalsh(K)[0] > 0
    C = lin.C0
    assert np.abs(C - C.T).max() <= 1e-12 * np.abs(C).max() and np.linalg.eigvalsh(C)[0] > 0


def test_K0_is_jacobian_of_elastic_forces(cell):
    """K0 = ∂(A(q)T(q))/∂q at q0, by central differences of the nonlinear generalized forces."""
    P, EA = 1000.0, np.linspace(0.7, 1.6, 33)
    lin = tenscell.linearize(cell, P=P, EA=EA)
    law = lambda l: EA * (l / lin.l0 - 1)  # noqa: E731
    h = 1e-6
    J = np.zeros((cell.n, cell.n))
    for i in range(cell.n):
        e = np.zeros(cell.n)
        e[i] = h
        J[:, i] = (generalized_forces(cell, cell.q0 + e, law)[0] - generalized_forces(cell, cell.q0 - e, law)[0]) / (2 * h)
    np.testing.assert_allclose(lin.K0, J, atol=1e-5 * np.abs(lin.K0).max())
    # and the general tangent-stiffness routine agrees away from the reference too
    q = cell.q0 + 1e-3
    g = member_geometry(cell.coords, q)
    Kt = tangent_stiffness(g, law(g.lengths), EA / lin.l0)
    Jq = np.column_stack([
        (generalized_forces(cell, q + h * np.eye(cell.n)[i], law)[0] - generalized_forces(cell, q - h * np.eye(cell.n)[i], law)[0]) / (2 * h)
        for i in range(cell.n)
    ])
    np.testing.assert_allclose(Kt, Jq, atol=1e-5 * np.abs(Kt).max())


def test_K0_linear_in_P_and_EA(cell):
    """K0 = P·Kp + Σ EA_j K_j: exactly linear in P and in each EA_j."""
    rng = np.random.default_rng(2)
    EA1, EA2 = rng.uniform(0.5, 2, 33), rng.uniform(0.5, 2, 33)
    k = lambda P, EA: tenscell.linearize(cell, P=P, EA=EA, check=False).K0  # noqa: E731
    np.testing.assert_allclose(k(700.0, EA1) + k(1300.0, EA2), k(2000.0, EA1 + EA2), rtol=1e-12, atol=1e-10)
    lin = tenscell.linearize(cell, P=900.0, EA=EA1)
    np.testing.assert_allclose(lin.K0, 900.0 * lin.Kp + np.einsum("m,mij->ij", EA1, lin.K_j), rtol=1e-12, atol=1e-10)


def test_paper_load_and_output_vectors(lin):
    """With the paper's coordinates, H0 = −e_Z1 and D0 = e_Z1 (Z1 is coordinate 9 of Eq. 2)."""
    e = np.zeros(24)
    e[8] = 1.0
    np.testing.assert_allclose(lin.H0, -e, atol=1e-15)
    np.testing.assert_allclose(lin.D0, e, atol=1e-15)


# ---- response -------------------------------------------------------------------------
def test_passivity(lin):
    """G'' > 0 at every frequency when every damper is positive (1e-3 to 1e5 Hz)."""
    _, Gpp = tenscell.moduli(lin, F_WIDE)
    assert np.all(Gpp > 0)


@given(P=st.floats(200, 5000), EA=st.lists(st.floats(0.01, 100), min_size=33, max_size=33),
       c=st.lists(st.floats(0.01, 100), min_size=33, max_size=33))
@settings(max_examples=25, deadline=None)
def test_passivity_heterogeneous(cell, P, EA, c):
    lin = tenscell.linearize(cell, P=P, EA=np.array(EA), c=np.array(c))
    _, Gpp = tenscell.moduli(lin, F_WIDE)
    assert np.all(Gpp > 0)


def test_static_and_high_frequency_limits(lin):
    Gp, Gpp = tenscell.moduli(lin, np.array([1e-6, 1e8]))
    G0 = tenscell.response.static_modulus(lin)
    x = np.linalg.solve(lin.K0, -lin.H0)
    np.testing.assert_allclose(G0, 0.5 / lin.L / (lin.D0 @ x), rtol=1e-12)
    np.testing.assert_allclose(Gp[0], G0, rtol=1e-9)
    eta = tenscell.response.viscosity_limit(lin)
    np.testing.assert_allclose(Gpp[1] / (2 * np.pi * 1e8), eta, rtol=1e-6)
    assert G0 > 0 and 300 < G0 < 310  # P=1000, EA=c=1: 304.92 Pa


def test_spectral_equals_direct_solve(lin):
    f = np.logspace(-3, 5, 41)
    np.testing.assert_allclose(tenscell.compliance(lin, f), _direct(lin, 2 * np.pi * f), rtol=1e-10)


@given(s=st.floats(0.05, 20.0))
@settings(max_examples=15, deadline=None)
def test_time_scaling(cell, s):
    """Multiplying every c by s maps G(f) to G(s·f)."""
    f = np.logspace(-2, 3, 13)
    c = np.linspace(0.5, 2.0, 33)
    G1 = np.array(tenscell.moduli(tenscell.linearize(cell, 1500.0, EA=1.3, c=s * c), f))
    G2 = np.array(tenscell.moduli(tenscell.linearize(cell, 1500.0, EA=1.3, c=c), s * f))
    np.testing.assert_allclose(G1, G2, rtol=1e-9)


@given(s=st.floats(0.01, 100.0))
@settings(max_examples=15, deadline=None)
def test_joint_linearity(cell, s):
    """Scaling P, EA and c together by s scales G by s."""
    f = np.logspace(-2, 3, 13)
    EA, c = np.linspace(0.5, 2.0, 33), np.linspace(2.0, 0.3, 33)
    G1 = np.array(tenscell.moduli(tenscell.linearize(cell, s * 800.0, EA=s * EA, c=s * c), f))
    G2 = np.array(tenscell.moduli(tenscell.linearize(cell, 800.0, EA=EA, c=c), f))
    np.testing.assert_allclose(G1, s * G2, rtol=1e-9)


def test_coordinate_invariance_angles_vs_local():
    """Two parametrizations (paper angles, local gnomonic chart) give the same J."""
    f = np.logspace(-3, 5, 33)
    for alpha, delta in [(0.0, 50.0), (0.1, 49.0)]:
        Js = []
        for kind in ("angles", "local"):
            c = tenscell.paper_cell(alpha=alpha, delta=math.radians(delta), parametrization=kind)
            Js.append(tenscell.compliance(tenscell.linearize(c, 2000.0, EA=np.linspace(1, 2, 33)), f))
        np.testing.assert_allclose(Js[0], Js[1], rtol=1e-10)


def test_relaxation_spectrum(lin):
    spec = tenscell.linear.relaxation_spectrum(lin)
    V = spec.modes
    np.testing.assert_allclose(V.T @ lin.C0 @ V, np.eye(24), atol=1e-10)
    np.testing.assert_allclose(V.T @ lin.K0 @ V, np.diag(spec.rates), atol=1e-8 * spec.rates.max())
    assert np.all(spec.rates > 0) and np.all(spec.residues >= -1e-15)
    np.testing.assert_allclose(spec.weights.sum(), 0.5 / lin.L / tenscell.response.static_modulus(lin), rtol=1e-10)


def test_frequency_response_grid_matches_single_calls(cell):
    f, Ps = np.logspace(-1, 2, 7), np.array([600.0, 3000.0])
    r = tenscell.frequency_response(cell, f, Ps)
    for i, P in enumerate(Ps):
        Gp, Gpp = tenscell.moduli(tenscell.linearize(cell, P), f)
        np.testing.assert_allclose(r.G_storage[i], Gp, rtol=1e-13)
        np.testing.assert_allclose(r.G_loss[i], Gpp, rtol=1e-13)
    sl_p, sl_pp = r.slopes()
    assert sl_p.shape == (2, 7) and np.all(sl_pp > 0)
    np.testing.assert_allclose(r.loss_tangent, r.G_loss / r.G_storage)


def test_if_free_cell_uses_direct_solves():
    c = tenscell.paper_cell(intermediate_filaments=False)
    lin = tenscell.linearize(c, 1000.0)
    assert np.linalg.matrix_rank(lin.C0) < c.n  # an undamped mechanism
    with pytest.raises(ValueError, match="singular"):
        tenscell.linear.relaxation_spectrum(lin)
    Gp, Gpp = tenscell.moduli(lin, F_WIDE)
    assert np.all(np.isfinite(Gp)) and np.all(Gpp > 0)
    # a spectrum built on a round-off Cholesky of the singular C0 gave G'(1e-4 Hz) < 0 here
    for P in (300.0, 1000.0):
        lin = tenscell.linearize(c, P)
        np.testing.assert_allclose(tenscell.moduli(lin, 1e-4)[0], tenscell.response.static_modulus(lin), rtol=1e-6)


def test_if_free_curve_off_alpha_zero():
    """Near α = 0 the IF-free curve is prestressable; at α = 0.2 rad its self-stress compresses actin."""
    assert tenscell.paper_cell(alpha=0.05, intermediate_filaments=False).T0.min() > 0
    with pytest.raises(tenscell.model.NotPrestressableError, match="curve delta\\*\\(alpha\\) itself"):
        tenscell.paper_cell(alpha=0.2, intermediate_filaments=False)


# ---- bad input -------------------------------------------------------------------------
@pytest.mark.parametrize("kw, word", [
    (dict(P=0.0), "P"), (dict(P=-1.0), "P"), (dict(P=float("nan")), "P"), (dict(P="abc"), "P"),
    (dict(EA=0.0), "EA"), (dict(EA=-2.0), "EA"), (dict(EA=np.ones(5)), "EA"), (dict(EA=float("nan")), "EA"),
    (dict(c=0.0), "c"), (dict(c=float("inf")), "c"), (dict(c="x"), "c"),
])
def test_bad_linearize_input(cell, kw, word):
    with pytest.raises(ValueError, match=word):
        tenscell.linearize(cell, **kw)


@pytest.mark.parametrize("f", [0.0, -1.0, float("nan"), "abc", []])
def test_bad_frequency(lin, f):
    with pytest.raises(ValueError, match="frequency"):
        tenscell.moduli(lin, f)


@pytest.mark.parametrize("kw, word", [
    (dict(L=0.0), "L"), (dict(L=-1.0), "L"), (dict(L=float("nan")), "L"), (dict(L="a"), "L"),
    (dict(delta=0.0), "delta"), (dict(delta=2.0), "delta"), (dict(alpha=float("inf")), "alpha"),
])
def test_bad_cell_input(kw, word):
    with pytest.raises(ValueError, match=word):
        tenscell.paper_cell(**kw)


def test_unstable_reference_is_rejected():
    c = tenscell.paper_cell(delta=math.radians(44.0))
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="positive definite"):
        tenscell.linearize(c, 1000.0)


def test_load_on_fixed_node_is_rejected():
    s = tenscell.model.paper_structure(0.0, tenscell.model.DEFAULT_DELTA, 1.0)
    with pytest.raises(tenscell.model.StructureError, match="load"):
        tenscell.Structure(nodes=s.nodes, struts=s.struts, tendons=s.tendons, families=s.families, fixed=s.fixed,
                           load=tenscell.model.Point((0,), (1.0,)), probe=s.probe)
    with pytest.raises(tenscell.model.StructureError, match="probe"):
        tenscell.Structure(nodes=s.nodes, struts=s.struts, tendons=s.tendons, families=s.families, fixed=s.fixed,
                           load=s.load, probe=tenscell.model.Point((1, 2), (0.5, 0.5)))


def test_structure_validation_names_the_element():
    s = tenscell.model.paper_structure(0.0, tenscell.model.DEFAULT_DELTA, 1.0)
    bad = list(s.tendons)
    bad[17] = (4, 4)
    with pytest.raises(tenscell.model.StructureError, match="tendon 17 joins node 4 to itself"):
        tenscell.Structure(nodes=s.nodes, struts=s.struts, tendons=bad, families=s.families, fixed=s.fixed,
                           load=s.load, probe=s.probe)
    bad[17] = bad[3]
    with pytest.raises(tenscell.model.StructureError, match="duplicates"):
        tenscell.Structure(nodes=s.nodes, struts=s.struts, tendons=bad, families=s.families, fixed=s.fixed,
                           load=s.load, probe=s.probe)
    bad[17] = (3, 99)
    with pytest.raises(tenscell.model.StructureError, match="unknown node 99"):
        tenscell.Structure(nodes=s.nodes, struts=s.struts, tendons=bad, families=s.families, fixed=s.fixed,
                           load=s.load, probe=s.probe)
