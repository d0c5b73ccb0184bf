"""The nucleus: a stiff shell tied to the intermediate filaments (model.shapes.nucleated_cell), in structure files.

Limits that hold exactly: a vanishing nucleus stiffness with IF segments of the whole IF's Voigt time gives the
paper cell's moduli at every frequency; the static modulus rises monotonically with the nucleus stiffness.
"""
from __future__ import annotations

import numpy as np
import pytest

import tenscell
from tenscell.io.structure_files import structure_from_dict, structure_to_dict
from tenscell.laws import Springpot, Voigt, family_laws
from tenscell.linear.linearize import linearize_law
from tenscell.model.equilibrium import equilibrate, generalized_forces
from tenscell.model.shapes import nucleated_cell
from tenscell.model.structure import INTERMEDIATE_FILAMENT, NUCLEUS

PAPER = tenscell.paper_cell()
NUC = nucleated_cell()
P0 = 1000.0
F = np.logspace(-2, 3, 6)
RNG = np.random.default_rng(11)
EA = RNG.uniform(0.5, 2.0, PAPER.m)
C = RNG.uniform(0.5, 2.0, PAPER.m)
#: the nucleated cell's prestress giving the paper cell's tensions (T0 is normalized over 45 cables, not 33)
P_EQ = P0 * PAPER.T0[0] / NUC.T0[0]


def _voigt(e_nucleus):
    """Nucleated-cell Voigt tendons: the paper's EA on every IF segment, c scaled to the whole IF's time constant."""
    l, lp = NUC.lengths, PAPER.lengths
    EAn = np.concatenate([EA[:21], EA[21:], EA[21:], np.full(30, e_nucleus)])
    cn = np.concatenate([C[:21], C[21:] * lp[21:] / l[21:33], C[21:] * lp[21:] / l[33:45], np.zeros(30)])
    return Voigt(EA=EAn, c=cn)


def test_structure_and_self_stress():
    s = NUC.structure
    fam = np.array(s.families)
    assert NUC.n == 60 and NUC.m == 75
    assert np.sum(fam == NUCLEUS) == 30 and np.sum(fam == INTERMEDIATE_FILAMENT) == 24
    assert np.abs(NUC.A @ NUC.T0).max() < 1e-13
    cable = fam != NUCLEUS
    assert np.all(NUC.T0[cable] > 0) and np.all(NUC.T0[~cable] == 0)
    # the IFs pass straight through the nucleus nodes: outer and inner segments carry the same tension
    assert np.allclose(NUC.T0[21:33], NUC.T0[33:45], rtol=1e-14)
    np.testing.assert_allclose(NUC.T0[:21] / NUC.T0[0], PAPER.T0[:21] / PAPER.T0[0], rtol=1e-13)


def test_radius_out_of_range_is_refused():
    with pytest.raises(ValueError, match="radius"):
        nucleated_cell(radius=1.0)


def test_soft_nucleus_is_the_paper_cell():
    """Nucleus stiffness ε → 0: moduli → the paper cell's at every frequency, error O(ε) (first order)."""
    G0 = np.array(tenscell.moduli(linearize_law(PAPER, Voigt(EA=EA, c=C), P0), F))
    errs = []
    for eps in (1e-5, 1e-6):
        G = np.array(tenscell.moduli(linearize_law(NUC, _voigt(eps), P_EQ), F))
        errs.append(float(np.max(np.abs(G - G0) / np.abs(G0))))
    assert errs[1] < 1e-5 and errs[0] / errs[1] == pytest.approx(10, rel=0.05)


def test_static_modulus_rises_with_nucleus_stiffness_and_stays_positive_definite():
    """K0 grows in the PSD order with the nucleus EA and probe = load, so J(0) falls: G'(0) is non-decreasing."""
    G = [tenscell.response.static_modulus(linearize_law(NUC, _voigt(e), P_EQ)) for e in 10.0 ** np.arange(-4, 5)]
    assert np.all(np.diff(G) > 0)
    assert G[-1] > 2 * G[0]  # a stiff nucleus matters (691.9 against 306.5 Pa measured at EA_nucleus = 1e4 N)


def test_K0_is_the_jacobian_of_the_nonlinear_forces():
    law = _voigt(50.0)
    lin = linearize_law(NUC, law, P_EQ)
    placed = lin.law
    n = NUC.n
    Jac = np.zeros((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1e-6
        fp, _ = generalized_forces(NUC, NUC.q0 + e, placed.elastic)
        fm, _ = generalized_forces(NUC, NUC.q0 - e, placed.elastic)
        Jac[:, i] = (fp - fm) / 2e-6
    assert np.abs(Jac - lin.K0).max() < 1e-6 * np.abs(lin.K0).max()


def test_structure_file_round_trip():
    """A nucleated cell saved with its self-stress loads back as the same cell (same moduli to round-off)."""
    law = _voigt(20.0)
    law = Voigt(EA=law.EA, c=np.where(law.c > 0, law.c, 0.05))  # the file format wants c > 0
    d = structure_to_dict(NUC.structure, EA=law.EA, c=law.c, T0=NUC.T0, description="nucleated paper cell")
    assert sum(t["family"] == NUCLEUS for t in d["tendons"]) == 30
    sf = structure_from_dict(d)
    cell = equilibrate(sf.structure, T0=sf.T0)
    G = tenscell.moduli(linearize_law(cell, Voigt(EA=sf.EA, c=sf.c), P_EQ), F)
    G0 = tenscell.moduli(linearize_law(NUC, law, P_EQ), F)
    np.testing.assert_allclose(G, G0, rtol=1e-10)


def test_dynamic_laws_on_a_nucleated_cell():
    """Springpot filaments with a Voigt nucleus: the kernel and the realized model agree (the law works unchanged)."""
    law = family_laws(NUC, {NUCLEUS: Voigt(EA=100.0, c=0.0)}, default=Springpot(EA=1.0, kappa=0.5, alpha=0.2))
    lin = linearize_law(NUC, law, P_EQ)
    tau, rho, _ = lin.pencil.retardation()
    from tenscell.linear.spectrum import modal_compliance

    J = tenscell.compliance(lin, F)
    assert np.max(np.abs(modal_compliance(tau, rho, 2 * np.pi * F) - J) / np.abs(J)) <= lin.realization.error * 2


def test_prestressed_nucleus():
    """nucleus_load f: the shell carries f·T_IF at each node (unique: statically determinate), the inner IF segments
    (1 − f)·T_IF. A prestressed shell needs stiffness (compressed short edges soften it): EA = 1e3 N is unstable at
    f = 0.6, 1e5 N stable; as the nucleus stiffens its prestress stops mattering (second order in 1/EA: measured
    ratio 102 per decade from 3e5 to 3e6 N, where round-off, ~1e-9 relative at EA/1 N = 3e6, is 0.3 % of the
    difference); f → 0 is the stress-free nucleus (first order in f)."""
    from tenscell.linear.modal import NotPositiveDefiniteError
    from tenscell.response import static_modulus

    c = nucleated_cell(nucleus_load=0.6)
    assert np.abs(c.A @ c.T0).max() < 1e-13
    np.testing.assert_allclose(c.T0[33:45], 0.4 * c.T0[21:33], rtol=1e-12)
    shell = c.T0[45:]
    assert shell.min() < 0 < shell.max()  # the shell is prestressed, in both signs

    def G0(cell, e):
        EAn = np.concatenate([np.ones(45), np.full(30, e)])
        return static_modulus(linearize_law(cell, Voigt(EA=EAn, c=1.0), P0 * PAPER.T0[0] / cell.T0[0]))

    with pytest.raises(NotPositiveDefiniteError):
        G0(c, 1e3)
    assert G0(c, 1e5) > 0
    free = [G0(NUC, e) for e in (3e5, 3e6)]
    loaded = [G0(c, e) for e in (3e5, 3e6)]
    d = [abs(a - b) / b for a, b in zip(loaded, free)]
    assert d[1] < 1e-6 and d[0] / d[1] == pytest.approx(100, rel=0.1)
    small = [abs(G0(nucleated_cell(nucleus_load=f), 1e3) / G0(NUC, 1e3) - 1) for f in (1e-3, 1e-4)]
    assert small[0] / small[1] == pytest.approx(10, rel=0.05)
