"""report.html: the Markdown report's own text, rendered, with its figures embedded; one self-contained page.

* **One source of truth**: every heading and every table cell of ``report.md`` appears in ``report.html`` (the page
  renders the same sections; a section dropped or rewritten for the page fails).
* **Self-contained**: every image a ``data:image/png`` URI that decodes to the very PNG bytes given (fit.png is the
  page's fit figure), no script, no style sheet or image fetched from anywhere, every ``#anchor`` of the contents
  present on the page.
* **Escaped**: a data file named like markup shows as text, never as markup.
* **Every fit command writes it**: ``tenscell fit`` (with ``profile.png`` and its figure when it profiled), and a
  population's output set.
"""
from __future__ import annotations

import base64
import json
import re
from html.parser import HTMLParser

import numpy as np
import pytest

from tenscell import fitting
from tenscell.cli import main as cli_main
from tenscell.fitting.models.formulas import structural_damping_moduli
from tenscell.io.data import RheologyData
from tenscell.reports.fit import fit_markdown
from tenscell.reports.html_page import FIGURE_PLACES, fit_report_html, markdown_html, markdown_report_html

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


class _Page(HTMLParser):
    """Text, element ids, links, images and tags of an HTML page."""

    def __init__(self):
        super().__init__()
        self.text: list[str] = []
        self.ids: set[str] = set()
        self.hrefs: list[str] = []
        self.images: list[str] = []
        self.tags: set[str] = set()

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        if tag == "a" and a.get("href"):
            self.hrefs.append(a["href"])
        if tag == "img":
            self.images.append(a.get("src", ""))
        if tag == "link" or (tag == "script" and a.get("src")):
            self.images.append(a.get("href") or a.get("src"))

    def handle_data(self, data):
        self.text.append(data)


def _parse(html: str) -> _Page:
    page = _Page()
    page.feed(html)
    page.close()
    return page


def _words(text: str) -> str:
    """Text as a reader sees it: no Markdown marks, whitespace collapsed."""
    return " ".join(text.replace("`", "").replace("**", "").replace("\\|", "|").split())


def _data(name: str = "pl.csv") -> RheologyData:
    f = np.logspace(-2, 2, 12)
    G = structural_damping_moduli(2 * np.pi * f, 300.0, 1.2, 0.0)
    return RheologyData(f, G.real, G.imag, G_storage_sd=0.05 * G.real, G_loss_sd=0.05 * G.imag, source=name)


@pytest.fixture(scope="module")
def fitted():
    result = fitting.fit(_data(), model="structural-damping+newtonian", starts=2, seed=0, progress=False)
    result.compute_profile("needed")
    return result


def _png(seed: int) -> bytes:
    return PNG_MAGIC + bytes(np.random.default_rng(seed).integers(0, 256, 64, dtype=np.uint8))


def test_the_page_is_the_markdown_report_with_its_figures(fitted):
    figures = {"fit": _png(1), "residuals": _png(2), "profile": _png(3)}
    html = fit_report_html(fitted, figures=figures)
    page = _parse(html)
    text = _words(" ".join(page.text))
    md = fit_markdown(fitted)
    # every heading and every table cell of report.md, word for word
    headings = [ln.lstrip("#").strip() for ln in md.splitlines() if ln.startswith("## ")]
    assert len(headings) >= 5 and "Profile likelihood" in " ".join(headings)
    for h in headings:
        assert _words(h) in text, h
    cells = [c.strip() for ln in md.splitlines() if ln.startswith("|") and not set(ln) <= set("|-: ")
             for c in re.split(r"(?<!\\)\|", ln.strip("|"))]
    assert len(cells) > 40
    missing = [c for c in cells if _words(c) not in text]
    assert not missing, missing[:5]
    # each figure embedded once, byte for byte, where FIGURE_PLACES puts it
    decoded = [base64.b64decode(src.split(",", 1)[1]) for src in page.images]
    assert sorted(decoded) == sorted(figures.values())
    assert all(src.startswith("data:image/png;base64,") for src in page.images)
    at = {k: html.index(base64.b64encode(figures[k]).decode()) for k in figures}
    h2 = [m.start() for m in re.finditer("<h2 id=", html)]
    assert at["fit"] < h2[0]  # after the summary, before the first section
    errors = html.index('<h2 id="errors"')
    assert max(h for h in h2 if h < errors) < at["residuals"] < errors
    profile = html.index('<h2 id="profile-likelihood')
    assert profile < at["profile"] < min(h for h in h2 if h > profile)
    # self-contained: nothing to fetch, nothing to run; the contents' anchors are on the page
    assert "script" not in page.tags and "link" not in page.tags and "iframe" not in page.tags
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", html)
    assert page.hrefs and all(h.startswith("#") and h[1:] in page.ids for h in page.hrefs)


def test_names_and_text_are_escaped():
    data = _data('<script>alert("x")</script>.csv')
    result = fitting.fit(data, model="structural-damping", starts=1, seed=0, progress=False)
    html = fit_report_html(result, title="a <b>title</b>")
    page = _parse(html)
    assert "script" not in page.tags and "b" not in page.tags
    assert '<script>alert("x")</script>.csv' in " ".join(page.text)
    assert "<title>a &lt;b&gt;title&lt;/b&gt;</title>" in html
    with pytest.raises(ValueError, match="unknown name"):
        fit_report_html(result, figures={"movie": _png(0)})


def test_markdown_rendering_and_a_report_of_any_kind():
    toc: list = []
    out = markdown_html("## A `b` c\n\n| x | y |\n|---|---|\n| 1 | <i>2</i> |\n\n## A b c\n", toc)
    assert toc == [("a-b-c", "A b c"), ("a-b-c-2", "A b c")]  # unique anchors
    assert '<div class="table"><table>' in out and "&lt;i&gt;2&lt;/i&gt;" in out and "<i>" not in out
    page = markdown_report_html("# Population fit\n\nSummary.\n\n## Cells\n\ntext", [("a caption", _png(5))])
    parsed = _parse(page)
    assert "<title>Population fit</title>" in page and parsed.images
    assert page.index("Summary.") < page.index("a caption") < page.index("<h2 id=\"cells\"")
    assert set(FIGURE_PLACES) == {"fit", "residuals", "profile"}


def _csv(path):
    d = _data()
    rows = ["frequency_Hz,G_storage_Pa,G_loss_Pa,G_storage_sd_Pa,G_loss_sd_Pa"]
    rows += [f"{f:.10g},{a:.10g},{b:.10g},{c:.10g},{e:.10g}"
             for f, a, b, c, e in zip(d.frequency_hz, d.G_storage, d.G_loss, d.G_storage_sd, d.G_loss_sd)]
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("profile", ["yes", "no"])
def test_fit_command_writes_report_html(tmp_path, monkeypatch, profile):
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    out = tmp_path / "out"
    assert cli_main(["fit", str(_csv(tmp_path / "pl.csv")), "--model", "structural-damping+newtonian",
                     "--validate", "no", "--starts", "2", "--profile", profile, "--out", str(out)]) == 0
    html = (out / "report.html").read_text(encoding="utf-8")
    page = _parse(html)
    images = [base64.b64decode(src.split(",", 1)[1]) for src in page.images]
    assert all(i.startswith(PNG_MAGIC) for i in images)
    assert (out / "fit.png").read_bytes() in images  # the page's fit figure is fit.png
    text = _words(" ".join(page.text))
    assert _words((out / "report.md").read_text().splitlines()[0].lstrip("# ")) in text
    manifest = json.loads((out / "manifest.json").read_text())
    listed = json.dumps(manifest)
    assert "report.html" in listed
    if profile == "yes":
        assert (out / "profile.png").read_bytes() in images and len(images) == 3 and "profile.png" in listed
    else:
        assert not (out / "profile.png").exists() and len(images) == 2
