"""The fitted cell from the command line: creep, simulate and show with --from-fit."""
from __future__ import annotations

import json

import numpy as np
import pytest

from tenscell.cli import main as cli_main
from tenscell.fitting import fit
from tenscell.io.data import bundled
from tenscell.fitting import VoigtModel


@pytest.fixture(scope="module")
def fit_json(tmp_path_factory):
    """fit.json of a fast per-family fit of the prestress sweep (its model prestress is s × prestress in Pa)."""
    result = fit(bundled("stamenovic2002"), model=VoigtModel(tendons="per-family"), starts=1, hops=2, seed=0, progress=False)
    path = tmp_path_factory.mktemp("fit") / "fit.json"
    path.write_text(json.dumps(result.to_dict()))
    return path, result


def test_creep_from_fit_is_the_fitted_cells_linear_creep(fit_json, tmp_path):
    path, result = fit_json
    out = tmp_path / "creep"
    assert cli_main(["creep", "--from-fit", str(path), "--t-min", "0.1", "--t-max", "10", "--out", str(out)]) == 0
    doc = json.loads((out / "creep.json").read_text())
    P = result.value("s") * float(np.median(result.data.prestress))
    assert doc["model"]["prestress_N"] == pytest.approx(P)
    assert doc["steps"] == []  # no nonlinear steps by default with --from-fit
    pc = result.predicted_creep(0.1, 10.0, 61)
    # creep.json is in m/N; the fit's prediction in 1/Pa is J·2L
    assert doc["power_law_fits"]["linear"]["alpha"] == pytest.approx(pc.alpha, rel=1e-9)
    assert doc["power_law_fits"]["linear"]["A_m_per_N"] * 2 * result.model.L == pytest.approx(pc.A, rel=1e-9)


def test_simulate_from_fit_builds_the_fitted_law(fit_json):
    # the flags' plumbing (the integration itself is tested in test_dynamics)
    from tenscell.cli import build_parser
    from tenscell.cli.dynamics import law_from_args

    path, result = fit_json
    args = build_parser().parse_args(["simulate", "--from-fit", str(path), "--prestress", "500", "--amplitude", "0.01",
                                      "--freq", "0.1", "--out", "unused"])
    cell, law, _ = law_from_args(args)
    assert args.prestress_N == pytest.approx(result.value("s") * 500.0)
    np.testing.assert_array_equal(law.EA, result.model.EA)
    assert cell.strut_length == pytest.approx(result.model.L)
    np.testing.assert_allclose(np.asarray(law.elastic(cell.lengths)), args.prestress_N * cell.T0, rtol=1e-9)


def test_show_from_fit(fit_json, tmp_path):
    path, result = fit_json
    assert cli_main(["show", "--from-fit", str(path), "--modes", "0", "--out", str(tmp_path / "show")]) == 0
    text = (tmp_path / "show" / "fit_summary.txt").read_text()
    assert f"P={result.value('s') * np.median(result.data.prestress):.6g} N" in text


@pytest.mark.parametrize("extra,match", [
    (["--EA", "3"], "--EA cannot be combined with --from-fit"),
    (["--L", "2"], "--L cannot be combined with --from-fit"),
])
def test_from_fit_refuses_model_options(fit_json, tmp_path, capsys, extra, match):
    path, _ = fit_json
    assert cli_main(["creep", "--from-fit", str(path), *extra, "--out", str(tmp_path / "x")]) == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_from_fit_errors(tmp_path, capsys):
    bad = tmp_path / "fit.json"
    bad.write_text("{}")
    assert cli_main(["creep", "--from-fit", str(bad), "--out", str(tmp_path / "x")]) == 2
    assert "no fitted model" in capsys.readouterr().err
    assert cli_main(["show", "--out", str(tmp_path / "x")]) == 2
    assert "TARGET" in capsys.readouterr().err
    assert cli_main(["show", "paper", "--from-fit", str(bad), "--out", str(tmp_path / "x")]) == 2
    assert "cannot be combined with --from-fit" in capsys.readouterr().err


def test_fitted_cell_with_inert_prestress_refuses_a_nonlinear_run_but_gives_linear_creep(tmp_path, capsys):
    from tenscell import paper_cell
    from tenscell.fitting.fitted import FittedCell

    rng = np.random.default_rng(0)
    cell = paper_cell()
    model = FittedCell(cell=cell, EA=10 ** rng.uniform(-7, 6, cell.m), c=10 ** rng.uniform(0, 3, cell.m), P=5.6e-8)
    path = tmp_path / "fit.json"
    path.write_text(json.dumps({"model": model.to_dict()}))
    assert cli_main(["creep", "--from-fit", str(path), "--out", str(tmp_path / "c")]) == 0
    assert cli_main(["creep", "--from-fit", str(path), "--amplitude", "1e-12", "--out", str(tmp_path / "d")]) == 2
    assert "integration noise" in capsys.readouterr().err


# --- fit: --bound, --fix, --holdout --------------------------------------------------------------
@pytest.mark.parametrize("flag,match", [
    (["--bound", "EA=1e3:1e-3"], "--bound: EA=1e3:1e-3: reversed or empty interval; the lower bound 1000 N must be "
                                 "below the upper bound 0.001 N"),
    (["--bound", "X-Y=1:2"], "unknown parameter kind 'X-Y'"),
    (["--bound", "X=1:2"], "--bound X=1:2: no parameter or parameter kind 'X'"),  # a name only a --model could have
    (["--bound", "c=1"], "c: expected LO:HI in N·s/m"),
    (["--fix", "L"], "expected NAME=VALUE"),
    (["--fix", "L=-1"], "--fix: -1 is out of range"),
    (["--bound", "s=1:2"], "--bound s=1:2: no parameter or parameter kind 's'"),
    (["--fix", "c_actin=1"], "--fix c_actin=1: no parameter named 'c_actin'"),
    (["--fix", "L=5000"], "--fix L=5000: outside its bounds"),
    (["--holdout", "10:1"], "FMIN 10 Hz must be below FMAX 1 Hz"),
    (["--holdout", "1e5:1e6"], "holds 0 of the 16 points"),
])
def test_fit_flags_refused_naming_the_flag(tmp_path, capsys, flag, match):
    out = tmp_path / "fit"
    assert cli_main(["fit", "bundled:fabry2001", "--tendons", "uniform", *flag, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert match in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_fit_with_bound_fix_and_holdout(tmp_path):
    out = tmp_path / "fit"
    code = cli_main(["fit", "bundled:fabry2001", "--tendons", "per-family", "--damping", "per-family",
                     "--fix", "L=1", "--fix", "c_actin=2", "--bound", "EA=1e-2:1e6", "--holdout", "0.3:3",
                     "--starts", "1", "--baseline-starts", "1", "--out", str(out)])
    assert code in (0, 1)
    doc = json.loads((out / "fit.json").read_text())
    pars = {p["name"]: p for p in doc["parameters"]}
    assert pars["L"]["value"] == 1.0 and not pars["L"]["vary"]
    assert pars["c_actin"]["value"] == 2.0 and not pars["c_actin"]["vary"]
    assert pars["EA_actin"]["lower"] == pytest.approx(1e-2) and pars["EA_actin"]["upper"] == pytest.approx(1e6)
    assert doc["n_points"] == 16 - 3  # 0.3..3 Hz holds 3 of the 16 frequencies (0.46, 1, 2.2 Hz)
    cmp_ = doc["model_comparison"]
    assert cmp_["holdout_Hz"] == [0.3, 3.0] and cmp_["n_holdout_points"] == 3
    rows = {m["model"]: m for m in cmp_["models"]}
    assert rows["structural damping (power law)"]["holdout_rms_log10_error"] < 1e-3  # the law the data came from
    assert all(m["holdout_rms_log10_error"] is not None for m in cmp_["models"])
    # fixing c and L breaks the gauge: L is not analysed (fixed), no combination is relabelled
    assert not doc["identifiability"]["gauge_removed"]
    md = (out / "report.md").read_text()
    assert "held-out RMS log10 error" in md and "that no model was fitted to" in md


def test_fit_creep_file(tmp_path):
    import tenscell
    from tenscell.io.creep_data import CreepData, write_creep_csv

    cell = tenscell.paper_cell()
    t = np.logspace(-2, 1, 8)
    J = tenscell.creep_compliance(tenscell.linearize(cell, P=4.0, EA=2.0, c=0.5), t, continuum=True)
    path = tmp_path / "creep.csv"
    write_creep_csv(CreepData(time_s=t, compliance=J, compliance_sd=0.02 * J), path)
    out = tmp_path / "fit"
    assert cli_main(["fit", str(path), "--tendons", "uniform", "--starts", "1", "--out", str(out)]) == 0
    doc = json.loads((out / "fit.json").read_text())
    assert doc["datasets"][0]["axis"] == "time" and doc["rms_log10_error"] < 0.01
    assert doc["identifiability"]["sigma_source"] == "data standard deviations"
    rows = (out / "fit.csv").read_text().splitlines()
    assert "creep_compliance_model_per_Pa" in rows[0] and len(rows) == 1 + t.size
    md = (out / "report.md").read_text()
    assert "creep compliance J(t)" in md and "J data (1/Pa)" in md


def test_study_sensitivity_from_fit_takes_the_fitted_paper_cell(fit_json, tmp_path, capsys):
    from tenscell.studies.sensitivity import paper_cell_of_fit

    path, result = fit_json
    kw = paper_cell_of_fit(path)
    assert kw["L"] == pytest.approx(result.model.L) and kw["P"] == pytest.approx(
        result.value("s") * np.median(result.data.prestress))
    np.testing.assert_array_equal(kw["EA"], result.model.EA)
    assert cli_main(["study", "no-if", "--from-fit", str(path), "--out", str(tmp_path / "x")]) == 2
    assert "applies to study sensitivity" in capsys.readouterr().err


def test_fit_uses_one_process_per_cpu_by_default_and_timing_is_ordered(tmp_path, capsys):
    from tenscell._parallel import usable_cpus

    out = tmp_path / "fit"
    code = cli_main(["fit", "bundled:stamenovic2002", "--tendons", "per-family", "--starts", "3", "--out", str(out)])
    assert code in (0, 1)
    assert f"with voigt-per-family: 3 start(s), {min(3, usable_cpus())} process(es)" in \
        capsys.readouterr().err
    doc = json.loads((out / "fit.json").read_text())
    t = doc["timing"]
    # the command's clock: the fit starts, meets its tolerance, ends; then the baseline; then the outputs
    assert 0 <= t["fit_started_s"] <= t["fit_finished_s"] <= t["baseline_finished_s"] <= t["outputs_started_s"]
    if doc["tolerance_met"]:
        assert t["fit_started_s"] <= t["tolerance_met_s"] <= t["fit_finished_s"]
        assert t["tolerance_met_s"] == pytest.approx(t["fit_started_s"] + doc["time_to_tolerance_s"], abs=1e-3)
    assert (out / "fit.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"  # drawn in the worker, written here


def test_gauge_window_holds_the_prestress_scale_in_the_papers_range(tmp_path, monkeypatch):
    """`--gauge-window` = `--bound s=0.01:100` (the old `--anchored`): springpot-tension+visc, whose free fit shrinks s
    to about 2e-3 m², ends with s inside [0.01, 100] m² (L = s^-1/2 within 0.1-10 m), and fit.json records the bounds."""
    from tenscell.fitting.shares import GAUGE_WINDOW_L, GAUGE_WINDOW_S

    assert GAUGE_WINDOW_S == pytest.approx((1 / GAUGE_WINDOW_L[1] ** 2, 1 / GAUGE_WINDOW_L[0] ** 2))
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    out = tmp_path / "anch"
    status = cli_main(["fit", "bundled:stamenovic2002", "bundled:fabry2001", "--model", "springpot-tension+visc",
                       "--gauge-window", "--starts", "1", "--validate", "no", "--profile", "no", "--jobs", "1",
                       "--out", str(out)])
    assert status in (0, 1)
    s = next(p for p in json.loads((out / "fit.json").read_text())["parameters"] if p["name"] == "s")
    assert GAUGE_WINDOW_S[0] * (1 - 1e-9) <= s["value"] <= GAUGE_WINDOW_S[1] * (1 + 1e-9)
    assert (s["lower"], s["upper"]) == pytest.approx(GAUGE_WINDOW_S)


@pytest.mark.parametrize("flag, factor", [(["--anchored"], 1.5), (["--anchored=exact"], 1.0), (["--anchored", "2"], 2.0)])
def test_anchored_holds_sigma_to_the_measured_prestress(tmp_path, monkeypatch, flag, factor):
    """`--anchored [FACTOR|exact]`: σ (the tendons' virial stress) within ×/÷FACTOR of the measured prestress; fit.json
    and the report give σ / measured and the anchor."""
    from tenscell.model import paper_cell
    from tenscell.model.prestress import virial_prestress

    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    out = tmp_path / "anch"
    status = cli_main(["fit", "bundled:stamenovic2002", "bundled:fabry2001", "--model", "springpot+visc", *flag,
                       "--starts", "1", "--validate", "no", "--profile", "no", "--jobs", "1", "--out", str(out)])
    assert status in (0, 1)
    doc = json.loads((out / "fit.json").read_text())
    s = next(p for p in doc["parameters"] if p["name"] == "s")
    s_sigma = virial_prestress(paper_cell()).scale_m2
    pre = doc["structure"]["prestress"]
    assert pre["sigma_over_measured"] == pytest.approx(s["value"] / s_sigma, rel=1e-9)
    assert 1 / factor * (1 - 1e-9) <= pre["sigma_over_measured"] <= factor * (1 + 1e-9)
    assert pre["anchor"]["factor"] == pytest.approx(factor)
    if factor == 1.0:
        assert not s["vary"] and s["value"] == pytest.approx(s_sigma, rel=1e-12)
    else:
        assert (s["lower"], s["upper"]) == pytest.approx((s_sigma / factor, s_sigma * factor), rel=1e-12)
    assert "σ / measured =" in (out / "report.md").read_text()


@pytest.mark.parametrize("extra, match", [
    (["bundled:fabry2001", "--anchored"], "--anchored: this fit has no prestress scale s"),
    (["bundled:stamenovic2002", "--anchored", "--bound", "s=1:2"], "give it or --bound s=LO:HI, not both"),
    (["bundled:stamenovic2002", "--anchored", "--fix", "s=1"], "give it or --fix s=VALUE, not both"),
    (["bundled:stamenovic2002", "--anchored", "--gauge-window"], "give one of them"),
    (["bundled:stamenovic2002", "--anchored=0.5"], "--anchored 0.5: the factor must lie in (1, 100]"),
    (["bundled:stamenovic2002", "--anchored", "0.5"], "--anchored [FACTOR|exact]"),
    (["bundled:stamenovic2002", "--anchored=1"], "--anchored [FACTOR|exact]"),
    (["bundled:stamenovic2002", "--anchored=tight"], "--anchored tight: not a factor"),
    (["bundled:fabry2001", "--gauge-window"], "--gauge-window: this fit has no prestress scale s"),
])
def test_anchored_refusals(tmp_path, capsys, extra, match):
    out = tmp_path / "x"
    assert cli_main(["fit", *extra, "--model", "springpot+visc", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert match in err and err.count("\n") == 1 and not out.exists()


def test_the_fit_command_runs_with_one_blas_thread_throughout(monkeypatch):
    # the report's quantities and the figures evaluate the model outside the library's hot paths: with several BLAS
    # threads on a busy machine they cost several times the fit (tenscell.cli.fit.run)
    from threadpoolctl import threadpool_info, threadpool_limits

    import tenscell.cli.fit as cli_fit

    seen = []
    monkeypatch.setattr(cli_fit, "_run", lambda args: seen.append(
        [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]) or 0)
    with threadpool_limits(limits=2, user_api="blas"):
        outside = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
        if not outside or max(outside) < 2:
            pytest.skip("the BLAS libraries here run one thread whatever they are asked")
        assert cli_fit.run(None) == 0
    assert seen and seen[0] and set(seen[0]) == {1}
