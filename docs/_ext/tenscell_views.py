"""Sphinx extension of the tenscell documentation: pages that show an interactive 3D view draw it with plotly.js
served by the site itself.

A structure's or a cell's notebook repr (:func:`tenscell.plotting.interactive.view_html`) draws with the page's
``window.Plotly`` and fetches plotly.js from plotly's CDN only where the page has none. This extension gives every
page whose body holds such a view (``class="tenscell-view"``) a ``<script>`` of ``_static/plotly.min.js``, copied
from the installed plotly package: the built site fetches nothing from elsewhere and works offline. Pages without a
view load nothing more.
"""
from __future__ import annotations

import shutil
from pathlib import Path

#: the marker of a view in a page's body (the class of the view's <div>)
MARKER = 'class="tenscell-view"'
SCRIPT = "plotly.min.js"


def _plotly_js() -> Path | None:
    try:
        import plotly
    except ImportError:  # the views fell back to static images: nothing to serve
        return None
    path = Path(plotly.__file__).parent / "package_data" / SCRIPT
    return path if path.is_file() else None


def _page(app, pagename, templatename, context, doctree):
    if MARKER in (context.get("body") or "") and _plotly_js() is not None:
        app.add_js_file(SCRIPT)


def _copy(app, exc):
    source = _plotly_js()
    if exc is None and app.builder.format == "html" and source is not None:
        target = Path(app.outdir) / "_static" / SCRIPT
        target.parent.mkdir(parents=True, exist_ok=True)
        if not target.exists() or target.stat().st_size != source.stat().st_size:
            shutil.copyfile(source, target)


def setup(app):
    app.connect("html-page-context", _page)
    app.connect("build-finished", _copy)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
