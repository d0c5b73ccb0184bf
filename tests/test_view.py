"""The interactive 3D view of a structure (tenscell.plotting.interactive, plotly) and a structure's notebook repr.

* The view draws the structure itself: every member once, its ends at the nodes' positions, one trace per family
  with the paper's colours, the anchors at the fixed nodes; a large lattice as the section structure_3d draws.
* Its HTML: a standalone file carries plotly.js (opens offline), a fragment uses the page's plotly.js and reaches
  for the CDN only where the page has none; the figure's JSON cannot close its script element early.
* Without plotly: the static picture and the command that installs plotly, never an error.
"""
from __future__ import annotations

import json
import re
import sys

import numpy as np
import pytest

import tenscell as tc
from tenscell.model import lattices

pytest.importorskip("plotly", reason="plotly is not installed (pip install 'tenscell[view]')")

from tenscell.plotting.interactive import structure_view, structure_view_html, view_html  # noqa: E402


def _segments(trace) -> np.ndarray:
    """A line trace's members as (n, 2, 3): point pairs between the NaN gaps."""
    pts = np.column_stack([np.asarray(trace.x, float), np.asarray(trace.y, float), np.asarray(trace.z, float)])
    return pts.reshape(-1, 3, 3)[:, :2]


def test_the_view_draws_every_member_between_its_nodes():
    cell = tc.paper_cell()
    s = cell.structure
    fig = structure_view(cell)
    lines = {t.name.rsplit(" (", 1)[0]: t for t in fig.data if t.type == "scatter3d" and t.mode == "lines"}
    struts, actin, ifs = (_segments(lines[k]) for k in ("struts (microtubules)", "actin", "intermediate filaments"))
    families = np.asarray(s.families)
    tendons = np.asarray(s.tendons).reshape(-1, 2)
    np.testing.assert_allclose(struts, s.nodes[np.asarray(s.struts).reshape(-1, 2)])
    np.testing.assert_allclose(actin, s.nodes[tendons[families == "actin"]])
    np.testing.assert_allclose(ifs, s.nodes[tendons[families == "intermediate_filament"]])
    assert lines["actin"].line.color == "#000000" and lines["intermediate filaments"].line.color == "#ff0000"
    anchors = next(t for t in fig.data if t.name == "anchors")
    np.testing.assert_allclose(np.column_stack([anchors.x, anchors.y, anchors.z]), s.nodes[sorted(s.fixed)])
    assert cell.describe() in fig.layout.title.text


def test_a_large_lattice_is_shown_as_a_section():
    block, _ = lattices.lattice_structure(3, 3, 2)
    members = len(block.struts) + len(block.tendons)
    fig = structure_view(block, max_members=200)
    drawn = sum(len(_segments(t)) for t in fig.data if t.type == "scatter3d" and t.mode == "lines" and t.name != "load")
    assert 200 <= drawn < members and "members drawn" in fig.layout.title.text
    assert sum(len(_segments(t)) for t in structure_view(block).data
               if t.type == "scatter3d" and t.mode == "lines" and t.name != "load") == members


def test_standalone_and_fragment_html():
    cell = tc.paper_cell()
    page = structure_view_html(cell)
    assert page.startswith("<!DOCTYPE html>") and len(page) > 1_000_000  # plotly.js inline: opens offline
    markup = page.split("</script>", 1)[1]  # after the library (whose own text names plotly's CDN for map data)
    assert "cdn.plot.ly" not in markup and "<script src" not in page
    fragment = structure_view_html(cell, plotlyjs="auto", full_html=False)
    assert len(fragment) < 100_000 and "if (window.Plotly)" in fragment and "<script src" not in fragment
    spec = re.search(r'<script type="application/json" id="[^"]+-figure">(.*?)</script>', fragment, re.S).group(1)
    assert len(json.loads(spec)["data"]) >= 4
    bare = structure_view_html(cell, plotlyjs="none", full_html=False)  # the page brings plotly.js itself
    assert "if (window.Plotly)" not in bare and "<script src" not in bare and len(bare) < 100_000
    assert 'src="https://cdn.plot.ly/' in structure_view_html(cell, plotlyjs="cdn", full_html=False)
    with pytest.raises(ValueError, match="plotlyjs"):
        structure_view_html(cell, plotlyjs="maybe")
    # a name that looks like markup cannot close the figure's script element
    evil = tc.paper_cell().structure
    frag = structure_view_html(evil, plotlyjs="none", full_html=False, title="</script><b>x</b>")
    assert frag.count("</script>") == frag.count("<script")


def test_the_notebook_repr_is_the_view_or_the_static_picture(monkeypatch):
    cell = tc.paper_cell()
    html = cell._repr_html_()
    assert 'class="tenscell-view"' in html and "13 nodes" in html
    assert 'class="tenscell-view"' in cell.structure._repr_html_()
    for name in ("plotly", "plotly.graph_objects"):
        monkeypatch.setitem(sys.modules, name, None)
    static = view_html(cell)
    assert static.startswith('<img src="data:image/png;base64,') and "pip install &#x27;tenscell[view]&#x27;" in static
    assert 'class="tenscell-view"' not in cell._repr_html_()
