"""Form-finding: recovers known shapes, satisfies equilibrium checked independently, reports failure."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import tenscell
from tenscell.model.formfinding import FormFindingError, find_form, pin_jointed
from tenscell.model.lattices import _module
from tenscell.model.structure import Point, Structure

SQRT38 = math.sqrt(3.0 / 8.0)


def _icosahedron(X):
    _, struts, cables = _module(1.0, 0.25)
    p = Point(nodes=(4, 6), weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    return Structure(nodes=X, struts=tuple(struts), tendons=tuple(cables), families=("actin",) * 24, fixed=(),
                     load=p, probe=p, name="icosahedron")


def _perturbed(seed, amount=0.12, L=1.0):
    """The regular icosahedron's topology at a randomly disturbed shape, struts kept at length L."""
    X0, struts, _ = _module(L, L / 4)
    rng = np.random.default_rng(seed)
    X = X0 + amount * L * rng.standard_normal(X0.shape)
    for a, b in struts:
        mid, d = 0.5 * (X[a] + X[b]), X[a] - X[b]
        X[a], X[b] = mid + 0.5 * L * d / np.linalg.norm(d), mid - 0.5 * L * d / np.linalg.norm(d)
    return X


def _strut_balance(structure, T):
    """Independent equilibrium check for rigid struts: at each strut the cable forces on its two ends
    must be equal and opposite and along the strut (then a strut force balances them)."""
    x = structure.nodes
    f = np.zeros_like(x)
    for (a, b), t in zip(structure.tendons, T):
        e = (x[b] - x[a]) / np.linalg.norm(x[b] - x[a])
        f[a] += t * e
        f[b] -= t * e
    worst = 0.0
    for tail, head in structure.struts:
        u = (x[head] - x[tail]) / np.linalg.norm(x[head] - x[tail])
        if tail not in structure.fixed:
            worst = max(worst, np.linalg.norm(f[head] + f[tail]))
        worst = max(worst, np.linalg.norm(f[head] - (f[head] @ u) * u))  # no component across the strut
    for i in structure.point_nodes:
        worst = max(worst, np.linalg.norm(f[i]))
    return worst / np.abs(T).max()


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_recovers_regular_icosahedron_from_perturbed_start(seed):
    X = _perturbed(seed)
    res = find_form(_icosahedron(X), force_density=1.0, rest_length=0.3)
    x = res.structure.nodes
    assert res.stable and res.rigid_body_dof == 6 and res.residual < 1e-12
    l = np.array([np.linalg.norm(x[a] - x[b]) for a, b in res.structure.tendons])
    np.testing.assert_allclose(l, SQRT38, rtol=1e-10)  # the 24 equal cables of the expanded octahedron
    np.testing.assert_allclose(res.structure.strut_lengths, 1.0, rtol=1e-13)  # rigid struts untouched
    # all 12 nodes on one sphere of radius sqrt(5)/4 L; parallel struts L/2 apart
    r = np.linalg.norm(x - x.mean(axis=0), axis=1)
    np.testing.assert_allclose(r, math.sqrt(5.0) / 4.0, rtol=1e-10)
    s = np.asarray(res.structure.struts)
    u = (x[s[:, 1]] - x[s[:, 0]])
    mids = 0.5 * (x[s[:, 0]] + x[s[:, 1]])
    for i in range(6):
        for j in range(i + 1, 6):
            if abs(abs(u[i] @ u[j]) - 1.0) < 1e-9:
                assert abs(np.linalg.norm(mids[i] - mids[j]) - 0.5) < 1e-10
    np.testing.assert_allclose(res.tensions, 0.3 * (SQRT38 / 0.3 - 1.0) * 1.0, rtol=1e-9)  # w (l - r)
    np.testing.assert_allclose(res.cell.T0, 1 / math.sqrt(24.0), rtol=1e-9)
    assert _strut_balance(res.structure, res.tensions) < 1e-11


def test_force_density_method_has_the_affine_family():
    """With r = 0 the icosahedron's equilibria form a 3-parameter family (affine shears): form-finding
    still lands on an exact equilibrium, but it is generally not the regular one and not a strict minimum."""
    res = find_form(_icosahedron(_perturbed(1)), force_density=1.0)
    assert res.residual < 1e-12 and _strut_balance(res.structure, res.tensions) < 1e-11
    l = np.array([np.linalg.norm(res.structure.nodes[a] - res.structure.nodes[b]) for a, b in res.structure.tendons])
    assert np.ptp(l) > 1e-3
    assert res.stable is False
    np.testing.assert_allclose(res.tensions, l, rtol=1e-14)  # T = w l with w = 1 N/m


def test_cable_net_matches_linear_force_density_method():
    """Cables only between fixed supports: the classic (linear) force-density method, solved independently."""
    rng = np.random.default_rng(5)
    ring = np.array([[math.cos(t), math.sin(t), 0.3 * math.sin(2 * t)] for t in np.linspace(0, 2 * math.pi, 9)[:-1]])
    inner = 0.3 * rng.standard_normal((5, 3))
    X = np.vstack([ring, inner])
    tendons = [(i, 8 + (i % 5)) for i in range(8)] + [(8 + i, 8 + j) for i in range(5) for j in range(i + 1, 5)]
    w = rng.uniform(0.5, 2.0, len(tendons))
    p = Point(nodes=(8,), weights=(1.0,))
    st = Structure(nodes=X, struts=(), tendons=tuple(tendons), families=("actin",) * len(tendons),
                   fixed=tuple(range(8)), load=p, probe=p)
    res = find_form(st, force_density=w)
    # D_ff x_f = -D_fs x_s, the force-density matrix restricted to free nodes
    free, fixed = list(range(8, 13)), list(range(8))
    D = np.zeros((13, 13))
    for (a, b), q in zip(tendons, w):
        D[a, a] += q
        D[b, b] += q
        D[a, b] -= q
        D[b, a] -= q
    x_free = np.linalg.solve(D[np.ix_(free, free)], -D[np.ix_(free, fixed)] @ X[fixed])
    np.testing.assert_allclose(res.structure.nodes[free], x_free, atol=1e-12)
    np.testing.assert_array_equal(res.structure.nodes[fixed], X[fixed])
    assert res.stable and res.rigid_body_dof == 0


def test_elastic_struts_return_to_their_lengths():
    X = _perturbed(2)
    st = pin_jointed(_icosahedron(X))
    res = find_form(st, force_density={"actin": 1.0}, rest_length=0.3)
    x = res.structure.nodes
    fam = np.array(st.families)
    l = np.array([np.linalg.norm(x[a] - x[b]) for a, b in st.tendons])
    np.testing.assert_allclose(l[fam == "strut"], 1.0, rtol=1e-10)
    np.testing.assert_allclose(l[fam == "actin"], SQRT38, rtol=1e-8)
    assert np.all(res.tensions[fam == "strut"] < 0) and np.all(res.tensions[fam == "actin"] > 0)
    np.testing.assert_allclose(res.tensions[fam == "strut"] / res.tensions[fam == "actin"][0], -math.sqrt(6), rtol=1e-7)


def test_paper_cell_topology_form_finds_to_a_usable_cell():
    """From a crude shape of the paper's anchored topology to a cell whose moduli are computed."""
    st = tenscell.model.paper_structure(0.0, math.radians(50), 1.0)
    rng = np.random.default_rng(3)
    X = st.nodes.copy()
    X[12] += 0.1 * rng.standard_normal(3)  # nucleus off centre
    res = find_form(dataclasses.replace(st, nodes=X, equal_tension_groups=()),
                    force_density={"actin": 1.0, "intermediate_filament": 0.3})
    assert res.stable and res.rigid_body_dof == 0
    assert np.all(res.cell.T0 > 0)
    assert _strut_balance(res.structure, res.tensions) < 1e-11
    Gp, Gpp = tenscell.moduli(tenscell.linearize(res.cell, 1000.0), [0.01, 100.0])
    assert np.all(Gp > 0) and np.all(Gpp > 0) and Gp[1] > Gp[0]


def test_reports_when_no_configuration_exists():
    # cables and nothing to hold them apart: the net shrinks to a point
    X = np.random.default_rng(0).standard_normal((4, 3))
    p = Point(nodes=(0,), weights=(1.0,))
    st = Structure(nodes=X, struts=(), tendons=((0, 1), (1, 2), (2, 3), (3, 0)), families=("actin",) * 4,
                   fixed=(), load=p, probe=p, name="bare net")
    with pytest.raises(FormFindingError, match="bare net: no prestressable configuration found"):
        find_form(st)
    # a structure that needs more iterations than allowed says so
    with pytest.raises(FormFindingError, match="did not converge in 2 Newton steps"):
        find_form(_icosahedron(_perturbed(4, amount=0.3)), rest_length=0.3, max_iter=2)
    # rest lengths longer than the cables can reach: slack
    with pytest.raises(FormFindingError, match="slack"):
        find_form(_icosahedron(_perturbed(1)), rest_length=0.8)
    assert issubclass(FormFindingError, tenscell.model.NotPrestressableError)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"force_density": -1.0}, "force_density of tendon 0"),
        ({"force_density": {"actin_typo": 1.0}}, "no value for family 'actin'"),
        ({"force_density": np.ones(3)}, "force_density must be"),
        ({"rest_length": -0.1}, "rest_length of tendon 0"),
        ({"max_iter": 0}, "max_iter"),
    ],
)
def test_bad_options(kwargs, message):
    with pytest.raises(ValueError, match=message):
        find_form(_icosahedron(_perturbed(1)), **kwargs)
