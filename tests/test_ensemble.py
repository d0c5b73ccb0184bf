"""Large ensembles of a distributed mechanism (issue 18 item 3): the population engine's mean and spread.

Physics, not snapshots: the fit's few-assignment average is one sample of the ensemble's expectation, so it
lies within its sampling error of the ensemble mean; an ensemble of the fit's own K and seed *is* the fit's
average; every member is a passive cell; the numbers do not depend on where the chunks ran.
"""
from __future__ import annotations

import dataclasses
import json
import math
import re

import numpy as np
import pytest

from tenscell import paper_cell
from tenscell.cli import main as cli_main
from tenscell.fitting.fitted import FittedMechanism
from tenscell.fitting.models.catalog import MECHANISMS
from tenscell.population import ensemble as ens
from tenscell.population import mechanism_ensemble

F = np.logspace(-2, 3, 11)
PRESTRESS = [500.0, 1500.0]


def _model(name="voigt-lognormal-damping", **values) -> FittedMechanism:
    base = {"voigt-lognormal-damping": {"EA_actin": 1.0, "EA_intermediate_filament": 0.2, "c": 0.3,
                                        "c_decades": 1.0},
            "voigt-compact": {"EA_actin": 1.0, "EA_intermediate_filament": 0.2, "c_actin": 0.3,
                              "c_intermediate_filament": 1.0},
            "voigt-trap-damping+visc": {"EA_actin": 1.0, "EA_intermediate_filament": 0.2, "c": 0.01,
                                        "c_exponent": 0.5, "eta_cytoplasm": 1e-3}}[name]
    return FittedMechanism(MECHANISMS[name], paper_cell(), {**base, **values}, s=1e-3, prestress_pa=(500.0, 1500.0))


@pytest.fixture(scope="module")
def large():
    return mechanism_ensemble(_model(), F, PRESTRESS, K=600, workers=0, progress=False)


def test_the_fit_average_lies_within_its_sampling_error_of_the_ensemble_mean(large):
    # both estimate one expectation: their difference has the standard error sd·√(1/8 + 1/K) per point; 4 of
    # them over 44 correlated points fails a correct ensemble with probability ~1e-3 (seeded: deterministic)
    zs, zl = large.reference_z()
    assert large.reference_K == 8 and large.K == 600 and large.n_failed == 0
    assert max(zs, zl) < 4.0, (zs, zl)
    # and the check sees another distribution: the 8-assignment average of a spread 1.5 decades wide instead of
    # 1 lies 8-9 standard errors off (what an ensemble of the wrong distribution would look like)
    wider = _model(c_decades=1.5)
    ref = np.array([np.add(*(np.asarray(g) * u for g, u in zip(wider.moduli(F, p), (1, 1j)))) for p in PRESTRESS])
    assert min(dataclasses.replace(large, reference=ref).reference_z()) > 4.0
    # the spread is real (log-normal damping over one decade), so the check above has something to test
    rs, rl = large.relative_spread()
    assert rs > 0.05 and rl > 0.2
    # the band holds the mean, and the standard error is sd/√K
    lo, hi = large.band()
    assert np.all(lo.real <= large.mean.real) and np.all(large.mean.real <= hi.real)
    np.testing.assert_allclose(large.sem.real, large.sd.real / math.sqrt(600), rtol=1e-12)


def test_an_ensemble_of_the_fits_own_K_and_seed_is_the_fits_average():
    # the same 8 assignments (mechanism seed) through the chunked engine: the mean is the fit's moduli, to
    # round-off (an average of 8 moduli of size ~1: a few ulps)
    r = mechanism_ensemble(_model(), F, PRESTRESS, K=8, workers=0, progress=False)
    np.testing.assert_allclose(r.mean, r.reference, rtol=1e-12)
    other = mechanism_ensemble(_model(), F, PRESTRESS, K=8, seed=5, workers=0, progress=False)
    assert not np.allclose(other.mean, r.reference, rtol=1e-6)  # another seed: other assignments


def test_a_vanishing_spread_has_no_spread():
    r = mechanism_ensemble(_model(c_decades=1e-9), F, [1000.0], K=20, workers=0, progress=False)
    # the spread enters as 1e-9·ln10·z: every assignment is the homogeneous cell to ~1e-8
    assert np.all(r.sd.real <= 1e-7 * r.mean.real) and np.all(r.sd.imag <= 1e-7 * r.mean.imag)
    hom = _model("voigt-compact", c_actin=0.3, c_intermediate_filament=0.3).moduli(F, 1000.0)
    np.testing.assert_allclose(r.mean[0].real, hom[0], rtol=1e-7)
    np.testing.assert_allclose(r.mean[0].imag, hom[1], rtol=1e-7)


def test_every_member_is_passive():
    # a trap model at its heaviest allowed tail (exponent 0.5) spreads the damping over many decades
    r = mechanism_ensemble(_model("voigt-trap-damping+visc"), np.logspace(-3, 4, 15), PRESTRESS, K=200, workers=0,
                           progress=False)
    assert r.n_failed == 0
    assert np.all(r.members.imag >= 0) and r.passive
    assert np.all(r.members.real > 0)


def test_the_numbers_do_not_depend_on_how_the_work_is_split(monkeypatch):
    a = mechanism_ensemble(_model(), F, PRESTRESS, K=130, workers=0, progress=False)
    monkeypatch.setattr(ens, "CHUNK", 7)
    monkeypatch.setattr(ens, "MAX_STACK", 5)  # several frequency blocks per chunk and prestress
    b = mechanism_ensemble(_model(), F, PRESTRESS, K=130, workers=0, progress=False)
    np.testing.assert_allclose(a.members, b.members, rtol=1e-13)  # per-matrix LU: the same arithmetic


def test_the_same_seed_gives_the_same_numbers_on_a_worker_pool():
    here = mechanism_ensemble(_model(), F, PRESTRESS, K=200, seed=3, workers=0, progress=False)
    pool = mechanism_ensemble(_model(), F, PRESTRESS, K=200, seed=3, workers=2, progress=False)
    assert here.workers == 0 and pool.workers == 2
    # the same LU per matrix on one BLAS thread everywhere; rtol 1e-12 leaves room for another CPU's kernels
    np.testing.assert_allclose(pool.members, here.members, rtol=1e-12)


@pytest.mark.parametrize("kwargs, word", [
    ({"K": 1}, "K (assignments)"), ({"K": 2.5}, "K (assignments)"), ({"K": True}, "K (assignments)"),
    ({"K": 10**6}, "K (assignments)"), ({"workers": -1}, "workers"), ({"workers": 1.5}, "workers"),
    ({"seed": -2}, "seed"),
])
def test_bad_arguments_are_refused_before_any_work(kwargs, word, monkeypatch):
    from tenscell.population import _engine

    monkeypatch.setattr(_engine, "run_tasks", lambda *a, **k: pytest.fail("work started"))
    with pytest.raises(ValueError, match=re.escape(word)) as err:
        mechanism_ensemble(_model(), F, **kwargs)
    assert "\n" not in str(err.value)


def test_a_mechanism_without_a_distribution_has_no_ensemble():
    with pytest.raises(ValueError, match="no ensemble"):
        mechanism_ensemble(_model("voigt-compact"), F, K=10)
    with pytest.raises(ValueError, match="per-tendon fit"):
        mechanism_ensemble(object(), F, K=10)


# ---- command line -------------------------------------------------------------------------------
@pytest.fixture()
def fits(tmp_path):
    out = {}
    for name in ("voigt-lognormal-damping", "voigt-compact"):
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps({"model": _model(name).to_dict()}))
        out[name] = path
    return out


def test_moduli_ensemble_writes_the_results_table(fits, capsys):
    assert cli_main(["moduli", "--from-fit", str(fits["voigt-lognormal-damping"]), "--ensemble", "60",
                     "--prestress", "500,1500", "--freq", "0.1,10", "--workers", "0"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    header = lines[0].split(",")
    r = mechanism_ensemble(_model(), [0.1, 10.0], PRESTRESS, K=60, workers=0, progress=False)
    assert header == list(r.to_dataframe().columns)
    rows = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    np.testing.assert_allclose(rows, r.to_dataframe().to_numpy(float), rtol=1e-9)  # 10 significant digits


@pytest.mark.parametrize("argv, word", [
    (["--ensemble", "1"], "--ensemble"),
    (["--ensemble", "0", "--workers", "2"], "--workers"),  # 0: no ensemble, as for fit and study
    (["--workers", "2"], "--workers"),
    (["--ensemble", "10", "--workers", "-1"], "--workers"),
    # the cost, before any work: 1e11 solves (over a day at any plausible µs per solve) and ~6 TB of members
    (["--ensemble", "100000", "--freq", "0.01:1000:1000000"], "--ensemble: estimated"),
])
def test_moduli_refuses_bad_ensemble_flags(fits, argv, word, capsys):
    assert cli_main(["moduli", "--from-fit", str(fits["voigt-lognormal-damping"]), *argv]) == 2
    captured = capsys.readouterr()
    assert word in captured.err and len(captured.err.strip().splitlines()) == 1 and captured.out == ""


def test_moduli_refuses_an_ensemble_of_a_homogeneous_mechanism_or_without_a_fit(fits, capsys):
    assert cli_main(["moduli", "--from-fit", str(fits["voigt-compact"]), "--ensemble", "10"]) == 2
    assert cli_main(["moduli", "--ensemble", "10"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "no ensemble" in err[0] and "--from-fit" in err[1]


def test_study_refuses_bad_ensemble_flags_before_any_fit(tmp_path, capsys):
    for argv in (["--ensemble", "1"], ["--ensemble", "0", "--workers", "2"], ["--ensemble", "-3"]):
        assert cli_main(["study", "mechanisms", "bundled:fabry2001", *argv, "--out", str(tmp_path / "m")]) == 2
        assert not (tmp_path / "m").exists()
        err = capsys.readouterr().err.strip()
        assert "--ensemble" in err or "--workers" in err
        assert len(err.splitlines()) == 1
    assert cli_main(["study", "sensitivity", "--ensemble", "20", "--out", str(tmp_path / "s")]) == 2


def test_the_command_line_limits_are_the_librarys():
    # the parser imports no numpy, so it keeps its own copies of the limits: they must agree
    from tenscell.cli._args import ENSEMBLE_MAX_K
    from tenscell.cli.study import STUDY_ENSEMBLE_K

    assert ENSEMBLE_MAX_K == ens.MAX_K and STUDY_ENSEMBLE_K == ens.DEFAULT_K


def test_the_study_evaluates_the_distributed_mechanism_with_the_lowest_bic():
    from tenscell.io.data import bundled
    from tenscell.studies.mechanisms import mechanisms_study

    data = [bundled("fabry2001")]
    s = mechanisms_study(data, mechanisms=["voigt-compact", "voigt-lognormal-damping", "voigt-lognormal-stiffness"],
                         starts=1, hops=0, validate=False, falsify=False, ensemble=40, workers=0, progress=False)
    distributed = [r for r in s.rows if r.name != "voigt-compact"]
    best = min(distributed, key=lambda r: r.bic)
    assert s.ensemble is not None and s.ensemble.mechanism == best.name and s.ensemble.K == 40
    # at the data's frequencies and the fit's own prestress (no data set states one: model prestress, N)
    np.testing.assert_array_equal(s.ensemble.frequency_hz, np.unique(data[0].frequency_hz))
    assert s.ensemble.prestress_unit == "N"
    Gs, Gl = best.model.moduli(s.ensemble.frequency_hz)
    np.testing.assert_allclose(s.ensemble.reference[0], Gs + 1j * Gl, rtol=1e-12)
    none = mechanisms_study(data, mechanisms=["voigt-compact"], starts=1, hops=0, validate=False, falsify=False, ensemble=40,
                            progress=False)
    assert none.ensemble is None  # nothing distributed: nothing to draw


def test_the_study_refuses_a_bad_ensemble_before_any_fit(monkeypatch):
    from tenscell.io.data import bundled
    from tenscell.studies import mechanisms as study

    monkeypatch.setattr("tenscell._parallel.starmap", lambda *a, **k: pytest.fail("fits started"))  # the fits' pool
    for kwargs in ({"ensemble": 1}, {"ensemble": 50, "workers": -1}):
        with pytest.raises(ValueError, match="K \\(assignments\\)|workers|1 assignment has no spread"):
            study.mechanisms_study([bundled("fabry2001")], mechanisms=["voigt-lognormal-damping"], **kwargs)


def test_fit_model_with_an_ensemble_writes_it_beside_the_fit(tmp_path):
    out = tmp_path / "fit"
    code = cli_main(["fit", "bundled:stamenovic2002", "--model", "voigt-lognormal-damping", "--starts", "1",
                     "--ensemble", "30", "--out", str(out)])
    assert code in (0, 1)  # 1: not within --tolerance (one start); the outputs exist either way
    from tenscell.fitting import load_any_fit

    model = load_any_fit(out / "fit.json")
    table = np.loadtxt(out / "ensemble.csv", delimiter=",", skiprows=1)
    header = (out / "ensemble.csv").read_text().splitlines()[0].split(",")
    # at the data's 8 stated prestresses (Pa) and one frequency; the fit's average is the model's moduli
    assert header[0] == "prestress_Pa" and table.shape[0] == 8
    i = header.index("G_storage_fit_average_Pa")
    Gs = [model.moduli([0.1], p)[0][0] for p in table[:, 0]]
    np.testing.assert_allclose(table[:, i], Gs, rtol=1e-12)
    assert "30 assignments" in (out / "ensemble.md").read_text() and (out / "ensemble.png").stat().st_size > 0


@pytest.mark.parametrize("argv, word", [
    (["--model", "voigt-compact", "--ensemble", "20"], "no ensemble"),
    (["--model", "voigt-lognormal-damping", "--ensemble", "1"], "--ensemble"),
    (["--ensemble", "20"], "--ensemble"),  # the per-tendon fit
])
def test_fit_refuses_an_ensemble_it_cannot_have_before_fitting(argv, word, tmp_path, capsys):
    assert cli_main(["fit", "bundled:fabry2001", *argv, "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip()
    assert word in err and len(err.splitlines()) == 1 and not (tmp_path / "x").exists()


def test_an_assignment_that_is_not_a_stable_cell_is_left_out_and_counted(monkeypatch):
    """One member whose K(ω) cannot be solved: its row is NaN, n_failed counts it, the statistics use the rest."""
    from tenscell.fitting.models.mechanism import MechanismProblem

    ref = mechanism_ensemble(_model(), F, PRESTRESS, K=12, workers=0, progress=False)
    bad_u = {}
    original = MechanismProblem.evaluate

    def failing(self, phi, omega, P, jac, dP=None):
        u = self.shape_maps[0][3]
        if any(np.array_equal(row, bad_u["row"]) for row in u):  # the stack holding assignment 5 fails as a whole
            return None
        return original(self, phi, omega, P, jac, dP)

    from tenscell.fitting.models.mechanism import bare_problem

    full = bare_problem(dataclasses.replace(_model().mechanism, assignments=12), paper_cell())
    bad_u["row"] = full.shape_maps[0][3][5]
    monkeypatch.setattr(MechanismProblem, "evaluate", failing)
    r = mechanism_ensemble(_model(), F, PRESTRESS, K=12, workers=0, progress=False)
    assert r.n_failed == 1 and np.all(np.isnan(r.members[5])) and not r.stable[5]
    keep = np.arange(12) != 5
    np.testing.assert_allclose(r.members[keep], ref.members[keep], rtol=1e-13)  # the others, solved one by one
    np.testing.assert_allclose(r.mean.real, ref.members[keep].real.mean(axis=0), rtol=1e-13)


def test_an_ensemble_shows_its_spread_in_a_notebook(large):
    import html as _html

    out = _html.unescape(large._repr_html_())
    rs, rl = large.relative_spread()
    zs, zl = large.reference_z()
    assert f"EnsembleResult: {large.mechanism}" in out and f"{large.K} ({large.n_failed} not a stable cell)" in out
    assert f"G′ {100 * rs:.3g} %, G″ {100 * rl:.3g} %" in out and f"within {zs:.2g} (G′) and {zl:.2g} (G″)" in out
