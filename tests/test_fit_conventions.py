"""How a fit's statistics are counted, said where they are shown (issue 36 item 2).

AIC and BIC: tenscell's full Gaussian log-likelihood (σ counted as a parameter when it is estimated) and lmfit's
n ln(χ²/n) + 2k beside it; the two differ by a constant for data without standard deviations, so model rankings
agree. A fit's status: tolerance met, an optimum that misses the tolerance, or a search stopped by its budget.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tenscell import fitting
from tenscell.fitting.records import CRITERIA_CONVENTION, STATUSES, information_criteria, lmfit_criteria
from tenscell.io.data import RheologyData, bundled


def test_lmfit_and_tenscell_differ_by_the_gaussian_constant_and_sigma():
    rng = np.random.default_rng(3)
    for n, k in [(50, 5), (12, 3), (300, 36)]:
        r = rng.normal(0, 0.02, n)
        aic, bic, _ = information_criteria(r, k, sigma_known=False)
        aic_l, bic_l = lmfit_criteria(r, k)
        const = n * (1 + math.log(2 * math.pi))
        assert aic - aic_l == pytest.approx(const + 2, abs=1e-9 * abs(aic))
        assert bic - bic_l == pytest.approx(const + math.log(n), abs=1e-9 * abs(bic))
    # the pair: lmfit -291.3 and tenscell -147.4 on the same fit are 50 residuals apart by this constant
    assert 50 * (1 + math.log(2 * math.pi)) + 2 == pytest.approx(-147.4 - (-291.3), abs=0.05)


def test_lmfit_criteria_are_lmfits_own():
    lmfit = pytest.importorskip("lmfit")
    x = np.linspace(0, 1, 40)
    y = 2 * x + 1 + np.random.default_rng(0).normal(0, 0.05, x.size)
    params = lmfit.Parameters()
    params.add("a", 1.0)
    params.add("b", 0.0)
    res = lmfit.minimize(lambda p: p["a"] * x + p["b"] - y, params)
    assert lmfit_criteria(res.residual, res.nvarys) == pytest.approx((res.aic, res.bic), rel=1e-12)


def test_rankings_agree_without_standard_deviations():
    rng = np.random.default_rng(1)
    fits = [(rng.normal(0, s, 60), k) for s, k in [(0.01, 8), (0.012, 4), (0.02, 2)]]
    ours = [information_criteria(r, k, sigma_known=False)[0] for r, k in fits]
    theirs = [lmfit_criteria(r, k)[0] for r, k in fits]
    assert np.argsort(ours).tolist() == np.argsort(theirs).tolist()
    assert np.allclose(np.diff(ours), np.diff(theirs))


@pytest.fixture(scope="module")
def result():
    return fitting.fit(bundled("fabry2001"), model="springpot+visc", starts=1, hops=2, progress=False)


def test_the_fit_states_both_conventions_everywhere(result, tmp_path):
    from tenscell.io.outputs import write_json
    from tenscell.reports._format import num
    from tenscell.reports.fit import fit_markdown
    from tenscell.reports.html import fit_html

    doc = result.to_dict()
    ic = doc["information_criteria"]
    assert (ic["AIC"], ic["BIC"]) == (doc["AIC"], doc["BIC"]) == result.information_criteria()
    assert (ic["lmfit"]["AIC"], ic["lmfit"]["BIC"]) == result.information_criteria_lmfit()
    assert ic["convention"] == CRITERIA_CONVENTION and ic["sigma_counted"] is True
    assert ic["k"] == ic["lmfit"]["k"] + 1  # σ estimated: counted by tenscell, not by lmfit
    write_json(tmp_path / "fit.json", doc)
    assert json.loads((tmp_path / "fit.json").read_text())["status"] == result.status
    md = fit_markdown(result)
    html = fit_html(result)
    aic_l, bic_l = result.information_criteria_lmfit()
    for text, shown in ((md, num(aic_l, 5)), (html, f"{aic_l:.1f}")):
        assert "lmfit" in text and "σ" in text and shown in text.replace("−", "-")
    assert STATUSES[result.status] in md


def _power_law(n=8):
    f = np.logspace(-1, 2, n)
    return RheologyData(frequency_hz=f, G_storage=300 * f ** 0.2 * (1 + 0.02 * np.sin(5 * f)),
                        G_loss=80 * f ** 0.25)


def test_a_status_for_each_way_a_fit_ends():
    data = _power_law()
    met = fitting.fit(data, model="springpot+visc", starts=1, hops=2, tolerance=0.5, progress=False)
    assert met.status == "tolerance met" and met.converged
    budget = fitting.fit(data, model="springpot+visc", starts=1, hops=1, tolerance=1e-9, progress=False)
    assert budget.status == "stopped by budget" and not budget.converged
    assert "budget" in budget.stop_reason and budget.verdict == "NOT converged: stopped by its budget"
    optimum = fitting.fit(data, model="springpot+visc", starts=2, hops=40, patience=2, tolerance=1e-9,
                          progress=False)
    assert optimum.status == "optimum, tolerance not met" and not optimum.converged
    assert optimum.verdict == "tolerance not met at an optimum" and "budget" not in optimum.stop_reason
