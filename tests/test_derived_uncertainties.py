"""Every number a fit report derives from the parameters carries its ± (delta method), or says "not determined".

The library propagates the parameters' covariance Σ = σ²(JᵀJ)⁺ through a forward-difference gradient in the
ln-parameters (step 1e-5, tenscell.fitting.derived). Here an independent propagation recomputes each quantity
with the public functions at θ ± h·e_k with another step (h = 1e-3, central), builds Σ from the problem's Jacobian
with numpy's pseudo-inverse, and compares. The two gradients differ by the truncation errors: forward about
1e-5·|g″/g′|/2 (measured ≤ 1.8e-4 relative at step 1e-4 on these quantities, so ≤ 2e-5 at 1e-5), central
h²·|g‴|/6 ≲ 1e-6; and by rounding ≲ 1e-13/1e-5 = 1e-8. The two covariances differ by rounding amplified by
cond(J)² (asserted below 1e8, so ≲ 1e-8). A relative tolerance of 1e-4 lies above all of these and far below any
real mistake (a missed factor σ, a wrong step, a gradient over the wrong parameters or a covariance of θ instead
of ln θ all change the result by O(1)).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import tenscell
from tenscell.fitting.curves import frequency_slopes, prestress_slopes
from tenscell.io.data import bundled
from tenscell.reports.fit import fit_markdown
from tenscell.fitting import VoigtModel, prestress_activity

H = 1e-3
RTOL = 1e-4


def _independent_errors(result, quantity) -> np.ndarray:
    """σ·sqrt(∇gᵀ (JᵀJ)⁻¹ ∇g) with the analysed parameters' Jacobian and a central difference of step H."""
    ident = result.identifiability()
    pr = result.problem
    free_index = np.cumsum(pr.free) - 1
    cols = [int(free_index[list(pr.names).index(n)]) for n in ident.names]
    J = pr.jacobian(result.theta)[:, cols]
    assert ident.rank == len(cols) and np.linalg.cond(J) < 1e4  # full rank, well conditioned (cond² < 1e8)
    cov = ident.sigma**2 * np.linalg.pinv(J.T @ J)
    grads = []
    for c in cols:
        sides = []
        for sign in (1, -1):
            theta = result.theta.copy()
            theta[c] += sign * H
            sides.append(np.atleast_1d(quantity(dataclasses.replace(result, theta=theta,
                                                                    parameters=pr.parameters(theta)))))
        grads.append((sides[0] - sides[1]) / (2 * H))
    G = np.array(grads).T  # (quantities, parameters)
    return np.sqrt(np.einsum("ij,jk,ik->i", G, cov, G))


@pytest.fixture(scope="module")
def prestress_fit():
    return tenscell.fit(bundled("stamenovic2002"), model=VoigtModel(tendons="per-family"), starts=1, progress=False)


@pytest.fixture(scope="module")
def frequency_fit():
    data = tenscell.read_data("tests/data/trios_lims_temperature_steps.txt", temperature=25)
    return tenscell.fit(data, model=VoigtModel(tendons="per-family"), starts=1, progress=False)


def test_prestress_lines_elasticities_and_creep_errors_match_an_independent_propagation(prestress_fit):
    r = prestress_fit
    q = r.derived
    checks = {
        "prestress_lines[0]": lambda x: prestress_slopes(x, dataset=0),
        "reference_storage": lambda x: prestress_activity(x).reference_storage,
        "reference_share": lambda x: prestress_activity(x).reference_share,
        "creep_alpha": lambda x: x.predicted_creep().alpha,
        "creep_J": lambda x: x.predicted_creep().J[::10],
    }
    for key, quantity in checks.items():
        ours = q.stderr[key][::10] if key == "creep_J" else q.stderr[key]
        assert np.all(np.isfinite(ours)) and np.all(ours > 0), key
        np.testing.assert_allclose(ours, _independent_errors(r, quantity), rtol=RTOL, err_msg=key)
    # the gauge: a prestress in N carries the error of P/L², and says so
    assert q.notes["reference_prestress_N"][0] == "(of P/L²)"
    # P = s × prestress (Pa): its relative error is that of s, whose ln is a parameter (1e-5: the forward step's
    # truncation, (e^h − 1)/h − 1 ≈ h/2 = 5e-6)
    ident = r.identifiability()
    np.testing.assert_allclose(q.stderr["reference_prestress_N"] / q.values["reference_prestress_N"],
                               ident.standard_errors[ident.names.index("s")], rtol=1e-5)


def test_frequency_slopes_match_an_independent_propagation(frequency_fit):
    r = frequency_fit
    f = r.data.frequency_hz

    def slopes(x):
        _, s1, s2 = frequency_slopes(x, float(f.min()), float(f.max()), 1000, dataset=0)
        return [s1.max(), s2.min(), s2.max()]  # interior extrema and end points: smooth in θ

    ours = r.derived.stderr["frequency_slopes[0]"][1:]
    np.testing.assert_allclose(ours, _independent_errors(r, slopes), rtol=RTOL)


def test_reports_show_the_errors(prestress_fit, frequency_fit):
    md = fit_markdown(prestress_fit)
    lines = md.split("straight lines over the data's prestress range")[1].splitlines()
    fitted = next(line for line in lines if line.startswith("| fitted model"))
    assert fitted.count("+/-") == 4
    data_row = next(line for line in lines if line.startswith("| data (least squares)"))
    assert data_row.count("+/-") == 4  # the data's own line: ordinary least-squares errors
    row = next(line for line in md.split("for each prestress of the data")[1].splitlines() if line.startswith("| 0"))
    assert row.count("+/-") == 4 and "(of P/L²)" in row
    creep = md.split("## Creep of the fitted cell")[1].split("## ")[0] if "## Creep of the fitted cell" in md else \
        md.split("## Predicted creep of the fitted cell")[1].split("## ")[0]
    table_rows = [line for line in creep.splitlines() if line.startswith("| ") and "t (s)" not in line]
    assert table_rows and all(line.count("+/-") == 2 for line in table_rows)
    errors = md.split("## Errors")[1]
    assert all(line.count("+/-") == 2 for line in errors.splitlines() if line.startswith("| ") and "Pa)" not in line
               and "---" not in line)
    text = frequency_fit.report()
    assert "decades" in text and "+/-" in next(line for line in text.splitlines() if "stiffness spread" in line)
    doc = frequency_fit.to_dict()["derived"]
    assert set(doc["frequency_slopes[0]"]) == {"value", "stderr", "note"}


def test_undetermined_numbers_say_so():
    """A per-tendon fit of a prestress sweep sees 10 of its 31 parameter combinations: the stiffness spread moves
    along unseen ones (and its top sits at a bound), so it has no error and the report says why."""
    r = tenscell.fit(bundled("stamenovic2002"), model=VoigtModel(tendons="per-tendon"), starts=1, progress=False)
    ident = r.identifiability()
    assert ident.rank < ident.n_analysed
    q = r.derived
    shown = [q.text("stiffness_spread", i) for i in range(3)]
    assert all("+/- not determined (" in s for s in shown), shown
    assert any("a combination the data do not see" in s for s in shown)
    md = fit_markdown(r)
    assert "+/- not determined (" in md.split("## Stiffness spread")[1].split("## ")[0]
    # the rule itself: a gradient along an unseen direction is not determined, along a seen one it is
    V = ident.directions
    assert ident.propagate(V[:, -1])[0] is None and "do not see" in ident.propagate(V[:, -1])[1]
    se, note = ident.propagate(V[:, 0])
    assert note == "" and se == pytest.approx(ident.sigma / ident.singular_values[0], rel=1e-12)
    unknown = dataclasses.replace(ident, sigma=None)
    assert unknown.propagate(V[:, 0]) == (None, "(σ unknown: as many seen combinations as residuals)")
    assert ident.propagate(np.zeros(ident.n_analysed))[0] is None  # set by bounds alone: not an estimate


def test_the_data_lines_errors_are_ordinary_least_squares():
    """The data's own lines against prestress: the slope and intercept errors of scipy.stats.linregress."""
    from scipy.stats import linregress

    from tenscell.io.data import RheologyData
    from tenscell.reports.fit import _data_slopes

    rng = np.random.default_rng(4)
    P = np.linspace(350.0, 1900.0, 7)
    Gs, Gl = 0.2 * P + 82 + rng.normal(0, 5, P.size), 0.05 * P + 32 + rng.normal(0, 2, P.size)
    data = RheologyData(frequency_hz=np.full(P.size, 0.1), G_storage=Gs, G_loss=Gl, prestress=P, source="lines")
    text = _data_slopes(data)
    for k, G in enumerate((Gs, Gl)):
        ref = linregress(P, G)
        for j, (value, err) in enumerate(((ref.slope, ref.stderr), (ref.intercept, ref.intercept_stderr))):
            shown = text[2 * k + j]
            assert f"{value:.4g}" in shown and f"{err:.2g}" in shown, (shown, value, err)


def test_a_worker_computing_half_the_gradient_changes_nothing(prestress_fit):
    """The fit command hands half of the moved parameter vectors to its worker process: same numbers (the same
    evaluations, in another process: identical up to the last bits of a different BLAS call order)."""
    from tenscell._parallel import background
    from tenscell.fitting.derived import derived_quantities
    from tenscell.fitting.result import report_quantities

    alone = prestress_fit.derived
    with background() as worker:
        shared = derived_quantities(prestress_fit, report_quantities, executor=worker)
    for key, se in alone.stderr.items():
        np.testing.assert_allclose(shared.stderr[key], se, rtol=1e-9, equal_nan=True, err_msg=key)
        assert shared.notes[key] == alone.notes[key]
