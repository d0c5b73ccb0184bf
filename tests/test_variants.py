"""The discussion's variants and the future work: physics checks a wrong model fails.

No-IF cell (singular C0, the G'' peak), tangent linearization and the
stiffening law (against finite differences of the exact nonlinear forces),
semiflexible struts (convergence to rigid struts at rate 1/EA_s), the regular
and cylindrical references, the validity map, and the study commands.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tenscell import compliance, linearize, moduli, paper_cell
from tenscell.linear import NotPositiveDefiniteError
from tenscell.model import REGULAR_DELTA, NotPrestressableError
from tenscell.response import static_modulus
from tenscell import cli
from tenscell.laws import StiffeningFilament
from tenscell.model import shapes
from tenscell.studies import references, semiflexible, stiffening
from tenscell.studies.no_if import loss_peak, no_if_study
from tenscell.model.equilibrium import generalized_forces
from tenscell.linear.linearize import linearize_tangent, relaxation_spectrum
from tenscell.model.structure import INTERMEDIATE_FILAMENT, STRUT

F = np.logspace(-2, 3, 21)


def _G(lin, f=F):
    return (0.5 / lin.L) / compliance(lin, f)


def _fd_jacobian(cell, tensions_fn, h=1e-6):
    """Central-difference Jacobian of the exact generalized forces A(q)·T(l(q)) at q0."""
    n = cell.n
    Jac = np.zeros((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        fp, _ = generalized_forces(cell, cell.q0 + e, tensions_fn)
        fm, _ = generalized_forces(cell, cell.q0 - e, tensions_fn)
        Jac[:, i] = (fp - fm) / (2 * h)
    return Jac


# ---- 1. no intermediate filaments --------------------------------------------------------------
@pytest.fixture(scope="module")
def no_if():
    return paper_cell(intermediate_filaments=False)


def test_no_if_damping_is_singular_and_compliance_is_right(no_if):
    lin = linearize(no_if, P=300.0)
    lam = np.linalg.eigvalsh(lin.C0)
    assert no_if.n == 21 and lam[0] < 1e-12 * lam[-1]
    with pytest.raises(ValueError, match="singular"):
        relaxation_spectrum(lin)
    # low-frequency limit must be the static modulus (the spectral route through a
    # rounding-level Cholesky factor gave -1294 Pa here against 65.9 Pa)
    Gs, _ = moduli(lin, [1e-5])
    assert Gs[0] == pytest.approx(static_modulus(lin), rel=1e-6)
    # direct solve agrees with an explicit complex solve
    w = 2 * np.pi * 37.0
    x = np.linalg.solve(lin.K0 + 1j * w * lin.C0, -lin.H0)
    assert compliance(lin, [37.0])[0] == pytest.approx(lin.D0 @ x, rel=1e-12)


def test_no_if_loss_peak_exists_and_scales(no_if):
    lin = linearize(no_if, P=1000.0)
    pk = loss_peak(lin)
    assert 1e-4 < pk.frequency_hz < 1e8
    _, Gl = moduli(lin, [pk.frequency_hz / 3, pk.frequency_hz, pk.frequency_hz * 3])
    assert Gl[1] > Gl[0] and Gl[1] > Gl[2] and Gl[1] == pytest.approx(pk.height, rel=1e-12)
    # c -> s·c maps G(f) to G(s·f): the peak moves to f/s at the same height
    pk10 = loss_peak(linearize(no_if, P=1000.0, c=10.0))
    assert pk10.frequency_hz == pytest.approx(pk.frequency_hz / 10, rel=1e-5)
    assert pk10.height == pytest.approx(pk.height, rel=1e-9)
    # P, EA, c all × s scales G by s at the same f
    pk2 = loss_peak(linearize(no_if, P=2000.0, EA=2.0, c=2.0))
    assert pk2.frequency_hz == pytest.approx(pk.frequency_hz, rel=1e-5)
    assert pk2.height == pytest.approx(2 * pk.height, rel=1e-9)


def test_no_if_high_frequency_limit_is_the_prestress_held_mechanism(no_if):
    s = no_if_study(prestress=(500.0, 1000.0), f_hz=[1.0, 1e7], EA_values=(1.0,), c_values=(1.0,))
    assert s.mechanism_residual < 1e-12
    Gs, Gl = moduli(linearize(no_if, P=500.0), [1e9])
    assert Gs[0] == pytest.approx(s.storage_limit_per_P * 500.0, rel=1e-6)
    assert Gl[0] < 1e-3 * Gs[0]
    assert s.peak_exponents[0] == pytest.approx(1.0, abs=0.01)


def test_with_ifs_there_is_no_loss_peak():
    with pytest.raises(ValueError, match="no peak"):
        loss_peak(linearize(paper_cell(), P=1000.0))


# ---- tangent linearization and the stiffening law ---------------------------------------------------
def test_linearize_tangent_reproduces_linearize():
    cell = paper_cell()
    rng = np.random.default_rng(3)
    EA, c = rng.uniform(0.5, 2, cell.m), rng.uniform(0.5, 2, cell.m)
    a = linearize(cell, 800.0, EA, c)
    b = linearize_tangent(cell, 800.0, (EA + 800.0 * cell.T0) / cell.lengths, c)
    assert np.allclose(b.K0, a.K0, rtol=0, atol=1e-12 * np.abs(a.K0).max())
    assert np.allclose(b.EA, a.EA) and np.allclose(b.l0, a.l0)
    assert np.allclose(_G(b), _G(a), rtol=1e-12)


def test_linearize_tangent_rejects_bad_input():
    cell = paper_cell()
    with pytest.raises(ValueError, match="tangent"):
        linearize_tangent(cell, 1000.0, -np.ones(cell.m))
    with pytest.raises(ValueError, match="c"):
        linearize_tangent(cell, 1000.0, np.ones(cell.m), c=-1.0)


def test_exponential_law_tangent_inverse_and_linear_limit():
    l0, EA = 0.8, 2.0
    l = np.linspace(0.7, 1.1, 9)
    for b in (0.0, 0.5, 3.0):
        law = StiffeningFilament(EA=EA, c=0.0, b=b, l0=np.full(l.size, l0))
        h = 1e-6
        fd = (law.elastic(l + h) - law.elastic(l - h)) / (2 * h)
        assert np.allclose(law.stiffness_at_rest(l), fd, rtol=1e-7)
        T = law.elastic(l)
        assert np.allclose(law.rest_lengths(l, T), l0, rtol=1e-13)
    # b -> 0 is the linear spring, continuously
    tiny = StiffeningFilament(EA=EA, c=0.0, b=1e-9, l0=np.full(l.size, l0))
    zero = StiffeningFilament(EA=EA, c=0.0, b=0.0, l0=np.full(l.size, l0))
    assert np.allclose(tiny.elastic(l), EA * (l / l0 - 1), rtol=1e-8, atol=1e-12)
    assert np.array_equal(zero.elastic(l), EA * (l / l0 - 1))
    with pytest.raises(ValueError, match="b"):
        StiffeningFilament(EA=EA, c=0.0, b=-1.0)
    with pytest.raises(ValueError, match="EA"):
        StiffeningFilament(EA=0.0, c=0.0, b=1.0)


def test_stiffening_reduces_to_voigt_at_zero_stiffening():
    cell = paper_cell()
    ref = linearize(cell, 1500.0)
    zero = stiffening.linearize_stiffening(cell, 1500.0, b=0.0)
    tiny = stiffening.linearize_stiffening(cell, 1500.0, b=1e-10)
    assert np.allclose(zero.K0, ref.K0, rtol=0, atol=1e-12 * np.abs(ref.K0).max())
    assert np.allclose(_G(zero), _G(ref), rtol=1e-12)
    assert np.allclose(_G(tiny), _G(ref), rtol=1e-6)


def test_stiffening_stiffness_is_the_jacobian_of_the_nonlinear_forces():
    cell = paper_cell()
    P, b = 1000.0, 0.05
    lin = stiffening.linearize_stiffening(cell, P, b=b)
    bb = np.zeros(cell.m)
    bb[cell.structure.family_indices(INTERMEDIATE_FILAMENT)] = b

    law = StiffeningFilament(EA=1.0, c=1.0, b=bb, l0=lin.l0)

    def tensions(l):
        return law.elastic(l)

    f0, _ = generalized_forces(cell, cell.q0, tensions)
    assert np.abs(f0).max() < 1e-10 * P  # the rest lengths give equilibrium at q0
    assert np.allclose(tensions(cell.lengths), P * cell.T0, rtol=1e-12)
    Jac = _fd_jacobian(cell, tensions)
    assert np.allclose(Jac, lin.K0, rtol=0, atol=1e-6 * np.abs(lin.K0).max())
    # and it stiffens: the cell is stiffer than with linear IFs at the same prestress
    assert static_modulus(lin) > 1.05 * static_modulus(linearize(cell, P))


def test_stiffening_study_makes_G_grow_faster_than_linear_in_P():
    s = stiffening.stiffening_study(b=(0.0, 0.01), prestress=(500.0, 1000.0, 4500.0), f_hz=(1.0,))
    ex = s.exponent()[:, 0]
    assert ex[1] > ex[0] + 0.1
    assert np.all(s.G[1].real > s.G[0].real)


# ---- semiflexible struts ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def semi():
    return shapes.semiflexible_paper_cell()


def test_semiflexible_cell_shares_the_rigid_self_stress(semi):
    rigid = paper_cell()
    struts = semi.structure.family_indices(STRUT)
    assert semi.n == 30 and semi.m == 39 and struts.tolist() == list(range(33, 39))
    assert np.allclose(semi.T0[:33], rigid.T0, atol=1e-13)
    assert np.all(semi.T0[struts] < 0)
    assert semi.strut_length == pytest.approx(1.0)


def test_semiflexible_stiffness_is_the_jacobian_of_the_nonlinear_forces(semi):
    P = 1000.0
    lin = semiflexible.linearize_semiflexible(semi, P, EA_strut=5e3)
    EA = lin.EA
    Jac = _fd_jacobian(semi, lambda l: EA * (l / lin.l0 - 1))
    assert np.allclose(Jac, lin.K0, rtol=0, atol=1e-6 * np.abs(lin.K0).max())


def test_semiflexible_converges_to_rigid_at_rate_one_over_EA(semi):
    rigid = _G(linearize(paper_cell(), 1000.0))
    err = []
    for EAs in (1e6, 1e7, 1e8):
        G = _G(semiflexible.linearize_semiflexible(semi, 1000.0, EA_strut=EAs, c_strut=0.0))
        err.append(np.max(np.abs(G / rigid - 1)))
    assert err[2] < 1e-4
    assert err[0] / err[1] == pytest.approx(10.0, rel=0.02)
    assert err[1] / err[2] == pytest.approx(10.0, rel=0.02)
    s = semiflexible.semiflexible_study(EA_strut=np.logspace(6, 9, 7), f_hz=F)
    assert s.rate_storage == pytest.approx(-1.0, abs=0.02) and s.rate_loss == pytest.approx(-1.0, abs=0.02)


def test_softer_struts_give_a_softer_cell(semi):
    g = [_G(semiflexible.linearize_semiflexible(semi, 1000.0, EA_strut=e), [0.01])[0].real for e in (700.0, 2e3, 1e4, 1e6)]
    assert np.all(np.diff(g) > 0)


def test_semiflexible_rejects_struts_softer_than_their_compression_and_buckling(semi):
    comp = -1000.0 * semi.T0[33]
    with pytest.raises(ValueError, match="EA_strut"):
        semiflexible.linearize_semiflexible(semi, 1000.0, EA_strut=0.9 * comp)
    EI = 10.0
    Pcr = semiflexible.euler_critical_prestress(semi, EI)
    assert Pcr * comp / 1000.0 == pytest.approx(math.pi ** 2 * EI / 1.0 ** 2, rel=1e-12)
    semiflexible.linearize_semiflexible(semi, 0.99 * Pcr, EI=EI, EA_strut=1e6)
    with pytest.raises(semiflexible.BucklingError, match="Euler"):
        semiflexible.linearize_semiflexible(semi, 1.01 * Pcr, EI=EI, EA_strut=1e6)
    with pytest.raises(ValueError, match="no elastic struts"):
        semiflexible.linearize_semiflexible(paper_cell(), 1000.0)


# ---- other references -------------------------------------------------------------------------------
def test_regular_cell_has_the_if_free_self_stress():
    with pytest.raises(NotPrestressableError):
        paper_cell(0.0, REGULAR_DELTA)
    cell = shapes.regular_cell()
    assert np.allclose(cell.T0[:21], 1 / math.sqrt(21), rtol=1e-12)
    assert np.all(cell.T0[21:] == 0)
    assert np.abs(cell.A @ cell.T0).max() < 1e-13
    G = _G(linearize(cell, 1000.0))
    assert np.all(G.real > 0) and np.all(G.imag > 0)
    cell2 = shapes.regular_cell(L=2.0)
    assert cell2.strut_length == pytest.approx(2.0)
    assert np.allclose(_G(linearize(cell2, 1000.0)), _G(linearize(cell, 1000.0), 2 * F) / 4, rtol=1e-9)


def test_cylindrical_reference_lies_on_the_cylinder_and_is_valid():
    cell = shapes.cylindrical_cell()
    x = cell.structure.nodes
    r = np.linalg.norm(x[:12, :2], axis=1)
    assert np.ptp(r) < 1e-12 and r[0] == pytest.approx(1 / math.sqrt(8), rel=1e-12)
    assert np.allclose(cell.structure.strut_lengths, 1.0, rtol=1e-12)
    ifs = cell.structure.family_indices(INTERMEDIATE_FILAMENT)
    assert np.all(cell.T0 > 0.1) and np.ptp(cell.T0[ifs]) < 1e-12
    # threefold symmetric: a +120° turn about the axis maps the nodes onto each other
    c, s = math.cos(2 * math.pi / 3), math.sin(2 * math.pi / 3)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    perm = shapes.TURN
    assert all(np.allclose(turn @ x[i], x[perm[i]], atol=1e-12) for i in range(13))
    lin = linearize(cell, 1000.0)
    assert np.all(np.linalg.eigvalsh(lin.K0) > 0)
    # a different strut length obeys G_L(f) = G_1(L·f)/L²
    lin2 = linearize(shapes.cylindrical_cell(L=2.0), 1000.0)
    assert np.allclose(_G(lin2), _G(lin, 2 * F) / 4, rtol=1e-9)


def test_cylindrical_search_reproduces_the_stored_reference():
    p = references.find_cylindrical_reference()
    assert np.allclose(p, shapes.CYLINDRICAL_PARAMETERS, atol=1e-8)
    with pytest.raises(ValueError, match="5 entries"):
        references.find_cylindrical_reference(start=(0.0, 1.0))


def test_prestress_map_agrees_with_the_cell_constructors():
    d = np.radians([44.0, 50.0, 56.0])
    mp = references.prestress_map([0.0], d)
    assert mp.status[:, 0].tolist() == [references.NOT_STABLE, references.VALID, references.NOT_PRESTRESSABLE]
    with pytest.raises(NotPositiveDefiniteError):
        linearize(paper_cell(0.0, d[0]), 1000.0)
    with pytest.raises(NotPrestressableError):
        paper_cell(0.0, d[2])
    assert mp.if_tension[1, 0] == pytest.approx(paper_cell().T0[-1], rel=1e-12)
    with pytest.raises(ValueError, match="delta"):
        references.prestress_map([0.0], [2.0])


# ---- the commands -----------------------------------------------------------------------------------
def test_study_command_writes_its_outputs(tmp_path, capsys):
    assert cli.main(["study", "stiffening", "--out", str(tmp_path)]) == 0
    for name in ("stiffening.csv", "stiffening.png", "stiffening.md"):
        assert (tmp_path / name).stat().st_size > 0
    text = (tmp_path / "stiffening.md").read_text()
    assert "exponent of G' in P" in text
    assert cli.main(["study", "sensitivity", "--out", str(tmp_path), "--draws", "0"]) == 2
    assert "--draws" in capsys.readouterr().err
    assert cli.main(["study", "nonsense", "--out", str(tmp_path)]) == 2
