"""Large structures of point nodes (lattices) assemble K0 and C0 from 3×3 node blocks on one shared pattern.

The fast path (:class:`tenscell.model.equilibrium.NodeBlocks`) is checked against the reference path (member
Hessians summed plus the Gram product A diag(g) Aᵀ) and against the physics it must satisfy: K0 is the Jacobian of
the elastic forces, A(q0)·T0 = 0, and K0 + σC0 on the shared pattern is the sum scipy forms.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp

import tenscell
from tenscell.linear.assembly import assemble_damping, assemble_stiffness
from tenscell.linear.pencil import _same_pattern
from tenscell.model import equilibrium as eq
from tenscell.model.structure import member_values

SHAPE = (5, 4, 4)  # 1,896 coordinates: sparse


@pytest.fixture(scope="module")
def cell():
    return tenscell.model.lattice_cell(*SHAPE)


@pytest.fixture(scope="module")
def reference_geometry(cell):
    """The cell's geometry with its Hessians, through the general chain rule (not the point-node path)."""
    geom = eq.member_geometry(cell.coords, cell.q0)
    return dataclasses.replace(geom, point_nodes=False)


def _rel(A, B) -> float:
    return float(abs(sp.csr_matrix(A) - sp.csr_matrix(B)).max() / abs(sp.csr_matrix(B)).max())


def test_lattice_geometry_is_point_nodes_without_hessians(cell):
    assert cell.sparse and cell.geometry.point_nodes
    assert cell.geometry.hess is None  # never formed: the node blocks need only e and l


def test_point_geometry_matches_the_chain_rule(cell, reference_geometry):
    """∇l and ∇²l of the point-node formula equal the general chain rule with unit Jacobians, to the bit."""
    fast = eq.member_geometry(cell.coords, cell.q0)
    kin = eq.kinematics(cell.coords, cell.q0)
    a, b = cell.coords.tendon_nodes.T
    M = np.concatenate([kin.jac[a], -kin.jac[b]], axis=2)
    e = fast.directions
    proj = (np.eye(3)[None] - e[:, :, None] * e[:, None, :]) / fast.lengths[:, None, None]
    np.testing.assert_array_equal(fast.grad, np.einsum("mxk,mx->mk", M, e))
    np.testing.assert_array_equal(fast.hess, np.matmul(M.transpose(0, 2, 1), np.matmul(proj, M)))


@pytest.mark.parametrize("weights", ["hessian", "gram", "both"])
def test_node_blocks_equal_the_reference_assembly(cell, reference_geometry, weights):
    rng = np.random.default_rng(3)
    h = rng.standard_normal(cell.m) if weights != "gram" else None
    g = rng.random(cell.m) if weights != "hessian" else None
    fast = eq.member_stiffness(cell.geometry, h, g, A=cell.A, sparse=True)
    ref = None
    if h is not None:
        ref = eq.assemble_hessian(reference_geometry, h, sparse=True)
    if g is not None:
        G = eq.weighted_gram(cell.A, g)
        ref = G if ref is None else ref + G
    # sums of the same products in another order: rounding, relative to the largest entry
    assert _rel(fast, ref) <= 1e-14
    ref = sp.csr_matrix(ref)
    ref.eliminate_zeros()
    inside = sp.csr_matrix((np.ones(ref.nnz), ref.indices, ref.indptr), shape=ref.shape)
    covered = sp.csr_matrix((np.ones(fast.nnz), fast.indices, fast.indptr), shape=fast.shape)
    assert (inside - inside.multiply(covered)).nnz == 0  # every nonzero of the reference is in the pattern
    if weights == "both":  # entries zero for every weight are left out, as the sum of sparse products does
        assert fast.nnz == ref.nnz
    assert abs(fast - fast.T).max() == 0.0  # symmetric to the bit


def test_prestress_stiffness_and_k0_against_reference(cell, reference_geometry):
    Kp_ref = eq.assemble_hessian(reference_geometry, cell.T0, sparse=True) + eq.weighted_gram(cell.A, cell.T0 / cell.lengths)
    assert _rel(cell.Kp, Kp_ref) <= 1e-14
    EA = member_values(cell.structure, {"strut": 1e3, "default": 1.0})
    lin = tenscell.linearize(cell, P=1000.0, EA=EA, c=1.0)
    k = (EA + 1000.0 * cell.T0) / cell.lengths
    K_ref = 1000.0 * eq.assemble_hessian(reference_geometry, cell.T0, sparse=True) + eq.weighted_gram(cell.A, k)
    assert _rel(lin.K0, K_ref) <= 1e-14
    assert _rel(lin.C0, eq.weighted_gram(cell.A, np.ones(cell.m))) <= 1e-14
    # complex tangents (a dynamic law's k*(ω)) take the reference path
    Kc = sp.csr_matrix(assemble_stiffness(cell, 1000.0, k * (1 + 0.3j)))
    assert np.iscomplexobj(Kc.data)
    assert _rel(Kc.real, lin.K0) <= 1e-14
    assert _rel(Kc.imag, 0.3 * eq.weighted_gram(cell.A, k)) <= 1e-14


def test_self_stress_and_k0_is_the_force_jacobian(cell):
    """A(q0)·T0 = 0, and K0 equals the central-difference Jacobian of the elastic forces A(q)·T(l(q))."""
    assert np.abs(cell.A @ cell.T0).max() <= 1e-12 * np.abs(cell.T0).max()
    P = 1000.0
    EA = member_values(cell.structure, {"strut": 1e3, "default": 1.0})
    T = P * cell.T0
    l0 = cell.lengths * EA / (EA + T)  # Eq. 11

    def forces(q):
        return eq.generalized_forces(cell, q, lambda l: EA * (l / l0 - 1.0))[0]

    K0 = sp.csr_matrix(tenscell.linearize(cell, P=P, EA=EA, c=1.0).K0)
    rng = np.random.default_rng(0)
    h = 1e-6
    for i in rng.choice(cell.n, 12, replace=False):
        e = np.zeros(cell.n)
        e[i] = h
        col = (forces(cell.q0 + e) - forces(cell.q0 - e)) / (2 * h)
        # central differences: error ~h²·|f'''| plus rounding |f|·ε/h, both far below 1e-6 of the column
        np.testing.assert_allclose(K0[:, i].toarray().ravel(), col, atol=1e-6 * np.abs(col).max())


def test_shifted_matrix_on_the_shared_pattern(cell):
    EA = member_values(cell.structure, {"strut": 1e3, "default": 1.0})
    lin = tenscell.linearize(cell, P=1000.0, EA=EA, c=2.0)
    assert _same_pattern(lin.K0, lin.C0)
    sigma = 37.5
    Ks = lin.pencil.shifted(sigma)
    ref = (lin.K0 + sigma * lin.C0).tocsr()
    assert abs(Ks - ref).max() == 0.0
    assert _same_pattern(Ks, lin.K0) and Ks.has_sorted_indices
    assert _rel(assemble_damping(cell, np.full(cell.m, 2.0)), lin.C0) == 0.0


def test_answers_unchanged_against_dense(cell):
    """G' and G'' of the sparse lattice (node blocks, Lanczos) against the dense modal path on the same matrices."""
    EA = member_values(cell.structure, {"strut": 1e3, "default": 1.0})
    lin = tenscell.linearize(cell, P=1000.0, EA=EA, c=1.0)
    f = np.logspace(-2, 3, 20)
    Gp, Gpp = tenscell.moduli(lin, f)
    K, C = lin.K0.toarray(), lin.C0.toarray()
    import scipy.linalg

    tau, V = scipy.linalg.eigh(C, K)
    rho = (lin.D0 @ V) * (-lin.H0 @ V)
    J = (rho[None] / (1 + 2j * np.pi * f[:, None] * tau[None])).sum(axis=1)
    G = (0.5 / lin.L) / J
    np.testing.assert_allclose(Gp + 1j * Gpp, G, rtol=1e-9)
