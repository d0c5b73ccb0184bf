"""The physical prestress σ (tenscell.model.prestress): the tendons' virial stress, checked by physics."""
from __future__ import annotations

import math

import numpy as np
import pytest

from tenscell.model import equilibrate, expanded_octahedron, lattice_cell, nucleated_cell, paper_cell, sphere_cell
from tenscell.model.prestress import hull_volume, tendon_forces, virial_prestress
from tenscell.model.shapes import semiflexible_paper_cell
from tenscell.model.structure import cable_mask


@pytest.fixture(scope="module")
def cells():
    return {"paper": paper_cell(), "no IFs": paper_cell(intermediate_filaments=False), "sphere12": sphere_cell(12),
            "lattice": lattice_cell(2, 2, 1), "nucleated": nucleated_cell(),
            "semiflexible": semiflexible_paper_cell(), "free": equilibrate(expanded_octahedron())}


def test_sigma_is_positive_and_proportional_to_P(cells):
    for name, cell in cells.items():
        v = virial_prestress(cell)
        assert v.sigma_per_P > 0, name
        P = np.array([0.3, 1.0, 7.5])
        np.testing.assert_allclose(v.sigma(P), P * v.sigma_per_P, rtol=1e-14)
        assert v.prestress_at(v.sigma(2.5)) == pytest.approx(2.5, rel=1e-14)
        assert v.scale_m2 * v.sigma_per_P == pytest.approx(1.0, rel=1e-14)
        # the mean normal stress is a third of the trace of the tensor, and the tensor is symmetric
        assert np.trace(v.tensor_per_N) / 3 == pytest.approx(v.sigma_per_P, rel=1e-12)
        np.testing.assert_allclose(v.tensor_per_N, v.tensor_per_N.T, atol=1e-14 * v.trace_per_P)


@pytest.mark.parametrize("build", [lambda L: paper_cell(L=L), lambda L: sphere_cell(12, L=L),
                                   lambda L: lattice_cell(2, 1, 1, L=L)])
def test_sigma_is_invariant_under_the_strut_length_gauge(build):
    """(P, EA, c, L) → (λ²P, λ²EA, λc, λL) leaves the moduli unchanged; σ must not change either: V ∝ λ³, T·l ∝ λ³."""
    lam = 2.7
    a, b = virial_prestress(build(1.0)), virial_prestress(build(lam))
    assert b.volume_m3 == pytest.approx(lam**3 * a.volume_m3, rel=1e-10)
    assert b.sigma(lam**2 * 1.3) == pytest.approx(a.sigma(1.3), rel=1e-10)
    assert b.scale_m2 == pytest.approx(lam**2 * a.scale_m2, rel=1e-10)


def test_the_nodal_virial_of_the_tendons_equals_their_tension_virial(cells):
    """An independent route: −Σ_nodes x_n·f_n over the tendons' nodal forces, from any origin, is Σ T·l."""
    for name, cell in cells.items():
        v = virial_prestress(cell)
        f = tendon_forces(cell, P=2.0)
        np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-12)
        for origin in (np.zeros(3), np.array([3.0, -1.0, 0.5])):
            x = np.asarray(cell.structure.nodes) - origin
            assert -np.sum(x * f) == pytest.approx(2.0 * v.tension_virial_m, rel=1e-12), name


def _member_forces(cell, P=1.0):
    """Nodal forces of every member (tendons, elastic struts, nucleus) of a cell of point nodes."""
    st = cell.structure
    pairs = np.asarray(st.tendons).reshape(-1, 2)
    x = np.asarray(st.nodes, dtype=float)
    d = x[pairs[:, 1]] - x[pairs[:, 0]]
    pull = (P * np.asarray(cell.T0) / np.linalg.norm(d, axis=1))[:, None] * d
    f = np.zeros_like(x)
    np.add.at(f, pairs[:, 0], pull)
    np.add.at(f, pairs[:, 1], -pull)
    return f


@pytest.mark.parametrize("name", ["semiflexible", "lattice"])
def test_the_struts_and_the_substrate_balance_the_tendons_virial(cells, name):
    """With the struts as members (their forces from the self-stress, not from σ's formula): every free node is in
    equilibrium, and Σ_tendons T·l = −Σ_struts T·l + Σ_anchors x·R (the substrate's reactions R)."""
    cell = cells[name]
    st = cell.structure
    f = _member_forces(cell)
    free = np.setdiff1d(np.arange(st.n_nodes), st.fixed)
    np.testing.assert_allclose(f[free], 0.0, atol=1e-9)
    cable = cable_mask(st.families)
    struts_virial = float(np.sum(cell.T0[~cable] * cell.lengths[~cable]))
    assert struts_virial < 0  # compression
    R = -f[list(st.fixed)]
    anchors = float(np.sum(np.asarray(st.nodes)[list(st.fixed)] * R))
    assert virial_prestress(cell).tension_virial_m == pytest.approx(-struts_virial + anchors, rel=1e-9)


def test_a_free_structure_has_no_net_virial(cells):
    """Free standing, no substrate: the struts carry exactly the tendons' virial (Σ over all members of T·l = 0).
    Each rigid strut takes equal and opposite tendon forces along its axis; their virial is its compression × L."""
    cell = cells["free"]
    st = cell.structure
    f = tendon_forces(cell)
    x = np.asarray(st.nodes)
    struts = 0.0
    for tail, head in st.struts:
        u = (x[head] - x[tail]) / np.linalg.norm(x[head] - x[tail])
        np.testing.assert_allclose(f[tail] + f[head], 0.0, atol=1e-12)
        np.testing.assert_allclose(np.cross(f[head], u), 0.0, atol=1e-12)
        struts += -float(f[head] @ u) * np.linalg.norm(x[head] - x[tail])  # compression C·L (tendons pull inward)
    assert struts == pytest.approx(virial_prestress(cell).tension_virial_m, rel=1e-12)


def test_elastic_struts_leave_the_tendons_stress_unchanged(cells):
    assert virial_prestress(cells["semiflexible"]).sigma_per_P == pytest.approx(
        virial_prestress(cells["paper"]).sigma_per_P, rel=1e-12)


def test_the_paper_cells_hull_and_the_convention():
    v = virial_prestress(paper_cell())
    assert v.volume_m3 == pytest.approx(0.385, abs=5e-4)  # the 13 nodes' hull, L = 1
    # the paper cell is not isotropic: its vertical normal stress exceeds the horizontal ones
    sxx, syy, szz = v.normal_stresses_per_P
    assert sxx == pytest.approx(syy, rel=1e-12) and szz > sxx
    assert v.trace_per_P == pytest.approx(3 * v.sigma_per_P, rel=1e-14)


def test_hull_volume_of_known_solids():
    cube = np.array([[i, j, k] for i in (0, 2.0) for j in (0, 2.0) for k in (0, 2.0)])
    assert hull_volume(cube) == pytest.approx(8.0, rel=1e-12)
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    assert hull_volume(tet) == pytest.approx(1 / 6, rel=1e-12)
    with pytest.raises(ValueError, match="span no volume"):
        hull_volume(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]]))


def test_a_lattice_is_isotropic_and_cheap():
    """A cubic lattice's tendon stress is isotropic; a larger one costs O(m) (no matrix is formed)."""
    v = virial_prestress(lattice_cell(3, 3, 2))
    s = v.normal_stresses_per_P
    np.testing.assert_allclose(s, s.mean(), rtol=1e-9)
    assert math.isfinite(v.sigma_per_P)


def test_bad_input():
    with pytest.raises(ValueError, match="Cell"):
        virial_prestress("paper")
