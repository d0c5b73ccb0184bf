"""The linear-algebra core (tenscell.linear.modal): one decomposition per model, dense and sparse agree.

Each test states an invariant: a model is factorized/decomposed once whatever is asked of it;
the sparse (Lanczos) route gives the dense answer for creep, relaxation, the spectrum and the
limits; CHOLMOD detects an indefinite K0; the prestress grid equals the per-model path.
"""
from __future__ import annotations

import copy
import dataclasses
import math
import pickle

import numpy as np
import pytest
import scipy.sparse as sp

import tenscell
import tenscell.linear.definite as definite
import tenscell.linear.modal as modal
from tenscell import _threads
from tenscell.io.structure_files import member_values
from tenscell.timedomain import creep_spectrum, stress_relaxation

F = np.logspace(-2, 3, 25)
T = np.logspace(-5, 2, 40)


def _lattice_EA(cell):
    return member_values(cell.structure, {"strut": 1e3, "default": 1.0})


def _as_sparse(lin):
    """The same model with scipy.sparse matrices: it takes the sparse (CHOLMOD + Lanczos) route."""
    return dataclasses.replace(lin, K0=sp.csr_matrix(lin.K0), C0=sp.csr_matrix(lin.C0))


@pytest.fixture(scope="module")
def mid():
    """A 450-coordinate lattice, dense, and its sparse twin."""
    cell = tenscell.model.lattice_cell(3, 3, 2)
    lin = tenscell.linearize(cell, 1000.0, _lattice_EA(cell), 1.0)
    return lin, _as_sparse(lin)


# ---- one factorization / decomposition per model -------------------------------------------
def test_sparse_model_is_factorized_once_per_matrix(monkeypatch):
    calls = []
    real = definite.factorize_spd

    def counting(A, what="the matrix", perm=None):
        calls.append(what)
        return real(A, what, perm)

    monkeypatch.setattr(definite, "factorize_spd", counting)
    cell = tenscell.model.lattice_cell(4, 4, 4)
    assert cell.sparse
    lin = tenscell.linearize(cell, 1000.0, _lattice_EA(cell), 1.0)  # the check: K0's Cholesky
    assert calls == ["K0"]
    tenscell.moduli(lin, F)
    tenscell.moduli(lin, np.logspace(-1, 2, 7))  # other frequencies: same shifted factor, same run
    creep_spectrum(lin)
    stress_relaxation(lin)
    tenscell.linear.relaxation_spectrum(lin)
    tenscell.response.static_modulus(lin)
    tenscell.response.viscosity_limit(lin)
    tenscell.summary.relaxation_modes(lin, 2)  # the slowest modes: a probe on the check's own factor, then K0 − λ0C0
    assert calls.count("K0") == 1 and len(calls) == 3, calls  # K0 once, K0 + σC0 once, K0 − λ0C0 once
    # without the check, the frequency response and the time domain share one factorization
    calls.clear()
    lin2 = tenscell.linearize(cell, 1500.0, _lattice_EA(cell), 1.0, check=False)
    tenscell.moduli(lin2, F)
    creep_spectrum(lin2)
    tenscell.linear.relaxation_spectrum(lin2)
    assert len(calls) == 1 and calls[0] != "K0", calls


@pytest.mark.parametrize("c, viscosity", [(1.0, 0.0), ("decades", 0.0), (1.0, 0.1)])  # C0 whitened by the
# prestress family; by K0's factor; a cytoplasm's own C0 (the family is not asked for it)
def test_dense_model_is_decomposed_once(monkeypatch, c, viscosity):
    calls = []
    real, real_syevd = np.linalg.eigh, definite._syevd

    def counting(a, *args, **kw):
        calls.append(np.shape(a))
        return real(a, *args, **kw)

    def counting_syevd(a, *args, **kw):
        calls.append(np.shape(a))
        return real_syevd(a, *args, **kw)

    monkeypatch.setattr(modal.np.linalg, "eigh", counting)
    monkeypatch.setattr(definite, "_syevd", counting_syevd)
    cell = tenscell.paper_cell()
    c = np.logspace(-6, 2, cell.m) if c == "decades" else c
    lin = tenscell.linearize(cell, 1000.0, c=c, viscosity=viscosity)
    assert (lin.pencil.family is None) == (not np.isscalar(c) or viscosity > 0)
    tenscell.moduli(lin, F)
    tenscell.moduli(lin, F[::2])
    creep_spectrum(lin)
    stress_relaxation(lin)
    tenscell.linear.relaxation_spectrum(lin)
    tenscell.response.viscosity_limit(lin)
    tenscell.summary.relaxation_modes(lin, 2)
    assert calls == [(lin.cell.n, lin.cell.n)]


def test_pencil_is_not_shared_by_copies(mid):
    lin, lin_s = mid
    J = tenscell.compliance(lin_s, F)
    twin = copy.copy(lin_s)  # the cached factors are dropped (native factors do not pickle) and rebuilt
    assert "pencil" not in twin.__dict__
    np.testing.assert_allclose(tenscell.compliance(twin, F), J, rtol=1e-12)
    assert dataclasses.replace(lin, P=lin.P).pencil is not lin.pencil


# ---- sparse equals dense --------------------------------------------------------------------
def test_sparse_creep_and_relaxation_equal_dense(mid):
    lin, lin_s = mid
    cd, cs = creep_spectrum(lin), creep_spectrum(lin_s)
    assert cs.error_estimate < 1e-9 and cd.error_estimate == 0.0
    Jd, Js = cd.compliance(T), cs.compliance(T)
    np.testing.assert_allclose(Js, Jd, rtol=1e-9)
    assert cs.static == pytest.approx(cd.static, rel=1e-12)
    assert cs.times.size < 0.5 * cd.times.size  # the load-excited part only: a reduced model
    rd, rs = stress_relaxation(lin), stress_relaxation(lin_s)
    np.testing.assert_allclose(rs.force(T), rd.force(T), rtol=1e-8)
    assert rs.equilibrium == pytest.approx(rd.equilibrium, rel=1e-12)
    assert rs.impulse == pytest.approx(rd.impulse, rel=1e-9)
    assert tenscell.response.viscosity_limit(lin_s) == pytest.approx(tenscell.response.viscosity_limit(lin), rel=1e-9)
    assert tenscell.response.static_modulus(lin_s) == pytest.approx(tenscell.response.static_modulus(lin), rel=1e-12)


def test_sparse_relaxation_spectrum_reproduces_the_compliance(mid):
    lin, lin_s = mid
    spec = tenscell.linear.relaxation_spectrum(lin_s)
    w = 2 * np.pi * F
    J = (spec.residues[None, :] / (spec.rates[None, :] + 1j * w[:, None])).sum(axis=1)
    np.testing.assert_allclose(J, tenscell.compliance(lin, F), rtol=1e-9)
    assert np.all(spec.rates > 0) and np.all(spec.residues > -1e-12 * spec.residues.max())
    # a Gauss quadrature of the load's spectral measure: the sum rules hold, and its vectors are
    # C0-normalized Ritz vectors (a cluster of equal local rates shows up as one Ritz pair)
    assert np.sum(spec.residues / spec.rates) == pytest.approx(lin.pencil.static_compliance(), rel=1e-12)
    dense = tenscell.linear.relaxation_spectrum(lin)
    assert np.sum(spec.residues) == pytest.approx(np.sum(dense.residues), rel=1e-9)
    assert dense.rates[0] * (1 - 1e-9) <= spec.rates[0] and spec.rates[-1] <= dense.rates[-1] * (1 + 1e-9)
    np.testing.assert_allclose(np.einsum("ik,ik->k", spec.modes, lin.C0 @ spec.modes), 1.0, rtol=1e-9)


def test_sparse_creep_with_probe_other_than_load(mid):
    lin, _ = mid
    probe = np.zeros(lin.cell.n)
    probe[7] = 1.0
    other = dataclasses.replace(lin, D0=probe)
    np.testing.assert_allclose(creep_spectrum(_as_sparse(other)).compliance(T), creep_spectrum(other).compliance(T),
                               rtol=1e-8, atol=1e-10 * abs(creep_spectrum(other).static))
    with pytest.raises(ValueError, match="probe is not the load"):
        tenscell.linear.relaxation_spectrum(_as_sparse(other))


def test_sparse_singular_damping_is_instantaneous_compliance(monkeypatch):
    """The IF-free cell leaves a mechanism undamped: J(0+) > 0 in both routes."""
    lin = tenscell.linearize(tenscell.paper_cell(intermediate_filaments=False), 1000.0)
    cd, cs = creep_spectrum(lin), creep_spectrum(_as_sparse(lin))
    assert cd.instantaneous > 0
    assert cs.instantaneous == pytest.approx(cd.instantaneous, rel=1e-8)
    np.testing.assert_allclose(cs.compliance(T), cd.compliance(T), rtol=1e-9)
    with pytest.raises(ValueError, match="singular"):
        tenscell.linear.relaxation_spectrum(_as_sparse(lin))


def test_cholmod_detects_indefinite_K0(monkeypatch):
    lin = tenscell.linearize(tenscell.paper_cell(delta=math.radians(44.0)), 1000.0, check=False)
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="pivot"):
        _as_sparse(lin).pencil.check()
    assert lin.pencil.family is not None  # a member of the prestress family: the same criterion, K0's Cholesky
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="smallest eigenvalue -"):
        lin.pencil.check()
    unchecked = tenscell.linearize(lin.cell, 1000.0, check=False)
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="Cholesky factor does not exist"):
        unchecked.pencil.modes  # noqa: B018 - the family's modes check it too, by the same criterion
    cell = lin.cell
    own = tenscell.linearize(cell, 1000.0, c=np.logspace(-6, 2, cell.m), check=False)
    assert own.pencil.family is None  # C0 too ill-conditioned to whiten by: K0's own factor is the check
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="smallest eigenvalue -"):
        own.pencil.check()


# ---- prestress grids ---------------------------------------------------------------------------
def test_grid_equals_models_and_checks_every_prestress():
    cell = tenscell.paper_cell()
    Ps = np.array([300.0, 1000.0, 4000.0])
    r = tenscell.frequency_response(cell, F, Ps, EA=2.0, c=0.5)
    for i, P in enumerate(Ps):
        np.testing.assert_allclose(r.J[i], tenscell.compliance(tenscell.linearize(cell, P, 2.0, 0.5), F), rtol=1e-11)
    bad = tenscell.paper_cell(delta=math.radians(44.0))
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="P=1000"):
        tenscell.frequency_response(bad, F, [1000.0, 2000.0])


def test_prestress_loop_is_the_grids_family():
    """``moduli(linearize(cell, P), f)`` over prestresses whitens C0 once: one family, the grid's numbers, and
    the modes of the model's own pencil (whitened by K0's factor) to round-off."""
    cell = tenscell.paper_cell()
    Ps = np.array([300.0, 1000.0, 4000.0])
    lins = [tenscell.linearize(cell, P, 2.0, 0.5) for P in Ps]
    families = {id(lin.pencil.family[0]) for lin in lins}
    assert len(families) == 1 and [lin.pencil.family[1] for lin in lins] == list(Ps)
    r = tenscell.frequency_response(cell, F, Ps, EA=2.0, c=0.5)
    for i, lin in enumerate(lins):
        J = tenscell.compliance(lin, F)
        np.testing.assert_allclose(J, r.J[i], rtol=1e-12)
        own = modal.Pencil(lin.K0, lin.C0, -lin.H0, lin.D0)  # the K0-whitened route
        np.testing.assert_allclose(J, modal.modal_compliance(own.modes.tau, own.modes.weights, 2 * np.pi * F),
                                   rtol=1e-11)
        np.testing.assert_allclose(lin.pencil.modes.tau, own.modes.tau, rtol=1e-11)
        V = lin.pencil.modes.vectors  # K0-orthonormal, ascending τ, as Pencil.modes promises
        np.testing.assert_allclose(V.T @ lin.K0 @ V, np.eye(cell.n), atol=1e-11)
        np.testing.assert_allclose(V.T @ lin.C0 @ V, np.diag(lin.pencil.modes.tau), atol=1e-11 * own.modes.tau.max())
    assert not lins[0].C0.flags.writeable  # every model of the family shares its C0


def test_family_needs_a_well_conditioned_damping():
    """C0 is whitened once only when its Cholesky pivots span less than FAMILY_PIVOT_RATIO: a damping spread over
    decades keeps each model's own K0 route, and the grid falls back to it with the same numbers."""
    cell = tenscell.paper_cell()
    wide = np.logspace(-6, 2, cell.m)
    C0 = modal.assemble_damping(cell, wide)
    d = np.diagonal(np.linalg.cholesky(C0)) ** 2
    assert d.min() < modal.FAMILY_PIVOT_RATIO * d.max()
    assert modal.PrestressFamily.build(cell.Kp, cell.Kp, C0, cell.load, cell.probe) is None
    Ps = np.array([500.0, 2000.0])
    r = tenscell.frequency_response(cell, F, Ps, c=wide)
    for i, P in enumerate(Ps):
        lin = tenscell.linearize(cell, P, c=wide)
        assert lin.pencil.family is None
        np.testing.assert_array_equal(r.J[i], tenscell.compliance(lin, F))
        # the static compliance stays exact through K0's factor
        np.testing.assert_allclose(lin.pencil.modes.weights.sum(), lin.pencil.static_compliance(), rtol=1e-12)


def test_family_member_copies_give_the_same_numbers():
    lin = tenscell.linearize(tenscell.paper_cell(), 1500.0)
    J = tenscell.compliance(lin, F)
    for twin in (copy.deepcopy(lin), pickle.loads(pickle.dumps(lin))):
        assert twin.pencil.family is not None
        np.testing.assert_array_equal(tenscell.compliance(twin, F), J)
    thick = tenscell.linearize(tenscell.paper_cell(), 1500.0, viscosity=0.1)  # another C0: its own route
    assert thick.pencil.family is None


def test_continuum_factor_is_the_papers():
    assert modal.continuum_factor(2.0) == 0.25
    J = np.array([1e-3 + 2e-4j])
    np.testing.assert_allclose(modal.modulus(J, 2.0), 0.25 / J)


# ---- threads ---------------------------------------------------------------------------------------
def test_hot_paths_run_with_one_blas_thread_and_restore():
    from threadpoolctl import threadpool_info

    seen = []

    @_threads.hot_path
    def probe():
        seen.append({i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"})

    before = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    probe()
    assert seen[-1] == {1}
    assert [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"] == before
    with _threads.threads("all"):
        probe()
    assert sorted(seen[-1]) == sorted(set(before))
    assert tenscell.compliance.__wrapped__  # the public hot paths are marked


class _FakeBlas:
    """A BLAS library's controller (threadpoolctl's): its file and thread count."""

    def __init__(self, path, n):
        self.filepath, self.num_threads = path, n

    def set_num_threads(self, n):
        self.num_threads = n


def test_a_blas_library_loaded_inside_a_block_is_limited_by_the_next_entry_and_restored(monkeypatch):
    first, later = _FakeBlas("libopenblas-numpy.so", 2), _FakeBlas("libscipy_openblas.so", 2)
    libs = [[first]]
    monkeypatch.setattr(_threads, "_blas_libraries", lambda: libs[0])
    with _threads.limited():
        assert first.num_threads == 1
        libs[0] = [first, later]  # scipy's linear algebra imported inside the block brings its own library
        with _threads.limited():
            assert later.num_threads == 1
        assert later.num_threads == 1  # still the outer block's: restored when it ends, not before
    assert first.num_threads == 2 and later.num_threads == 2


def test_thread_setting_validates(monkeypatch):
    with pytest.raises(ValueError, match="threads"):
        _threads.set_threads(0)
    monkeypatch.setenv(_threads.ENV_VAR, "two")
    with pytest.raises(ValueError, match=_threads.ENV_VAR):
        _threads.thread_count()
    monkeypatch.setenv(_threads.ENV_VAR, "3")
    assert _threads.thread_count() == 3
    with _threads.threads(2):
        assert _threads.thread_count() == 2
    assert _threads.thread_count() == 3


def test_dense_decompositions_and_analyses_run_with_one_blas_thread(monkeypatch):
    """The pencil's own decompositions and the analyses built on them pin BLAS threads wherever they are called from.

    Small dense factorizations with several OpenBLAS threads ran ~170x slower here (a 24x24 triangular solve:
    8 ms against 46 µs), so an analysis that forgot the pin paid it on every mode.
    """
    from threadpoolctl import threadpool_info, threadpool_limits

    from tenscell.sensitivity import analytic_elasticities

    def blas_threads():
        return {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    seen = []
    real, real_syevd = np.linalg.eigh, definite._syevd

    def eigh(*a, **kw):
        seen.append(blas_threads())
        return real(*a, **kw)

    def syevd(*a, **kw):  # a member of a prestress family: one LAPACK call per model
        seen.append(blas_threads())
        return real_syevd(*a, **kw)

    with threadpool_limits(limits=2, user_api="blas"):
        # some bundled BLAS builds (cvxopt's) run one thread whatever is asked: watch those that take two
        two = {path for path, n in blas_threads().items() if n == 2}
        if not two:
            pytest.skip("no BLAS library here can run two threads")
        monkeypatch.setattr(np.linalg, "eigh", eigh)
        monkeypatch.setattr(definite, "_syevd", syevd)
        lin = tenscell.linearize(tenscell.paper_cell(), P=1000.0, EA=1.0, c=1.0)
        lin.pencil.modes  # noqa: B018 - called outside any public hot path
        analytic_elasticities(tenscell.linearize(tenscell.paper_cell(), P=500.0, EA=1.0, c=1.0), [0.1])
        assert all(blas_threads()[path] == 2 for path in two)  # and the caller's setting is back
    assert len(seen) == 2 and all(s[path] == 1 for s in seen for path in two)
