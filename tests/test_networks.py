"""The power-law study's structures (tenscell.model.networks), checked by physics: self-stress, form-finding's
force-density Laplacian, positive definiteness, passivity, the static limit, the out-of-plane reduction of the
simplex nets to diffusion on their graph, the exact prestress scaling, and the damping rules."""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

import tenscell
from tenscell.model.networks import (ISOSTATIC_CONNECTIVITY, TETHER, DilutedNet, SimplexNet, damping_by_length,
                                     damping_by_tension, diluted_net, free_connectivity, simplex_exponent, simplex_net)
from tenscell.model.structure import member_values
from tenscell.response import static_modulus


def _dense(M):
    return M.toarray() if sp.issparse(M) else np.asarray(M)


@pytest.fixture(scope="module")
def sub_isostatic():
    return diluted_net(DilutedNet(size=3, connectivity=4.5, seed=1))


@pytest.fixture(scope="module")
def gasket():
    return simplex_net(SimplexNet(module_nodes=3, depth=3))


def _self_stress_residual(cell):
    A = _dense(cell.A)
    return np.linalg.norm(A @ cell.T0) / (np.abs(A).max() * np.linalg.norm(cell.T0))


@pytest.mark.parametrize("spec", [DilutedNet(size=3, connectivity=4.5, seed=1), DilutedNet(size=3, connectivity=8.0),
                                  SimplexNet(module_nodes=3, depth=3), SimplexNet(module_nodes=4, depth=2)])
def test_prestressable_with_every_cable_in_tension(spec):
    cell = diluted_net(spec) if isinstance(spec, DilutedNet) else simplex_net(spec)
    assert _self_stress_residual(cell) < 1e-12
    assert np.all(cell.T0 > 0)  # every member is a cable
    assert cell.lengths.min() > 1e-9 * cell.lengths.max()


def test_diluted_net_reaches_its_connectivity_and_keeps_three_cables_per_node():
    for z in (4.5, 6.0, 8.0):
        cell = diluted_net(DilutedNet(size=4, connectivity=z, seed=2))
        st = cell.structure
        n_free = st.n_nodes - len(st.fixed)
        assert abs(free_connectivity(st) - z) <= 2.0 / n_free + 1e-12
        fixed = np.zeros(st.n_nodes, bool)
        fixed[list(st.fixed)] = True
        degree = np.bincount(np.asarray(st.tendons).ravel(), minlength=st.n_nodes)
        assert degree[~fixed].min() >= 3


def test_force_density_form_finding_makes_the_prestress_stiffness_a_graph_laplacian(sub_isostatic):
    """Kp = Σ T0 (∇²l + a aᵀ/l) = Σ (T0/l) I₃ on each cable's nodes: with one force density q = T0/l, the
    force-density Laplacian times the identity in x, y, z."""
    cell = sub_isostatic
    q = cell.T0 / cell.lengths
    assert np.ptp(q) < 1e-10 * q.max()
    Kp = _dense(cell.Kp)
    st = cell.structure
    free = np.setdiff1d(np.arange(st.n_nodes), st.fixed)
    index = -np.ones(st.n_nodes, int)
    index[free] = np.arange(free.size)
    L = np.zeros((free.size, free.size))
    for (a, b), qj in zip(np.asarray(st.tendons), q):
        for u, v in ((a, b), (b, a)):
            if index[u] >= 0:
                L[index[u], index[u]] += qj
                if index[v] >= 0:
                    L[index[u], index[v]] -= qj
    # point-node coordinates of a structure without struts: x, y, z of each free node in turn
    assert np.allclose(Kp, np.kron(L, np.eye(3)), atol=1e-12 * np.abs(Kp).max())


def test_below_isostatic_the_prestress_alone_holds_the_floppy_modes(sub_isostatic):
    cell = sub_isostatic
    assert free_connectivity(cell.structure) < ISOSTATIC_CONNECTIVITY
    A = _dense(cell.A)
    Km = (A / cell.lengths) @ A.T  # EA = 1: the cables' own stiffness
    ev = np.linalg.eigvalsh(Km)
    assert np.sum(ev < 1e-10 * ev.max()) >= cell.n - cell.m  # fewer cables than coordinates: floppy
    lin = tenscell.linearize(cell, P=0.01, EA=1.0, c=1.0)  # K0 = P·Kp + Km: positive definite (the check)
    assert np.linalg.eigvalsh(_dense(lin.K0)).min() > 0


def test_passive_and_static_limit(sub_isostatic, gasket):
    f = np.logspace(-4, 4, 33)
    for cell, EA, c in ((sub_isostatic, 1.0, 0.3),
                        (gasket, member_values(gasket.structure, {"actin": 1.0, TETHER: 1e-6}), 0.2)):
        lin = tenscell.linearize(cell, P=0.05, EA=EA, c=c)
        Gs, Gl = tenscell.moduli(lin, f)
        assert np.all(Gl > 0) and np.all(Gs > 0)
        G0 = static_modulus(lin)
        Gs_low, _ = tenscell.moduli(lin, [1e-9])
        assert Gs_low[0] == pytest.approx(G0, rel=1e-6)


def _node_count(k, depth):
    n = k
    for _ in range(depth):
        n = k * n - k * (k - 1) // 2  # k copies share one corner per pair
    return n


@pytest.mark.parametrize("k, depth", [(3, 1), (3, 3), (4, 2), (5, 2)])
def test_simplex_net_counts(k, depth):
    st = simplex_net(SimplexNet(module_nodes=k, depth=depth)).structure
    fam = np.array(st.families)
    cables = np.asarray(st.tendons)[fam != TETHER]
    nodes = _node_count(k, depth)
    assert len(cables) == k * (k - 1) // 2 * k ** depth
    degree = np.bincount(cables.ravel(), minlength=nodes)[:nodes]
    assert sorted(set(degree.tolist())) == [k - 1, 2 * (k - 1)]  # corners: one module; the rest: two
    assert np.sum(degree == k - 1) == k
    assert np.sum(fam == TETHER) == 2 * (nodes - k)  # two tethers per free node
    assert np.allclose(st.nodes[:nodes, 2], 0.0)  # the net lies in its plane


def test_simplex_net_out_of_plane_is_diffusion_on_its_graph(gasket):
    """The probe's vertical compliance equals the scalar resolvent of P·q·L + tether springs + iω·(tether dampers)
    on the free nodes (in-plane and out-of-plane motions decouple exactly in a flat prestressed net)."""
    cell = gasket
    st = cell.structure
    fam = np.array(st.families)
    net = fam != TETHER
    EA = np.where(net, 1.0, 1e-3)
    c = np.where(net, 0.7, 0.2)
    P = 0.3
    lin = tenscell.linearize(cell, P=P, EA=EA, c=c)
    f = np.logspace(-2, 3, 11)
    J = tenscell.compliance(lin, f)
    tend = np.asarray(st.tendons)
    nodes = int(tend[net].max()) + 1
    free = np.setdiff1d(np.arange(nodes), st.fixed)
    index = -np.ones(nodes, int)
    index[free] = np.arange(free.size)
    K = np.zeros((free.size, free.size))
    for (a, b), t, l in zip(tend[net], cell.T0[net], cell.lengths[net]):
        for u, v in ((a, b), (b, a)):
            if index[u] >= 0:
                K[index[u], index[u]] += P * t / l
                if index[v] >= 0:
                    K[index[u], index[v]] -= P * t / l
    C = np.zeros(free.size)
    for (a, _), t, l, e, cj in zip(tend[~net], cell.T0[~net], cell.lengths[~net], EA[~net], c[~net]):
        K[index[a], index[a]] += (e + P * t) / l  # a vertical tether: axial stiffness along z
        C[index[a]] += cj
    p = index[st.probe.nodes[0]]
    e_p = np.zeros(free.size)
    e_p[p] = 1.0
    J_scalar = np.array([np.linalg.solve(K + 2j * math.pi * fk * np.diag(C), e_p)[p] for fk in f])
    assert np.allclose(J, J_scalar, rtol=1e-9)


def test_simplex_net_prestress_only_rescales_frequency(gasket):
    """With tethers that carry (almost) no stiffness, every out-of-plane stiffness is P·q: G(f, 2P) = 2·G(f/2, P)."""
    cell = gasket
    EA = member_values(cell.structure, {"actin": 1.0, TETHER: 1e-12})
    c = member_values(cell.structure, {"actin": 1.0, TETHER: 0.3})
    f = np.logspace(-2, 2, 9)
    G1 = np.array(tenscell.moduli(tenscell.linearize(cell, P=0.1, EA=EA, c=c), f))
    G2 = np.array(tenscell.moduli(tenscell.linearize(cell, P=0.2, EA=EA, c=c), 2 * f))
    assert np.allclose(G2, 2 * G1, rtol=1e-5)  # the tethers' prestress (1e-6 of the cables') breaks it at 1e-6


def test_simplex_exponent_is_hilfer_blumen():
    assert simplex_exponent(3) == pytest.approx(1 - math.log(3) / math.log(5))
    assert simplex_exponent(4) == pytest.approx(0.2263, abs=1e-4)
    assert simplex_exponent(3) > simplex_exponent(4) > simplex_exponent(5) > 0


def test_damping_rules(sub_isostatic):
    cell = diluted_net(DilutedNet(size=3, connectivity=6.0))
    l = cell.lengths
    c = damping_by_length(cell, 2.0, 1.5)
    assert np.allclose(c[1:] / c[0], (l[1:] / l[0]) ** 1.5)
    assert np.exp(np.mean(np.log(c))) > 0 and damping_by_length(cell, 2.0, 0.0) == pytest.approx(np.full(cell.m, 2.0))
    P, F = 3.0, 0.05
    ct = damping_by_tension(cell, 1.0, P, F)
    T = P * cell.T0
    assert np.allclose(np.log(ct[1:] / ct[0]), -(T[1:] - T[0]) / F)
    assert np.log(ct) @ np.ones(cell.m) == pytest.approx(-(T - T.mean()).sum() / F)  # c at the mean force
    with pytest.raises(ValueError, match="exponent"):
        damping_by_length(cell, 1.0, 20.0)


@pytest.mark.parametrize("bad, match", [(dict(size=1), "size"), (dict(connectivity=2.0), "connectivity"),
                                        (dict(seed=-1), "seed"), (dict(span=0.0), "span")])
def test_diluted_net_refuses_bad_specs(bad, match):
    with pytest.raises(ValueError, match=match):
        DilutedNet(**bad)


@pytest.mark.parametrize("bad, match", [(dict(module_nodes=2), "module_nodes"), (dict(depth=0), "depth"),
                                        (dict(tether_tension=2.0), "tether_tension"),
                                        (dict(module_nodes=6, depth=9), "modules")])
def test_simplex_net_refuses_bad_specs(bad, match):
    with pytest.raises(ValueError, match=match):
        SimplexNet(**bad)
