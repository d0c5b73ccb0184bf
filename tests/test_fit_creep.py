"""Creep compliance from the spectrum and its kernels (tenscell.fitting.models.voigt_creep); creep data files."""
from __future__ import annotations

from decimal import Decimal, getcontext

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

import tenscell
from tenscell.fitting.models.voigt_creep import creep_from_modes, pair_kernels, step_kernel
from tenscell.timedomain import creep_compliance
from tenscell.fitting import VoigtModel


def _closed(a, b, t):
    """φ and h from their partial fractions in 50-digit decimal arithmetic (the cancellation-free reference)."""
    getcontext().prec = 50
    out_phi, out_h = [], []
    for ti in np.atleast_1d(t):
        A, B, T = Decimal(float(a)), Decimal(float(b)), Decimal(float(ti))
        ea, eb = (-A * T).exp(), (-B * T).exp()
        if A == B:
            phi = (1 - ea - A * T * ea) / (A * A)
            h = T * ea
        else:
            phi = 1 / (A * B) + ea / (A * (A - B)) - eb / (B * (A - B))
            h = (eb - ea) / (A - B)
        out_phi.append(float(phi))
        out_h.append(float(h))
    return np.array(out_phi), np.array(out_h)


@pytest.mark.parametrize("a,b", [(0.3, 7.0), (2.0, 0.05), (40.0, 1e-3)])
def test_pair_kernels_match_partial_fractions_and_quadrature(a, b):
    t = np.array([0.0, 0.01, 0.3, 1.0, 5.0])
    phi, h = pair_kernels([a, b], t)
    ref_phi, ref_h = _closed(a, b, t)
    np.testing.assert_allclose(phi[:, 0, 1], ref_phi, rtol=1e-12, atol=1e-40)
    np.testing.assert_allclose(h[:, 0, 1], ref_h, rtol=1e-12, atol=1e-40)
    np.testing.assert_array_equal(phi[:, 0, 1], phi[:, 1, 0])
    # φ is the integral of h
    for i, ti in enumerate(t):
        q = scipy.integrate.quad(lambda s: (np.exp(-b * s) - np.exp(-a * s)) / (a - b), 0.0, ti, epsabs=0,
                                 epsrel=1e-12)[0]
        assert phi[i, 0, 1] == pytest.approx(q, rel=1e-9, abs=1e-300)


def test_pair_kernels_equal_and_nearly_equal_rates():
    t = np.array([1e-3, 0.2, 1.0, 3.0, 40.0])
    for a in (0.05, 0.9, 2.0, 30.0):
        phi, h = pair_kernels([a, a, a * (1 + 1e-9)], t)
        exact_phi, exact_h = _closed(a, a, t)
        np.testing.assert_allclose(phi[:, 0, 1], exact_phi, rtol=1e-12)
        np.testing.assert_allclose(h[:, 0, 1], exact_h, rtol=1e-12)
        near_phi, near_h = _closed(a, a * (1 + 1e-9), t)
        np.testing.assert_allclose(phi[:, 0, 2], near_phi, rtol=1e-12)
        np.testing.assert_allclose(h[:, 0, 2], near_h, rtol=1e-12)
        # the diagonal is the same function
        np.testing.assert_allclose(phi[:, 0, 0], exact_phi, rtol=1e-12)


def test_pair_kernels_continuous_across_the_series_switch():
    # F switches from its Taylor series to the closed form at max(λt) = 0.5
    t = np.array([1.0])
    for b in (0.0001, 0.2, 0.4999):
        lo = pair_kernels([0.5 - 1e-12, b], t)[0][0, 0, 1]
        hi = pair_kernels([0.5 + 1e-12, b], t)[0][0, 0, 1]
        assert hi == pytest.approx(lo, rel=1e-10)
        assert lo == pytest.approx(_closed(0.5, b, t)[0][0], rel=1e-10)


def test_step_kernel_and_creep_match_timedomain():
    cell = tenscell.paper_cell()
    rng = np.random.default_rng(2)
    lin = tenscell.linearize(cell, P=3.0, EA=10 ** rng.uniform(-1, 2, cell.m), c=10 ** rng.uniform(-1, 1, cell.m))
    K0, C0 = np.asarray(lin.K0), np.asarray(lin.C0)
    lam, V = scipy.linalg.eigh(K0, C0)  # VᵀC0V = I
    alpha, beta = lin.D0 @ V, -lin.H0 @ V
    t = np.logspace(-3, 2, 30)
    np.testing.assert_allclose(creep_from_modes(lam, alpha, beta, t), creep_compliance(lin, t), rtol=1e-9)
    g = step_kernel(lam, np.array([0.0, 1.0]))
    assert np.all(g[0] == 0.0)
    np.testing.assert_allclose(g[1], -np.expm1(-lam) / lam, rtol=1e-14)


# --- creep data files ------------------------------------------------------------------------
def test_creep_csv_round_trip_and_detection(tmp_path):
    from tenscell.io.creep_data import CreepData, read_creep_csv, read_measurements, write_creep_csv
    from tenscell.io.data import RheologyData

    d = CreepData(time_s=[0.1, 0.3, 1.0], compliance=[1e-3, 1.3e-3, 1.7e-3], compliance_sd=[1e-5, 1e-5, 2e-5],
                  source="mem", comments=("synthetic",))
    p = tmp_path / "creep.csv"
    write_creep_csv(d, p)
    back = read_creep_csv(p)
    np.testing.assert_array_equal(back.time_s, d.time_s)
    np.testing.assert_array_equal(back.compliance, d.compliance)
    np.testing.assert_array_equal(back.compliance_sd, d.compliance_sd)
    assert back.comments == ("synthetic",) and back.kind == "creep"
    np.testing.assert_allclose(back.weights, d.compliance * np.log(10) / d.compliance_sd)
    assert isinstance(read_measurements(p), CreepData)
    moduli = tmp_path / "moduli.csv"
    tenscell.io.data.write_csv(tenscell.io.data.bundled("fabry2001"), moduli)
    assert isinstance(read_measurements(moduli), RheologyData)
    df = back.to_dataframe()
    assert list(df.columns) == ["time_s", "creep_compliance_per_Pa", "creep_compliance_sd_per_Pa"]


@pytest.mark.parametrize("text,match", [
    ("time_s,J\n1,2\n", "unknown column"),
    ("time_s\n1\n", "missing required column"),
    ("time_s,creep_compliance_per_Pa\n1,-2\n", "line 2.*must be > 0"),
    ("time_s,creep_compliance_per_Pa\n1,abc\n", "not a finite number"),
    ("time_s,creep_compliance_per_Pa\n", "no data rows"),
])
def test_creep_csv_errors_name_the_line(tmp_path, text, match):
    from tenscell.io.creep_data import read_creep_csv
    from tenscell.io.data import DataError

    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(DataError, match=match):
        read_creep_csv(p)


# --- creep data in fits: residuals, analytic Jacobian, joint fits -----------------------------------
def _creep_data(cell, t, P, EA, c, L=1.0, prestress_pa=None):
    from tenscell.fitting.fitted import scaled_cell
    from tenscell.io.creep_data import CreepData

    lin = tenscell.linearize(scaled_cell(cell, L), P=P, EA=EA, c=c)
    J = creep_compliance(lin, t, continuum=True)
    pre = None if prestress_pa is None else np.full(t.size, prestress_pa)
    return CreepData(time_s=t, compliance=J, prestress=pre, source="synthetic creep")


@pytest.mark.parametrize("tendons,damping", [("per-tendon", "uniform"), ("per-family", "per-family"),
                                             ("uniform", "uniform")])
def test_creep_residuals_match_the_core_pipeline_and_jacobian_matches_fd(tendons, damping):
    from tenscell.fitting import make_problem
    from tenscell.io.creep_data import CreepData

    cell = tenscell.paper_cell()
    t = np.logspace(-2, 2, 9)
    p = make_problem(CreepData(time_s=t, compliance=np.full(t.size, 1e-3)), cell, tendons=tendons, damping=damping)
    rng = np.random.default_rng(7)
    phi = rng.normal(0.0, 0.5, p.n_params) + np.log(np.r_[np.ones(p.n_ea + p.n_c), 5.0, 1.3])
    theta = phi[p.free]
    vals = p.values(theta)
    EA, c = vals[: p.n_ea][p.ea_groups], vals[p.n_ea: p.n_ea + p.n_c][p.c_groups]
    ref = _creep_data(cell, t, vals[-2], EA, c, L=vals[-1])
    np.testing.assert_allclose(p.creep(theta), ref.compliance, rtol=1e-10)
    J = p.jacobian(theta)
    np.testing.assert_allclose(J, p.jacobian_fd(theta, 1e-6), rtol=1e-5, atol=1e-7 * np.abs(J).max())


def test_joint_creep_frequency_and_prestress_jacobian():
    from tenscell.fitting import make_problem
    from tenscell.io.data import RheologyData, bundled

    cell = tenscell.paper_cell()
    t = np.logspace(-1, 1, 5)
    f = np.logspace(-1, 1, 4)
    creep = _creep_data(cell, t, 3.0, 1.0, 1.0, prestress_pa=300.0)
    freq = RheologyData(f, np.ones(4), np.ones(4))  # prestress not stated: fitted (P_data)
    p = make_problem([bundled("stamenovic2002"), creep, freq], cell, tendons="per-family")
    assert p.n_creep == 5 and p.n_residuals == 2 * (8 + 4) + 5
    assert list(p.rows(1)) == list(range(24, 29))
    theta = np.random.default_rng(2).normal(0.0, 0.4, p.n_free) + p.fixed_log[p.free]
    J = p.jacobian(theta)
    np.testing.assert_allclose(J, p.jacobian_fd(theta, 1e-6), rtol=1e-5, atol=1e-7 * np.abs(J).max())


def test_joint_fit_of_creep_and_frequency_data_recovers_the_model():
    from tenscell.fitting import fit
    from tenscell.io.data import RheologyData

    cell = tenscell.paper_cell()
    P, EA, c, L = 4.0, 2.0, 0.5, 1.0
    t = np.logspace(-2, 1, 8)
    f = np.logspace(-1, 2, 8)
    creep = _creep_data(cell, t, P, EA, c).with_prestress(400.0)
    Gs, Gl = tenscell.moduli(tenscell.linearize(cell, P=P, EA=EA, c=c), f)
    freq = RheologyData(f, Gs, Gl, prestress=np.full(f.size, 400.0), source="synthetic moduli")
    r = fit([creep, freq], cell, model=VoigtModel(tendons="uniform"), starts=2, hops=3, seed=0, fixed={"L": L}, progress=False)
    assert max(x.rms_log10_error for x in r.fits) < 1e-3
    assert r.fits[0].axis == "time" and r.fits[0].J_model.shape == t.shape
    assert r.value("EA") == pytest.approx(EA, rel=1e-3)
    assert r.value("c") == pytest.approx(c, rel=1e-3)
    assert r.value("s") * 400.0 == pytest.approx(P, rel=1e-2)
