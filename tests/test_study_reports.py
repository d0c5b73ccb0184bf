"""Study reports follow the run's parameters, and the study results follow the result conventions.

Each study is run with parameters other than the defaults; its Markdown
report must print those (and numbers computed from them), never the
defaults. Each result has a short repr, a unit-named DataFrame and a plot
on given axes.
"""
from __future__ import annotations

import numpy as np
import pytest

from tenscell import paper_cell
from tenscell.laws import stiffening_law
from tenscell.dynamics import creep_response, oscillatory_response
from tenscell.reports.sensitivity import sensitivity_markdown
from tenscell.reports.studies import no_if_markdown, references_markdown, semiflexible_markdown, stiffening_markdown
from tenscell.sensitivity import analytic_elasticities
from tenscell.studies import sensitivity_study
from tenscell.studies.no_if import no_if_study
from tenscell.studies.references import references_study
from tenscell.studies.semiflexible import semiflexible_study
from tenscell.studies.stiffening import linearize_stiffening, stiffening_study


@pytest.fixture(scope="module")
def studies():
    return {
        "no_if": no_if_study(prestress=(150.0, 300.0), f_hz=np.logspace(-1, 4, 11), EA=2.0, c=4.0, reference_P=300.0,
                             EA_values=(2.0, 20.0), c_values=(4.0, 40.0), window_hz=250.0),
        "references": references_study(prestress=(700.0, 1400.0), f_hz=np.logspace(-1, 2, 7), EA=3.0, c=0.5,
                                       map_alpha=np.radians([0.0, 5.0]), map_delta=np.radians([48.0, 50.0, 52.0]),
                                       curve_alpha=np.radians([0.0])),
        "semiflexible": semiflexible_study(EA_strut=np.logspace(5, 8, 4), f_hz=np.logspace(-1, 2, 7), P=600.0, EA=3.0,
                                           c=0.7, c_strut=0.2),
        "stiffening": stiffening_study(b=(0.0, 0.2), prestress=(800.0, 1600.0), f_hz=(2.0,), EA=2.5, c=0.4),
        "sensitivity": sensitivity_study(3, seed=3, change=0.05, P=1500.0, EA=2.0, c=0.6, f_hz=np.logspace(-1, 2, 5),
                                         progress=False),
    }


def test_no_if_report_follows_its_parameters(studies):
    s = studies["no_if"]
    md = no_if_markdown(s)
    assert "EA = 2 N, c = 4 N·s/m" in md and "at c = 4 N·s/m" in md
    assert "f ≤ 250 Hz" in md and "1000" not in md
    assert "At P = 300 N" in md and "EA = 1 N" not in md
    assert f"{s.peaks[0].frequency_hz:.5g}" in md
    assert "Not shown" in md


def test_references_report_follows_its_parameters(studies):
    s = studies["references"]
    md = references_markdown(s)
    assert "EA = 3 N, c = 0.5 N·s/m" in md and "EA = 1 N" not in md
    assert f"P = {s.map.P:g} N" in md  # the map's stability check at the study's middle prestress
    assert "G'(0.1 Hz)" in md and "G'(100 Hz)" in md and "0.01 Hz" not in md
    assert "| 700 |" in md and "| 1400 |" in md


def test_semiflexible_report_follows_its_parameters(studies):
    s = studies["semiflexible"]
    md = semiflexible_markdown(s)
    assert "tendons EA = 3 N, c = 0.7 N·s/m; P = 600 N" in md and "c_s = 0.2 N·s/m" in md
    assert f"{s.n_struts} struts" in md
    assert "EA = 1 N" not in md and "P = 1000" not in md


def test_stiffening_report_follows_its_parameters(studies):
    s = studies["stiffening"]
    md = stiffening_markdown(s)
    assert "EA = 2.5 N, c = 0.4 N·s/m" in md and "EA = 1 N" not in md
    assert "G'(2 Hz)" in md and "1 Hz" not in md
    assert f"{len(s.stiffening_indices)} intermediate_filament tendons" in md
    assert f"{s.G[1, -1, 0].real:.5g}" in md
    # the claim about G'' follows the computed ratios, whichever way they go
    falls = s.G[:, -1, 0].imag / s.G[:, 0, 0].imag < 1
    assert ("G'' falls with prestress" in md) == bool(falls.any())


def test_sensitivity_report_follows_its_parameters(studies):
    s = studies["sensitivity"]
    md = sensitivity_markdown(s)
    assert "P = 1500 N" in md and "EA = 2 N" in md and "c = 0.6 N·s/m" in md
    assert "(±5%)" in md and "±0.05 rad" in md and "±0.025 rad" in md and "±10%" not in md
    assert "3 draws (seed 3)" in md
    assert "P = 1000" not in md and "EA = 1 N" not in md


def test_study_results_follow_the_result_conventions(studies):
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    objs = list(studies.values()) + [studies["sensitivity"].elasticities, studies["sensitivity"].monte_carlo[0],
                                      studies["references"].map]
    for obj in objs:
        r = repr(obj)
        assert r.startswith("<") and len(r.splitlines()) <= 6, r
        df = obj.to_dataframe()
        assert len(df) > 0
        # single-panel results draw on the axes given, two-panel ones on the pair given
        fig, axes = plt.subplots(1, 2)
        try:
            out = obj.plot(ax=axes[0])
            assert out is axes[0]
        except ValueError as err:
            assert "2 panel(s)" in str(err)
            out = obj.plot(ax=axes)
            assert list(np.ravel(out)) == list(axes)
        plt.close(fig)
    cols = studies["stiffening"].to_dataframe().columns
    assert {"b", "prestress_N", "frequency_Hz", "G_storage_Pa", "G_loss_Pa"} <= set(cols)


def test_time_domain_results_follow_the_result_conventions():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    cell = paper_cell()
    law = stiffening_law(cell, 1000.0, b=0.3)
    r = oscillatory_response(cell, law, 0.1, 1.0, cycles=1, samples_per_cycle=32, n_harmonics=5)
    c = creep_response(cell, law, 0.1, np.logspace(-3, -1, 4))
    for obj in (r, r.harmonics, r.simulation, c):
        assert len(repr(obj).splitlines()) <= 6
        df = obj.to_dataframe()
        assert len(df) > 0 and any(col.endswith(("_s", "_Hz", "_N")) for col in df.columns)
        fig, ax = plt.subplots()
        assert obj.plot(ax=ax) is ax
        plt.close(fig)
    assert {"time_s", "probe_displacement_m", "force_N"} <= set(r.to_dataframe().columns)


def test_stiffening_elasticities_rows_carry_the_law_parameters():
    el = analytic_elasticities(linearize_stiffening(paper_cell(), 1000.0, b=0.2), [1.0])
    ifs = paper_cell().structure.family_indices("intermediate_filament")
    assert [n for n in el.names if n.startswith("b[")] == [f"b[{j}]" for j in ifs]
    assert el.groups[el.index(f"b[{ifs[0]}]")] == "b IF"
