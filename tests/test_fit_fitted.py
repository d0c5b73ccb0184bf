"""A fitted cell is a model like any other: scaled cell, linear model, fit.json round trip, predicted creep."""
from __future__ import annotations

import json

import numpy as np
import pytest

import tenscell
from tenscell.fitting.fitted import FittedCell, load_fit, predicted_creep, scaled_cell
from tenscell.timedomain import creep_compliance, fit_power_law
from tenscell.fitting import VoigtModel

F = np.logspace(-2, 3, 9)


@pytest.fixture(scope="module")
def cell():
    return tenscell.paper_cell()


def _fitted_like(cell, seed=0):
    """Stiffnesses over 13 decades and a prestress far below them, as the Fig. 5 fit gives."""
    rng = np.random.default_rng(seed)
    return 10 ** rng.uniform(-7, 6, cell.m), 10 ** rng.uniform(0, 4, cell.m), 5.6e-8


@pytest.mark.parametrize("L", [0.37, 2.9])
def test_scaled_cell_is_the_cell_at_that_strut_length(cell, L):
    big = scaled_cell(cell, L)
    assert big.strut_length == pytest.approx(L, rel=1e-14)
    assert big.parameters["L"] == L
    np.testing.assert_allclose(big.T0, cell.T0, rtol=1e-12)
    ref = tenscell.paper_cell(L=L)
    EA, c, P = _fitted_like(cell)
    np.testing.assert_allclose(np.array(tenscell.moduli(tenscell.linearize(big, P=1.0, EA=EA, c=c), F)),
                               np.array(tenscell.moduli(tenscell.linearize(ref, P=1.0, EA=EA, c=c), F)), rtol=1e-9)
    # the gauge: the scaled cell with (λ²P, λ²EA, λc) has the reference cell's moduli
    np.testing.assert_allclose(np.array(tenscell.moduli(tenscell.linearize(big, P=L**2, EA=L**2 * EA, c=L * c), F)),
                               np.array(tenscell.moduli(tenscell.linearize(cell, P=1.0, EA=EA, c=c), F)), rtol=1e-9)


def test_fitted_model_round_trips_through_json_exactly(cell, tmp_path):
    EA, c, P = _fitted_like(cell, 1)
    model = FittedCell(cell=scaled_cell(cell, 0.7161638852932695), EA=EA, c=c, P=P, source="test")
    G = np.array(model.moduli(F))
    path = tmp_path / "fit.json"
    path.write_text(json.dumps({"rms_log10_error": 0.0, "model": model.to_dict()}))
    back = load_fit(path)
    np.testing.assert_array_equal(back.EA, model.EA)
    np.testing.assert_array_equal(back.c, model.c)
    assert back.P == model.P and back.s is None
    assert back.cell.describe() == model.cell.describe()
    np.testing.assert_allclose(np.array(back.moduli(F)), G, rtol=1e-12)
    assert "FittedCell" in repr(back)


def test_prestress_scale_model(cell):
    EA, c, _ = _fitted_like(cell, 2)
    model = FittedCell(cell=cell, EA=EA, c=c, s=0.01, prestress_pa=(350.0, 1000.0, 1900.0))
    assert model.prestress() == pytest.approx(10.0)  # the median measured prestress × s
    assert model.prestress(500.0) == pytest.approx(5.0)
    assert model.linear(500.0).P == pytest.approx(5.0)
    with pytest.raises(ValueError, match="either a prestress P"):
        FittedCell(cell=cell, EA=EA, c=c, P=1.0, s=0.01)
    with pytest.raises(ValueError, match="fitted prestress P"):
        FittedCell(cell=cell, EA=EA, c=c, P=1.0).prestress(100.0)


@pytest.mark.parametrize("content,match", [("not json", "not valid JSON"), ('{"x": 1}', "no fitted model"),
                                           ('{"model": {"format": "other"}}', "not a tenscell fitted model"),
                                           ('{"schema": 99, "model": {}}', "schema 99"),
                                           ('{"model": {"format": "tenscell-fitted-mechanism"}}', "model.mechanism: missing")])
def test_load_fit_errors_name_the_flag_and_file(tmp_path, content, match):
    p = tmp_path / "fit.json"
    p.write_text(content)
    with pytest.raises(ValueError, match=f"--from-fit .*{match}"):
        load_fit(p)


def test_predicted_creep_matches_timedomain(cell):
    EA, c, P = _fitted_like(cell, 3)
    lin = tenscell.linearize(scaled_cell(cell, 0.5), P=P, EA=EA, c=c)
    pc = predicted_creep(lin, 0.1, 10.0, 31)
    J = creep_compliance(lin, pc.t, continuum=True)
    np.testing.assert_allclose(pc.J, J, rtol=1e-12)
    assert pc.alpha == pytest.approx(fit_power_law(pc.t, J).alpha, rel=1e-12)
    assert pc.to_dict()["window_s"] == [0.1, 10.0]
    # in 1/Pa: long after every retardation time J tends to 1/G'(0) (a well-conditioned cell for this one)
    rng = np.random.default_rng(5)
    lin = tenscell.linearize(cell, P=10.0, EA=10 ** rng.uniform(-1, 2, cell.m), c=10 ** rng.uniform(-1, 1, cell.m))
    t_long = 1e3 * tenscell.timedomain.creep_spectrum(lin).times.max()
    assert predicted_creep(lin, t_long, 10 * t_long, 3).J[-1] == pytest.approx(1 / tenscell.response.static_modulus(lin),
                                                                                 rel=1e-9)


def test_linearize_law_accepts_a_fitted_cell_and_rejects_wrong_rest_lengths(cell):
    from tenscell.dynamics import linearize_law
    from tenscell.laws import voigt_law

    EA, c, P = _fitted_like(cell, 4)
    law = voigt_law(cell, P=P, EA=EA, c=c)
    lin = linearize_law(cell, law)  # round-off in EA·(l/l0 − 1) is of order eps·EA ≫ the tensions here
    assert lin.P == pytest.approx(P, rel=1e-3)
    bad = voigt_law(cell, P=P, EA=EA, c=c)
    object.__setattr__(bad, "l0", np.asarray(bad.l0) * (1 - 1e-9))  # a genuine departure from Eq. (11)
    with pytest.raises(ValueError, match="do not hold"):
        linearize_law(cell, bad)


# --- from a real fit ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def small_fits():
    from tenscell.fitting import fit
    from tenscell.io.data import bundled

    kw = dict(starts=1, hops=2, seed=0, progress=False)
    return (fit(bundled("fabry2001"), model=VoigtModel(tendons="per-family"), fixed={"L": 0.8}, **kw),
            fit(bundled("stamenovic2002"), model=VoigtModel(tendons="uniform"), **kw))


def test_fit_json_rebuilds_the_fitted_cell_to_rounding(small_fits, tmp_path):
    for result in small_fits:
        d = result.data
        path = tmp_path / "fit.json"
        path.write_text(json.dumps(result.to_dict()))
        back = load_fit(path)
        assert back.L == pytest.approx(result.model.L, rel=1e-15)
        if d.kind == "prestress":
            for p in np.unique(d.prestress):
                sel = d.prestress == p
                np.testing.assert_allclose(np.array(back.moduli(d.frequency_hz[sel], p)),
                                           np.array(result.moduli(d.frequency_hz[sel], prestress_pa=p)), rtol=1e-12)
        else:
            np.testing.assert_allclose(np.array(back.moduli(d.frequency_hz)), np.array(result.moduli(d.frequency_hz)),
                                       rtol=1e-12)
        # the linear model is the fitted cell's, at the fitted strut length
        assert result.linear.cell.strut_length == pytest.approx(result.model.L)
        np.testing.assert_array_equal(result.linear.EA, result.model.EA)


def test_report_has_identifiability_comparison_and_creep_sections(small_fits):
    from tenscell.fitting.scores import compare_models
    from tenscell.reports.fit import fit_markdown

    freq, pres = small_fits
    md = fit_markdown(freq, comparison=compare_models(freq))
    ident = freq.identifiability()
    creep = freq.predicted_creep()
    assert "## How well the data determine the parameters" in md
    assert f"see **{ident.rank} independent parameter combinations**" in md
    assert "## Against the phenomenological standard" in md and "structural damping (power law)" in md
    # a frequency sweep covering the creep window's frequencies constrained the creep: not called a prediction
    assert "## Creep of the fitted cell (restates the fitted data)" in md and "it is not a prediction" in md
    # a power law is printed only where the local exponent is constant to within POWER_LAW_SPAN
    from tenscell.reports.fit_analysis import POWER_LAW_SPAN

    power = float(np.ptp(creep.exponent)) <= POWER_LAW_SPAN
    assert (f"t^**{creep.alpha:.3g}**" in md) == power and ("not a power law" in md) == (not power)
    assert "not raw measurements" in md  # the bundled files say they are generated from published laws
    # L fixed: no gauge to remove, plain labels
    assert not ident.gauge_removed and ident.fixed == ("L",) and "c" in ident.labels
    md2 = fit_markdown(pres)
    assert "no prestress dependence" in md2 and "## Predicted creep" in md2
    doc = pres.to_dict()
    assert doc["model"]["s_m2"] == pytest.approx(pres.value("s")) and doc["identifiability"]["gauge_removed"]
    assert doc["predicted_creep"]["window_s"] == [0.1, 10.0]


def test_moduli_over_many_prestresses_equal_the_per_prestress_pipeline(small_fits):
    """FitResult.moduli batches a prestress grid (one eigensolve); each point must equal its own linear model."""
    from tenscell.linear.assembly import modulus
    from tenscell.response import compliance

    result = small_fits[1]  # the prestress sweep: its prestress (Pa) maps to the model's
    P_pa = np.array([300.0, 700.0, 1500.0, 2500.0])
    f = np.array([0.05, 0.1, 1.0, 20.0])
    Gs, Gl = result.moduli(f, prestress_pa=P_pa)
    for k in range(P_pa.size):
        lin = result.problem.linear_at(result.theta, float(result.prestress_model(P_pa[k])))
        G = modulus(compliance(lin, [f[k]]), result.problem.L_ref)[0]
        assert Gs[k] == pytest.approx(G.real, rel=1e-10) and Gl[k] == pytest.approx(G.imag, rel=1e-10)
    # a grid with one prestress keeps the per-prestress path; broadcasting still pairs f with P
    Gs1, _ = result.moduli(f, prestress_pa=P_pa[1])
    assert Gs1[1] == pytest.approx(Gs[1], rel=1e-10)


def test_cells_and_fits_pickle_for_worker_processes(small_fits):
    """A fit's baseline runs in a worker process and comes back pickled: cell and fit survive exactly."""
    import pickle

    result = small_fits[1]
    back = pickle.loads(pickle.dumps(result))
    assert back.cell.describe() == result.cell.describe() and dict(back.cell.parameters) == dict(result.cell.parameters)
    with pytest.raises(TypeError):  # still read-only after the trip
        back.cell.parameters["x"] = 1.0
    np.testing.assert_array_equal(back.theta, result.theta)
    f = np.array([0.1, 1.0])
    np.testing.assert_array_equal(back.moduli(f, prestress_pa=[500.0, 900.0]), result.moduli(f, prestress_pa=[500.0, 900.0]))
