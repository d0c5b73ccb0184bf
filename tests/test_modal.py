"""The linear-algebra core (tenscell.linear.modal): one decomposition per model, dense and sparse agree.

Each test states an invariant: a model is factorized/decomposed once whatever is asked of it;
the sparse (Lanczos) route gives the dense answer for creep, relaxation, the spectrum and the
limits; CHOLMOD detects an indefinite K0; the prestress grid equals the per-model path.
"""
from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest
import scipy.sparse as sp

import tenscell
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
    real = modal.factorize_spd

    def counting(A, what="the matrix", perm=None):
        calls.append(what)
        return real(A, what, perm)

    monkeypatch.setattr(modal, "factorize_spd", counting)
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
    tenscell.summary.relaxation_modes(lin, 2)  # the slowest modes run on the check's own factor
    assert calls.count("K0") == 1 and len(calls) == 2, calls  # K0 once, K0 + σC0 once
    # without the check, the frequency response and the time domain share one factorization
    calls.clear()
    lin2 = tenscell.linearize(cell, 1500.0, _lattice_EA(cell), 1.0, check=False)
    tenscell.moduli(lin2, F)
    creep_spectrum(lin2)
    tenscell.linear.relaxation_spectrum(lin2)
    assert len(calls) == 1 and calls[0] != "K0", calls


def test_dense_model_is_decomposed_once(monkeypatch):
    calls = []
    real = np.linalg.eigh

    def counting(a, *args, **kw):
        calls.append(np.shape(a))
        return real(a, *args, **kw)

    lin = tenscell.linearize(tenscell.paper_cell(), 1000.0)
    monkeypatch.setattr(modal.np.linalg, "eigh", counting)
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
    with pytest.raises(tenscell.linear.NotPositiveDefiniteError, match="smallest eigenvalue"):
        lin.pencil.check()


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
    real = np.linalg.eigh

    def eigh(*a, **kw):
        seen.append(blas_threads())
        return real(*a, **kw)

    with threadpool_limits(limits=2, user_api="blas"):
        # some bundled BLAS builds (cvxopt's) run one thread whatever is asked: watch those that take two
        two = {path for path, n in blas_threads().items() if n == 2}
        if not two:
            pytest.skip("no BLAS library here can run two threads")
        monkeypatch.setattr(np.linalg, "eigh", eigh)
        lin = tenscell.linearize(tenscell.paper_cell(), P=1000.0, EA=1.0, c=1.0)
        lin.pencil.modes  # noqa: B018 - called outside any public hot path
        analytic_elasticities(tenscell.linearize(tenscell.paper_cell(), P=500.0, EA=1.0, c=1.0), [0.1])
        assert all(blas_threads()[path] == 2 for path in two)  # and the caller's setting is back
    assert len(seen) == 2 and all(s[path] == 1 for s in seen for path in two)
