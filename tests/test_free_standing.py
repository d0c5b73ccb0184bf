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


def test_rigid_body_modes_are_found_once_per_cell(monkeypatch):
    """Every model of a free-standing cell (a prestress loop) shares one basis, computed once and read-only."""
    import tenscell.model.formfinding as ff

    calls = []
    real = ff.rigid_body_modes
    monkeypatch.setattr(ff, "rigid_body_modes", lambda coords: calls.append(1) or real(coords))
    cell = equilibrate(snelson_prism(1.0, 1.0), parametrization="local")
    lins = [tc.linearize(cell, P=P, EA=50.0, c=1.0) for P in (0.5, 1.0, 2.0)]
    assert len(calls) == 1 and all(lin.basis is lins[0].basis for lin in lins)
    assert not lins[0].basis.flags.writeable
    other = equilibrate(snelson_prism(0.7, 1.3), parametrization="local")
    assert tc.linearize(other, P=1.0, EA=50.0, c=1.0).basis.shape == lins[0].basis.shape and len(calls) == 2


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


def test_rollers_are_the_free_structure_with_the_held_directions_removed():
    """Per-direction supports on point nodes: K0 is exactly the unsupported K0 without the held coordinates'
    rows and columns (a held direction is a coordinate removed), and 3 + 2 + 1 supports hold every rigid motion."""
    import dataclasses

    from tenscell.model import StructureError, pin_jointed
    from tenscell.model.coordinates import kinematics

    free = pin_jointed(snelson_prism(1.0, 1.0))  # the peers' bar model: every node a point node
    held = {0: "xyz", 1: "yz", 2: "z"}
    sup = dataclasses.replace(free, fixed=(0,), supports=((2, "z"), (1, "zy")))
    assert sup.supports == ((1, "yz"), (2, "z"))
    EA = np.where(np.array(free.families) == "strut", 100.0, 1.0)
    cf, cs = equilibrate(free), equilibrate(sup)
    np.testing.assert_allclose(cs.T0, cf.T0, rtol=1e-12)  # two SVDs of well-conditioned equilibrium matrices
    lf = tc.linearize(cf, P=1.0, EA=EA, c=1.0, check=False)
    ls = tc.linearize(cs, P=1.0, EA=EA, c=1.0)
    assert ls.basis is None  # no rigid-body motion left
    keep = [3 * i + "xyz".index(a) for i in range(6) for a in "xyz" if a not in held.get(i, "")]
    Kf, Ks = np.asarray(lf.K0), np.asarray(ls.K0)
    # the same sums of the same terms, in another order: a few ulps of the largest entry
    np.testing.assert_allclose(Ks, Kf[np.ix_(keep, keep)], rtol=0, atol=64 * np.finfo(float).eps * np.abs(Kf).max())
    q = cs.coords.q0 + 0.01 * np.random.default_rng(1).standard_normal(cs.n)
    x = kinematics(cs.coords, q).x
    assert x[1, 1] == free.nodes[1, 1] and x[1, 2] == free.nodes[1, 2] and x[2, 2] == free.nodes[2, 2]
    with pytest.raises(StructureError, match="end of a rigid strut"):
        dataclasses.replace(snelson_prism(1.0, 1.0), supports=((0, "z"),))
    with pytest.raises(StructureError, match="held in every direction"):
        dataclasses.replace(free, supports=((0, "xyz"),))
    with pytest.raises(StructureError, match="must be some of"):
        dataclasses.replace(free, supports=((0, "w"),))


# ---- the analyses downstream of linearize: elasticities, the linear steady state, the time domain -------------
#: central differences of ln G with relative step 1e-5: truncation ~1e-10 (relative), rounding ~1e-16/1e-5 amplified
#: by the restricted pencil's condition number (< 1e4 here: EA/P = 50, one decade of tensions) ~1e-7 — an absolute
#: error in the elasticity, whatever its size (measured 6.8e-9 on an elasticity of 2.5e-3 under OpenBLAS's
#: Prescott kernel). rtol 1e-6 and atol 1e-7 sit above both and far below a missing projection (which changes G by
#: O(1) or fails outright)
FD_STEP, FD_RTOL, FD_ATOL = 1e-5, 1e-6, 1e-7


@pytest.mark.parametrize("build", [lambda: snelson_prism(1.0, 1.0), expanded_octahedron])
def test_elasticities_of_free_standing_structures(build):
    """Exact elasticities through the restricted pencil: each equals a central difference of ln G', ln G'' from
    tc.moduli, and together they obey Euler's rule (G is homogeneous of degree 1 in P, every EA and every c)."""
    from tenscell.sensitivity import analytic_elasticities

    cell = equilibrate(build())  # default parametrization: the octahedron's vertical struts need the local chart
    f = np.array([0.1, 1.0, 10.0])
    EA = np.linspace(40.0, 60.0, cell.m)
    c = np.linspace(1.0, 2.0, cell.m)
    lin = tc.linearize(cell, P=1.0, EA=EA, c=c)
    assert lin.basis is not None
    el = analytic_elasticities(lin, f)
    total = el.complex.sum(axis=0)
    np.testing.assert_allclose(total.real, 1.0, rtol=0, atol=1e-9)  # Euler: Σ θ ∂lnG/∂θ = 1

    def G(P=1.0, EA=EA, c=c):
        Gs, Gl = tc.moduli(tc.linearize(cell, P=P, EA=EA, c=c), f)
        return np.log(Gs), np.log(Gl)

    checks = {"P": lambda s: G(P=1.0 + s), "EA[0]": lambda s: G(EA=EA * np.r_[1 + s, np.ones(cell.m - 1)]),
              f"c[{cell.m - 1}]": lambda s: G(c=c * np.r_[np.ones(cell.m - 1), 1 + s])}
    for name, at in checks.items():
        (sp, lp), (sm, lm) = at(FD_STEP), at(-FD_STEP)
        k = el.index(name)
        np.testing.assert_allclose(el.storage[k], (sp - sm) / (2 * FD_STEP), rtol=FD_RTOL, atol=FD_ATOL,
                                   err_msg=name)
        np.testing.assert_allclose(el.loss[k], (lp - lm) / (2 * FD_STEP), rtol=FD_RTOL, atol=FD_ATOL, err_msg=name)


def test_linear_steady_state_and_the_time_domain_of_a_free_standing_structure():
    from tenscell.dynamics import linear_steady_state, oscillatory_response
    from tenscell.dynamics.loads import SineForce
    from tenscell.linear.rigid import solve_full
    from tenscell.model.formfinding import rigid_body_modes

    cell = equilibrate(snelson_prism(1.0, 1.0))
    lin = tc.linearize(cell, P=1.0, EA=50.0, c=1.0)
    f = 2.0
    x = solve_full(lin, 2j * np.pi * f, -lin.H0)
    R = rigid_body_modes(cell.coords)
    assert np.abs(R.T @ x).max() <= 1e-12 * np.abs(x).max()  # no rigid-body motion in the response
    J = tc.compliance(lin, [f])[0]
    assert lin.D0 @ x == pytest.approx(J, rel=1e-12)  # the same solve as the compliance, lifted back
    load = SineForce(1e-3, f)
    q = linear_steady_state(lin, load)
    np.testing.assert_allclose(q - cell.q0, (x * load.phasor).real, rtol=0, atol=1e-15)
    with pytest.raises(tc.dynamics.SimulationError) as info:
        oscillatory_response(cell, lin.tendon_law, 1e-3, f, cycles=2)
    msg = str(info.value)
    assert "\n" not in msg and "free-standing" in msg and "6 rigid-body motion(s)" in msg


def test_auto_parametrization_falls_back_for_vertical_struts():

    auto = equilibrate(expanded_octahedron())
    local = equilibrate(expanded_octahedron(), parametrization="local")
    assert auto.coords.kind == "local" and "vertical" in auto.coords.note and "note: strut(s) 0, 1" in repr(auto)
    np.testing.assert_array_equal(auto.T0, local.T0)
    f = [0.1, 1.0]
    np.testing.assert_array_equal(tc.moduli(tc.linearize(auto, P=10.0, EA=5.0, c=1.0), f)[1],
                                  tc.moduli(tc.linearize(local, P=10.0, EA=5.0, c=1.0), f)[1])
    # what the fallback avoids: the paper's angles are singular at a vertical strut (α moves nothing)
    with pytest.raises(tc.linear.NotPositiveDefiniteError):
        tc.linearize(equilibrate(expanded_octahedron(), parametrization="angles"), P=10.0, EA=5.0, c=1.0)
    # structures without a vertical strut keep the paper's angles and their coordinate names
    paper = equilibrate(tc.paper_cell().structure)
    assert paper.coords.kind == "angles" and paper.coords.note == "" and paper.coords.labels[0] == "delta[0]"


@pytest.mark.parametrize("arm", [0.5, 2.0])
def test_laws_with_internal_dynamics_on_a_free_standing_structure(arm):
    """A Snelson prism with standard-linear-solid tendons: the exact kernel (one complex solve per frequency on the
    complement of the rigid-body motions) and the realized pencil (one internal variable per tendon, exact for
    this law, restricted to the complement (R, 0): a rigid-body motion stretches no tendon, so no arm moves) are
    two computations of the same J(ω) and agree to the conditioning of the solves. (Maxwell tendons, which relax
    completely, leave this prism only its prestress stiffness: static compliance ~1e15 m/N at P = 1 N, a
    near-mechanism whose two computations differ by the same 1e15 condition number, so it is not compared.)"""
    cell = equilibrate(snelson_prism(1.0, 1.0))
    law = tc.laws.StandardLinearSolid(EA=50.0, EA_arm=arm * 50.0, c=1.0)
    lin = tc.linear.linearize_law(cell, law, 1.0)
    assert lin.basis is not None and "6 rigid-body motion(s) removed" in lin.notes[0]
    f = np.logspace(-1, 2, 7)
    exact = tc.compliance(lin, f)  # the law's exact dynamic tangent
    m = lin.pencil.modes  # the realized pencil on the complement
    from tenscell.linear.spectrum import modal_compliance

    realized = modal_compliance(m.tau, m.weights, 2 * np.pi * f)
    # both are solves of systems with condition < 1e4 (EA/P = 50 over a decade of tensions): 1e-9 relative
    np.testing.assert_allclose(realized, exact, rtol=1e-9)
    Gs, Gl = tc.moduli(lin, f)
    assert np.all(Gs > 0) and np.all(Gl > 0)
    creep = tc.timedomain.creep_spectrum(lin)  # the time domain through the restricted realized pencil
    assert np.all(np.diff(creep.compliance(np.logspace(-3, 2, 20))) >= 0)
