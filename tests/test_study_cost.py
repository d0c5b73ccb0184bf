"""`tenscell study mechanisms` says what it will cost before its first fit, and refuses a run beyond a day.

Its estimate is its plan's (tenscell.studies.protocol): every fit's task weighs the model evaluations it is expected
to take, and each model's rate is one evaluation's CPU, timed by the plan's probe of that model.
"""
from __future__ import annotations

import pytest

from tenscell.cli import main
from tenscell.fitting import search
from tenscell.fitting.models.catalog import PER_TENDON_VOIGT
from tenscell.io.data import bundled
from tenscell.studies.mechanisms import REFIT_SHARE, STUDY, evaluations_of


def _plan(names, **options):
    data = (bundled("stamenovic2002"), bundled("fabry2001"))
    return STUDY.plan({"datasets": data, "mechanisms": names, "starts": 3, "hops": 4, "ensemble": 0, **options})


def test_the_estimate_counts_every_fit_of_the_study():
    from tenscell.fitting.validation import splits
    from tenscell.studies.falsification import UNLIKE_KINDS

    data = (bundled("stamenovic2002"), bundled("fabry2001"))
    rate = search.EVALUATIONS_PER_START_HOP
    main_fit = 3 * 5  # starts × (hops + 1); a refit, warm at the main fit, takes REFIT_SHARE of its evaluations
    # alone: the main fit, then the anchored refit (maxwell is a mechanism)
    one = _plan(("maxwell",), validate=False, falsify=False).kinds()[evaluations_of("maxwell")]
    assert one == pytest.approx(rate["mechanism"] * (1 + REFIT_SHARE) * main_fit)
    # with the held-out splits, the unlike versions of the sweep and the flat-loss-tangent lines
    n_split = len(splits(data))
    assert n_split >= 2
    full = _plan(("maxwell",))
    assert full.kinds()[evaluations_of("maxwell")] == pytest.approx(
        rate["mechanism"] * (1 + REFIT_SHARE * (1 + n_split + len(UNLIKE_KINDS) + 1)) * main_fit)
    # a structure-free baseline: a formula's fits, its held-out refits at the same share
    formula = full.kinds()[evaluations_of("structural-damping-prestress+newtonian")]
    assert formula == pytest.approx(rate["formula"] * (1 + REFIT_SHARE * n_split) * main_fit)
    both = _plan(("maxwell", PER_TENDON_VOIGT))
    # the per-tendon fit searches at least 30 hops; its 37 parameters are too many for the refits
    assert both.kinds()[evaluations_of(PER_TENDON_VOIGT)] == pytest.approx(rate["voigt-per-tendon"] * 3 * 31)
    # every kind of task has its probe, and the structure-free baselines are planned beside the models
    assert {p.kind for p in both.calibration} == set(both.kinds())
    assert any(k.startswith("evaluation of structural-damping") for k in both.kinds())


def test_the_probes_give_every_kind_a_rate_and_the_estimate_scales_with_the_plan():
    from tenscell.studies.protocol import calibrate

    small, large = _plan(("maxwell",), validate=False, falsify=False), _plan(("maxwell",), starts=6)
    rates, machine = calibrate(small)
    assert set(rates) == set(small.kinds()) and all(r > 0 for r in rates.values())
    # twice the starts: twice the evaluations of every fit, so more than twice the CPU of the smaller plan (its
    # referee's refits come on top)
    assert large.estimate_cpu({**rates, **calibrate(large)[0]}) > 2 * small.estimate_cpu(rates)


def test_the_study_announces_its_cost_first(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("TENSCELL_PROGRESS", raising=False)
    assert main(["study", "mechanisms", "bundled:fabry2001", "--mechanisms", "maxwell", "--starts", "1", "--hops",
                 "0", "--jobs", "1", "--ensemble", "0", "--out", str(tmp_path / "m")]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if line.startswith("tenscell: ")]
    first = next(i for i, line in enumerate(lines) if line.startswith("tenscell: estimated "))
    assert first < next(i for i, line in enumerate(lines) if line.startswith("tenscell: study mechanisms"))
    assert "of CPU per evaluation of maxwell" in lines[first]


def test_a_study_beyond_a_day_is_refused_before_any_fit(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(search.EVALUATIONS_PER_START_HOP, "mechanism", 1e12)
    out = tmp_path / "m"
    assert main(["study", "mechanisms", "bundled:fabry2001", "--mechanisms", "maxwell", "--ensemble", "0",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert not any(e.startswith("tenscell: study") for e in err)
    assert "--starts: estimated" in err[-1] and "more than the 24 h one run may take" in err[-1] and "--mechanisms" in err[-1]
    assert not out.exists()


@pytest.mark.parametrize("flag", ["--starts", "--hops"])
def test_the_refusal_names_what_to_change(flag, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(search.EVALUATIONS_PER_START_HOP, "mechanism", 1e12)
    assert main(["study", "mechanisms", "bundled:fabry2001", "--mechanisms", "maxwell", "--ensemble", "0",
                 "--out", str(tmp_path / "m")]) == 2
    assert flag in capsys.readouterr().err.splitlines()[-1]


@pytest.mark.parametrize("argv, says", [
    (["--mechanisms", "nonsense"], "--mechanisms: unknown mechanism 'nonsense'"),
    (["--mechanisms", ","], "--mechanisms ',': no mechanism named"),
    (["--ensemble", "1"], "--ensemble: 1 assignment has no spread"),
    (["--ensemble", "0", "--workers", "2"], "--workers applies to the study's ensemble"),
])
def test_bad_options_are_refused_in_one_line_before_any_work(argv, says, tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["study", "mechanisms", "bundled:fabry2001", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0] and not out.exists()
