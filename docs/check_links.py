"""Every internal link of the built documentation reaches a page and, when it names one, an anchor on it.

Run after the HTML build (``make docs`` does): ``python docs/check_links.py docs/_build/html``. External links
are not fetched (the build must work offline); a link to a missing page or a missing ``#anchor`` (a Markdown
heading renamed, a ``[source]`` back-link to an object viewcode did not index) fails with one line per link.
"""
from __future__ import annotations

import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urldefrag, urlsplit


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.links: list[str] = []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("id", "name") and v:
                self.ids.add(v)
            elif k == "href" and v and tag == "a":
                self.links.append(v)


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8", errors="replace"))
    return page


def broken_links(root: Path) -> list[str]:
    """``"page: href"`` for every internal link whose page or anchor does not exist."""
    pages = {p.resolve(): _parse(p) for p in root.rglob("*.html")}
    bad = []
    for path, page in pages.items():
        for href in page.links:
            if urlsplit(href).scheme or href.startswith(("//", "mailto:", "javascript:")):
                continue  # external: not checked offline
            target, fragment = urldefrag(href)
            dest = (path.parent / unquote(target)).resolve() if target else path
            if dest.is_dir():
                dest = dest / "index.html"
            if dest.suffix != ".html":
                if not dest.exists():
                    bad.append(f"{path.relative_to(root.resolve())}: {href} (no such file)")
                continue
            if dest not in pages:
                bad.append(f"{path.relative_to(root.resolve())}: {href} (no such page)")
            elif fragment and unquote(fragment) not in pages[dest].ids:
                bad.append(f"{path.relative_to(root.resolve())}: {href} (no such anchor)")
    return sorted(set(bad))


def main(argv: list[str]) -> int:
    root = Path(argv[1] if len(argv) > 1 else "docs/_build/html")
    if not root.is_dir():
        print(f"check_links: {root} is not a directory; build the docs first (make docs)", file=sys.stderr)
        return 2
    bad = broken_links(root)
    for line in bad:
        print(f"broken link: {line}", file=sys.stderr)
    print(f"check_links: {len(bad)} broken internal link(s) in {root}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
