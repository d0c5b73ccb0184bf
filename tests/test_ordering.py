"""The fill-reducing orderings of the sparse path (geometric nested dissection, METIS by size) and their use by the pencil."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import tenscell
import tenscell.linear.ordering as ordering
from tenscell.io.structure_files import member_values
from tenscell.linear.sparse import NotPositiveDefinite, factorize_spd


def _grid(n):
    """3D Laplacian on an n³ grid (+ a small diagonal shift: positive definite) and the grid points."""
    I = sp.identity(n)
    D = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    A = (sp.kron(sp.kron(D, I), I) + sp.kron(sp.kron(I, D), I) + sp.kron(sp.kron(I, I), D)).tocsr()
    g = np.arange(n, dtype=float)
    pts = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    return A + 0.1 * sp.identity(n ** 3), pts


def _lattice(shape=(5, 4, 4)):
    cell = tenscell.model.lattice_cell(*shape)
    return cell, member_values(cell.structure, {"strut": 1e3, "default": 1.0})


def test_separator_disconnects_the_halves():
    """Removing the separator leaves no matrix entry between the two halves of any set."""
    rng = np.random.default_rng(3)
    pts = rng.uniform(size=(600, 3))
    d = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    i, j = np.nonzero(np.triu(d < 0.15, 1))
    box = rng.integers(0, 3, size=600)  # three sets cut at once
    active = rng.uniform(size=600) > 0.1
    upper = pts[:, 0] > 0.5
    sep = ordering._separator(i, j, box, active, upper)
    assert sep.any()
    keep = active & ~sep
    across = keep[i] & keep[j] & (box[i] == box[j]) & (upper[i] != upper[j])
    assert not across.any()
    # and it is one side's boundary per set, the smaller one
    for b in range(3):
        s = sep & (box == b)
        assert np.all(upper[s]) or not np.any(upper[s])


def test_nested_dissection_is_a_permutation_that_solves():
    A, pts = _grid(20)
    perm = ordering.nested_dissection(A, pts)
    assert np.array_equal(np.sort(perm), np.arange(A.shape[0]))
    F_nd, F_amd = factorize_spd(A, perm=perm), factorize_spd(A)
    b = np.random.default_rng(0).standard_normal(A.shape[0])
    # κ(A) ≈ 12.1/0.1 ≈ 120: both solves are exact to a few hundred ulps of the solution
    np.testing.assert_allclose(A @ F_nd.solve(b), b, atol=1e-11 * np.abs(b).max())
    np.testing.assert_allclose(F_nd.solve(b), F_amd.solve(b), rtol=0, atol=1e-11 * np.abs(F_amd.solve(b)).max())


def test_a_set_of_one_location_is_not_cut():
    A, _ = _grid(5)
    perm = ordering.nested_dissection(A, np.zeros((125, 3)), leaf=8)  # nowhere to cut: left as it is
    np.testing.assert_array_equal(perm, np.arange(125))


def test_given_ordering_still_proves_positive_definiteness():
    A, pts = _grid(8)
    indefinite = A - 1.0 * sp.identity(512)  # the Laplacian's smallest eigenvalue is 3(2 − 2cos(π/9)) ≈ 0.36
    with pytest.raises(NotPositiveDefinite):
        factorize_spd(indefinite, perm=ordering.nested_dissection(indefinite, pts, leaf=16))


def test_cholmod_options_are_restored():
    from cvxopt import cholmod

    A, pts = _grid(6)
    before = dict(cholmod.options)
    factorize_spd(A, perm=ordering.nested_dissection(A, pts, leaf=16))
    assert dict(cholmod.options) == before


def test_lattice_factor_has_less_fill_than_amd(monkeypatch):
    """What the ordering is for: at 11,520 coordinates (above MIN_SIZE) the factor of K0 is smaller than AMD's
    (measured 1.69e6 against 2.67e6 nonzeros; the margin below is far outside any tie-breaking difference)."""
    cell, EA = _lattice((8, 8, 8))
    assert cell.n >= ordering.MIN_SIZE
    nd = tenscell.linearize(cell, 1000.0, EA, 1.0).pencil
    monkeypatch.setattr(ordering, "MIN_SIZE", 10 ** 9)
    amd = tenscell.linearize(cell, 1000.0, EA, 1.0).pencil
    assert nd.ordering is not None and amd.ordering is None
    assert nd.cholesky.fill < 0.8 * amd.cholesky.fill


@pytest.mark.parametrize("law, method", [("voigt", "geometric"), ("sls", "geometric"), ("voigt", "metis"),
                                         ("sls", "metis")])
def test_lattice_moduli_with_and_without_the_ordering(monkeypatch, law, method):
    """The pencil's nested dissection changes the work, not the answer (internal variables located too)."""
    if method == "metis":
        pytest.importorskip("pymetis")
        monkeypatch.setattr(ordering, "METIS_FROM", 100)
    else:
        monkeypatch.setattr(ordering, "METIS_FROM", 10 ** 9)
    cell, EA = _lattice()
    f = np.logspace(-2, 3, 9)

    def moduli():
        if law == "voigt":
            lin = tenscell.linearize(cell, 1000.0, EA, 1.0)
        else:
            lin = tenscell.linear.linearize_law(cell, tenscell.laws.StandardLinearSolid(EA=EA, EA_arm=EA, c=1.0), 1000.0)
        return lin, np.array(tenscell.moduli(lin, f))

    monkeypatch.setattr(ordering, "MIN_SIZE", 10 ** 9)
    lin_amd, G_amd = moduli()
    assert lin_amd.pencil.ordering is None
    monkeypatch.setattr(ordering, "MIN_SIZE", 100)
    lin_nd, G_nd = moduli()
    perm = lin_nd.pencil.ordering
    assert perm is not None and np.array_equal(np.sort(perm), np.arange(lin_nd.K0.shape[0]))
    # both are Lanczos answers converged to 1e-12 (relative) in J
    np.testing.assert_allclose(G_nd, G_amd, rtol=1e-9)


def test_metis_ordering_is_a_permutation_that_keeps_locations_together():
    pytest.importorskip("pymetis")
    A, pts = _grid(12)
    pts3 = np.repeat(pts, 3, axis=0)  # three unknowns per location, coupled like a node's coordinates
    A3 = sp.kron(A, np.ones((3, 3))).tocsr() + 10.0 * sp.identity(3 * A.shape[0])
    perm = ordering.metis_dissection(A3, pts3)
    assert np.array_equal(np.sort(perm), np.arange(A3.shape[0]))
    loc = perm // 3  # the location of each position: its three unknowns are numbered together
    assert np.all(loc.reshape(-1, 3) == loc[::3, None])
    F, F_amd = factorize_spd(A3, perm=perm), factorize_spd(A3)
    b = np.random.default_rng(1).standard_normal(A3.shape[0])
    np.testing.assert_allclose(F.solve(b), F_amd.solve(b), rtol=0, atol=1e-11 * np.abs(F_amd.solve(b)).max())


def test_ordering_is_chosen_by_size(monkeypatch):
    A, pts = _grid(20)  # 8,000 unknowns
    assert ordering.fill_reducing(A, None) is None
    monkeypatch.setattr(ordering, "MIN_SIZE", 10 ** 5)
    assert ordering.fill_reducing(A, pts) is None  # AMD below MIN_SIZE
    monkeypatch.setattr(ordering, "MIN_SIZE", 100)
    monkeypatch.setattr(ordering, "METIS_FROM", 10 ** 5)
    np.testing.assert_array_equal(ordering.fill_reducing(A, pts), ordering.nested_dissection(A, pts))
    monkeypatch.setattr(ordering, "METIS_FROM", 100)
    monkeypatch.setattr(ordering, "_pymetis", lambda: None)  # without pymetis: the geometric one
    np.testing.assert_array_equal(ordering.fill_reducing(A, pts), ordering.nested_dissection(A, pts))


def test_metis_has_less_fill_than_the_geometric_dissection_at_16k(monkeypatch):
    """Why METIS from METIS_FROM: at 16,281 coordinates its factor of K0 is smaller (measured 2.86e6 against
    3.98e6 nonzeros; the margin is far outside any tie-breaking difference)."""
    pytest.importorskip("pymetis")
    cell, EA = _lattice((9, 9, 9))
    assert cell.n >= ordering.METIS_FROM
    metis = tenscell.linearize(cell, 1000.0, EA, 1.0).pencil
    monkeypatch.setattr(ordering, "_pymetis", lambda: None)
    geometric = tenscell.linearize(cell, 1000.0, EA, 1.0).pencil
    assert metis.cholesky.fill < 0.85 * geometric.cholesky.fill


def test_node_graph_is_the_location_graph_of_point_nodes():
    """For point nodes (three unknowns per location, consecutive) METIS is given the graph of the matrix's 3×3
    blocks (no sort of the locations): the same graph as the location graph, up to numbering its vertices."""
    cell, EA = _lattice((5, 4, 4))
    lin = tenscell.linearize(cell, 1000.0, EA, 1.0)
    A = sp.csr_matrix(abs(lin.K0) + abs(lin.C0))
    pts = ordering.coordinate_locations(cell.coords)
    assert ordering._in_triples(pts)
    _, c1, xadj1, adj1 = ordering._node_graph(A, pts)
    group, c2, xadj2, adj2 = ordering._location_graph(A, pts)
    node_at = np.argsort(group[0::3])  # location index -> node
    assert np.unique(group[0::3]).size == group[0::3].size  # one node per location here
    G1 = sp.csr_matrix((np.ones(adj1.size), adj1, xadj1), shape=(c1.size, c1.size))
    G2 = sp.csr_matrix((np.ones(adj2.size), adj2, xadj2), shape=(c2.size, c2.size))
    assert (G1[node_at][:, node_at] != G2).nnz == 0 and G1.nnz == G2.nnz > 0
    np.testing.assert_array_equal(c1, c2)
    assert not ordering._in_triples(np.arange(12.0).reshape(4, 3).repeat(3, axis=0)[1:-2])  # triples out of step
