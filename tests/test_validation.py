"""Out of sample (tenscell.fitting.validation): the splits, the held-out error, the verdict against the formula."""
from __future__ import annotations

import json

import numpy as np
import pytest

from tenscell.cli import main as cli_main
from tenscell.fitting import fit
from tenscell.fitting.models.formulas import structural_damping_moduli
from tenscell.fitting.validation import (NO_BETTER, OutOfSample, held_out_rms, out_of_sample, out_of_sample_verdict,
                                         splits, standard_baselines)
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
                                       "fabry2001_hasm_powerlaw: ≤ 1 Hz", "fabry2001_hasm_powerlaw: ≤ 10 Hz",
                                       "fabry2001_hasm_powerlaw: ≤ 30 Hz"]
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


def test_a_law_predicts_its_own_held_out_points_and_a_wrong_one_does_not():
    data = _law()
    (s,) = [x for x in splits(data) if x.name.endswith("≤ 10 Hz")]
    right = fit(s.train, model="structural-damping+newtonian", starts=2, progress=False)
    assert held_out_rms(right, s) < 1e-4
    wrong = fit(s.train, model="structural-damping", starts=2, progress=False)  # no Newtonian upturn
    assert held_out_rms(wrong, s) > 0.05
    oos = out_of_sample("structural-damping+newtonian", data, starts=2)
    assert oos.rms.shape == (3,) and oos.worst < 1e-3 and oos.mean <= oos.worst


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
    means = [m["held_out_rms_mean"] for m in doc["models"]]
    assert means == sorted(means) and len(doc["splits"]) == 3
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
