"""The interactive 3D view of a structure (plotly, the optional extra ``tenscell[view]``): turn, zoom, hover a node.

:func:`structure_view` gives a :class:`plotly.graph_objects.Figure` coloured as the paper's Fig. 1 (the colours of
:data:`tenscell.plotting.structures.MEMBER_STYLE`: struts grey and thick, actin black, intermediate filaments red,
anchors blue, the load a green cone); :func:`structure_view_html` the same view as HTML — a standalone file that
carries plotly.js inline and opens offline (``plotlyjs="inline"``), or a fragment for a page or a notebook that draws
with the page's plotly.js and fetches it from plotly's CDN only where the page has none (``plotlyjs="auto"``: what a
structure's and a cell's notebook repr use). Where plotly is not installed, :func:`view_html` falls back to the static
view (:func:`tenscell.plotting.structure_3d` as an embedded PNG) with the command that installs plotly.
"""
from __future__ import annotations

import base64
import json
import uuid
from html import escape
from typing import TYPE_CHECKING, Any

import numpy as np

from .structures import MEMBER_STYLE, _member_pairs, _section

if TYPE_CHECKING:
    from ..model.structure import Structure

__all__ = ["structure_view", "structure_view_html", "view_html", "MAX_MEMBERS_VIEWED", "PLOTLYJS_MODES"]

#: above this many members the view shows a section (a slab through the middle, as :func:`structure_3d` does):
#: WebGL draws tens of thousands of segments smoothly, but a solid block of them shows nothing
MAX_MEMBERS_VIEWED = 20_000
#: how :func:`structure_view_html` brings plotly.js: ``"inline"`` (the whole library in the file: it opens offline,
#: about 5 MB), ``"auto"`` (the page's ``window.Plotly`` when it has one, else plotly's CDN), ``"cdn"``, ``"none"``
#: (the page provides it)
PLOTLYJS_MODES = ("inline", "auto", "cdn", "none")
_OTHER_COLORS = ("#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b")


def _plotly():
    from .._optional import require

    return require("plotly.graph_objects")


def _css(color: str) -> str:
    from matplotlib.colors import to_hex

    return to_hex(color)


def _segments(x: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The members as one polyline with gaps (NaN between segments): what a plotly line trace draws at once."""
    pts = np.full((3 * len(pairs), 3), np.nan)
    pts[0::3] = x[pairs[:, 0]]
    pts[1::3] = x[pairs[:, 1]]
    return pts[:, 0], pts[:, 1], pts[:, 2]


def _member_traces(go, structure: Structure, x: np.ndarray, keep, width_scale: float) -> list:
    S, T = _member_pairs(structure)
    families = np.asarray(structure.families, dtype=object)
    if keep is not None:
        S, T, families = S[keep[0]], T[keep[1]], families[keep[1]]
    groups = {"strut": S}
    for fam in dict.fromkeys(families.tolist()):  # elastic struts (family "strut") are drawn as the rigid ones
        groups[fam] = np.concatenate([groups.get(fam, np.zeros((0, 2), np.intp)), T[families == fam]])
    others = iter(_OTHER_COLORS * 10)
    traces = []
    for fam, pairs in groups.items():
        if not len(pairs):
            continue
        st = MEMBER_STYLE.get(fam)
        color = _css(st["color"]) if st else next(others)
        width = (st["linewidth"] if st else 0.9) * 2.6 * width_scale
        label = st["label"] if st else fam
        xs, ys, zs = _segments(x, pairs)
        traces.append(go.Scatter3d(x=xs, y=ys, z=zs, mode="lines", name=f"{label} ({len(pairs)})",
                                   line={"color": color, "width": max(width, 1.0)}, hoverinfo="skip"))
    return traces


def structure_view(structure, x=None, title: str | None = None, *, load: bool = True, height: int = 560,
                   max_members: int = MAX_MEMBERS_VIEWED):
    """The structure as an interactive 3D figure (plotly), coloured as the paper's Fig. 1.

    Parameters
    ----------
    structure : Structure or Cell
        A cell is drawn as its structure, titled with its description.
    x : ndarray, shape (n_nodes, 3), optional
        Node positions to draw (m); default the structure's reference.
    title : str, optional
        Default the structure's name (a cell's description).
    load : bool
        Draw the load point and direction (a green cone).
    height : int
        Height of the view (pixels); its width follows the page.
    max_members : int
        A structure with more members is shown as the section :func:`tenscell.plotting.structure_3d` draws (the
        members in the thinnest slab through its middle, across y, that holds this many); the title says so.

    Returns
    -------
    plotly.graph_objects.Figure
        Hovering a node shows its index, name and position (m).

    Raises
    ------
    tenscell.MissingDependency
        plotly is not installed (``pip install 'tenscell[view]'``).
    """
    go = _plotly()
    cell_title = structure.describe() if hasattr(structure, "structure") else None
    s: Structure = getattr(structure, "structure", structure)
    x = s.nodes if x is None else np.asarray(x, dtype=float)
    keep, note = _section(s, x, max_members)
    shown = len(s.struts) + len(s.tendons) if keep is None else int(keep[0].sum() + keep[1].sum())
    traces = _member_traces(go, s, x, keep, float(min(1.0, np.sqrt(300.0 / max(shown, 1)))))
    names = s.node_names or tuple(str(i) for i in range(s.n_nodes))
    nodes = np.arange(s.n_nodes) if keep is None else np.unique(np.concatenate(
        [_member_pairs(s)[0][keep[0]].ravel(), _member_pairs(s)[1][keep[1]].ravel()]))
    text = [f"node {i} ({escape(str(names[i]))})<br>({x[i, 0]:.4g}, {x[i, 1]:.4g}, {x[i, 2]:.4g}) m" for i in nodes]
    traces.append(go.Scatter3d(x=x[nodes, 0], y=x[nodes, 1], z=x[nodes, 2], mode="markers", name="nodes",
                               marker={"size": 2.5 if nodes.size < 500 else 1.2, "color": "#52606d"}, text=text,
                               hoverinfo="text", showlegend=False))
    fixed = np.intersect1d(np.asarray(s.fixed, dtype=np.intp), nodes)
    if fixed.size:
        traces.append(go.Scatter3d(x=x[fixed, 0], y=x[fixed, 1], z=x[fixed, 2], mode="markers", name="anchors",
                                   marker={"size": 6, "color": "#1f4fd1", "symbol": "diamond"}, hoverinfo="skip"))
    if load:
        p = s.load
        at = np.asarray(p.weights) @ x[list(p.nodes)]
        d = np.asarray(p.direction, dtype=float) * 0.25 * float(np.ptp(x, axis=0).max() or 1.0)
        tail = at - d
        traces.append(go.Scatter3d(x=[tail[0], at[0]], y=[tail[1], at[1]], z=[tail[2], at[2]], mode="lines",
                                   name="load", line={"color": "#2ca02c", "width": 6}, hoverinfo="skip"))
        traces.append(go.Cone(x=[at[0]], y=[at[1]], z=[at[2]], u=[d[0]], v=[d[1]], w=[d[2]], sizemode="absolute",
                              sizeref=0.35 * float(np.linalg.norm(d)), anchor="tip", showscale=False,
                              colorscale=[[0, "#2ca02c"], [1, "#2ca02c"]], name="load", hoverinfo="skip",
                              showlegend=False))
    head = title or cell_title or s.name
    axis = {"showbackground": True, "backgroundcolor": "#f7f9fb", "gridcolor": "#d9e2ec", "zerolinecolor": "#bcccdc"}
    fig = go.Figure(traces)
    fig.update_layout(
        title={"text": escape(head) + (f"<br><sup>{escape(note)}</sup>" if note else ""), "x": 0.02,
               "font": {"size": 15}},
        height=int(height), margin={"l": 0, "r": 0, "t": 60 if note else 44, "b": 0},
        legend={"yanchor": "top", "y": 0.98, "x": 0.01, "bgcolor": "rgba(255,255,255,0.8)", "font": {"size": 12}},
        scene={"aspectmode": "data", "xaxis": {"title": {"text": "x (m)"}, **axis},
               "yaxis": {"title": {"text": "y (m)"}, **axis}, "zaxis": {"title": {"text": "z (m)"}, **axis},
               "camera": {"eye": {"x": 1.25, "y": -1.25, "z": 0.65}}},
        paper_bgcolor="white", font={"family": "system-ui, -apple-system, Segoe UI, Roboto, Arial, sans-serif"},
    )
    return fig


def _cdn_url() -> str:
    from plotly.offline import get_plotlyjs_version

    return f"https://cdn.plot.ly/plotly-{get_plotlyjs_version()}.min.js"


def _figure_json(fig) -> str:
    """The figure's JSON, safe inside a ``<script>`` element (no ``</`` can close it early)."""
    return fig.to_json().replace("</", "<\\/").replace("<!--", "<\\!--")


def structure_view_html(structure, *, plotlyjs: str = "inline", full_html: bool = True, **view: Any) -> str:
    """:func:`structure_view` as HTML: a standalone page (``full_html``) or a ``<div>`` fragment.

    Parameters
    ----------
    structure : Structure or Cell
    plotlyjs : {"inline", "auto", "cdn", "none"}
        How plotly.js comes to the page (:data:`PLOTLYJS_MODES`): ``"inline"`` puts the library in the HTML (a file
        that opens offline); ``"auto"`` draws with the page's plotly.js and loads it from plotly's CDN only where the
        page has none (a notebook, a documentation page that provides it); ``"cdn"`` always loads it; ``"none"``
        expects the page to provide it.
    full_html : bool
        A complete document (``<!DOCTYPE html>``...) or a fragment to place in a page.
    **view
        Passed to :func:`structure_view` (``title``, ``x``, ``height``...).
    """
    if plotlyjs not in PLOTLYJS_MODES:
        raise ValueError(f"plotlyjs: expected one of {', '.join(PLOTLYJS_MODES)}, got {plotlyjs!r}")
    fig = structure_view(structure, **view)
    height = int(fig.layout.height or 560)
    div = f"tenscell-view-{uuid.uuid4().hex[:12]}"
    config = json.dumps({"responsive": True, "displaylogo": False, "scrollZoom": True})
    library = ""
    if plotlyjs == "inline":
        from plotly.offline import get_plotlyjs

        library = f'<script type="text/javascript">{get_plotlyjs()}</script>\n'
    elif plotlyjs == "cdn":
        library = f'<script src="{_cdn_url()}" charset="utf-8"></script>\n'
    load = ("draw();" if plotlyjs != "auto" else
            "if (window.Plotly) { draw(); } else { var s = document.createElement('script'); "
            f"s.src = '{_cdn_url()}'; s.onload = draw; document.head.appendChild(s); }}")
    body = (f'<div class="tenscell-view" id="{div}" style="width: 100%; height: {height}px;"></div>\n'
            f'<script type="application/json" id="{div}-figure">{_figure_json(fig)}</script>\n'
            "<script type=\"text/javascript\">(function () {\n"
            f"  var id = '{div}';\n"
            "  function draw() {\n"
            "    var fig = JSON.parse(document.getElementById(id + '-figure').textContent);\n"
            f"    window.Plotly.newPlot(id, fig.data, fig.layout, {config});\n"
            "  }\n"
            f"  {load}\n"
            "})();</script>\n")
    if not full_html:
        return library + body
    title = escape(str(fig.layout.title.text or "structure").split("<br>")[0])
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{title}</title>\n{library}</head>\n<body style=\"margin: 0.5rem;\">\n{body}</body>\n</html>\n")


def view_html(structure, **view: Any) -> str:
    """What a notebook shows for a structure or a cell: the interactive view (``plotlyjs="auto"``), or, where plotly
    is not installed, the static view (:func:`tenscell.plotting.structure_3d`, an embedded PNG) and the command that
    installs plotly."""
    from .._optional import MissingDependency, install_hint

    try:
        return structure_view_html(structure, plotlyjs="auto", full_html=False, **view)
    except MissingDependency:
        pass
    from ._style import png_bytes
    from .structures import structure_3d

    s = getattr(structure, "structure", structure)
    title = view.get("title") or (structure.describe() if hasattr(structure, "structure") else s.name)
    png = base64.b64encode(png_bytes(structure_3d(s, title=title))).decode("ascii")
    return (f'<img src="data:image/png;base64,{png}" alt="{escape(title)}" style="max-width: 100%;">'
            f"<p>A static view: the interactive one needs plotly (<code>{escape(install_hint('plotly'))}</code>)."
            "</p>")
