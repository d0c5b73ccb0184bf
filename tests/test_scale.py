"""Larger cells and the sparse path: spheres, lattices, sparse factorization, Lanczos compliance."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import tenscell
import tenscell.model.equilibrium as equilibrium
from tenscell.linear.sparse import NotPositiveDefinite, factorize_spd
from tenscell.model.equilibrium import self_stress_lp
from tenscell.linear.krylov import krylov_compliance
from tenscell.model.lattices import lattice_module_tensions
from tenscell.io.structure_files import member_values

FREQS = np.logspace(-2, 3, 40)


def _direct(lin, f):
    """Reference compliance by one dense complex solve per frequency."""
    K, C = (m.toarray() if sp.issparse(m) else m for m in (lin.K0, lin.C0))
    return np.array([lin.D0 @ np.linalg.solve(K + 2j * np.pi * fk * C, -lin.H0) for fk in f])


def _lattice_EA(cell):
    return member_values(cell.structure, {"strut": 1e3, "default": 1.0})


# ---- spheres -------------------------------------------------------------------------
@pytest.mark.parametrize("n", [6, 12, 30])
def test_sphere_cells(n):
    cell = tenscell.model.sphere_cell(n)
    s = cell.structure
    assert len(s.struts) == n and s.n_nodes == 2 * n + 1 and len(s.fixed) == 3
    fam = np.array(s.families)
    assert np.sum(fam == "actin") == 4 * n - 3 and np.sum(fam == "intermediate_filament") == 2 * n
    np.testing.assert_allclose(s.strut_lengths, 1.0, rtol=1e-12)
    assert np.all(cell.T0 > 0) and abs(np.linalg.norm(cell.T0) - 1.0) < 1e-12
    assert np.max(np.abs(cell.A @ cell.T0)) < 1e-10
    assert np.all(s.nodes[list(s.fixed), 2] == 0.0)
    assert np.all(s.nodes[:, 2] > (-1e-12 if n < 30 else -0.04))  # the 30-strut triangles are dented
    lin = tenscell.linearize(cell, P=1000.0)  # checks K0 positive definite
    Gp, Gpp = tenscell.moduli(lin, FREQS)
    J = tenscell.compliance(lin, FREQS)
    np.testing.assert_allclose(J, _direct(lin, FREQS), rtol=1e-10)
    assert np.all(Gp > 0) and np.all(Gpp > 0)
    assert np.all(np.diff(Gp) >= -1e-9 * Gp.max())  # storage modulus rises with frequency
    assert abs(tenscell.response.log_slope(FREQS, Gpp)[0] - 1.0) < 1e-2  # Voigt elements: G'' ∝ f at low f


def test_sphere_rejects_other_sizes():
    with pytest.raises(ValueError, match="n_struts must be one of"):
        tenscell.model.sphere_cell(8)


# ---- lattices ------------------------------------------------------------------------
def test_module_tensions():
    t = lattice_module_tensions(0.25, intermediate_filaments=False)
    assert abs(t["strut"] + math.sqrt(6.0)) < 1e-12  # the regular icosahedron
    with pytest.raises(tenscell.model.NotPrestressableError, match="intermediate filaments not in tension"):
        lattice_module_tensions(0.25)  # the regular member has slack IFs, as in the paper
    with pytest.raises(tenscell.model.NotPrestressableError, match="no symmetric self-stress"):
        lattice_module_tensions(0.21, intermediate_filaments=False)
    t = lattice_module_tensions(0.21)
    assert t["intermediate_filament"] > 0 and t["strut"] < 0


@pytest.mark.parametrize("shape", [(3, 2, 1), (2, 2, 2)])
def test_lattice_shares_nodes_and_self_stress(shape):
    nx, ny, nz = shape
    st, T0 = tenscell.model.lattice_structure(nx, ny, nz)
    N = nx * ny * nz
    faces = (nx - 1) * ny * nz + nx * (ny - 1) * nz + nx * ny * (nz - 1)
    assert st.n_nodes == 12 * N - 2 * faces + N  # two nodes per shared face, one centre per module
    assert st.n_tendons == 42 * N and len(st.fixed) == 2 * nx * ny
    cell = tenscell.model.lattice_cell(nx, ny, nz)
    assert np.max(np.abs(cell.A @ cell.T0)) < 1e-12
    cable = np.array([f != "strut" for f in st.families])
    assert np.all(cell.T0[cable] > 0) and np.all(cell.T0[~cable] < 0)
    # every member of a module belongs to one module only: the assembled state is the modules' sum
    assert len({frozenset(t) for t in st.tendons}) == st.n_tendons
    lin = tenscell.linearize(cell, 1000.0, _lattice_EA(cell), 1.0)
    np.testing.assert_allclose(tenscell.compliance(lin, FREQS), _direct(lin, FREQS), rtol=1e-10)


def test_lattice_bad_input():
    with pytest.raises(ValueError, match="nx must be a whole number >= 1"):
        tenscell.model.lattice_cell(0, 2)
    with pytest.raises(ValueError, match="offset must lie between"):
        tenscell.model.lattice_cell(2, 2, offset=0.6)


# ---- sparse versus dense on small structures -----------------------------------------
@pytest.mark.parametrize("which", ["paper", "sphere12", "sheet"])
def test_sparse_and_dense_paths_agree(monkeypatch, which):
    def build():
        if which == "paper":
            return tenscell.paper_cell(), 1.0
        if which == "sphere12":
            return tenscell.model.sphere_cell(12), 1.0
        c = tenscell.model.lattice_cell(2, 2, 1)
        return c, _lattice_EA(c)

    dense, EA = build()
    lin_d = tenscell.linearize(dense, 1000.0, EA, 1.0)
    J_d = tenscell.compliance(lin_d, FREQS)
    G0_d = tenscell.response.static_modulus(lin_d)
    monkeypatch.setattr(equilibrium, "SPARSE_THRESHOLD", 10)  # the whole pipeline goes sparse
    sparse_cell, _ = build()
    assert sparse_cell.sparse and sp.issparse(sparse_cell.Kp)
    np.testing.assert_allclose(sparse_cell.T0, dense.T0, atol=1e-10)  # LP self-stress (or given T0)
    lin_s = tenscell.linearize(sparse_cell, 1000.0, EA, 1.0)  # LDLᵀ positive-definiteness check
    assert sp.issparse(lin_s.K0)
    J_s = tenscell.compliance(lin_s, FREQS)  # one factorization + Lanczos
    np.testing.assert_allclose(J_s, J_d, rtol=1e-10)
    assert abs(tenscell.response.static_modulus(lin_s) / G0_d - 1) < 1e-12


def test_sparse_path_detects_unstable_reference(monkeypatch):
    monkeypatch.setattr(equilibrium, "SPARSE_THRESHOLD", 10)
    cell = tenscell.paper_cell(delta=math.radians(44.0))  # K0 loses definiteness below about 45.5°
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="pivot"):
        tenscell.linearize(cell, 1000.0)


def test_lp_self_stress_matches_svd():
    cell = tenscell.paper_cell()
    T = self_stress_lp(sp.csr_matrix(cell.A), cell.structure.families, cell.structure.equal_tension_groups)
    np.testing.assert_allclose(T, cell.T0, atol=1e-10)
    bad = tenscell.model.paper_structure(0.0, math.radians(60.0), 1.0)
    co = tenscell.model.coordinates.make_coordinates(bad)
    A = equilibrium.equilibrium_matrix(equilibrium.member_geometry(co, co.q0), sparse=True)
    with pytest.raises(tenscell.model.NotPrestressableError):
        self_stress_lp(A, bad.families, bad.equal_tension_groups)


@pytest.mark.parametrize("order", ["amd", "geometric", "metis"])
def test_medium_lattice_uses_sparse_path_end_to_end(monkeypatch, order):
    """Above the threshold without patching: Lanczos against per-frequency sparse LU solves, with each ordering
    the pencil may choose by size (the ordering changes the work, never the accuracy)."""
    from tenscell.linear import ordering

    if order != "amd":
        monkeypatch.setattr(ordering, "MIN_SIZE", 100)
        monkeypatch.setattr(ordering, "METIS_FROM", 100 if order == "metis" else 10 ** 9)
        if order == "metis":
            pytest.importorskip("pymetis")
    cell = tenscell.model.lattice_cell(5, 4, 4)
    assert cell.sparse and cell.n > equilibrium.SPARSE_THRESHOLD and cell.self_stress_dim == -1
    lin = tenscell.linearize(cell, 1000.0, _lattice_EA(cell), 1.0)
    f = np.logspace(-2, 3, 12)
    res = krylov_compliance(lin, f)
    K, C = lin.K0.tocsc(), lin.C0.tocsc()
    J_ref = np.array([lin.D0 @ spla.splu((K + 2j * np.pi * fk * C).tocsc(), permc_spec="MMD_AT_PLUS_A")
                      .solve(-lin.H0.astype(complex)) for fk in f])
    np.testing.assert_allclose(res.J, J_ref, rtol=1e-10)
    assert res.steps < 120 and res.error_estimate < 1e-12
    assert (lin.pencil.ordering is None) == (order == "amd")
    # the reduced model is a model of the same kind: positive relaxation rates
    assert np.all(res.rates > 0)


# ---- factorization and Lanczos on their own --------------------------------------------
def _laplacian_3d(n):
    I = sp.identity(n)
    D = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    return (sp.kron(sp.kron(D, I), I) + sp.kron(sp.kron(I, D), I) + sp.kron(sp.kron(I, I), D)).tocsr()


def test_sparse_cholesky_reduces_fill_and_solves():
    """CHOLMOD's fill-reducing ordering: far less fill than the natural order, and exact solves."""
    n = 12
    A = _laplacian_3d(n) + 0.1 * sp.identity(n ** 3)
    natural = spla.splu(A.tocsc(), permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    F = factorize_spd(A)
    assert F.fill < 0.6 * natural.L.nnz  # L only: the natural LU's L has the Cholesky factor's pattern
    b = np.random.default_rng(0).standard_normal(n ** 3)
    np.testing.assert_allclose(A @ F.solve(b), b, atol=1e-10)
    B = np.random.default_rng(1).standard_normal((n ** 3, 3)) + 1j
    np.testing.assert_allclose(A @ F.solve(B), B, atol=1e-10)


def test_factorize_spd_rejects_indefinite():
    A = _laplacian_3d(5) - 1.0 * sp.identity(125)  # the Laplacian's smallest eigenvalue is 3(2 − 2cos(π/6)) ≈ 0.80
    with pytest.raises(NotPositiveDefinite):
        factorize_spd(A)
    with pytest.raises(NotPositiveDefinite):
        factorize_spd(sp.diags([1.0, 0.0, 2.0]))


def test_krylov_polarization_for_probe_other_than_load():
    cell = tenscell.paper_cell()
    lin = tenscell.linearize(cell, 1000.0)
    probe = np.zeros(cell.n)
    probe[5] = 1.0  # another coordinate
    lin2 = dataclasses.replace(lin, K0=sp.csr_matrix(lin.K0), C0=sp.csr_matrix(lin.C0), D0=probe)
    res = krylov_compliance(lin2, FREQS)
    np.testing.assert_allclose(res.J, _direct(lin2, FREQS), rtol=1e-9, atol=1e-12 * np.abs(res.J).max())


def test_krylov_shift_choice_does_not_change_the_answer():
    cell = tenscell.model.lattice_cell(3, 3, 2)
    lin = tenscell.linearize(cell, 1000.0, _lattice_EA(cell), 1.0)
    lin = dataclasses.replace(lin, K0=sp.csr_matrix(lin.K0), C0=sp.csr_matrix(lin.C0))
    f = FREQS[::3]
    ref = _direct(lin, f)
    for shift in (0.0, 50.0, 2000.0):
        np.testing.assert_allclose(krylov_compliance(lin, f, shift=shift).J, ref, rtol=1e-10)


def test_sparse_relaxation_modes_are_eigenpairs():
    cell = tenscell.model.lattice_cell(5, 5, 4)
    lin = tenscell.linearize(cell, 1000.0, _lattice_EA(cell), 1.0)
    modes = tenscell.summary.relaxation_modes(lin, 3)
    K, C = lin.K0, lin.C0
    assert np.all(np.diff(modes.rates) >= 0) and modes.residuals is not None
    for lam, v, r in zip(modes.rates, modes.vectors.T, modes.residuals):
        assert r < 1e-2
        assert np.linalg.norm(K @ v - lam * (C @ v)) < max(100 * r, 1e-8) * np.linalg.norm(K @ v)  # norms differ
    # the slowest mode of the paper cell, through the sparse route, is the dense one
    dense = tenscell.linearize(tenscell.paper_cell(), 1000.0)
    lin_s = dataclasses.replace(dense, K0=sp.csr_matrix(dense.K0), C0=sp.csr_matrix(dense.C0))
    assert abs(tenscell.summary.relaxation_modes(lin_s, 1).rates[0] / tenscell.linear.relaxation_spectrum(dense).rates[0] - 1) < 1e-10
