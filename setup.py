"""Build-time only: the long description (the package index's page) is README.md with its relative links resolved.

README.md links to the documentation by relative paths (``docs/fitting.md``), which work in a clone and in the
source distribution, and lead nowhere on the package index's page. Everything else is in pyproject.toml; this
file gives setuptools the one field it computes (``readme`` is ``dynamic`` there).

The base of the links is ``[tool.tenscell] links`` in pyproject.toml, with ``{version}`` for the release (e.g. the
repository's tree at the release's tag). While the project has no public home it is empty: a relative link then
becomes its path in words ("fitting.md (docs/fitting.md in the source distribution)") and an image its caption, so
that the page has no link that leads nowhere. ``tests/test_packaging.py`` checks both forms.
"""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

from setuptools import setup

ROOT = Path(__file__).parent
#: a Markdown link or image whose target is not absolute (no scheme, no #anchor, no mailto:)
_RELATIVE = re.compile(r"(!?)\[([^\]]*)\]\((?![a-z][a-z0-9+.-]*:|#)([^)\s]+)\)")


def resolve_links(text: str, base: str) -> str:
    """``text`` (Markdown) with every relative link and image made absolute on ``base``, or, with no base, written
    as its path in the source distribution (an image: its caption and path)."""

    def one(m: re.Match) -> str:
        image, label, target = m.groups()
        if base:
            return f"{image}[{label}]({base}{target})"
        path = target.split("#")[0]
        words = label.strip("`") if label.strip("`") != path.rstrip("/") else ""
        where = f"`{path}` in the source distribution"
        if image:
            return f"*{label}* ({where})"
        return f"{words} ({where})" if words else where

    return _RELATIVE.sub(one, text)


def long_description() -> str:
    with open(ROOT / "pyproject.toml", "rb") as fh:
        config = tomllib.load(fh)
    version = re.search(r'__version__ = "([^"]+)"', (ROOT / "src" / "tenscell" / "_version.py").read_text()).group(1)
    base = config.get("tool", {}).get("tenscell", {}).get("links", "").format(version=version)
    return resolve_links((ROOT / "README.md").read_text(encoding="utf-8"), base)


if __name__ == "__main__":
    setup(long_description=long_description(), long_description_content_type="text/markdown")
