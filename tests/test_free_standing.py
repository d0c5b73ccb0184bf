"""Free-standing structures linearize with their rigid-body motions removed (the peers' test structures).

The Snelson prism's self-stress has the closed form of Tibert & Pellegrino (force densities of the vertical
cables sqrt(2 - 2cos(2π/3)) = sqrt(3) times those of the triangles, for any radius and height); the restricted
stiffness must have exactly the non-zero eigenvalues of K0 (its kernel is the 6 rigid-body motions).
"""
import numpy as np
import pytest

import tenscell as tc
from tenscell.model import Point, Structure, equilibrate, expanded_octahedron

#: eigenvalues of symmetric matrices of norm ~1e2 agree to a few ulps times the norm (LAPACK's backward error)
EIG_RTOL = 1e-12


def snelson_prism(R: float, H: float) -> Structure:
    """The 3-strut Snelson prism: triangles of radius R (m) at z = 0 and H, top turned by -30° (150° twist)."""
    a = 2 * np.pi * np.arange(3) / 3
    bottom = np.c_[R * np.cos(a), R * np.sin(a), np.zeros(3)]
    top = np.c_[R * np.cos(a - np.pi / 6), R * np.sin(a - np.pi / 6), np.full(3, H)]
    struts = tuple((i, 3 + (i + 2) % 3) for i in range(3))
    cables = ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3)) + tuple((i, 3 + i) for i in range(3))
    p = Point(nodes=(3, 4), weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    return Structure(nodes=np.vstack([bottom, top]), struts=struts, tendons=cables, families=("actin",) * 9,
                     fixed=(), load=p, probe=p, name="Snelson prism")


def _nonzero_eigenvalues_kept(lin):
    full = np.sort(np.linalg.eigvalsh(np.asarray(lin.K0)))
    kept = np.sort(np.linalg.eigvalsh(lin.pencil.K0))
    k = full.size - kept.size
    assert k == 6
    scale = full[-1]
    assert np.all(np.abs(full[:k]) <= EIG_RTOL * 100 * scale)  # the rigid-body kernel
    np.testing.assert_allclose(kept, full[k:], rtol=0, atol=EIG_RTOL * 100 * scale)
    assert kept[0] > 1e-6 * scale  # positive definite on the complement


@pytest.mark.parametrize("R, H", [(1.0, 1.0), (0.7, 1.3)])
def test_snelson_prism(R, H):
    cell = equilibrate(snelson_prism(R, H), parametrization="local")
    q = cell.T0 / cell.lengths
    np.testing.assert_allclose(q[6:] / q[:6].mean(), np.sqrt(3.0), rtol=1e-12)
    lin = tc.linearize(cell, P=1.0, EA=50.0, c=1.0)
    assert lin.basis.shape == (cell.n, cell.n - 6) and "6 rigid-body motion(s) removed" in lin.notes[0]
    _nonzero_eigenvalues_kept(lin)
    Gs, Gl = tc.moduli(lin, np.logspace(-1, 2, 7))
    assert np.all(Gs > 0) and np.all(Gl > 0)  # a passive, stable structure once the rigid motions are out


def test_expanded_octahedron():
    cell = equilibrate(expanded_octahedron(), parametrization="local")
    lin = tc.linearize(cell, P=10.0, EA=5.0, c=1.0)
    _nonzero_eigenvalues_kept(lin)
    assert tc.summarize(cell)[0].stable


def test_anchored_cells_are_unchanged():
    lin = tc.linearize(tc.paper_cell(), P=1000.0)
    assert lin.basis is None and lin.notes == () and lin.pencil.K0.shape == lin.K0.shape


def test_members_between_fixed_nodes_are_left_out_with_a_note():
    from tenscell.model import DEFAULT_DELTA, paper_structure

    s = paper_structure(0.0, DEFAULT_DELTA, 1.0)
    extra = Structure(nodes=s.nodes, struts=s.struts, tendons=list(s.tendons) + [(0, 2)],
                      families=list(s.families) + ["actin"], fixed=s.fixed, load=s.load, probe=s.probe,
                      equal_tension_groups=s.equal_tension_groups + ((len(s.tendons),),), name="extra")
    assert extra.tendons == s.tendons and extra.families == s.families
    assert extra.equal_tension_groups == s.equal_tension_groups
    assert "left out tendon(s) between two fixed nodes" in extra.notes[0] and "(0-2, actin)" in extra.notes[0]
    assert "note: left out" in repr(extra) and "left out" in tc.summarize(extra)[0].verdict
    # the same mechanics as without the member
    np.testing.assert_array_equal(tc.moduli(tc.linearize(equilibrate(extra), P=1000.0), [1.0])[0],
                                  tc.moduli(tc.linearize(equilibrate(s), P=1000.0), [1.0])[0])
