"""`tenscell study mechanisms` says what it will cost before its first fit, and refuses a run beyond a day."""
from __future__ import annotations

import pytest

from tenscell.cli import main
from tenscell.cli import _legacy_studies as study_cli
from tenscell.fitting.models.catalog import PER_TENDON_VOIGT
from tenscell.io.data import bundled


def test_the_estimate_counts_every_fit_of_the_study():
    from tenscell.fitting.validation import splits
    from tenscell.studies.falsification import UNLIKE_KINDS

    data = (bundled("stamenovic2002"), bundled("fabry2001"))
    rate = study_cli.EVALUATIONS_PER_START_HOP
    main = 3 * 5  # starts × (hops + 1); every refit runs to the main fit's budget
    # alone: the main fit, then the anchored refit (maxwell is a mechanism)
    one = study_cli.mechanisms_cost(data, ("maxwell",), starts=3, hops=4, jobs=2, validate=False, falsify=False)
    assert one.count == round(rate["mechanism"] * 2 * main) and one.parallel == 1  # one model: one worker
    # with the held-out splits, the unlike versions of the sweep and the flat-loss-tangent lines
    n_split = len(splits(data))
    assert n_split >= 2
    full = study_cli.mechanisms_cost(data, ("maxwell",), starts=3, hops=4, jobs=2)
    assert full.count == round(rate["mechanism"] * (2 + n_split + len(UNLIKE_KINDS) + 1) * main)
    both = study_cli.mechanisms_cost(data, ("maxwell", PER_TENDON_VOIGT), starts=3, hops=4, jobs=2)
    # the per-tendon fit searches at least 30 hops; its 37 parameters are too many for the refits
    assert both.count == full.count + round(rate["voigt-per-tendon"] * 3 * 31)
    assert both.parallel == 2 and both.seconds_per_unit > 0
    assert "2 model(s)" in both.line() and "2 workers" in both.line()


def test_the_study_announces_its_cost_first(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("TENSCELL_PROGRESS", raising=False)
    assert main(["study", "mechanisms", "bundled:fabry2001", "--mechanisms", "maxwell", "--starts", "1", "--hops",
                 "0", "--jobs", "1", "--ensemble", "0", "--out", str(tmp_path / "m")]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if line.startswith("tenscell: ")]
    first = next(i for i, line in enumerate(lines) if line.startswith("tenscell: estimated "))
    assert first < next(i for i, line in enumerate(lines) if line.startswith("tenscell: study mechanisms"))
    assert "per model evaluation" in lines[first]


def test_a_study_beyond_a_day_is_refused_before_any_fit(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(study_cli.EVALUATIONS_PER_START_HOP, "mechanism", 1e12)
    out = tmp_path / "m"
    assert main(["study", "mechanisms", "bundled:fabry2001", "--mechanisms", "maxwell", "--ensemble", "0",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 or all(not e.startswith("tenscell: study") for e in err)
    assert "--starts: estimated" in err[-1] and "more than the 24 h one run may take" in err[-1] and "--mechanisms" in err[-1]
    assert not out.exists()


@pytest.mark.parametrize("flag", ["--starts", "--hops"])
def test_the_refusal_names_what_to_change(flag, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(study_cli.EVALUATIONS_PER_START_HOP, "mechanism", 1e12)
    assert main(["study", "mechanisms", "bundled:fabry2001", "--mechanisms", "maxwell", "--ensemble", "0",
                 "--out", str(tmp_path / "m")]) == 2
    assert flag in capsys.readouterr().err
