"""Out of sample (tenscell.fitting.validation): the splits, the held-out error, the verdict against the formula."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from tenscell.cli import main as cli_main
from tenscell.fitting import fit, get_model
from tenscell.fitting.records import FitAlternative
from tenscell.fitting.models.formulas import structural_damping_moduli
from tenscell.fitting.validation import (BAND_COST, NO_BETTER, UNCONVERGED, HeldOutScore, OutOfSample, band_fits,
                                         held_out_rms, out_of_sample, out_of_sample_verdict, refit, rms_on,
                                         score_split, splits, standard_baselines, warm_start)
from tenscell.io.data import RheologyData, bundled


def _law(noise: float = 0.0, seed: int = 0) -> RheologyData:
    f = np.logspace(-2, 3, 16)
    G = structural_damping_moduli(2 * np.pi * f, 300.0, 1.2, 0.1)
    rng = np.random.default_rng(seed)
    return RheologyData(f, G.real * 10 ** rng.normal(0, noise, f.size), G.imag * 10 ** rng.normal(0, noise, f.size),
                        source="law.csv")


def test_splits_partition_each_cut_data_set_and_keep_the_others_whole():
    data = [bundled("stamenovic2002"), bundled("fabry2001")]
    found = splits(data)
    assert [s.name for s in found] == ["stamenovic2002_hasm_0p1Hz: top third of P held out",
                                       "stamenovic2002_hasm_0p1Hz: every third P held out",
                                       "stamenovic2002_hasm_0p1Hz: P ≤ 1000 Pa → above",
                                       *(f"fabry2001_hasm_powerlaw: ≤ {c} Hz" for c in ("0.3", "1", "3", "10", "30"))]
    for s in found:
        cut, whole = data[s.dataset], data[1 - s.dataset]
        assert s.train[1 - s.dataset] is whole
        train = s.train[s.dataset]
        assert train.n + s.held.n == cut.n
        key = (lambda d: d.prestress) if s.dataset == 0 else (lambda d: d.frequency_hz)
        assert set(key(train)).isdisjoint(key(s.held)) and set(key(train)) | set(key(s.held)) == set(key(cut))
    low = next(s for s in found if s.name.endswith("≤ 10 Hz"))
    assert low.train[1].frequency_hz.max() <= 10 < low.held.frequency_hz.min()
    top = found[0]
    assert top.held.prestress.min() > top.train[0].prestress.max()  # an extrapolation in P
    low_p = found[2]
    assert low_p.train[0].prestress.max() <= 1000 < low_p.held.prestress.min()


def test_a_law_predicts_its_own_held_out_points_and_a_wrong_one_does_not():
    data = _law()
    (s,) = [x for x in splits(data) if x.name.endswith("≤ 10 Hz")]
    right = fit(s.train, model="structural-damping+newtonian", starts=2, progress=False)
    assert held_out_rms(right, s) < 1e-4
    wrong = fit(s.train, model="structural-damping", starts=2, progress=False)  # no Newtonian upturn
    assert held_out_rms(wrong, s) > 0.05
    oos = out_of_sample("structural-damping+newtonian", data, starts=2)
    assert oos.rms.shape == (5,) and oos.worst < 1e-3 and oos.mean <= oos.worst


def test_the_verdict_compares_the_mean_with_a_ten_percent_margin():
    def row(name, structural, values):
        return OutOfSample(model=name, structural=structural, n_params=3, splits=("a", "b"),
                           rms=np.array(values, dtype=float))

    formula = row("f", False, [0.1, 0.1])
    better = out_of_sample_verdict(row("m", True, [0.05, 0.08]), formula)
    assert better.startswith("the structure does better out of sample")
    same = out_of_sample_verdict(row("m", True, [NO_BETTER * 0.1 + 1e-6] * 2), formula)
    assert same.startswith("the structure adds nothing measurable here")
    assert "no stable cell" in out_of_sample_verdict(row("m", True, [0.05, np.inf]), formula)


def test_a_model_not_scored_out_of_sample_is_absent_from_the_comparison_not_an_error():
    """A baseline that misses the data in sample is not refereed: the comparison has no row of it (get: None),
    while row() still names what is there."""
    from tenscell.fitting.validation import OutOfSampleComparison

    m = OutOfSample(model="m", structural=True, n_params=3, splits=("a",), rms=np.array([0.05]))
    comparison = OutOfSampleComparison(rows=(m,), model="m", verdict="", splits=("a",))
    assert comparison.get("m") is m and comparison.get("formula: aP + E0 + springpot") is None
    with pytest.raises(ValueError, match="no model named 'x' here; models: m"):
        comparison.row("x")


def test_a_warm_refit_fits_its_training_points_at_least_as_well_as_the_full_fit():
    data = _law(noise=0.02)
    full = fit(data, model="structural-damping+newtonian", starts=2, progress=False)
    s = next(x for x in splits(data) if x.name.endswith("≤ 1 Hz"))
    # one start, no hops: start 0 is the full fit itself, so the refit can only improve on it where it trains
    r = refit("structural-damping+newtonian", s.train, full, starts=1, hops=0)
    assert rms_on(r, s.train) <= rms_on(full, s.train) * (1 + 1e-9)
    score = score_split(r, s, full)
    assert score.converged and score.reference_train_rms == rms_on(full, s.train)
    assert score.band[0] <= score.held_out <= score.band[1]


def test_warm_start_matches_parameters_by_name_when_one_is_held():
    data = _law()
    full = fit(data, model="structural-damping+newtonian", starts=1, progress=False)
    held = get_model("structural-damping+newtonian").problem(data, fixed={"eta": 0.05})
    theta = warm_start(full, held)
    assert theta.shape == (held.n_free,)
    free = [n for n, f in zip(held.names, held.free) if f]
    assert np.allclose(np.exp(theta), [full.value(n) for n in free], rtol=1e-12)


def test_the_band_keeps_the_fits_within_ten_percent_of_the_best_cost():
    data = _law(noise=0.02)
    r = fit(data, model="structural-damping+newtonian", starts=1, progress=False)
    pb = r.problem
    cost = float(np.sum(pb.residuals(r.theta) ** 2))

    def alt(theta):
        return FitAlternative(start=1, rms_log10_error=0.0, parameters=pb.parameters(theta))

    # a parameter moved until the cost rises by about 5 % (in the band) and by 50 % (out of it)
    def moved(target):
        lo, hi = 0.0, 1.0
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            th = r.theta.copy()
            th[0] += mid
            lo, hi = (mid, hi) if np.sum(pb.residuals(th) ** 2) < target * cost else (lo, mid)
        return th

    inside, outside = moved(1 + (BAND_COST - 1) / 2), moved(1.5)
    with_alts = dataclasses.replace(r, alternatives=(alt(inside), alt(outside)))
    band = band_fits(with_alts)
    assert len(band) == 2 and np.allclose(band[1].theta, inside)
    Gs, _ = band[1].moduli(data.frequency_hz)
    assert not np.allclose(Gs, r.moduli(data.frequency_hz)[0])  # the band's fit is its own, not the best's


def test_a_refit_far_above_the_full_fit_on_its_training_points_is_not_converged():
    def score(train):
        return HeldOutScore(split="s", held_out=0.1, band=(0.1, 0.1), n_band=1, train_rms=train,
                            reference_train_rms=0.01)

    assert score(0.01 * UNCONVERGED).converged and not score(0.01 * UNCONVERGED * 1.01).converged
    bad = OutOfSample.from_scores("m", True, 3, [score(0.07), score(0.01)])
    formula = OutOfSample.from_scores("f", False, 3, [score(0.01), score(0.01)])
    assert bad.unconverged == ("s",) and out_of_sample_verdict(bad, formula).startswith("no verdict")


def test_a_verdict_holds_only_across_the_band():
    def row(name, bands):
        return OutOfSample.from_scores(name, name == "m", 3, [
            HeldOutScore(split=f"s{i}", held_out=lo, band=(lo, hi), n_band=2, train_rms=0.01)
            for i, (lo, hi) in enumerate(bands)])

    formula = row("f", [(0.1, 0.12), (0.1, 0.1)])
    narrow = out_of_sample_verdict(row("m", [(0.05, 0.06), (0.05, 0.06)]), formula)
    assert narrow.startswith("the structure does better")
    # the best fits are 50 % better, but another fit as good in training is worse than the formula's best
    wide = out_of_sample_verdict(row("m", [(0.05, 0.2), (0.05, 0.06)]), formula)
    assert wide.startswith("the structure adds nothing measurable here across the band")


def test_standard_baselines_follow_the_prestress():
    assert standard_baselines(bundled("fabry2001")) == ("structural-damping", "structural-damping+newtonian")
    assert standard_baselines([bundled("stamenovic2002"), bundled("fabry2001")])[1] == \
        "structural-damping-prestress+newtonian"


def test_the_fit_command_ranks_the_model_and_its_baselines_out_of_sample(tmp_path, capsys):
    out = tmp_path / "fit"
    code = cli_main(["fit", "bundled:fabry2001", "--model", "voigt-compact", "--starts", "1", "--tolerance", "1",
                     "--validate", "yes", "--out", str(out)])
    assert code in (0, 1)
    doc = json.loads((out / "fit.json").read_text())["out_of_sample"]
    names = {m["model"] for m in doc["models"]}
    assert names == {"voigt-compact", "voigt-compact (lumped)", "structural-damping", "structural-damping+newtonian"}
    assert len(doc["splits"]) == 5
    ranked = [(not m["converged"], m["held_out_rms_mean"]) for m in doc["models"]]
    assert ranked == sorted(ranked)  # converged refits first, by their mean
    assert doc["verdict"].startswith(("the structure does better", "the structure adds nothing"))
    report = (out / "report.md").read_text()
    assert "## Out of sample" in report and doc["verdict"] in report
    capsys.readouterr()
    out2 = tmp_path / "fit2"
    assert cli_main(["fit", "bundled:fabry2001", "--model", "voigt-compact", "--starts", "1", "--tolerance", "1",
                     "--validate", "no", "--out", str(out2)]) in (0, 1)
    assert json.loads((out2 / "fit.json").read_text())["out_of_sample"] is None
    # by default the refits run only when they cost at most a quarter of the fit: here the line says what they
    # would cost and how to ask for them
    out3 = tmp_path / "fit3"
    assert cli_main(["fit", "bundled:fabry2001", "--model", "voigt-compact", "--starts", "1", "--tolerance", "1",
                     "--out", str(out3)]) in (0, 1)
    assert json.loads((out3 / "fit.json").read_text())["out_of_sample"] is None
    assert "out of sample: not run by default" in capsys.readouterr().err


@pytest.mark.parametrize("flag", ["--validate", "--validate=maybe"])
def test_a_bad_validate_flag_is_refused(tmp_path, capsys, flag):
    assert cli_main(["fit", "bundled:fabry2001", flag, "--out", str(tmp_path / "x")]) == 2
    assert "--validate" in capsys.readouterr().err
