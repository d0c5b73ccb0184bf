"""What the structure carries (tenscell.fitting.shares): the split of dG*/dP checked against finite differences.

The references are independent evaluations of the kernel (tenscell.linear.dynamic.dynamic_compliance) at
prestresses P ± h:

* the whole dG*/dP: the mechanism problem's own moduli at s·(p ± h);
* the geometric part (transverse + axial, the paper's P·Kp): the same cell with the law's constitutive tension
  term frozen at the reference tension (for TensionSpringpot: beta·T0·P0 instead of beta·T0·P);
* the transverse part alone: every k* frozen at the reference, only P·ΣT0∇²l moving.

Central differences with h = 1e-4·P have a truncation error ~ h²|G'''| / |G'| ~ 1e-8 relative here, and a rounding
error ~ eps·κ(K)/1e-4; the tolerance 1e-6 is far below the parts themselves (a wrong sign or a missing
term is O(1)).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tenscell import paper_cell
from tenscell.fitting.models.catalog import MECHANISMS
from tenscell.fitting.models.mechanism import Field, FittedMechanism, Mechanism, make_mechanism_problem
from tenscell.fitting.shares import StructureShares, prestress_parts, structure_shares
from tenscell.io import bundled
from tenscell.laws import Springpot
from tenscell.linear.dynamic import dynamic_compliance
from tenscell.linear.assembly import modulus

DATA = (bundled("stamenovic2002"), bundled("fabry2001"))
CELL = paper_cell()
#: springpot-tension+visc near its bundled optimum (EA, kappa, alpha, alpha_T, eta, s, P_data[1]); beta = 1000 fixed
TENSION = {"EA": 6.675, "kappa": 138.0, "alpha": 0.2506, "alpha_T": 0.1734, "eta_cytoplasm": 0.234,
           "s": 1.906e-3, "P_data[1]": 1070.0}
RTOL = 1e-6


def _theta(pb, values):
    return np.log([values[n] for n, f in zip(pb.names, pb.free) if f])


def _tension_problem():
    pb = make_mechanism_problem(DATA, MECHANISMS["springpot-tension+visc"])
    return pb, _theta(pb, TENSION)


def _G_at(pb, phi, P, w):
    return pb.evaluate(phi, w, np.full(w.size, P), jac=False).G


def _parts_at_half_newton():
    """The problem, its log-parameters, two frequencies (rad/s), P = 0.5 N and prestress_parts there."""
    pb, th = _tension_problem()
    phi = pb.full(th)
    w = 2 * np.pi * np.array([0.1, 3.0])
    G, parts = prestress_parts(pb, phi, 0.5, w)
    return pb, phi, w, 0.5, G, parts


def test_total_derivative_is_the_finite_difference_of_the_moduli():
    pb, phi, w, P, G, parts = _parts_at_half_newton()
    h = 1e-4 * P
    fd = P * (_G_at(pb, phi, P + h, w) - _G_at(pb, phi, P - h, w)) / (2 * h)
    assert np.max(np.abs(parts.sum(axis=0) - fd)) < RTOL * np.max(np.abs(fd))
    assert np.max(np.abs(G - _G_at(pb, phi, P, w))) < 1e-12 * np.max(np.abs(G))


def test_geometric_and_transverse_parts_are_the_finite_differences_with_the_law_frozen():
    pb, phi, w, P0, _, parts = _parts_at_half_newton()
    v = TENSION
    l, T0 = CELL.lengths, CELL.T0
    passive = Springpot(EA=v["EA"], kappa=v["kappa"], alpha=v["alpha"])
    active = Springpot._power(w, np.full(CELL.m, v["alpha_T"])) * (1000.0 * P0 * T0 / l)  # beta·T frozen at P0

    def G_frozen(P, kstar):
        return modulus(dynamic_compliance(CELL, P, kstar), CELL.strut_length)

    h = 1e-4 * P0
    geo = P0 * (G_frozen(P0 + h, passive.complex_stiffness(l, (P0 + h) * T0, w) + active)
                - G_frozen(P0 - h, passive.complex_stiffness(l, (P0 - h) * T0, w) + active)) / (2 * h)
    k_ref = passive.complex_stiffness(l, P0 * T0, w) + active
    transverse = P0 * (G_frozen(P0 + h, k_ref) - G_frozen(P0 - h, k_ref)) / (2 * h)
    scale = np.max(np.abs(parts.sum(axis=0)))
    assert np.max(np.abs(parts[0] + parts[1] - geo)) < RTOL * scale
    assert np.max(np.abs(parts[0] - transverse)) < RTOL * scale
    # the constitutive part is large here (issue 26: the beta·T term carries ~98 % of dG'/dP)
    assert np.all(np.abs(parts[2].real) > 10 * np.abs((parts[0] + parts[1]).real))


def test_shares_over_the_range_of_the_bundled_fit():
    """springpot-tension+visc at its bundled optimum: about 2 % of ΔG' geometric (issue 26), the integral closes."""
    pb, th = _tension_problem()
    sh = structure_shares(pb, th)
    assert isinstance(sh, StructureShares)
    assert sh.prestress_pa[0] == pytest.approx(350.0) and sh.prestress_pa[-1] == pytest.approx(1900.0)
    assert np.allclose(sh.frequency_hz, [0.1])
    assert 0.0 < sh.geometric_share_storage < 0.05
    for mod in ("storage", "loss"):
        total = sh.share("geometric", mod) + sh.share("constitutive", mod)
        assert np.allclose(total, 1.0, atol=1e-12)
        assert np.allclose(sh.share("transverse", mod) + sh.share("axial", mod), sh.share("geometric", mod), atol=1e-12)
    assert sh.closure < 1e-5  # Simpson on 17 prestresses against G*(hi) − G*(lo)
    df = sh.to_dataframe()
    assert len(df) == 17 and "dG_storage_dP_constitutive_per_Pa" in df.columns
    assert "geometric prestress stiffness" in repr(sh)


@pytest.mark.parametrize("name", ["springpot+visc", "maxwell+visc", "voigt-compact+visc", "voigt-lognormal-damping"])
def test_laws_without_a_tension_term_are_all_geometric(name):
    """Springpot, Maxwell, Voigt (also distributed): ∂k*/∂T = 1/l, so the constitutive part is exactly 0."""
    pb = make_mechanism_problem(DATA, MECHANISMS[name])
    th = pb.initial_guess(np.random.default_rng(3))
    sh = structure_shares(pb, th, points=5)
    assert np.max(np.abs(sh.dG_constitutive)) < 1e-12 * np.max(np.abs(sh.dG))  # (1/l)·T − T/l: rounding only
    assert sh.geometric_share_storage == pytest.approx(1.0, abs=1e-10)


def test_a_fitted_mechanism_gives_the_same_shares():
    pb, th = _tension_problem()
    v = TENSION
    fm = FittedMechanism(mechanism=MECHANISMS["springpot-tension+visc"], cell=CELL,
                         values={k: v[k] for k in ("EA", "kappa", "alpha", "alpha_T", "eta_cytoplasm")} | {"beta": 1000.0},
                         s=v["s"], prestress_pa=(350.0, 1900.0, 1070.0))
    a = structure_shares(pb, th, points=5)
    b = structure_shares(fm, frequency_hz=0.1, points=5)
    assert np.allclose(a.dG, b.dG, rtol=1e-12, atol=0)
    with pytest.raises(ValueError, match="frequency_hz is required"):
        structure_shares(fm)
    with pytest.raises(ValueError, match="theta"):
        structure_shares(fm, th, frequency_hz=0.1)


def test_a_fit_without_stated_prestress_gives_the_local_derivative():
    pb = make_mechanism_problem(bundled("fabry2001"), MECHANISMS["springpot+visc"])
    th = pb.initial_guess(np.random.default_rng(0))
    sh = structure_shares(pb, th)
    assert sh.prestress_n.size == 1 and np.isnan(sh.prestress_pa[0]) and sh.closure == 0.0
    assert sh.frequency_hz.size == bundled("fabry2001").n
    assert np.allclose(sh.share("geometric", "storage"), 1.0)


def test_bad_options():
    pb, th = _tension_problem()
    with pytest.raises(ValueError, match="theta"):
        structure_shares(pb)
    with pytest.raises(ValueError, match="odd"):
        structure_shares(pb, th, points=4)
    with pytest.raises(ValueError, match="low <= high"):
        structure_shares(pb, th, prestress_pa=(900.0, 400.0))
    with pytest.raises(ValueError, match="part must be"):
        structure_shares(pb, th, points=3).share("elastic")


def test_one_stated_prestress_gives_the_local_share():
    """A frequency sweep stated at one prestress (1000 Pa): the share is the local one there, the limit of the
    shares over a range shrinking onto it (Simpson over a range of ±0.01 % differs by O(h²) of the share's
    curvature in P, far below the 1e-6 asked)."""
    pb, th = _tension_problem()
    point = structure_shares(pb, th, prestress_pa=(1000.0, 1000.0))
    narrow = structure_shares(pb, th, prestress_pa=(999.9, 1000.1))
    assert point.prestress_pa.size == 1
    for part in ("geometric", "constitutive"):
        for mod in ("storage", "loss"):
            np.testing.assert_allclose(point.share(part, mod), narrow.share(part, mod), rtol=1e-6, atol=1e-9)


def test_shares_are_invariant_under_the_time_scaling():
    """kappa → λ^α kappa, beta → λ^α_T beta, η → λη at f → f/λ leaves G* and so every part unchanged."""
    lam = 5.0
    mech = Mechanism("t", "TensionSpringpot", (
        Field("EA", "stiffness", "shared"), Field("kappa", "coefficient", "shared"), Field("alpha", "exponent", "shared"),
        Field("beta", "ratio", "shared"), Field("alpha_T", "exponent", "shared")), viscosity=True)
    pb = make_mechanism_problem(DATA, mech)
    v = dict(TENSION, beta=1000.0)
    a = structure_shares(pb, _theta(pb, v), frequency_hz=[0.1, 2.0], points=5)
    w = dict(v, kappa=v["kappa"] * lam ** v["alpha"], beta=v["beta"] * lam ** v["alpha_T"],
             eta_cytoplasm=v["eta_cytoplasm"] * lam)
    b = structure_shares(pb, _theta(pb, w), frequency_hz=[0.1 / lam, 2.0 / lam], points=5)
    assert np.allclose(a.dG_geometric, b.dG_geometric, rtol=1e-9) and np.allclose(a.dG, b.dG, rtol=1e-9)
    assert math.isclose(a.geometric_share_storage, b.geometric_share_storage, rel_tol=1e-9)


def test_a_law_without_tension_terms_has_its_shares_by_construction():
    """springpot tendons have no tension term: P·Kp carries all of dG'/dP whatever the parameters, and the summary
    says so rather than "± not determined"; the computed shares are 1 and 0 to rounding."""
    from tenscell.fitting import fit
    from tenscell.io.data import bundled

    r = fit([bundled("stamenovic2002"), bundled("fabry2001")], model="springpot-alpha-family+visc", starts=1,
            hops=0, progress=False)
    st = r.structure
    np.testing.assert_allclose(st.quantities.values["geometric_storage"], 1.0, atol=1e-9)
    np.testing.assert_allclose(st.quantities.values["constitutive_storage"], 0.0, atol=1e-9)
    assert st.share_text("geometric", "storage") == "100 % (by construction: Springpot tendons have no tension terms)"
    assert st.share_text("constitutive", "loss").startswith("0 % (by construction")
    assert "not determined" not in st.share_verdict()
