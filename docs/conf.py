"""Sphinx configuration of the tenscell documentation (``make docs``)."""
from __future__ import annotations

import os
import sys
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")     # the examples and the notebook draw into files
os.environ.setdefault("TENSCELL_PROGRESS", "0")  # no progress bars in the built pages
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "docs" / "_ext"))  # tenscell_views: plotly.js served by the site for the 3D views

import tenscell  # noqa: E402

project = "tenscell"
author = "tenscell developers"
copyright = "tenscell developers, MIT licence"
release = version = tenscell.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_nb",
    "sphinx_gallery.gen_gallery",
    "tenscell_views",
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "**.ipynb_checkpoints", "jupyter_execute"]
templates_path = ["_templates"]

# ---- API reference from the numpydoc docstrings ----
autosummary_generate = True
autosummary_ignore_module_all = False        # a module's public names are its __all__
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"                   # the numpydoc sections state types and units
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False


# ---- guides (Markdown) and the tutorial notebook ----
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
nb_execution_mode = "force"                  # the tutorial runs at every build, so it cannot go stale
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True

# ---- the example gallery ----
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "within_subsection_order": "FileNameSortKey",
    # "Examples using this" on every API page (the templates in _templates/autosummary add the mini-gallery)
    "doc_module": ("tenscell",),
    "backreferences_dir": "api/generated/backreferences",
}

# [source] links only from the pages of the module that defines an object: following the top-level re-exports
# (tenscell.X defined in tenscell.sub) wrote back-links to anchors no page has (docs/check_links.py finds them)
viewcode_follow_imported_members = False

html_theme = "pydata_sphinx_theme"
html_title = f"tenscell {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
# the theme's light/dark mode on a reader's first visit: without it the theme reads an empty mode and logs a console
# error ("Got invalid theme mode"; tests/test_browser.py fails on console errors)
html_context = {"default_mode": "auto"}
html_static_path: list[str] = []


# ---- the API reference page is generated from tenscell's export table, so a name added there appears here ----
_SECTIONS = {
    "model": "Structures and cells",
    "io.structure_files": "Structure files",
    "laws": "Tendon laws",
    "linear": "Linearization",
    "response": "Frequency response",
    "timedomain": "Creep and relaxation",
    "io": "Measured data",
    "summary": "Summaries",
    "dynamics": "Nonlinear time domain",
    "fitting": "Fitting",
    "sensitivity": "Sensitivity",
    "studies": "Studies of the paper's discussion",
    "population": "Populations of cells",
    "_threads": "Settings",
    "_errors": "Errors",
}
#: subpackages and modules documented whole (their __all__), below the top-level entry points, in pipeline order
API_MODULES = ["tenscell.model", "tenscell.laws", "tenscell.linear", "tenscell.response", "tenscell.timedomain",
               "tenscell.io", "tenscell.summary", "tenscell.dynamics", "tenscell.fitting", "tenscell.sensitivity",
               "tenscell.studies", "tenscell.population", "tenscell.reports", "tenscell.plotting"]


def _section(module: str) -> str:
    for prefix in sorted(_SECTIONS, key=len, reverse=True):
        if module == prefix or module.startswith(prefix + "."):
            return _SECTIONS[prefix]
    return module


def _write_api_index() -> None:
    groups: dict[str, list[str]] = {}
    for module, names in tenscell._EXPORTS.items():
        groups.setdefault(_section(module), []).extend(names)
    lines = ["API reference", "=============", "",
             "The entry points are importable from the top level (``import tenscell as tc; tc.paper_cell()``);",
             "everything else from its subpackage (``tc.model.regular_cell``, ``from tenscell.laws import Voigt``),",
             "listed under Modules. Submodules load on first use. Units are SI: N, m, s, Pa, Hz.", "",
             ".. currentmodule:: tenscell", ""]
    for title, names in groups.items():
        lines += [title, "-" * len(title), "", ".. autosummary::", "   :toctree: generated", ""]
        lines += [f"   {n}" for n in sorted(names, key=str.lower)] + [""]
    lines += ["Modules", "-------", "", ".. autosummary::", "   :toctree: generated", ""]
    lines += [f"   {m.removeprefix('tenscell.')}" for m in API_MODULES if _importable(m)] + [""]
    target = Path(__file__).parent / "api" / "index.rst"
    target.parent.mkdir(exist_ok=True)
    text = "\n".join(lines)
    if not target.exists() or target.read_text() != text:
        target.write_text(text)


def _importable(module: str) -> bool:
    import importlib.util

    return importlib.util.find_spec(module) is not None


_write_api_index()


# ---- docstrings written for terminals as well as for Sphinx ----
import re  # noqa: E402

# "|G|", "|ΔG'/G'|": absolute values in plain-text docstrings, not reST substitutions
_ABS = re.compile(r"(?<![`|\\\w])\|([^|`\s][^|`]*?)\|(?![`|_\w])")


def _absolute_values(app, what, name, obj, options, lines):
    lines[:] = [_ABS.sub(r"\\|\1\\|", line) for line in lines]


def _constant_docs(app, what, name, obj, options, lines):
    """A top-level constant (``tenscell.DEFAULT_DELTA``) shows the ``#:`` comment of its own module, not the
    docstring of ``float``."""
    short = name.rsplit(".", 1)[-1]
    if what not in ("data", "attribute") or short not in tenscell._WHERE:
        return
    from sphinx.pycode import ModuleAnalyzer

    try:
        docs = ModuleAnalyzer.for_module(f"tenscell.{tenscell._WHERE[short]}").find_attr_docs()
    except Exception:  # a module without source (never in this package)
        return
    comment = docs.get(("", short))
    if comment:
        lines[:] = [line for line in comment if line is not None]


def _skip_top_level_names(app, what, name, obj, skip, options):
    """On a module's page, leave out what has its own page as a top-level name (one description each)."""
    if what == "module" and name in tenscell._WHERE and getattr(tenscell, name, None) is obj:
        return True
    return None


def setup(app):
    app.connect("autodoc-process-docstring", _constant_docs, priority=50)
    app.connect("autodoc-process-docstring", _absolute_values, priority=100)
    app.connect("autodoc-skip-member", _skip_top_level_names)
