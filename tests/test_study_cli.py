"""`tenscell study`: a table of studies on the protocol and one writer (tables by column name, figures through their
plotters, pages), each study's estimate from its plan."""
from __future__ import annotations

import csv
from pathlib import Path

import pytest

from tenscell.cli import main
from tenscell.cli import study as study_cli
from tenscell.cli._study_output import write_study_result
from tenscell.io.data import bundled
from tenscell.studies.protocol import FIGURE, Figure, Study, StudyResult, Table


#: the measured cells of study real-cells (never shipped: its plan reads them, so it is skipped where they are absent)
REAL = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "real-cells"


def _plan(name):
    study = study_cli.load_study(name)
    options = {"data": (bundled("fabry2001"),)} if "data" in study.options else {}
    if name == "real-cells":
        if not REAL.is_dir():
            pytest.skip(f"the measured-cell data are not at {REAL} (never shipped with tenscell)")
        options = {"data_dir": str(REAL)}
    return study, study.plan(options)


@pytest.mark.parametrize("name", sorted(study_cli.STUDIES))
def test_every_study_follows_the_protocol_and_calibrates_every_kind_of_its_tasks(name):
    study, plan = _plan(name)
    assert isinstance(study, Study) and study.name == name and plan.study == name
    probed = {p.kind for p in plan.calibration}
    assert set(plan.kinds()) <= probed, f"{name}: no probe for {set(plan.kinds()) - probed}"
    assert plan.figures >= 0 and plan.tasks  # a study that draws nothing (structures: tables, a page) says 0
    # the estimate counts every task of the plan: each kind's rate doubled doubles its share of the estimate
    rates = dict.fromkeys(probed, 1.0) | {FIGURE: 1.0}
    assert plan.estimate_cpu(dict.fromkeys(probed, 2.0)) == pytest.approx(2 * plan.estimate_cpu(rates))


def test_the_parser_lists_every_study_and_loads_none():
    import sys

    before = {m for m in sys.modules if m.startswith("tenscell.studies.")}
    from tenscell.cli import build_parser

    build_parser()
    assert {m for m in sys.modules if m.startswith("tenscell.studies.")} == before


def test_the_writer_puts_tables_by_column_name_figures_and_pages(tmp_path):
    import numpy as np

    f = np.logspace(0, 2, 5)
    result = StudyResult("demo", tables=(Table.from_records("t", [{"a_Hz": 1.0, "b": "x"}, {"b": "y", "a_Hz": 2.5}]),),
                         figures=(Figure("f.png", "calibration_figure", (f, f)),), pages=(("p.md", "# page\n"),))
    write_study_result(tmp_path, result)
    with open(tmp_path / "t.csv") as fh:
        assert list(csv.reader(fh)) == [["a_Hz", "b"], ["1.0", "x"], ["2.5", "y"]]
    assert (tmp_path / "f.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "p.md").read_text() == "# page\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(result.files())


def test_the_study_announces_its_estimate_revises_it_and_says_how_it_compared(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("TENSCELL_PROGRESS", raising=False)
    assert main(["study", "sensitivity", "--draws", "20", "--out", str(tmp_path / "s")]) == 0
    lines = [x for x in capsys.readouterr().err.splitlines() if x.startswith("tenscell: ")]
    first = next(i for i, x in enumerate(lines) if x.startswith("tenscell: estimated "))
    assert first < next(i for i, x in enumerate(lines) if x.startswith("tenscell: study sensitivity"))
    assert "of a CPU" in lines[first]
    done = [x for x in lines if "tasks done" in x]
    assert len(done) == 3 and "left" in done[0] and done[-1].split()[1] == "3/3"
    assert "(estimated " in lines[-1] and "finished in" in lines[-1]


def test_a_plan_beyond_a_day_is_refused_naming_its_sizing_flag(tmp_path, capsys, monkeypatch):
    from tenscell.studies import sensitivity

    monkeypatch.setitem(sensitivity.DRAW_UNITS, "all", 1e9)
    out = tmp_path / "s"
    assert main(["study", "sensitivity", "--draws", "20", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("tenscell study: error: --draws: estimated") and "one run may take" in err[-1]
    assert not out.exists()
