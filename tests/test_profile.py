"""Profile-likelihood intervals, identified combinations and what the structure carries, checked against what a
correct analysis must satisfy.

* **A known one-sided answer.** A pure power law (the structural-damping law, no Newtonian term) with 5 % standard
  deviations, fitted by the law *with* a Newtonian term: the best fit puts the viscosity η at its lower bound, so
  the profile of η must be open below and bounded above. Its 95 % end is checked independently: a full multi-start
  fit with η held there must lie 3.84 above the best in χ² (the data's sd are known, so −2 ln L is χ² plus a
  constant). The tolerance, 0.1 of 3.84, is that of the crossing's linear interpolation after 5 bisections
  (the bracket is then 1/32 of a grid step of 1.4 decades, over which χ² grows by a few units).
* **The quadratic limit.** For a well-determined parameter of a model that is nearly linear in its ln-parameters
  (G0 and α of the power law, fitted by the law itself), Wilks' interval is the local one, ``exp(ln θ ± z·se)``:
  within 2 % here.
* **Invariance to the grid**: 7 or 11 starting values give the same interval within the bisection's resolution.
* **Identified pairs**: a Jacobian that sees ln a + ln b strongly and ln a − ln b weakly (or not at all) gives the
  combination a·b with its value and the standard error of the covariance (JᵀJ)⁻¹ (pseudo-inverse when exact).
* **The strut-length gauge**: the strut length of the paper's convention, L/√s, does not move along
  ``(P, EA, c, L) → (λ²P, λ²EA, λc, λL)``.
* **A mechanism's held field** (``beta`` of ``springpot-tension+visc``): freed only to be profiled; along its
  profile ``beta·s`` stays put (the data determine the product), and the profile passes through the fit itself.
"""
from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from tenscell import fitting
from tenscell.cli import main as cli_main
from tenscell.fitting.identifiability import identifiability, simple_exponent
from tenscell.fitting.models.formulas import structural_damping_moduli
from tenscell.fitting.profile import LEVELS, needs_profile, profile_intervals, profile_parameter
from tenscell.fitting.records import FitParameter, information_criteria
from tenscell.fitting.shares import prestress_scale
from tenscell.io import bundled
from tenscell.io.data import RheologyData
from tenscell.reports.fit import fit_markdown

F = np.logspace(-2, 2, 16)
SD = 0.05  # relative standard deviation of G', G''


def _power_law() -> RheologyData:
    G = structural_damping_moduli(2 * np.pi * F, 300.0, 1.2, 0.0)  # no Newtonian term
    return RheologyData(F, G.real, G.imag, G_storage_sd=SD * G.real, G_loss_sd=SD * G.imag)


@pytest.fixture(scope="module")
def newtonian_fit():
    return fitting.fit(_power_law(), model="structural-damping+newtonian", starts=3, seed=0, progress=False)


def _m2lnL(result) -> float:
    pr = result.problem
    return information_criteria(pr.residuals(result.theta), 0, sigma_known=True, weights=pr.weights)[2]


# ---- a known one-sided answer ------------------------------------------------------------------------------------
def test_the_viscosity_the_data_barely_see_is_bounded_above_only(newtonian_fit):
    r = newtonian_fit
    assert dict(needs_profile(r)) == {"eta": "at its lower bound"}
    p = profile_parameter(r, "eta", refine=5, progress=False)
    for iv in p.intervals:
        assert iv.lower is None and iv.upper is not None and iv.kind == "bounded above"
        assert not iv.disjoint
    assert p.interval(0.6827).upper < p.interval(0.95).upper
    # independently: the best fit with eta held at the 95 % end lies 3.84 above the best in chi²
    held = fitting.fit(_power_law(), model="structural-damping+newtonian", starts=4, seed=1, progress=False,
                       fixed={"eta": p.interval(0.95).upper})
    assert _m2lnL(held) - p.reference == pytest.approx(LEVELS[1][1], abs=0.1 * LEVELS[1][1])
    assert _m2lnL(r) - p.reference == pytest.approx(0.0, abs=1e-6)  # the fit is the profile's minimum
    assert np.all(p.delta >= -1e-9)
    assert "bounded above by" in p.interval(0.95).text("Pa·s") and "not bounded below within" in \
        p.interval(0.95).text("Pa·s")


def test_the_interval_does_not_depend_on_the_starting_grid(newtonian_fit):
    a = profile_parameter(newtonian_fit, "eta", points=7, refine=5, progress=False)
    b = profile_parameter(newtonian_fit, "eta", points=11, refine=5, progress=False)
    lo, hi = (math.log(x) for x in a.bounds)
    resolution = (hi - lo) / 6 / 2**5  # the widest grid step over the bisections
    for level, _ in LEVELS:
        assert abs(math.log(a.interval(level).upper / b.interval(level).upper)) <= resolution


@pytest.mark.parametrize("name", ["G0", "alpha"])
def test_a_well_determined_parameter_has_the_local_interval(name):
    # the law without the Newtonian term: with it, eta (at its bound, held by the local analysis) is refitted by the
    # profile and widens G0's interval on the side where a Newtonian term helps
    r = fitting.fit(_power_law(), model="structural-damping", starts=2, seed=0, progress=False)
    ident = r.identifiability()
    se = float(ident.standard_errors[ident.names.index(name)])
    p = profile_parameter(r, name, refine=5, progress=False)
    v = r.value(name)
    for (_, t), iv in zip(LEVELS, p.intervals):
        z = math.sqrt(t)
        assert iv.kind == "two-sided"
        assert math.log(iv.lower / v) == pytest.approx(-z * se, rel=0.02)
        assert math.log(iv.upper / v) == pytest.approx(z * se, rel=0.02)


def test_profile_set_and_its_documents(newtonian_fit):
    ps = profile_intervals(newtonian_fit, progress=False)
    assert [p.name for p in ps] == ["eta"] and ps.refits == ps["eta"].refits > 0
    doc = ps.to_dict()
    json.dumps(doc, allow_nan=False)
    assert doc["profiles"][0]["intervals"][1]["lower"] is None  # open below: null
    df = ps.to_dataframe()
    assert list(df["level"]) == [lv for lv, _ in LEVELS] and np.isnan(df["lower"]).all()
    assert "delta_m2lnL" in ps["eta"].to_dataframe().columns
    with pytest.raises(KeyError, match="no profile of"):
        ps["G0"]
    asked = profile_intervals(newtonian_fit, ["G0"], points=5, refine=1, progress=False)
    assert asked["G0"].reason == "asked for"


def test_bad_requests(newtonian_fit):
    with pytest.raises(ValueError, match="no parameter named"):
        profile_parameter(newtonian_fit, "nope")
    with pytest.raises(ValueError, match="points"):
        profile_parameter(newtonian_fit, "eta", points=2)
    with pytest.raises(ValueError, match="parameters must be"):
        profile_intervals(newtonian_fit, "some")
    with pytest.raises(ValueError, match="do not overlap"):
        profile_parameter(newtonian_fit, "alpha", bounds=(2.0, 3.0))


# ---- identified pairs ------------------------------------------------------------------------------------------
@dataclasses.dataclass
class _Linear:
    """A problem whose weighted residuals are J·θ − y (σ = 1 known)."""

    J: np.ndarray
    names: tuple = ("a", "b", "c")

    @property
    def free(self):
        return np.ones(len(self.names), dtype=bool)

    @property
    def n_params(self):
        return len(self.names)

    def gauge(self):
        return np.zeros(self.n_params)

    def parameters(self, theta):
        return tuple(FitParameter(n, float(math.exp(t)), 1e-9, 1e9, "") for n, t in zip(self.names, theta))

    def jacobian(self, theta):
        return self.J

    def residuals(self, theta):
        return 0.01 * np.ones(self.J.shape[0])


@pytest.mark.parametrize("eps", [1e-3, 0.0])
def test_a_product_whose_factors_are_not_determined(eps):
    rng = np.random.default_rng(3)
    u, w, x = rng.normal(size=(3, 30))
    J = 10 * np.column_stack([u, u + eps * w, x])  # sees ln a + ln b, and ln a − ln b only through eps (or not at all)
    theta = np.log([2.0, 5.0, 3.0])
    ident = identifiability(_Linear(J), theta, sigma_known=True)
    (combo,) = ident.identified()
    assert dict(combo.exponents) == {"a": 1.0, "b": 1.0}
    assert combo.words() == "a·b" and combo.value == pytest.approx(10.0)
    g = np.array([1.0, 1.0, 0.0])
    expected = math.sqrt(g @ np.linalg.pinv(J.T @ J) @ g)
    assert combo.standard_error == pytest.approx(expected, rel=1e-6)
    assert all(not se <= 0.1 for _, se in combo.factor_errors)
    assert ident.to_dict()["identified_combinations"][0]["words"] == "a·b"


def test_nothing_is_identified_when_each_parameter_is_determined():
    rng = np.random.default_rng(5)
    ident = identifiability(_Linear(rng.normal(size=(30, 3)) * 100), np.zeros(3), sigma_known=True)
    assert ident.identified() == ()


def test_simple_exponents():
    assert simple_exponent(0.97) == 1.0 and simple_exponent(-0.52) == -0.5 and simple_exponent(0.8) == 0.8


# ---- the prestress scale under the gauge -----------------------------------------------------------------------
def test_the_paper_strut_length_does_not_move_along_the_gauge():
    r = fitting.fit([bundled("stamenovic2002"), bundled("fabry2001")], tendons="uniform", starts=2, seed=0, hops=3,
                    progress=False)
    pr = r.problem
    g = pr.gauge()[pr.free]
    base = prestress_scale(r)
    for lam in (0.5, 3.0):
        theta = r.theta + math.log(lam) * g
        moved = dataclasses.replace(r, theta=theta, parameters=pr.parameters(theta))
        sc = prestress_scale(moved)
        assert sc.L_cell == pytest.approx(lam * base.L_cell, rel=1e-9)
        assert sc.L_paper == pytest.approx(base.L_paper, rel=1e-9)
        assert sc.ratio == pytest.approx(base.ratio, rel=1e-9)
    assert r.structure.shares is None  # the Voigt cell: no tension terms to share with


# ---- a mechanism's held field ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def tension_fit():
    return fitting.fit([bundled("stamenovic2002"), bundled("fabry2001")], model="springpot-tension+visc", starts=2,
                       seed=0, hops=4, progress=False)


def test_a_held_field_is_profiled_freed_and_its_product_with_s_stays_put(tension_fit):
    r = tension_fit
    assert ("beta", "held at 1000 by the mechanism (not fitted)") in needs_profile(r)
    p = profile_parameter(r, "beta", points=5, refine=1, progress=False)
    assert p.held and "beta" not in r.problem.names and p.value == 1000.0
    own = int(np.argmin(np.abs(np.log(p.values / 1000.0))))
    # the profile passes through the fit itself: no refit at the held value
    pr = r.problem
    m2 = information_criteria(pr.residuals(r.theta), 0, sigma_known=False)[2]
    assert p.m2lnL[own] == pytest.approx(m2, abs=1e-9)
    assert tuple(p.others) == tuple(n for n in pr.names)
    np.testing.assert_allclose(p.other_values[own], [q.value for q in r.parameters], rtol=1e-12)
    s = {c.other: c for c in p.compensations}["s"]
    assert s.exponent == 1.0 and s.words == "beta·s"
    assert s.value == pytest.approx(1000.0 * r.value("s"), rel=1e-12)
    assert s.spread_ln < 0.25 * s.range_ln
    lo, hi = p.share_range()
    assert lo <= r.structure.quantities.values["geometric_storage"][0] <= hi


def test_what_the_structure_carries_in_the_report_and_fit_json(tension_fit, tmp_path):
    r = tension_fit
    st = r.structure
    sh = st.shares
    np.testing.assert_allclose(st.quantities.values["geometric_storage"], sh.share("geometric", "storage"))
    np.testing.assert_allclose(st.quantities.values["geometric_storage"] + st.quantities.values["constitutive_storage"],
                               1.0, atol=1e-12)
    assert st.scale.L_paper == pytest.approx(1.0 / math.sqrt(r.value("s")))
    assert st.scale.in_gauge_window == (0.1 <= st.scale.L_paper <= 10.0)
    md = fit_markdown(r)
    order = [md.index(h) for h in ("## What the data determine", "## What the structure carries", "## Parameters")]
    assert order == sorted(order)
    assert "Their profile intervals were not computed" in md  # beta and EA need one; none was asked for
    r.compute_profile(["beta"], points=5, refine=1, progress=False)
    md = fit_markdown(r)
    assert "**beta·s = " in md and "the P·Kp share of ΔG′ runs from" in md
    from tenscell.io.outputs import write_json

    write_json(tmp_path / "fit.json", r.to_dict())
    doc = json.loads((tmp_path / "fit.json").read_text())
    assert doc["structure"]["shares"]["geometric_storage"]["value"][0] == pytest.approx(
        float(st.quantities.values["geometric_storage"][0]))
    assert doc["structure"]["prestress"]["L_paper_convention_m"] == pytest.approx(st.scale.L_paper)
    assert doc["profile"]["profiles"][0]["name"] == "beta"


# ---- the command line ----------------------------------------------------------------------------------------------
def _csv(path):
    d = _power_law()
    rows = ["frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa,G_loss_sd_Pa"]
    rows += [f"{f:.10g},{a:.10g},{b:.10g},{c:.10g},{e:.10g}"
             for f, a, b, c, e in zip(d.frequency_hz, d.G_storage, d.G_loss, d.G_storage_sd, d.G_loss_sd)]
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("flag", ["yes", "no"])
def test_fit_profile_flag(tmp_path, flag):
    data = _csv(tmp_path / "pl.csv")
    out = tmp_path / "out"
    code = cli_main(["fit", str(data), "--model", "structural-damping+newtonian", "--validate", "no", "--starts", "2",
                     "--profile", flag, "--out", str(out)])
    assert code == 0
    doc = json.loads((out / "fit.json").read_text())
    report = (out / "report.md").read_text()
    if flag == "no":
        assert doc["profile"] is None and "were not computed" in report
    else:
        assert [p["name"] for p in doc["profile"]["profiles"]] == ["eta"]
        assert "## Profile likelihood" in report and "bounded above by" in report


def test_fit_profile_flag_refuses_other_values(tmp_path, capsys):
    assert cli_main(["fit", str(_csv(tmp_path / "pl.csv")), "--profile", "maybe", "--out", str(tmp_path / "o")]) == 2
    assert "--profile" in capsys.readouterr().err
