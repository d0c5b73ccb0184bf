"""Self-contained HTML pages of the reports: ``report.html`` beside ``report.md``.

A page is the Markdown report itself — the same renderers, section by section (:func:`tenscell.reports.fit.fit_sections`
for a fit) — rendered to HTML by markdown-it-py (CommonMark with tables; raw HTML in a report's text is escaped,
never passed through), with the report's figures embedded as base64 PNG between its sections. One inline style
sheet, a table of contents, no script, nothing fetched: the file opens offline, from an e-mail or an archive, and
shows what ``report.md`` says, word for word, with the pictures beside it.
"""
from __future__ import annotations

import base64
import re
from html import escape
from typing import Mapping, Sequence

__all__ = ["markdown_html", "figure_html", "html_page", "fit_report_html", "markdown_report_html", "FIGURE_PLACES",
           "STYLE_SHEET"]

#: where each figure of a fit goes: (section name of :func:`tenscell.reports.fit.fit_sections`, "before" or "after"
#: it, caption); a figure whose section the report leaves out goes after the last section
FIGURE_PLACES: dict[str, tuple[str, str, str]] = {
    "fit": ("summary", "after", "Data (circles) and the fitted model (lines); dotted: the baseline."),
    "residuals": ("errors", "before", "log10 model − log10 data at every point (decades); shaded: ± the tolerance; "
                                      "grey crosses: the baseline."),
    "profile": ("profile", "after", "Profile likelihood: Δ(−2 ln L) with every other parameter refitted at each held "
                                    "value; the 68 % and 95 % thresholds and the intervals' ends."),
}

#: the page's one style sheet (inline): readable tables (a header row, alternate shading, numbers not wrapped), wide
#: tables scroll inside their box instead of widening the page, figures as wide as the text
STYLE_SHEET = """
:root { color-scheme: light; }
body { font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
       color: #1d2329; background: #fff; margin: 0; }
main { max-width: 1180px; margin: 0 auto; padding: 1.5rem 2rem 4rem; }
header.page { border-bottom: 3px solid #2a6f97; margin-bottom: 1.2rem; }
header.page h1 { font-size: 1.55rem; margin: 0.4rem 0 0.3rem; line-height: 1.25; }
header.page p { color: #52606d; margin: 0 0 0.8rem; font-size: 0.9rem; }
h2 { font-size: 1.25rem; margin: 2.2rem 0 0.6rem; padding-bottom: 0.2rem; border-bottom: 1px solid #d9e2ec; }
h3 { font-size: 1.05rem; margin: 1.6rem 0 0.5rem; }
code { font: 0.88em/1.4 ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace; background: #f0f4f8;
       padding: 0.05em 0.3em; border-radius: 3px; }
nav.toc { background: #f7f9fb; border: 1px solid #d9e2ec; border-radius: 6px; padding: 0.6rem 1rem;
          font-size: 0.9rem; }
nav.toc ol { margin: 0.3rem 0 0; padding-left: 1.4rem; columns: 2; column-gap: 2rem; }
nav.toc a { color: #2a6f97; text-decoration: none; }
nav.toc a:hover { text-decoration: underline; }
div.table { overflow-x: auto; margin: 0.8rem 0 1rem; border: 1px solid #d9e2ec; border-radius: 6px; }
table { border-collapse: collapse; font-size: 0.86rem; width: max-content; min-width: 100%; }
th { background: #e9eff5; text-align: left; font-weight: 600; }
th, td { padding: 0.32rem 0.7rem; border-bottom: 1px solid #e4e9ef; vertical-align: top; }
td { font-variant-numeric: tabular-nums; }
tbody tr:nth-child(even) td { background: #f9fbfc; }
tbody tr:hover td { background: #eef5fa; }
figure { margin: 1.2rem 0 1.6rem; }
figure img { display: block; max-width: 100%; height: auto; margin: 0 auto; }
figcaption { color: #52606d; font-size: 0.85rem; margin-top: 0.4rem; text-align: center; }
ul, ol { padding-left: 1.5rem; }
li { margin: 0.15rem 0; }
em { color: #334e68; }
footer { color: #7b8794; font-size: 0.8rem; border-top: 1px solid #d9e2ec; margin-top: 3rem; padding-top: 0.6rem; }
"""


def _renderer():
    """markdown-it-py: CommonMark with GFM tables, raw HTML escaped; each table in a scrolling box."""
    from markdown_it import MarkdownIt

    md = MarkdownIt("commonmark", {"html": False, "linkify": False, "typographer": False}).enable("table")

    def table_open(renderer, tokens, idx, options, env):
        return '<div class="table"><table>\n'

    def table_close(renderer, tokens, idx, options, env):
        return "</table></div>\n"

    md.add_render_rule("table_open", table_open)
    md.add_render_rule("table_close", table_close)
    return md


def _slug(text: str, taken: set[str]) -> str:
    base = re.sub(r"[^\w]+", "-", text.lower()).strip("-") or "section"
    slug, k = base, 2
    while slug in taken:
        slug, k = f"{base}-{k}", k + 1
    taken.add(slug)
    return slug


def markdown_html(text: str, toc: list[tuple[str, str]] | None = None, taken: set[str] | None = None) -> str:
    """Markdown ``text`` as HTML (raw HTML in it escaped). Every ``##`` heading gets an ``id``; with ``toc`` (a
    list) each is appended to it as ``(id, text)`` for a table of contents (``taken``: ids already used on the
    page)."""
    md = _renderer()
    tokens = md.parse(text)
    taken = set() if taken is None else taken
    for i, tok in enumerate(tokens):
        if tok.type == "heading_open" and tok.tag in ("h2", "h3"):
            title = tokens[i + 1].content
            slug = _slug(title.replace("`", ""), taken)
            tok.attrSet("id", slug)
            if toc is not None and tok.tag == "h2":
                toc.append((slug, title.replace("`", "").replace("*", "")))
    return md.renderer.render(tokens, md.options, {})


def figure_html(png: bytes, caption: str = "", alt: str = "") -> str:
    """A figure embedded in the page: the PNG as a ``data:`` URI, with its caption (escaped)."""
    data = base64.b64encode(png).decode("ascii")
    cap = f"<figcaption>{escape(caption)}</figcaption>" if caption else ""
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{escape(alt or caption or "figure")}">'
            f"{cap}</figure>\n")


def html_page(title: str, body: str, toc: Sequence[tuple[str, str]] = (), subtitle: str = "") -> str:
    """A complete HTML document: the title (escaped), a table of contents of ``toc`` (``(id, text)``), ``body``
    (already HTML) and a footer naming the tenscell version; the style sheet inline."""
    from .._version import __version__

    nav = ""
    if toc:
        items = "".join(f'<li><a href="#{escape(i)}">{escape(t)}</a></li>' for i, t in toc)
        nav = f'<nav class="toc"><strong>Contents</strong><ol>{items}</ol></nav>\n'
    sub = f"<p>{escape(subtitle)}</p>" if subtitle else ""
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f"<title>{escape(title)}</title>\n<style>{STYLE_SHEET}</style>\n</head>\n<body>\n<main>\n"
            f'<header class="page"><h1>{escape(title)}</h1>{sub}</header>\n{nav}{body}'
            f"<footer>Written by tenscell {escape(__version__)}: the same text as the Markdown report beside it, with "
            "its figures.</footer>\n</main>\n</body>\n</html>\n")


def _plain_title(title: str) -> str:
    return title.replace("`", "").replace("**", "")


def fit_report_html(result, baseline=None, title: str | None = None, comparison=None, validation=None,
                    figures: Mapping[str, bytes | None] | None = None) -> str:
    """``report.html`` of a fit: the sections of :func:`tenscell.reports.fit.fit_markdown` (the same text), each
    rendered to HTML, with ``figures`` (``{name: PNG bytes}``; names and places in :data:`FIGURE_PLACES`: the fit
    after the summary, the residuals before the error tables, the profiles in their section) between them.

    Parameters
    ----------
    result, baseline, title, comparison, validation
        As for :func:`tenscell.reports.fit.fit_markdown`.
    figures : mapping of str to bytes, optional
        PNG images by name (``"fit"``, ``"residuals"``, ``"profile"``; None or absent: not shown).
    """
    from .fit import fit_sections, report_title

    pngs: dict[str, bytes] = {k: v for k, v in (figures or {}).items() if v}
    unknown = set(pngs) - set(FIGURE_PLACES)
    if unknown:
        raise ValueError(f"figures: unknown name(s) {sorted(unknown)}; known: {', '.join(FIGURE_PLACES)}")
    sections = fit_sections(result, baseline, comparison=comparison, validation=validation)
    present = {name for name, lines in sections if lines}
    toc: list[tuple[str, str]] = []
    taken: set[str] = set()
    parts: list[str] = []
    placed: set[str] = set()

    def place(section: str, when: str) -> None:
        for name, (where, at, caption) in FIGURE_PLACES.items():
            if name in pngs and where == section and at == when:
                parts.append(figure_html(pngs[name], caption, alt=f"{name} figure"))
                placed.add(name)

    for name, lines in sections:
        if not lines:
            continue
        place(name, "before")
        parts.append(markdown_html("\n".join(lines), toc, taken))
        place(name, "after")
    for name in pngs:  # a figure whose section this report leaves out
        if name not in placed and FIGURE_PLACES[name][0] not in present:
            parts.append(figure_html(pngs[name], FIGURE_PLACES[name][2], alt=f"{name} figure"))
    head = _plain_title(title if title is not None else report_title(result))
    return html_page(head, "".join(parts), toc, subtitle=f"{result.verdict}; {len(result.datasets)} data set(s), "
                                                         f"{sum(d.n for d in result.datasets)} points")


def markdown_report_html(markdown: str, figures: Sequence[tuple[str, bytes]] = (), title: str | None = None) -> str:
    """Any Markdown report as a page, with ``figures`` (``(caption, PNG bytes)``) after its first section (its
    summary). The title is the report's ``# heading`` unless ``title`` is given."""
    lines = markdown.splitlines()
    head = title
    if lines and lines[0].startswith("# "):
        head = head or lines[0][2:].strip()
        lines = lines[1:]
    text = "\n".join(lines)
    cut = re.search(r"^## ", text, flags=re.M)
    first, rest = (text[: cut.start()], text[cut.start():]) if cut else (text, "")
    toc: list[tuple[str, str]] = []
    taken: set[str] = set()
    body = markdown_html(first, toc, taken) + "".join(figure_html(png, caption) for caption, png in figures)
    body += markdown_html(rest, toc, taken)
    return html_page(_plain_title(head or "Report"), body, toc)
