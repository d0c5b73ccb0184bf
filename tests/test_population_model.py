"""Populations fitted as one (tenscell.fitting.models.population): layout, block-sparse Jacobian, recovery of known
shared and per-cell parameters, identifiability by cell blocks, the fitted population, the scores, the command."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tenscell.fitting import FittedPopulation, Population, fit, load_fit
from tenscell.fitting.identifiability import identifiability
from tenscell.fitting.models import model_from_dict
from tenscell.fitting.models.catalog import MECHANISMS
from tenscell.fitting.models.formulas import FORMULAS, lumped_formula
from tenscell.fitting.problem import PENALTY
from tenscell.fitting.population_scores import (comment_values, exponent_stiffness, measurement_errors,
                                                population_cells, score_population, springpot_exponent,
                                                springpot_exponent_error)
from tenscell.io.data import DataError, RheologyData, read_csv

F = np.array([1.0, 3.0, 10.0, 30.0, 100.0, 200.0])
FORMULA = "structural-damping+newtonian"
XIE = Path(__file__).resolve().parents[2] / "shared" / "data" / "real-cells" / "xie2024_population"


def formula_cells(n=12, noise=0.01, seed=0, alpha=0.2, eta=0.5, f=F):
    """Cells of the power law + Newtonian term with a log-normal G0 per cell and shared alpha, eta."""
    rng = np.random.default_rng(seed)
    G0 = np.exp(rng.normal(math.log(300.0), 0.6, n))
    cells = []
    for k, g in enumerate(G0):
        G = FORMULAS[FORMULA].complex_modulus({"G0": g, "alpha": alpha, "eta": eta}, 2 * np.pi * f, 1.0)
        e = np.exp(rng.normal(0.0, noise * math.log(10), (2, f.size)))
        cells.append(RheologyData(f, G.real * e[0], G.imag * e[1], source=f"cell{k:02d}",
                                  comments=(f"aspect_ratio={1 + 0.1 * k:.2f} area={100 + k}",)))
    return cells, G0


def mechanism_cells(n=4, noise=0.0, seed=1):
    """Cells of springpot-tension+visc with shared material parameters and a log-normal prestress P per cell."""
    rng = np.random.default_rng(seed)
    template = RheologyData(F, np.full(F.size, 100.0), np.full(F.size, 30.0), source="template")
    pb = MECHANISMS["springpot-tension+visc"].problem(template)
    shared = {"EA": 30.0, "kappa": 3.0, "alpha": 0.6, "alpha_T": 0.15, "eta_cytoplasm": 0.05}
    P = np.exp(rng.normal(math.log(2.0), 0.5, n))
    cells = []
    for k, p in enumerate(P):
        theta = np.log([shared.get(n, p) for n in pb.names])
        Gs, Gl = pb.moduli_at(theta, F, np.full(F.size, p))
        e = np.exp(rng.normal(0.0, noise * math.log(10), (2, F.size)))
        cells.append(RheologyData(F, Gs * e[0], Gl * e[1], source=f"mcell{k}"))
    return cells, shared, P


# ---- the layout and the block-sparse Jacobian --------------------------------------------------------------
def test_layout_shared_once_per_cell_once_and_residuals_of_each_cell():
    cells, _ = formula_cells(5)
    pb = Population(FORMULA, per_cell=("G0",)).problem(cells)
    assert pb.names == ("alpha", "eta", "G0[0]", "G0[1]", "G0[2]", "G0[3]", "G0[4]")
    assert pb.n_shared == 2 and pb.n_free == 7 and pb.n_residuals == 2 * 5 * F.size
    theta = np.log([0.2, 0.4, 100, 200, 300, 400, 500.0])
    r = pb.residuals(theta)
    for k, d in enumerate(cells):  # the population's rows of cell k are that cell's own residuals
        own = FORMULAS[FORMULA].problem(d)
        np.testing.assert_allclose(r[pb.rows(k)], own.residuals(np.log([100.0 * (k + 1), 0.2, 0.4])), rtol=1e-13)


@pytest.mark.parametrize("base, per_cell", [(FORMULA, ("G0",)), (FORMULA, ("G0", "eta")),
                                            ("springpot-tension+visc", ("P",)),
                                            ("springpot+visc", ("P", "kappa_actin"))])
def test_sparse_jacobian_equals_finite_differences(base, per_cell):
    cells = formula_cells(3)[0] if base == FORMULA else mechanism_cells(3)[0]
    pb = Population(base, per_cell=per_cell).problem(cells)
    theta = pb.initial_guess(np.random.default_rng(0))
    J = pb._jacobian_from(pb._evaluate_constrained(pb.full(theta), jac=True))
    assert not pb.sparse_jacobian and isinstance(J, np.ndarray)  # a few cells: dense, the search's exact steps
    np.testing.assert_allclose(J, pb.jacobian_fd(theta, step=1e-6), rtol=1e-5, atol=1e-7 * np.abs(J).max())


def test_stacked_residuals_and_jacobian_are_each_cells_own_with_its_penalty():
    """The population assembles its residuals and Jacobian from the cells' stacked moduli: in each cell's rows, the
    cell's own problem's residuals and Jacobian columns, also for a cell whose evaluation found no stable cell."""
    cells, _, _ = mechanism_cells(4, noise=0.05)
    pb = Population("springpot-tension+visc", per_cell=("P",)).problem(cells)
    phi = pb.full(pb.initial_guess(np.random.default_rng(0)))
    out = list(pb._evaluate_constrained(phi, jac=True))
    out[2] = (None, None)  # cell 2 unstable
    r, J = pb._residuals_from(tuple(out)), pb._jacobian_from(tuple(out))
    for k, (cp, p) in enumerate(zip(pb.cells, pb.cell_phis(phi))):
        own = out[k] if k != 2 else cp._evaluate_constrained(p, jac=True)
        np.testing.assert_allclose(r[pb.rows(k)], cp._residuals_from(out[k]), rtol=1e-14)
        cols = np.r_[np.arange(pb.n_shared), pb.own_index(k)]
        order = [cp.names.index(n) for n in pb.shared_names + pb.own_names]  # the cell's columns in the population's
        expect = cp._jacobian_from(out[k])[:, order]
        np.testing.assert_allclose(J[pb.rows(k)][:, cols], expect, rtol=1e-13, atol=1e-300)
        assert (k == 2) == np.all(r[pb.rows(k)] == PENALTY) and np.any(cp._jacobian_from(own) != 0)
    assert not np.any(J[pb.rows(2)])


def test_large_population_jacobian_is_sparse_and_holds_the_small_ones_blocks():
    """Beyond DENSE_FREE free parameters the Jacobian is CSR (the search's LSMR steps); a sub-population's dense one
    is its rows and columns."""
    from tenscell.fitting.models.population import DENSE_FREE

    cells, G0 = formula_cells(DENSE_FREE)
    pb = Population(FORMULA, per_cell=("G0",)).problem(cells)
    assert pb.n_free == DENSE_FREE + 2 and pb.sparse_jacobian
    theta = np.log(np.r_[0.25, 0.4, 1.1 * G0])
    J = pb._jacobian_from(pb._evaluate_constrained(pb.full(theta), jac=True))
    assert J.format == "csr"
    few = np.array([3, 17, 40])
    sub = pb.subset(few)
    assert not sub.sparse_jacobian
    Js = sub._jacobian_from(sub._evaluate_constrained(sub.full(theta[np.r_[0:2, 2 + few]]), jac=True))
    rows = np.concatenate([pb.rows(int(k)) for k in few])
    rows = np.concatenate([rows[rows < pb.n_points], rows[rows >= pb.n_points]])  # the sub-population's order
    np.testing.assert_array_equal(Js, J[rows][:, np.r_[0:2, 2 + few]].toarray())


def test_sparsity_pattern_is_the_block_structure_and_grows_linearly_with_cells():
    """Each cell's rows depend on the shared columns and its own only: nonzeros Σ 2 n_k (p_shared + p_own)."""
    for n in (3, 6, 12):
        cells, _ = formula_cells(n)
        pb = Population(FORMULA, per_cell=("G0",)).problem(cells)
        S = pb.sparsity().toarray().astype(bool)
        assert S.sum() == 2 * n * F.size * (2 + 1)
        for k in range(n):
            rows = pb.rows(k)
            own = pb.own_index(k)
            allowed = np.zeros(pb.n_free, dtype=bool)
            allowed[:2] = True
            allowed[own] = True
            assert np.all(S[rows][:, allowed]) and not np.any(S[rows][:, ~allowed])
        # the numerical Jacobian has no nonzero outside the pattern
        theta = pb.initial_guess(np.random.default_rng(1))
        assert not np.any(pb.jacobian(theta)[~S])


def test_cells_in_another_order_permute_the_own_parameters_only():
    cells, _ = formula_cells(4)
    pop = Population(FORMULA, per_cell=("G0",))
    a, b = pop.problem(cells), pop.problem(cells[::-1])
    theta = np.log([0.2, 0.4, 100, 200, 300, 400.0])
    theta_b = np.concatenate([theta[:2], theta[2:][::-1]])
    ra, rb = a.residuals(theta), b.residuals(theta_b)
    for k in range(4):
        np.testing.assert_allclose(ra[a.rows(k)], rb[b.rows(3 - k)], rtol=1e-14)


# ---- fits that recover what generated the data ---------------------------------------------------------------
def test_formula_population_recovers_shared_and_per_cell_parameters_within_their_errors():
    cells, G0 = formula_cells(16, noise=0.01)
    res = fit(cells, model=Population(FORMULA, per_cell=("G0",)), starts=2, hops=1, seed=0, progress=False)
    assert res.rms_log10_error < 0.0125  # the noise is 0.01 decades
    for name, true in (("alpha", 0.2), ("eta", 0.5)):
        se = res.identifiability().relative_error(name)[0]
        assert abs(math.log(res.value(name) / true)) < 4 * se
    for k, true in enumerate(G0):
        se = res.identifiability().relative_error(f"G0[{k}]")[0]
        assert se is not None and abs(math.log(res.value(f"G0[{k}]") / true)) < 4 * se


def test_one_cell_scaled_moves_only_its_own_scale():
    """The power law's G* is proportional to G0 at a fixed exponent, so scaling one cell's data by λ scales its G0 by
    λ and leaves every other parameter and every residual as they were (at the optimum, to its tolerance)."""
    cells, _ = formula_cells(6, noise=0.02, seed=3)
    pop = Population("structural-damping", per_cell=("G0",))
    a = fit(cells, model=pop, starts=1, hops=0, progress=False)
    lam = 7.0
    c = cells[2]
    scaled = [*cells[:2], RheologyData(c.frequency_hz, lam * c.G_storage, lam * c.G_loss, source=c.source),
              *cells[3:]]
    b = fit(scaled, model=pop, starts=1, hops=0, progress=False)
    for p, q in zip(a.parameters, b.parameters):
        expect = lam if p.name == "G0[2]" else 1.0
        assert q.value / p.value == pytest.approx(expect, rel=1e-4)
    np.testing.assert_allclose(a.residuals, b.residuals, atol=1e-6)


def test_mechanism_population_recovers_prestress_and_material():
    cells, shared, P = mechanism_cells(4, noise=0.0)
    res = fit(cells, model=Population("springpot-tension+visc", per_cell=("P",)), starts=4, hops=1, seed=0,
              progress=False)
    assert res.rms_log10_error < 1e-4
    for name, true in shared.items():
        assert res.value(name) == pytest.approx(true, rel=1e-2)
    for k, p in enumerate(P):
        assert res.value(f"P[{k}]") == pytest.approx(p, rel=1e-2)


# ---- what the data determine -----------------------------------------------------------------------------------
@pytest.mark.parametrize("base, per_cell", [(FORMULA, ("G0",)), (FORMULA, ("G0", "alpha")),
                                            ("springpot-tension+visc", ("P",))])
def test_block_identifiability_equals_the_full_jacobians(base, per_cell):
    cells = formula_cells(5, noise=0.02)[0] if base == FORMULA else mechanism_cells(3, noise=0.01)[0]
    pb = Population(base, per_cell=per_cell).problem(cells)
    theta = pb.initial_guess(np.random.default_rng(2))
    full = identifiability(pb, theta)
    block = pb.identifiability(theta)
    assert block.sigma == pytest.approx(full.sigma, rel=1e-10) and block.dof == full.dof
    for name in pb.names:
        a, b = full.relative_error(name)[0], block.relative_error(name)[0]
        assert (a is None) == (b is None)
        if a is not None:
            assert b == pytest.approx(a, rel=1e-7)
    np.testing.assert_allclose(block.leverage, full.leverage, atol=1e-10)
    shared = [full.names.index(n) for n in block.names]
    np.testing.assert_allclose(block.correlation, full.correlation[np.ix_(shared, shared)], atol=1e-8)


def test_an_unseen_shared_direction_is_not_determined():
    """With G0 and alpha per cell and eta held near zero, the shared eta is invisible: not determined, as the full
    Jacobian says; the cells' own parameters stay determined."""
    cells, _ = formula_cells(4, eta=1e-9, noise=0.0)
    pb = Population(FORMULA, per_cell=("G0", "alpha")).problem(cells, bounds={"eta": (1e-12, 1.0)})
    theta = np.log([1e-9, *np.ravel([[300.0, 0.2]] * 4)])
    full, block = identifiability(pb, theta), pb.identifiability(theta)
    assert full.relative_error("eta")[0] is None and block.relative_error("eta")[0] is None
    assert block.relative_error("G0[1]")[0] is not None


# ---- the fitted population, fit.json ---------------------------------------------------------------------------
def test_fitted_population_round_trips_and_answers_as_its_cells(tmp_path):
    cells, _ = formula_cells(5)
    pop = Population(FORMULA, per_cell=("G0",))
    res = fit(cells, model=pop, starts=1, hops=0, progress=False)
    assert model_from_dict(json.loads(json.dumps(pop.to_dict()))) == pop
    doc = res.to_dict()
    assert doc["spec"]["class"] == "Population" and doc["population"]["n_cells"] == 5
    assert len(doc["identifiability"]["per_cell"]) == 5
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(doc))
    m = load_fit(path)
    assert isinstance(m, FittedPopulation) and m.n_cells == 5
    for k in range(5):
        np.testing.assert_allclose(m.cell_model(k).moduli(F)[0], res.moduli(F, dataset=k)[0], rtol=1e-12)
    typical = np.exp(np.median(np.log(m.per_cell["G0"])))
    assert m.typical.values["G0"] == pytest.approx(typical, rel=1e-12)
    np.testing.assert_allclose(m.moduli(F)[0], res.moduli(F)[0], rtol=1e-12)


def test_fitted_mechanism_population_answers_every_consumer_as_its_typical_cell():
    cells, _, _ = mechanism_cells(3)
    pb = Population("springpot-tension+visc", per_cell=("P",)).problem(cells)
    theta = pb.initial_guess(np.random.default_rng(0))
    m = pb.fitted(theta, None)
    typical = m.typical
    assert m.cell is typical.cell and m.structural and m.viscosity == typical.viscosity
    P = float(np.median(m.per_cell["P"]))
    assert m.prestress() == pytest.approx(P, rel=1e-12)
    for a, b in zip(m.voigt_tendons(P), typical.voigt_tendons(P)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(m.linear(P_N=P).K0, typical.linear(P_N=P).K0)
    np.testing.assert_allclose(m.cell_model(1).moduli(F)[0], pb.dataset_moduli_at(theta, F, m.per_cell["P"][1], 1)[0],
                               rtol=1e-12)


def test_bad_populations_are_refused_in_one_line():
    cells, _ = formula_cells(3)
    with pytest.raises(ValueError, match="per_cell: G1 is not a parameter"):
        Population(FORMULA, per_cell=("G1",)).problem(cells)
    with pytest.raises(ValueError, match="two or more cells"):
        Population(FORMULA, per_cell=("G0",)).problem(cells[:1])
    with pytest.raises(ValueError, match="G0 is a per-cell parameter"):
        Population(FORMULA, per_cell=("G0",)).problem(cells, fixed={"G0": 100.0})
    with pytest.raises(ValueError, match="gauge"):
        Population("voigt-uniform", per_cell=("P",)).problem(cells)
    with pytest.raises(ValueError, match="model of one cell"):
        Population(Population(FORMULA), per_cell=("G0",))
    stated = [cells[0], cells[1].with_prestress(100.0)]
    with pytest.raises(ValueError, match="differ from those of"):
        Population("springpot+visc").problem(stated)
    short = RheologyData(F[:1], np.array([1.0]), np.array([1.0]), source="short.csv")
    with pytest.raises(DataError, match="short.csv"):
        Population(FORMULA, per_cell=("G0",)).problem([cells[0], short])


def test_a_shared_parameter_can_be_held():
    cells, _ = formula_cells(4)
    res = fit(cells, model=Population(FORMULA, per_cell=("G0",)), fixed={"eta": 0.5}, starts=1, hops=0,
              progress=False)
    assert res.value("eta") == 0.5 and res.problem.n_free == 5


# ---- the scores ------------------------------------------------------------------------------------------------
def test_springpot_exponent_of_a_springpot_and_comment_values():
    w = 2 * np.pi * F
    G = 50.0 * (1j * w) ** 0.23
    assert springpot_exponent(F, G.real, G.imag) == pytest.approx(0.23, abs=1e-6)
    assert math.isnan(springpot_exponent(F[:1], G.real[:1], G.imag[:1]))
    d = RheologyData(F, G.real, G.imag, comments=("cell_line=A aspect_ratio=1.4 area=120.5; 1 point(s) G<=0",))
    assert comment_values(d) == {"aspect_ratio": 1.4, "area": 120.5}


def test_the_exponent_error_of_a_noisy_springpot_is_the_scatter_of_its_estimates():
    """Many seeded springpots with log-normal noise of known σ: the linear standard error of α and the residual σ
    match the spread of the estimates over the draws (to the sampling error of 400 draws)."""
    f = np.array([1.0, 3.0, 10.0, 30.0, 100.0])
    G = 200.0 * (2j * np.pi * f) ** 0.25
    rng = np.random.default_rng(7)
    est, ses, sigmas = [], [], []
    for _ in range(400):
        a, se, sig = springpot_exponent_error(f, G.real * 10 ** rng.normal(0, 0.02, f.size),
                                              G.imag * 10 ** rng.normal(0, 0.02, f.size))
        est.append(a), ses.append(se), sigmas.append(sig)
    assert np.std(est) == pytest.approx(np.median(ses), rel=0.15)
    assert np.sqrt(np.mean(np.square(sigmas))) == pytest.approx(0.02, rel=0.1)
    se_a, se_k = measurement_errors([RheologyData(f, G.real, G.imag)])
    assert se_a[0] < 1e-6 and se_k[0] < 1e-6  # an exact springpot: no scatter (beyond the fit's xatol 1e-7)


def test_measurement_scatter_loosens_a_relation_that_is_exact_by_construction():
    """Model cells on one curve (α falls as k rises): Spearman −1 without scatter; with the measurement's scatter
    added it loosens toward what the same scatter makes of the measured cells; with none added it stays exact."""
    rng = np.random.default_rng(3)
    k = 10 ** rng.uniform(2, 3, 60)
    alpha = 0.4 - 0.1 * np.log10(k / 100)
    se_a, se_k = np.full(60, 0.03), np.full(60, 0.1)
    # measurements of these cells: the relation after the scatter, over many independent measurements
    measured = [(alpha + rng.normal(0, 0.03, 60), k * 10 ** rng.normal(0, 0.1, 60)) for _ in range(200)]
    r = exponent_stiffness(*measured[0], alpha, k, se_a, se_k, draws=300)
    assert r.spearman_model == pytest.approx(-1.0) and r.slope_model == pytest.approx(-0.1)
    many = [exponent_stiffness(a, kk, alpha, k, se_a, se_k, draws=1) for a, kk in measured]
    assert np.mean([m.spearman_measured for m in many]) == pytest.approx(r.spearman_noisy[1], abs=0.03)
    assert np.mean([m.slope_measured for m in many]) == pytest.approx(r.slope_noisy[1], abs=0.005)
    assert -1 < r.spearman_noisy[1] < -0.3 and r.spearman_noisy[0] < r.spearman_noisy[1] < r.spearman_noisy[2]
    exact = exponent_stiffness(alpha, k, alpha, k, np.zeros(60), np.zeros(60), draws=5)
    assert exact.spearman_noisy[1] == pytest.approx(-1.0) and exact.slope_noisy[1] == pytest.approx(-0.1)


def test_scores_of_a_population_generated_by_the_population_model():
    """Data generated by the population (shared alpha, eta; G0 per cell): it beats the per-cell formulas on BIC
    (fewer parameters, the same fit), predicts held-out cells to about the noise, and its per-cell table and
    correlations are those of its fitted cells."""
    cells, G0 = formula_cells(10, noise=0.01, seed=5)
    pop = Population(FORMULA, per_cell=("G0",))
    sc = score_population(cells, pop, folds=5, starts=1, hops=0, progress=False)
    row, free3 = sc.row(pop.name), sc.row(FORMULA)
    assert row.n_params == 2 + 10 and free3.n_params == 3 * 10
    assert row.bic < free3.bic
    assert row.heldout_cells < 0.03 and all(x < 0.05 for x in row.heldout_frequencies)
    table = population_cells(sc.fit)
    assert list(table["G0_Pa"]) == pytest.approx([sc.fit.value(f"G0[{k}]") for k in range(10)])
    ec = sc.correlation("exponent", "stiffness")
    assert ec.n_cells == 10 and -1 <= ec.model <= 1
    assert sc.correlation("stiffness", "aspect_ratio").n_cells == 10
    assert sc.to_dataframe().shape[0] == 3 and "notes" in sc.to_dict()
    assert sc.relation is not None and sc.relation.n_cells == 10 and sc.to_dict()["exponent_stiffness"]["draws"] > 0
    from tenscell.reports.population_fit import population_fit_markdown

    text = population_fit_markdown(sc.fit, table, scores=sc)
    assert "Against independent per-cell formulas" in text and f"`{FORMULA}`" in text and sc.notes[0] in text


def test_scores_with_two_parameters_per_cell_anchor_two_numbers():
    cells, _ = formula_cells(6, noise=0.01, seed=6)
    sc = score_population(cells, Population(FORMULA, per_cell=("G0", "eta")), folds=3, starts=1, hops=0,
                          baselines=("structural-damping+newtonian",), progress=False)
    assert math.isfinite(sc.rows[0].heldout_cells) and sc.rows[0].n_params == 1 + 2 * 6
    assert any("two measured numbers" in n for n in sc.notes)
    with pytest.raises(ValueError, match="one or two per-cell"):
        score_population(cells, Population(FORMULA, per_cell=("G0", "eta", "alpha")), progress=False)
    with pytest.raises(ValueError, match="scale G0"):
        score_population(cells, Population(FORMULA, per_cell=("G0",)), baselines=("springpot+visc",),
                         progress=False)


@pytest.mark.skipif(not XIE.is_dir(), reason="the Xie et al. cells are not beside the repository (../shared/data)")
def test_measured_cells_fit_jointly_with_errors_for_every_parameter():
    cells = [read_csv(p) for p in sorted((XIE / "MDA-MB-436").glob("cell_*.csv"))][:12]
    res = fit(cells, model=Population(FORMULA, per_cell=("G0",)), starts=1, hops=0, progress=False)
    assert np.isfinite(res.rms_log10_error) and len(res.dataset_rms) == 12
    assert all(se is not None for se, _ in res.standard_errors)
    assert "aspect_ratio" in comment_values(cells[0])


# ---- the command ------------------------------------------------------------------------------------------------
def _write(cells, where: Path) -> Path:
    where.mkdir()
    for d in cells:
        rows = "\n".join(f"{f:g},{a:.8g},{b:.8g}" for f, a, b in zip(d.frequency_hz, d.G_storage, d.G_loss))
        (where / f"{d.source}.csv").write_text(f"# {d.comments[0]}\nfrequency_Hz,G_storage_Pa,G_loss_Pa\n{rows}\n")
    return where


def test_command_joint_fit_writes_its_output_set(tmp_path, capsys):
    from tenscell.cli import main

    cells, _ = formula_cells(6)
    pop = _write(cells, tmp_path / "pop")
    out = tmp_path / "out"
    code = main(["fit-population", str(pop), "--out", str(out), "--joint", "--model", FORMULA, "--starts", "1",
                 "--hops", "0", "--workers", "1", "--tolerance", "0.05"])
    assert code == 0, capsys.readouterr().err
    assert {p.name for p in out.iterdir()} >= {"fit.json", "fit.csv", "cells.csv", "report.md", "fit.png", "report.html"}
    assert "Shared parameters" in (out / "report.html").read_text(encoding="utf-8")
    m = load_fit(out / "fit.json")
    assert isinstance(m, FittedPopulation) and m.population.per_cell == ("G0",)
    import pandas as pd

    table = pd.read_csv(out / "cells.csv")
    assert len(table) == 6 and {"G0_Pa", "G0_stderr_Pa", "exponent_measured", "cell_id"} <= set(table.columns)
    assert "Shared parameters" in (out / "report.md").read_text()


@pytest.mark.parametrize("extra, words", [
    (["--model", FORMULA], ["--model", "--joint"]),
    (["--per-cell", "G0"], ["--per-cell", "--joint"]),
    (["--joint", "--tendons", "per-tendon"], ["--tendons", "joint fit"]),
    (["--joint", "--resume"], ["--resume"]),
    (["--joint", "--model", FORMULA, "--per-cell", "G9"], ["--per-cell G9", "not a parameter"]),
    (["--joint", "--per-cell", "P,kappa,alpha"], ["--per-cell", "one or two"]),
    (["--joint", "--per-cell", "P,,a"], ["--per-cell"]),
])
def test_command_refuses_joint_options_in_one_line(tmp_path, capsys, extra, words):
    from tenscell.cli import main

    pop = _write(formula_cells(3)[0], tmp_path / "pop")
    out = tmp_path / "out"
    assert main(["fit-population", str(pop), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and all(w in err for w in words), err
    assert not out.exists()


def test_command_refuses_an_unreadable_cell_naming_it(tmp_path, capsys):
    from tenscell.cli import main

    pop = _write(formula_cells(3)[0], tmp_path / "pop")
    (pop / "cell01.csv").write_text("frequency_Hz,G_storage_Pa,G_loss_Pa\n1,abc,2\n")
    assert main(["fit-population", str(pop), "--out", str(tmp_path / "o"), "--joint"]) == 2
    err = capsys.readouterr().err
    assert "cell01.csv" in err and "line 2" in err


def test_lumped_formula_population():
    """Any FitModel is a base: the lumped formula of springpot-tension+visc with its tension term's B per cell."""
    cells, _ = formula_cells(3)
    base = lumped_formula(MECHANISMS["springpot-tension+visc"])
    pb = Population(base, per_cell=("B",)).problem(cells)
    assert pb.shared_names == ("E0", "A", "alpha", "alpha_T", "eta") and pb.n_free == 5 + 3
