"""The structures study (tenscell.studies.structures): its plan, how a mechanism meets a structure, a small run."""
from __future__ import annotations

import math

import pytest

from tenscell.fitting.anchor import Anchor
from tenscell.model.prestress import virial_prestress
from tenscell.studies.protocol import Study
from tenscell.studies.structures import (ANCHORS, MECHANISMS, STRUCTURES, STUDY, STRUT_MARGIN, bundled_pair,
                                        search_space, structure_cell, structure_mechanism, structures_study)


def test_the_study_follows_the_protocol_and_plans_every_fit():
    assert isinstance(STUDY, Study) and STUDY.name == "structures"
    plan = STUDY.plan({"structures": ["6-strut paper cell", "12-strut sphere"], "mechanisms": list(MECHANISMS[:2])})
    # per structure and mechanism: the free fit from each seed, each anchor warm (after the free fits) and fresh
    assert plan.count() == 2 * 2 * (2 + 2 * 2)
    warm = plan.task("6-strut paper cell/springpot-alpha-family+visc/exact/warm")
    assert warm.needs == ("6-strut paper cell/springpot-alpha-family+visc/free/seed 0",
                          "6-strut paper cell/springpot-alpha-family+visc/free/seed 1")
    assert STUDY.plan({"anchors": ["exact"], "structures": ["6-strut paper cell"]}).count() == len(MECHANISMS)
    # a heavy structure: the free fit from one seed, each anchored fit warm only (one start)
    heavy = STUDY.plan({"structures": ["30-strut sphere"], "mechanisms": [MECHANISMS[0]]})
    assert [t.key.split("/", 2)[2] for t in heavy.tasks] == ["free/seed 0", "×/÷1.5/warm", "exact/warm"]
    assert heavy.tasks[1].args[-1]["starts"] == 1


@pytest.mark.parametrize("options, match", [
    ({"structures": ["dodecahedron"]}, "structures must be"),
    ({"mechanisms": ["voigt-per-tendon"]}, "mechanisms must be"),
    ({"anchors": []}, "anchors must be"),
    ({"colour": "red"}, "unknown option 'colour'"),
])
def test_bad_options_are_refused_before_any_work(options, match):
    with pytest.raises(ValueError, match=match):
        STUDY.plan(options)


def test_no_stated_prestress_is_refused():
    from tenscell.io.data import bundled

    with pytest.raises(ValueError, match="states its prestress"):
        STUDY.plan({"datasets": [bundled("fabry2001")]})


def test_a_mechanism_meets_a_structure_with_compression_members():
    """Elastic struts carry compression: a spring shared with the tendons is laid out per family there, and the
    struts' EA is bounded below by twice their largest compression at the top of the fit's prestresses."""
    paper, semi = structure_cell("6-strut paper cell"), structure_cell("6-strut, elastic struts")
    name = "springpot-alpha-family+visc"
    assert structure_mechanism(name, paper).name == name
    mech = structure_mechanism(name, semi)
    assert mech.name.endswith("[EA per family]")
    data = bundled_pair()
    names = mech.problem(data, semi).names
    assert {"EA_actin", "EA_intermediate_filament", "EA_strut", "kappa_strut", "alpha_strut"} <= set(names)
    space = search_space(semi, mech, data, Anchor(1.5))
    s_hi = Anchor(1.5).window(semi)[1]
    compression = -float(min(semi.T0))
    assert space["bounds"]["EA_strut"][0] == pytest.approx(STRUT_MARGIN * compression * s_hi * 1900.0, rel=1e-9)
    assert space["bounds"]["s"] == pytest.approx(Anchor(1.5).window(semi))
    # a nucleus at zero force and a one-family structure keep the mechanism as it is
    assert structure_mechanism(name, structure_cell("6-strut + nucleus")).name == name
    assert structure_mechanism(name, structure_cell("6-strut, no IFs")).name == name


def test_a_small_run():
    """One structure, one mechanism, every anchor: σ/measured is 1 held exact, within ×/÷1.5 anchored; the band holds
    the best fit; the ranking, the G1 check and the page come from the table."""
    r = structures_study(structures=["6-strut, no IFs"], mechanisms=["springpot+visc"],
                         search={"starts": 1, "hops": 1, "patience": 1, "max_nfev": 20})
    t = r.table("structures")
    rows = {row["anchor"]: row for row in t.records()}
    assert set(rows) == set(ANCHORS)
    assert rows["exact"]["sigma_over_measured"] == pytest.approx(1.0, rel=1e-9)
    assert Anchor(1.5).holds(rows["×/÷1.5"]["sigma_over_measured"])
    for row in rows.values():
        assert row["band_worst_rms_lo_decades"] == pytest.approx(row["worst_rms_decades"])
        assert row["band_worst_rms_lo_decades"] <= row["band_worst_rms_hi_decades"]
        assert 1 <= row["fits_in_band"] <= row["fits"]
        assert row["n_free"] <= 5  # one family (actin): a family layout gives one value
        assert row["rms_stamenovic2002_hasm_0p1Hz_decades"] > 0
    assert rows["exact"]["n_free"] == rows["free"]["n_free"] - 1  # s held
    ranking = r.table("structures_ranking").records()
    assert [x["anchor"] for x in ranking] == list(ANCHORS)
    check = r.checks[0]
    assert check.label.startswith("G1") and isinstance(check.met, bool)
    assert "Structures compared at the anchor" in r.pages[0][1] and r.files() == (
        "structures.csv", "structures_ranking.csv", "structures.md")
    assert math.isfinite(r.data.cpu_s) and len(r.data.records) == 6


def test_sigma_scale_of_every_structure():
    for name in STRUCTURES:
        assert virial_prestress(structure_cell(name)).sigma_per_P > 0, name
