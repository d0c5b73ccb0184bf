"""The prestress anchor (tenscell.fitting.anchor): σ held to the measured prestress, for every kind of model."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from tenscell.fitting.anchor import (DEFAULT_FACTOR, Anchor, anchor_of, parse_anchor, prestress_ratio,
                                     sigma_per_model_prestress)
from tenscell.io.data import bundled
from tenscell.model import paper_cell, sphere_cell
from tenscell.model.prestress import virial_prestress


@pytest.fixture(scope="module")
def pair():
    return [bundled("stamenovic2002"), bundled("fabry2001").with_prestress(1000.0)]


def test_the_window_is_the_scale_at_which_sigma_equals_the_measured_prestress():
    cell = paper_cell()
    s = virial_prestress(cell).scale_m2
    lo, hi = Anchor(2.0).window(cell)
    assert (lo, hi) == pytest.approx((s / 2, 2 * s), rel=1e-14)
    assert Anchor.exact().window(cell) == pytest.approx((s, s), rel=1e-14)
    assert Anchor().factor == DEFAULT_FACTOR
    # σ at P = s_σ·p is p: the scale is 1/(σ per unit P)
    assert virial_prestress(cell).sigma(s * 1234.0) == pytest.approx(1234.0, rel=1e-12)


def test_fit_options_for_a_mechanism_and_for_the_voigt_cell():
    cell = paper_cell()
    s = virial_prestress(cell).scale_m2
    assert Anchor(1.5).fit_options(cell, ("EA", "s")) == {"bounds": {"s": pytest.approx((s / 1.5, s * 1.5))},
                                                          "fixed": {}}
    assert Anchor.exact().fit_options(cell, ("EA", "s")) == {"bounds": {}, "fixed": {"s": pytest.approx(s)}}
    # the Voigt cell: L is a gauge of P/L²; the anchor holds it at the reference, or follows a given L as (L/L_ref)²
    opts = Anchor.exact().fit_options(cell, ("EA", "c", "s", "L"))
    assert opts["fixed"] == {"L": 1.0, "s": pytest.approx(s)}
    opts = Anchor(1.5).fit_options(cell, ("EA", "c", "s", "L"), fixed={"L": 2.0})
    assert opts["bounds"]["s"] == pytest.approx((4 * s / 1.5, 4 * s * 1.5))
    with pytest.raises(ValueError, match="fixed\\['s'\\]"):
        Anchor().fit_options(cell, ("s",), fixed={"s": 1.0})


def test_options_for_refuses_what_cannot_be_anchored(pair):
    with pytest.raises(ValueError, match="no data set states its prestress"):
        Anchor().options_for("springpot+visc", [bundled("fabry2001")])
    with pytest.raises(ValueError, match="structure-free"):
        Anchor().options_for("structural-damping", pair)
    with pytest.raises(ValueError, match="bounds\\['s'\\]"):
        Anchor().options_for("springpot+visc", pair, bounds={"s": (1, 2)})
    opts = Anchor().options_for("springpot+visc", pair, cell=sphere_cell(12), bounds={"stiffness": (1e-3, 1e6)})
    s = virial_prestress(sphere_cell(12)).scale_m2
    assert opts["bounds"] == {"stiffness": (1e-3, 1e6), "s": pytest.approx((s / 1.5, s * 1.5))}
    assert opts["fixed"] is None


@pytest.mark.parametrize("text, factor", [(None, DEFAULT_FACTOR), ("", DEFAULT_FACTOR), ("exact", 1.0),
                                          ("EXACT", 1.0), ("2", 2.0), ("1.25", 1.25)])
def test_parse_anchor(text, factor):
    assert parse_anchor(text).factor == factor


@pytest.mark.parametrize("text", ["0.5", "1", "-2", "nan", "inf", "1e9", "data.csv"])
def test_parse_anchor_refuses_in_one_line_with_the_syntax(text):
    with pytest.raises(ValueError) as err:
        parse_anchor(text)
    msg = str(err.value)
    assert msg.startswith(f"--anchored {text}") and "--anchored [FACTOR|exact]" in msg and "\n" not in msg


@pytest.mark.parametrize("bad", [0.5, 0.0, -1, math.nan, math.inf, True, "2", 1e3])
def test_anchor_refuses_bad_factors(bad):
    with pytest.raises(ValueError, match="factor"):
        Anchor(bad)


def test_holds():
    a = Anchor(1.5)
    assert a.holds(1.0) and a.holds(1.5) and a.holds(1 / 1.5) and not a.holds(1.51) and not a.holds(0.66)
    assert Anchor.exact().holds(1.0) and not Anchor.exact().holds(1.001)


def test_an_anchored_fit_reports_its_ratio_and_its_anchor(pair):
    """Held exact, σ/measured is 1 at every prestress; held ×/÷1.5, it lies within; the fit's bounds name its anchor."""
    from tenscell.fitting import fit

    search = dict(starts=1, hops=2, patience=1, seed=0, progress=False, max_nfev=30)
    cell = paper_cell()
    exact = fit(pair, model="springpot+visc", **Anchor.exact().options_for("springpot+visc", pair), **search)
    lo, hi = prestress_ratio(exact)
    assert lo == pytest.approx(1.0, rel=1e-9) and hi == pytest.approx(1.0, rel=1e-9)
    assert anchor_of(exact) == Anchor.exact()
    assert sigma_per_model_prestress(exact) == pytest.approx(virial_prestress(cell).sigma_per_P)
    loose = fit(pair, model="springpot+visc", **Anchor(1.5).options_for("springpot+visc", pair), **search)
    lo, hi = prestress_ratio(loose)
    assert Anchor(1.5).holds(lo) and Anchor(1.5).holds(hi) and lo == pytest.approx(hi, rel=1e-12)
    assert anchor_of(loose) == Anchor(1.5)


def test_the_voigt_cells_ratio_follows_its_strut_length(pair):
    """σ ∝ P/L² on the fitted cell: the same moduli at (λ²s, λL) give the same σ/measured."""
    from tenscell.fitting import fit

    search = dict(starts=1, hops=1, patience=1, seed=0, progress=False, max_nfev=5, tendons="uniform")
    a = fit(pair, fixed={"L": 1.0, "s": 0.3}, **search)
    b = fit(pair, fixed={"L": 2.0, "s": 1.2}, **search)
    assert prestress_ratio(a)[0] == pytest.approx(0.3 * virial_prestress(paper_cell()).sigma_per_P, rel=1e-12)
    assert prestress_ratio(b)[0] == pytest.approx(prestress_ratio(a)[0], rel=1e-12)


def test_the_old_anchored_window_is_the_gauge_window_and_warns():
    import tenscell.fitting.shares as shares

    with pytest.warns(DeprecationWarning, match="GAUGE_WINDOW_S"):
        old = shares.ANCHORED_S
    assert old == shares.GAUGE_WINDOW_S
    with pytest.warns(DeprecationWarning, match="GAUGE_WINDOW_L"):
        assert shares.ANCHORED_L == shares.GAUGE_WINDOW_L
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert shares.GAUGE_WINDOW_S == pytest.approx((0.01, 100.0))
    with pytest.raises(AttributeError):
        shares.NO_SUCH_NAME  # noqa: B018


def test_ratio_is_none_without_a_stated_prestress():
    from tenscell.fitting import fit

    r = fit(bundled("fabry2001"), model="springpot+visc", starts=1, hops=1, patience=1, seed=0, progress=False,
            max_nfev=5)
    assert prestress_ratio(r) is None and anchor_of(r) is None
    assert np.isfinite(sigma_per_model_prestress(r))
