"""What a notebook shows for a result (``_repr_html_``, rendered by tenscell.reports.html): the numbers it holds,
with their errors and where the data came from, and every text escaped."""
from __future__ import annotations

import html
import math
import re

import numpy as np
import pytest

import tenscell as tc
from tenscell._results import CORRELATION_THRESHOLD, LN_FACTOR_FROM, ln_error, plus_minus
from tenscell.io.data import RheologyData


def _cells(text: str) -> list[str]:
    return [html.unescape(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", text, flags=re.S)]


@pytest.fixture(scope="module")
def sweep():
    f = np.logspace(-1, 2, 10)
    G = 300.0 * (1j * f) ** 0.2 + 1j * 2 * np.pi * f * 0.5
    sd = 0.05 * np.abs(G)
    return RheologyData(f, G.real, G.imag, G_storage_sd=sd, G_loss_sd=sd, source="<img src=x onerror=alert(1)>.csv")


@pytest.fixture(scope="module")
def fitted(sweep):
    return tc.fit(sweep, model="structural-damping+newtonian", starts=2, seed=0, progress=False)


def test_a_fit_shows_verdict_quality_provenance_and_parameters_with_errors(fitted):
    out = fitted._repr_html_()
    assert out.startswith('<div class="tenscell-repr">') and out.endswith("</div>")
    cells = _cells(out)
    assert fitted.verdict in cells
    aic, bic = fitted.information_criteria()
    aic_l, bic_l = fitted.information_criteria_lmfit()
    criteria = next(c for c in cells if c.startswith(f"{aic:.1f} / {bic:.1f} ("))
    assert "lmfit's convention" in criteria and criteria.endswith(f"{aic_l:.1f} / {bic_l:.1f}")  # both, side by side
    assert f"{fitted.rms_log10_error:.4g}" in " ".join(cells)
    # provenance: the line the reader recorded, escaped (the file name holds markup)
    assert fitted.data.provenance.line() in cells
    assert "<img" not in out and "&lt;img src=x onerror=alert(1)&gt;.csv" in out
    # every parameter: its value and its error as the reports give it (a percentage or a factor)
    for p, (se, _) in zip(fitted.parameters, fitted.standard_errors):
        row = cells[cells.index(p.name): cells.index(p.name) + 4]
        assert float(row[1]) == pytest.approx(p.value, rel=1e-4)
        assert row[3].startswith(ln_error(se / p.value) if se is not None else "—")


def test_correlations_are_listed_as_lmfit_lists_them(fitted):
    pairs = fitted.correlations()
    assert all(abs(r) >= CORRELATION_THRESHOLD for _, _, r in pairs)
    assert [abs(r) for _, _, r in pairs] == sorted((abs(r) for _, _, r in pairs), reverse=True)
    out = html.unescape(fitted._repr_html_())
    for a, b, r in pairs[:10]:
        assert f"C({a}, {b}) = {r:+.4f}" in out
    assert f"C({a}, {b}) = {r:+.4f}" in fitted.report()  # the text report lists them too
    assert fitted.to_dict()["correlations"]["pairs"] == [{"a": a, "b": b, "rho": r} for a, b, r in pairs]


def test_errors_of_ln_parameters_are_factors_beyond_half_the_value():
    # one standard error σ of ln p moves p by a factor exp(σ): ±103 % would suggest a negative stiffness
    assert ln_error(0.048) == "±4.8 %"
    assert ln_error(1.033) == f"×/÷ {math.exp(1.033):.3g}" == "×/÷ 2.81"
    assert ln_error(None) == ln_error(math.inf) == ""
    assert plus_minus(6.675, 6.9, "N", ln=True) == f"6.675 N ×/÷ {math.exp(6.9 / 6.675):.3g}"
    assert plus_minus(6.675, 0.9 * LN_FACTOR_FROM * 6.675, "N", ln=True).endswith("(45.00%) N")
    # a quantity that may change sign keeps its absolute error; beyond the value it is a multiple, not 1626219 %
    assert plus_minus(0.002, 32.5) == "0.002 +/- 32.5 (1.6e+04× the value)"


def test_the_text_report_says_not_determined_once_per_reason():
    f = np.logspace(-1, 2, 6)
    data = RheologyData(f, 100 * f ** 0.2, 20 * f ** 0.2)
    r = tc.fit(data, tendons="per-tendon", starts=1, seed=0, progress=False)
    text = r.report()
    missing = [p.name for p, (se, _) in zip(r.parameters, r.standard_errors) if se is None]
    assert missing, "a 36-parameter fit to 6 points leaves parameters undetermined"
    assert "+/- not determined" not in text.split("[[Parameters]]")[1].split("[[Correlations]]")[0]
    reasons = [line for line in text.splitlines() if line.strip().startswith("(—) not determined:")]
    assert len(reasons) == len({note.strip("()") or "not determined by the data"
                                for _, (se, note) in zip(r.parameters, r.standard_errors) if se is None})
    # the Markdown report's error table: σ unknown is said once, not in every cell
    from tenscell.reports.fit import fit_markdown

    errors = fit_markdown(r).split("## Errors")[1].split("\n## ")[0]
    if r.identifiability().sigma is None:
        assert errors.lower().count("not determined") == 1 and "σ is unknown" in errors
    assert "(σ unknown)" not in errors


def test_data_show_what_they_are_and_where_they_came_from(sweep):
    out = sweep._repr_html_()
    assert "RheologyData: 10 points, frequency sweep" in out and "stated" in _cells(out)
    assert "<img" not in out
    creep = tc.read_data("tests/data/creep_compliance.tsv")
    cells = _cells(creep._repr_html_())
    assert creep.provenance.line() in cells
    assert f"{creep.time_s[0]:.4g}" in cells and f"{creep.compliance[-1]:.4g}" in cells


def test_a_response_grid_and_a_fitted_model_show_their_numbers(fitted):
    f = np.logspace(-1, 2, 9)
    resp = tc.frequency_response(tc.paper_cell(), f, [500.0, 1000.0])
    cells = _cells(resp._repr_html_())
    for i in range(2):
        for k in (0, 4, 8):
            assert f"{resp.G_storage[i, k]:.4g}, {resp.G_loss[i, k]:.4g}" in cells
    model = fitted.model
    cells = _cells(model._repr_html_())
    assert model.describe() in cells
    for name, value in model.values.items():
        assert cells[cells.index(name) + 1] == f"{value:.5g}"


def test_a_model_comparison_names_the_preferred_model(fitted, sweep):
    from tenscell.fitting.scores import compare_models

    other = tc.fit(sweep, model="structural-damping", starts=2, seed=0, progress=False)
    comp = compare_models(fitted, structural=False, baselines=(other,))
    out = html.unescape(comp._repr_html_())
    assert f"BIC prefers {comp.best('bic')}" in out
    for s in comp.scores:
        assert f"{s.bic:.1f}" in _cells(out)
