"""`make reproduce`'s mechanism table states its options, and the command it prints repeats its numbers; the
mechanisms study (and docs/fitting.md) differ from it by one stated prestress, which the table says."""
from __future__ import annotations

import json

import pytest

from tenscell.cli import main
from tenscell.cli.fit import BUNDLED_FREQUENCY_PRESTRESS_PA
from tenscell.cli.reproduce import MECHANISM_SEARCH, _same_fit_command
from tenscell.fitting import RECOMMENDED, fit, get_model
from tenscell.fitting.entry import prepare
from tenscell.io.data import bundled


NAME = RECOMMENDED  # the docs' headline fit is the recommended model


def _reproduce_data():
    return [bundled("stamenovic2002"), bundled("fabry2001").with_prestress(BUNDLED_FREQUENCY_PRESTRESS_PA)]


def test_a_stated_prestress_is_the_one_parameter_between_reproduce_and_the_study():
    spec = get_model(NAME)
    stated = spec.problem(*prepare(_reproduce_data(), None, 100, spec))
    free = spec.problem(*prepare([bundled("stamenovic2002"), bundled("fabry2001")], None, 100, spec))
    assert free.n_free == stated.n_free + 1
    assert set(free.names) - set(stated.names) == {"P_data[1]"}


def test_the_printed_command_repeats_reproduces_fit(tmp_path, monkeypatch):
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    r = fit(_reproduce_data(), model=NAME, jobs=1, progress=False, **MECHANISM_SEARCH)
    command = _same_fit_command(_reproduce_data(), NAME).replace("DIR", str(tmp_path / "fit"))
    assert command.startswith("tenscell fit ") and f"--prestress bundled:fabry2001={BUNDLED_FREQUENCY_PRESTRESS_PA:g}" \
        in command
    assert main(command.split()[1:] + ["--jobs", "1"]) in (0, 1)
    doc = json.loads((tmp_path / "fit" / "fit.json").read_text())
    aic, bic = r.information_criteria()
    assert doc["n_free_parameters"] == r.n_free
    assert doc["BIC"] == pytest.approx(bic, abs=1e-6)
    assert doc["rms_log10_error_per_dataset"] == pytest.approx(list(r.dataset_rms), abs=1e-9)


def test_the_docs_headline_fit_gives_the_numbers_the_docs_print(tmp_path, monkeypatch):
    """docs/fitting.md's `tenscell fit ... --model RECOMMENDED` ends as the docs say (status 1, explained)
    with the RMS, BIC and parameter counts its answer paragraph prints (read from the page, not typed here)."""
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "fitting.md").read_text(encoding="utf-8")
    command = re.search(r"^tenscell fit bundled:stamenovic2002 bundled:fabry2001 --model (\S+) --out SP$", page,
                        flags=re.M)
    assert command and command.group(1) == NAME
    said = re.search(r"RMS (\d\.\d+)\s+on\s+the\s+prestress\s+sweep\s+and\s+(\d\.\d+)\s+on\s+the\s+frequency\s+sweep;"
                     r"\s+BIC\s+([−-]\d+\.\d).*?(\d+)\s+of\s+its\s+(\d+)\s+parameters\s+determined", page, flags=re.S)
    assert said, "the answer paragraph of docs/fitting.md"
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    status = main(["fit", "bundled:stamenovic2002", "bundled:fabry2001", "--model", NAME, "--jobs", "1",
                   "--out", str(tmp_path / "SP")])
    doc = json.loads((tmp_path / "SP" / "fit.json").read_text())
    rms = doc["rms_log10_error_per_dataset"]
    assert (f"{rms[0]:.3f}", f"{rms[1]:.3f}") == (said.group(1), said.group(2))
    assert f"{doc['BIC']:.1f}" == said.group(3).replace("−", "-")
    assert doc["n_free_parameters"] == int(said.group(5))
    determined = sum(p["stderr"] is not None and p["stderr_percent"] <= 10 for p in doc["parameters"] if p["vary"])
    assert determined == int(said.group(4))
    # the exit status the page explains: 1 when the prestress sweep misses the tolerance, which the report says
    assert status == (0 if doc["converged"] else 1)
    if status == 1:
        assert "the prestress sweep's RMS misses the default tolerance" in page
        assert doc["status"] != "tolerance met"
        assert doc["information_criteria"]["status_means"] in (tmp_path / "SP" / "report.md").read_text()
