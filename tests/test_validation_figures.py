"""The validation page's figures (tenscell.plotting.validation) and how docs/update_validation.py puts them on the
page.

* Each figure draws the numbers it is given, where they belong: a band's ends and its best fit at their x, a
  population's least-squares slope dα/dlog10 k in its legend equal to the slope of the points drawn, each cell's
  slope pair at (measured, modelled); every title, label and legend inside the canvas (the journal check of
  tests/test_figures_inside.py).
* The page: the run's figures copied beside it and listed between the figure markers, in a fixed order with their
  captions; a figure a run did not draw is removed; the table markers untouched; every figure the committed page
  shows exists.
"""
from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # noqa: E402 - the measuring renderer

import matplotlib.pyplot as plt
import numpy as np
import pytest

from tenscell import plotting
from tenscell.plotting.validation import (cell_slopes_figure, heldout_bands, heldout_bands_figure,
                                          population_cells_figure)
from test_figures_inside import problems

DOCS = Path(__file__).resolve().parents[1] / "docs"


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_heldout_bands_draw_each_band_where_it_lies():
    models = ["springpot-alpha-family+visc", "maxwell+visc", "structural-damping+newtonian"]
    low = np.array([[0.06, 0.11], [0.2, np.nan], [0.09, 0.08]])
    high = low + np.array([[0.04, 0.07], [0.03, 0.0], [0.0, 0.0]])
    best = low + 0.01
    ax = heldout_bands(models, low, high, best, columns=["MCF-10A", "MDA-MB-436"], limit=0.08)
    segments = [seg for c in ax.collections for seg in c.get_segments()]
    drawn = sorted((round(s[0][0], 6), round(s[1][0], 6)) for s in segments)
    ok = np.isfinite(low)
    assert drawn == sorted(zip(np.round(low[ok], 6), np.round(high[ok], 6)))  # NaN: no band
    assert [t.get_text().replace("\n", " ") for t in ax.get_yticklabels()] == models
    assert any(np.allclose(line.get_xdata(), 0.08) for line in ax.get_lines())  # the limit
    with pytest.raises(ValueError, match="models × columns"):
        heldout_bands(models, low[:2], high[:2], columns=["MCF-10A", "MDA-MB-436"])
    fig = plotting.figure_of(heldout_bands_figure(models, low, high, best, columns=["MCF-10A", "MDA-MB-436"],
                                                  limit=0.08, reference=models[-1], title="held out"))
    assert problems(fig) == []


def _population(rng, n):
    k = 10 ** rng.normal(2.5, 0.3, n)
    alpha = 0.3 - 0.12 * np.log10(k) + rng.normal(0, 0.02, n)
    return {"stiffness_measured_Pa": k, "exponent_measured": alpha, "stiffness_model_Pa": k * 1.1,
            "exponent_model": 0.32 - 0.15 * np.log10(k * 1.1)}


def test_population_cells_state_the_slope_of_the_points_they_draw():
    rng = np.random.default_rng(0)
    lines = {"MCF-10A": _population(rng, 57), "MDA-MB-436": _population(rng, 25)}
    ax = population_cells_figure(lines, title="exponent against stiffness")
    assert problems(plotting.figure_of(ax)) == []
    for a, c in zip(ax, lines.values()):
        stated = dict(re.findall(r"(measured|model) ([+-][\d.]+)", a.get_title()))
        for label, name, k, alpha in (("measured cells", "measured", c["stiffness_measured_Pa"],
                                       c["exponent_measured"]),
                                      ("population model", "model", c["stiffness_model_Pa"], c["exponent_model"])):
            line = next(ln for ln in a.get_lines() if ln.get_label() == label)
            np.testing.assert_array_equal(line.get_xdata(), k)
            assert float(stated[name]) == pytest.approx(np.polyfit(np.log10(k), alpha, 1)[0], abs=6e-4)


def test_cell_slopes_sit_at_measured_against_modelled():
    rng = np.random.default_rng(1)
    meas = rng.normal(0.17, 0.03, 40)
    lines = {"MCF-10A": (meas, {"a": meas + 0.01, "b": 0.9 * meas}), "MDA-MB-436": (meas[:20], {"a": meas[:20]})}
    ax = cell_slopes_figure(lines, title="slopes")
    assert problems(plotting.figure_of(ax)) == []
    assert len(ax) == 4 and not ax[3].get_visible()  # (b, MDA-MB-436): not fitted there
    cells = next(ln for ln in ax[0].get_lines() if ln.get_label() == "cells")
    np.testing.assert_allclose(cells.get_ydata() - cells.get_xdata(), 0.01)
    assert "r = 1.00, RMS difference 0.010 (40 cells)" in ax[0].get_title()
    assert ax[0].get_xlim() == ax[3].get_xlim()  # one scale for every panel


@pytest.fixture(scope="module")
def update():
    path = DOCS / "update_validation.py"
    spec = importlib.util.spec_from_file_location("update_validation", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_page_shows_the_runs_figures_between_its_markers(update, tmp_path):
    out, docs = tmp_path / "build", tmp_path / "docs"
    out.mkdir()
    docs.mkdir()
    names = list(update.FIGURES)
    for name in names[:2]:
        (out / f"{name}.png").write_bytes(b"\x89PNG " + name.encode())
    stale = docs / update.IMAGE_DIR / f"{names[2]}.png"
    stale.parent.mkdir(parents=True)
    stale.write_bytes(b"old")
    copied = update.copy_figures(out, docs)
    assert copied == names[:2] and not stale.exists()
    assert (docs / update.IMAGE_DIR / f"{names[0]}.png").read_bytes() == b"\x89PNG " + names[0].encode()
    page = (f"# v\n\n{update.FIGURES_BEGIN}\n\nold\n\n{update.FIGURES_END}\n\n{update.BEGIN}\n\nt\n\n{update.END}\n")
    new = update.splice(page, update.figures_markdown(copied), "*stamp*", update.FIGURES_BEGIN, update.FIGURES_END)
    shown = re.findall(r"```\{figure\} (\S+)", new)
    assert shown == [f"img/validation/{n}.png" for n in names[:2]] and "old" not in new
    assert new.split(update.FIGURES_END)[1] == page.split(update.FIGURES_END)[1]  # the tables' part untouched
    assert update.figures_markdown([]) == "*This run drew no figure.*"


def test_every_figure_the_page_shows_is_committed(update):
    page = (DOCS / "validation.md").read_text(encoding="utf-8")
    assert page.count(update.FIGURES_BEGIN) == 1 and page.count(update.FIGURES_END) == 1
    assert page.count(update.BEGIN) == 1 and page.count(update.END) == 1
    shown = re.findall(r"```\{figure\} (\S+)", page) + re.findall(r"!\[[^\]]*\]\(([^)]+)\)", page)
    assert len(shown) >= 3  # the held-out bands, the population's cells, the per-cell slopes
    for target in shown:
        assert (DOCS / target).is_file(), target
