"""Sensitivity: analytic elasticities against finite differences, and the scaling sum rules.

Sum rules (exact consequences of the model's scalings):
* P, every EA and every c all × s  ->  G × s:       e_P + Σ e_EA + Σ e_c = 1;
* every c × s  ->  G(f) becomes G(s·f):             Σ e_c = ∂ln G/∂ln f;
* G_L(f) = G_1(L·f)/L² at fixed EA, c, P:           e_L = ∂ln G/∂ln f − 2.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from tenscell import compliance, linearize, paper_cell
from tenscell import sensitivity as S

F = np.logspace(-2, 3, 13)


def _lnG(cell, P, EA, c, f=F):
    return np.log((0.5 / cell.strut_length) / compliance(linearize(cell, P=P, EA=EA, c=c), f))


def _log_slope_in_f(lin, f=F, h=1e-5):
    Gp = 1 / compliance(lin, f * math.exp(h))
    Gm = 1 / compliance(lin, f * math.exp(-h))
    return (np.log(Gp) - np.log(Gm)) / (2 * h)


@pytest.fixture(scope="module")
def hetero():
    cell = paper_cell()
    rng = np.random.default_rng(7)
    return cell, rng.uniform(0.3, 3.0, cell.m), rng.uniform(0.3, 3.0, cell.m)


@pytest.mark.parametrize("intermediate_filaments", [True, False], ids=["with_IFs", "no_IFs_singular_C0"])
def test_analytic_elasticities_match_finite_differences(intermediate_filaments):
    cell = paper_cell(intermediate_filaments=intermediate_filaments)
    rng = np.random.default_rng(11)
    EA, c, P = rng.uniform(0.3, 3.0, cell.m), rng.uniform(0.3, 3.0, cell.m), 1300.0
    el = S.analytic_elasticities(linearize(cell, P, EA, c), F)
    # central differences: truncation ~h², rounding ~ε/h with ε ≈ 1e-14 the compliance's own rounding (C0 whitened
    # once per cell, cond(C0) ≈ 440 here), so h ≈ ε^(1/3): at h = 1e-5 both stay below 1e-9
    h = 1e-5
    for j in (0, 5, cell.m - 1):
        for name, vec in (("EA", EA), ("c", c)):
            up, dn = vec.copy(), vec.copy()
            up[j] *= math.exp(h)
            dn[j] *= math.exp(-h)
            args_up = (up, c) if name == "EA" else (EA, up)
            args_dn = (dn, c) if name == "EA" else (EA, dn)
            fd = (_lnG(cell, P, *args_up) - _lnG(cell, P, *args_dn)) / (2 * h)
            an = el.complex[el.index(f"{name}[{j}]")]
            assert np.allclose(an, fd, rtol=1e-5, atol=1e-8), (name, j)
    fd = (_lnG(cell, P * math.exp(h), EA, c) - _lnG(cell, P * math.exp(-h), EA, c)) / (2 * h)
    assert np.allclose(el.complex[el.index("P")], fd, rtol=1e-6, atol=1e-9)
    # storage/loss elasticities are the real-part rules applied to e: compare with FD of ln G', ln G''
    up = np.exp(_lnG(cell, P * math.exp(h), EA, c))
    dn = np.exp(_lnG(cell, P * math.exp(-h), EA, c))
    k = el.index("P")
    assert np.allclose(el.storage[k], (np.log(up.real) - np.log(dn.real)) / (2 * h), rtol=1e-6, atol=1e-9)
    assert np.allclose(el.loss[k], (np.log(up.imag) - np.log(dn.imag)) / (2 * h), rtol=1e-6, atol=1e-9)


def test_scaling_sum_rules(hetero):
    cell, EA, c = hetero
    lin = linearize(cell, 900.0, EA, c)
    el = S.analytic_elasticities(lin, F)
    assert np.allclose(el.group_sum("EA") + el.group_sum("c") + el.complex[el.index("P")], 1.0, atol=1e-12)
    assert np.allclose(el.group_sum("c"), _log_slope_in_f(lin), rtol=1e-7, atol=1e-9)


def test_geometry_elasticities_and_the_length_sum_rule():
    el = S.elasticities(f_hz=F)
    lin = linearize(paper_cell(), 1000.0)
    k = el.index("L")
    assert "central" in el.methods[k]
    assert np.allclose(el.complex[k], _log_slope_in_f(lin) - 2.0, rtol=1e-6, atol=1e-7)
    # δ and α: central differences with a checked step agree with an independent quotient (3× the step)
    d0 = math.radians(50.0)
    for name, relative, h in (("delta", True, 3e-4), ("alpha", False, 3e-4)):
        i = el.index(name)
        assert el.errors[i] < 1e-4
        at = (lambda s: dict(delta=d0 * math.exp(s))) if relative else (lambda s: dict(alpha=s, delta=d0))
        fd = (np.log(1 / compliance(linearize(paper_cell(**at(h)), 1000.0), F))
              - np.log(1 / compliance(linearize(paper_cell(**at(-h)), 1000.0), F))) / (2 * h)
        assert np.allclose(el.complex[i], fd, rtol=1e-4, atol=1e-4), name


def test_one_sided_difference_at_the_edge_of_the_valid_region():
    # just below the regular member the forward step leaves the prestressable band
    delta = math.radians(54.733)
    el = S.elasticities(delta=delta, f_hz=F, step=1e-4)
    i = el.index("delta")
    assert "one-sided backward" in el.methods[i]
    h = 2e-5
    fd = (np.log(1 / compliance(linearize(paper_cell(delta=delta), 1000.0), F))
          - np.log(1 / compliance(linearize(paper_cell(delta=delta * math.exp(-h)), 1000.0), F))) / h
    assert np.allclose(el.complex[i], fd, rtol=2e-2, atol=1e-2)


def test_perturbation_table_and_summary():
    table = S.perturbation_table(f_hz=F)
    rows = {r.name: r for r in table}
    # P: direct recomputation of the +10% row
    G0 = np.exp(_lnG(paper_cell(), 1000.0, 1.0, 1.0))
    G1 = np.exp(_lnG(paper_cell(), 1100.0, 1.0, 1.0))
    assert rows["P"].storage[1] == pytest.approx(np.max(np.abs(G1.real / G0.real - 1)), rel=1e-12)
    # c (all) × 1.1 multiplies G'' by 1.1 at low frequency (G'' = ωη there)
    assert rows["c (all)"].loss[1] == pytest.approx(0.10, abs=2e-3)
    # δ ± 10% leaves the valid band (45.5°–54.74° at α = 0) on both sides
    assert "−" in rows["delta (±10%)"].note and "+" in rows["delta (±10%)"].note
    assert not rows["delta (±5%)"].note and rows["delta (±5%)"].worst > 0.08
    el = S.elasticities(f_hz=F)
    summary = {s.group: s for s in S.summarize(el, table)}
    assert summary["EA actin"].n == 21 and summary["c IF"].n == 12
    assert summary["EA actin"].holds is True and summary["P"].holds is False
    # first-order consistency: a 10% change is about 0.1 × elasticity
    assert summary["P"].max_change_storage == pytest.approx(0.1 * summary["P"].max_elasticity_storage, rel=0.05)


def test_monte_carlo_is_seeded_and_bounded_by_the_elasticities():
    a = S.monte_carlo(30, seed=5, parameters="material", f_hz=F)
    b = S.monte_carlo(30, seed=5, parameters="material", f_hz=F)
    assert np.array_equal(a.change_storage, b.change_storage) and a.valid.all()
    el = S.elasticities(f_hz=F)
    rows = [i for i, g in enumerate(el.groups) if g.startswith(("EA", "c", "P"))]
    bound = 0.1 * np.max(np.abs(el.storage[rows]).sum(axis=0))  # triangle inequality, first order
    assert a.change_storage.max() <= 1.2 * bound
    full = S.monte_carlo(20, seed=1, f_hz=F)
    assert full.factors.shape == (20, 2 * 33 + 4) and np.all(np.abs(full.factors[:, -1]) <= 0.1)
    assert len(full.reasons) == 20


@pytest.mark.parametrize(
    "kwargs, match",
    [({"n": 0}, "draws"), ({"spread": 1.5}, "spread"), ({"parameters": "some"}, "parameters")],
)
def test_monte_carlo_rejects_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        S.monte_carlo(**{"n": 2, **kwargs})


def test_elasticities_reject_bad_step():
    with pytest.raises(ValueError, match="step"):
        S.elasticities(step=0.5)
