"""The pages as a person sees them: ``report.html``, the documentation's validation page and the interactive 3D view,
opened in a real headless browser.

The browser is Debian's ``chromium`` (``/usr/bin/chromium``; ``.ci/run`` installs it with apt where it is absent),
driven by playwright through its own connection to that executable: no browser is downloaded. playwright gives the
console messages, uncaught page errors and failed requests of a page as events and waits for what it loads, which
chromium's ``--screenshot``/``--dump-dom`` alone cannot report. Each test fails on a console error, a page error or
a failed request, checks that every image decoded (``naturalWidth > 0``) and that the 3D view drew its WebGL scene,
and takes a screenshot that must not be blank: its pixels vary (standard deviation of the grey levels), and enough
of them differ from the page's background. Where playwright or chromium is missing, the tests skip, saying which.

The validation page and the 3D view's page are built here from the documentation's own sources with the site's
theme (a small Sphinx build of just those pages, with ``docs/_ext/tenscell_views.py``); set ``TENSCELL_DOCS_HTML``
to a full build (``docs/_build/html`` after ``make docs``) to open that instead.
"""
from __future__ import annotations

import io
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: flags for a headless chromium in a container: no sandbox (root), no GPU, no network chatter of its own
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]
#: a screenshot is blank when the standard deviation of its grey levels is below this (0-255 scale) or fewer than
#: this fraction of its pixels differ from the page's background by more than 16 grey levels
MIN_GREY_SD = 8.0
MIN_INK = 0.01
#: console messages that are the browser's own notes on software rendering, not the page's
IGNORED = ("GPU stall due to ReadPixels", "willReadFrequently", "Automatic fallback to software WebGL")


def _chromium() -> str:
    path = shutil.which("chromium") or "/usr/bin/chromium"
    if not os.access(path, os.X_OK):
        pytest.skip("Debian's chromium is not installed (apt-get install -y chromium; .ci/run does it)")
    return path


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed (pip install playwright)")
    executable = _chromium()
    with sync_api.sync_playwright() as p:
        try:
            context = p.chromium.launch_persistent_context(
                str(tmp_path_factory.mktemp("chromium-profile")), executable_path=executable, headless=True,
                args=FLAGS[1:], viewport={"width": 1280, "height": 900}, device_scale_factor=1)
        except Exception as err:  # a chromium that cannot start here (missing libraries, no /dev/shm...)
            pytest.skip(f"chromium does not start: {str(err).splitlines()[0]}")
        yield context
        context.close()


class Visit:
    """A page opened in the browser, with everything it said that a reader would see go wrong."""

    def __init__(self, context, url: str, settle_ms: int = 500):
        self.page = context.new_page()
        self.errors: list[str] = []
        self.page.on("console", lambda m: self.errors.append(f"console {m.type}: {m.text}")
                     if m.type == "error" and not any(i in m.text for i in IGNORED) else None)
        self.page.on("pageerror", lambda e: self.errors.append(f"page error: {e}"))
        self.page.on("requestfailed", lambda r: self.errors.append(f"request failed: {r.url} ({r.failure})"))
        self.page.goto(url, wait_until="load", timeout=180_000)
        self.page.wait_for_timeout(settle_ms)

    def broken_images(self) -> list[str]:
        return self.page.evaluate("Array.from(document.images).filter(i => !i.complete || i.naturalWidth === 0)"
                                  ".map(i => i.src.slice(0, 80))")

    def screenshot(self, path: Path, selector: str | None = None) -> bytes:
        target = self.page.locator(selector).first if selector else self.page
        png = target.screenshot(path=str(path), **({} if selector else {"full_page": True}))
        self.page.close()
        return png


def blank_reason(png: bytes) -> str:
    """Why a screenshot is blank ("" when it is not): its pixels do not vary, or too few differ from the
    background (the most common grey level)."""
    from PIL import Image

    grey = np.asarray(Image.open(io.BytesIO(png)).convert("L"), dtype=float)
    sd = float(grey.std())
    background = np.bincount(grey.astype(int).ravel(), minlength=256).argmax()
    ink = float(np.mean(np.abs(grey - background) > 16))
    if sd < MIN_GREY_SD or ink < MIN_INK:
        return f"grey-level sd {sd:.2f} (< {MIN_GREY_SD}?), {100 * ink:.2f} % of pixels off the background"
    return ""


def test_blank_screenshots_are_told_apart():
    from PIL import Image

    def png(a):
        buf = io.BytesIO()
        Image.fromarray(a.astype(np.uint8)).save(buf, format="PNG")
        return buf.getvalue()

    white = np.full((200, 300), 255)
    assert blank_reason(png(white))
    dot = white.copy()
    dot[100, 150] = 0
    assert blank_reason(png(dot))  # one dark pixel on a white page is no page
    text = white.copy()
    text[40:160:6, 20:280] = 30  # lines of "text"
    assert blank_reason(png(text)) == ""


def _report(tmp_path: Path) -> Path:
    from tenscell.cli import main as cli_main
    from tenscell.fitting.models.formulas import structural_damping_moduli

    f = np.logspace(-2, 2, 12)
    G = structural_damping_moduli(2 * np.pi * f, 300.0, 1.2, 0.0)
    rows = ["frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa,G_loss_sd_Pa"]
    rows += [f"{a:.10g},{b:.10g},{c:.10g},{0.05 * b:.10g},{0.05 * c:.10g}" for a, b, c in zip(f, G.real, G.imag)]
    (tmp_path / "sweep.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "fit"
    assert cli_main(["fit", str(tmp_path / "sweep.csv"), "--model", "structural-damping+newtonian", "--validate",
                     "no", "--starts", "2", "--profile", "yes", "--out", str(out)]) == 0
    return out / "report.html"


def test_report_html_in_a_browser(browser, tmp_path, monkeypatch):
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    report = _report(tmp_path)
    visit = Visit(browser, report.as_uri())
    assert visit.broken_images() == []
    n_images = visit.page.evaluate("document.images.length")
    assert n_images == 3  # the fit, its residuals, the profile
    anchors = visit.page.evaluate("Array.from(document.querySelectorAll('nav a')).filter(a => "
                                  "!document.getElementById(a.hash.slice(1))).length")
    assert anchors == 0
    png = visit.screenshot(tmp_path / "report.png")
    assert visit.errors == []
    assert blank_reason(png) == ""


def _wait_for_views(visit: Visit, n: int) -> None:
    """Every 3D view drew: plotly's WebGL scene canvas is in each view's div, with its traces attached."""
    visit.page.wait_for_function(
        f"document.querySelectorAll('.tenscell-view').length === {n} && Array.from(document.querySelectorAll("
        "'.tenscell-view')).every(d => d.data && d.data.length > 0 && d.querySelector('canvas'))", timeout=120_000)


def test_the_3d_view_in_a_browser(browser, tmp_path):
    pytest.importorskip("plotly", reason="plotly is not installed (pip install 'tenscell[view]')")
    import tenscell as tc
    from tenscell.plotting.interactive import structure_view_html

    page = tmp_path / "cell.html"
    page.write_text(structure_view_html(tc.paper_cell()), encoding="utf-8")  # plotly.js inline: opens offline
    visit = Visit(browser, page.as_uri())
    _wait_for_views(visit, 1)
    traces = visit.page.evaluate("document.querySelector('.tenscell-view').data.map(t => t.name)")
    assert any(t.startswith("actin (21)") for t in traces) and any(t.startswith("struts") for t in traces)
    png = visit.screenshot(tmp_path / "view.png", ".tenscell-view")
    assert visit.errors == []
    assert blank_reason(png) == ""


def _docs_site(tmp_path: Path) -> Path:
    """The built documentation: ``TENSCELL_DOCS_HTML`` when set, else the validation page and the 3D view's page
    built here from their sources with the site's theme."""
    given = os.environ.get("TENSCELL_DOCS_HTML")
    if given:
        return Path(given).resolve()  # a path relative to the working directory (.ci/run gives docs/_build/html)
    for module in ("sphinx", "myst_nb", "pydata_sphinx_theme"):
        pytest.importorskip(module, reason=f"{module} is not installed (pip install 'tenscell[docs]')")
    src = tmp_path / "src"
    src.mkdir()
    for name in ("validation.md", "view.md"):
        shutil.copy(DOCS / name, src / name)
    shutil.copytree(DOCS / "img", src / "img")
    (src / "index.md").write_text("# tenscell\n\n```{toctree}\nvalidation\nview\n```\n")
    # the site's settings that shape these pages (docs/conf.py builds the whole site: API, gallery, tutorial)
    (src / "conf.py").write_text(
        'project = "tenscell"\nextensions = ["myst_nb", "tenscell_views"]\nhtml_theme = "pydata_sphinx_theme"\n'
        'html_context = {"default_mode": "auto"}\nmyst_heading_anchors = 3\nnb_execution_mode = "force"\n')
    out = tmp_path / "html"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(DOCS / "_ext"),
                                                        os.environ.get("PYTHONPATH", "")]),
           "TENSCELL_PROGRESS": "0", "MPLBACKEND": "Agg"}
    cmd = [sys.executable, "-m", "sphinx", "-b", "html", "-q", str(src), str(out)]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    return out


@pytest.fixture(scope="module")
def docs_site(tmp_path_factory):
    return _docs_site(tmp_path_factory.mktemp("docs"))


def test_the_validation_page_in_a_browser(browser, docs_site, tmp_path):
    visit = Visit(browser, (docs_site / "validation.html").as_uri())
    assert visit.broken_images() == []
    figures = visit.page.evaluate("Array.from(document.querySelectorAll('article img')).map(i => i.naturalWidth)")
    assert len(figures) >= 3 and min(figures) > 300  # the validation figures, at a readable size
    png = visit.screenshot(tmp_path / "validation.png")
    assert visit.errors == []
    assert blank_reason(png) == ""


def test_the_3d_view_page_of_the_docs_in_a_browser(browser, docs_site, tmp_path):
    pytest.importorskip("plotly", reason="plotly is not installed (pip install 'tenscell[view]')")
    visit = Visit(browser, (docs_site / "view.html").as_uri())
    _wait_for_views(visit, 3)  # the paper cell, the sphere, the lattice: drawn with the site's own plotly.js
    png = visit.screenshot(tmp_path / "view_page.png")
    assert visit.errors == []
    assert blank_reason(png) == ""
