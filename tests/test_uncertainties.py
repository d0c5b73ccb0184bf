"""Every fitted value with its standard error: lmfit's convention, one computation (identifiability) behind all."""
import json
import math
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

import tenscell
from tenscell._results import CORRELATION_THRESHOLD, plus_minus
from tenscell.fitting.scores import fit_structural_damping, structural_damping_moduli
from tenscell.fitting import VoigtModel

DATA = Path(__file__).parent / "data"


def test_lmfit_convention():
    assert plus_minus(0.23098637, 0.01329809) == "0.230986 +/- 0.0133 (5.76%)"
    assert plus_minus(0.23098637, 0.01329809, digits=4) == "0.231 +/- 0.013 (5.76%)"
    assert plus_minus(2.5, None, "Pa", "(at its lower bound)") == "2.5 Pa +/- not determined (at its lower bound)"
    assert plus_minus(2.5, math.inf) == "2.5 +/- not determined"


def test_structural_damping_errors_agree_with_curve_fit():
    """An independent computation (scipy's curve_fit covariance, finite-difference Jacobian, in the natural
    parameters G0, x, μ) gives the same standard errors and correlations to first order."""
    data = tenscell.read_data(DATA / "trios_lims_temperature_steps.txt", step=1)
    law = fit_structural_damping(data)
    G0, alpha, eta = (law.value(k) for k in ("G0", "alpha", "eta"))
    w = 2 * np.pi * data.frequency_hz
    y = np.concatenate([np.log10(data.G_storage), np.log10(data.G_loss)])

    def model(_, G0, x, mu):
        G = structural_damping_moduli(w, G0, x, mu)
        return np.concatenate([np.log10(G.real), np.log10(G.imag)])

    p, cov = scipy.optimize.curve_fit(model, w, y, p0=[G0, 1 + alpha, eta], xtol=1e-14, ftol=1e-14)
    np.testing.assert_allclose(p, [G0, 1 + alpha, eta], rtol=1e-6)
    se = np.sqrt(np.diag(cov))
    # the Jacobians differ by curve_fit's finite differences (relative ~1e-7): 1e-4 is far above that and far
    # below the factor (n-p)/(n-rank) = 1 or a missed ln -> linear chain rule (a factor x−1 ≈ 0.2) would make
    errors = dict(zip((p_.name for p_ in law.parameters), (e for e, _ in law.standard_errors)))
    ours = [errors["G0"], errors["alpha"], errors["eta"]]
    np.testing.assert_allclose(ours, se, rtol=1e-4)
    rho = cov / np.outer(se, se)
    listed = {(a, b): r for a, b, r in law.correlations()}
    listed.update({(b, a): r for (a, b), r in list(listed.items())})
    names = ("G0", "alpha", "eta")
    for i in range(3):
        for j in range(i + 1, 3):
            if abs(rho[i, j]) >= CORRELATION_THRESHOLD:
                assert listed[(names[i], names[j])] == pytest.approx(rho[i, j], abs=1e-4)
            else:
                assert (names[i], names[j]) not in listed
    text = law.report()
    for k in ("G0:", "alpha:", "eta:"):
        assert "+/-" in next(line for line in text.splitlines() if line.strip().startswith(k))
    doc = law.to_dict()
    row = next(p_ for p_ in doc["parameters"] if p_["name"] == "alpha")
    assert row["stderr"] == pytest.approx(se[1], rel=1e-4) and row["stderr_note"] == ""


@pytest.fixture(scope="module")
def fitted():
    data = tenscell.read_data(DATA / "trios_lims_temperature_steps.txt", temperature=25)
    return tenscell.fit(data, model=VoigtModel(tendons="per-family"), starts=1, progress=False)


def test_every_parameter_shows_its_error(fitted):
    ident = fitted.identifiability()
    df = fitted.parameters_dataframe()
    assert list(df.columns[:5]) == ["name", "value", "stderr", "stderr_percent", "stderr_note"]
    for (_, row), p in zip(df.iterrows(), fitted.parameters):
        if p.name in ident.names:
            se_ln = ident.standard_errors[ident.names.index(p.name)]
            if np.isfinite(se_ln):
                assert row["stderr"] == pytest.approx(p.value * se_ln, rel=1e-12)
                assert row["stderr_percent"] == pytest.approx(100 * se_ln, rel=1e-12)
                continue
        assert np.isnan(row["stderr"]) and row["stderr_note"], row  # never a bare value: the note says why
    lines = fitted.report().split("[[Parameters]]")[1].split("[[Correlations]]")[0].splitlines()
    shown = [line for line in lines if line.strip() and not line.strip().startswith(("(", "[["))]
    # each value with its error (+/- x, or a factor ×/÷ beyond 50 %), or "(—)" and the reason once under the table
    assert len(shown) == len(fitted.parameters) and all(("+/-" in line) or ("×/÷" in line) or ("(—)" in line)
                                                        for line in shown)
    reasons = [line for line in lines if line.strip().startswith("(—) not determined:")]
    undetermined = [p.name for p, (se, _) in zip(fitted.parameters, fitted.standard_errors) if se is None]
    assert sorted(n.strip() for line in reasons for n in line.split(": ")[1].split(",")) == \
        sorted(undetermined)
    for a, b, r in fitted.correlations():
        assert abs(r) >= CORRELATION_THRESHOLD
        i, j = ident.labels.index(a), ident.labels.index(b)
        assert r == ident.correlation[i, j]


def test_fit_json_carries_the_errors(fitted):
    doc = json.loads(json.dumps(fitted.to_dict(), allow_nan=False))
    for p, (se, note) in zip(doc["parameters"], fitted.standard_errors):
        assert p["stderr"] == se and p["stderr_note"] == note
    assert doc["correlations"]["threshold"] == CORRELATION_THRESHOLD


def test_model_standard_errors_and_fit_csv(fitted, tmp_path):
    """The fitted curve's standard error at each point: σ·sqrt(h)/w with h the hat matrix's diagonal, whose trace is
    the number of seen combinations (a projection's trace is its rank); written to fit.csv beside each model value."""
    import csv

    from tenscell.io.tables import fit_table

    ident = fitted.identifiability()
    assert np.sum(ident.leverage) == pytest.approx(ident.rank, rel=1e-10)
    assert np.all((ident.leverage >= -1e-12) & (ident.leverage <= 1 + 1e-12))
    se = fitted.model_standard_errors()
    assert se.shape == fitted.residuals.shape and np.all(se >= 0)
    np.testing.assert_allclose(se, ident.sigma * np.sqrt(np.clip(ident.leverage, 0, None)), rtol=1e-12)  # w = 1
    header, rows = fit_table(fitted, fitted)
    i, j = header.index("G_storage_model_Pa"), header.index("G_storage_model_stderr_Pa")
    n = fitted.datasets[0].n
    for k, row in enumerate(rows):
        assert row[j] == pytest.approx(row[i] * math.log(10) * se[k], rel=1e-12)
    path = tmp_path / "fit.csv"
    with open(path, "w", newline="") as fh:
        csv.writer(fh).writerows([header, *rows])
    assert len(rows) == n
