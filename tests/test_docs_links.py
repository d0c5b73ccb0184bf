"""The documentation's link check (docs/check_links.py, run by `make docs`) finds missing pages and anchors."""
import importlib.util
from pathlib import Path

spec = importlib.util.spec_from_file_location("check_links", Path(__file__).parents[1] / "docs" / "check_links.py")
check_links = importlib.util.module_from_spec(spec)
spec.loader.exec_module(check_links)


def test_missing_pages_and_anchors_are_found(tmp_path):
    (tmp_path / "api").mkdir()
    (tmp_path / "index.html").write_text(
        '<a href="api/page.html#here">ok</a> <a href="api/page.html#gone">anchor</a> <a href="nowhere.html">page</a>'
        ' <a href="https://example.org/#x">external, not fetched</a> <a href="#top">self</a><div id="top"></div>')
    (tmp_path / "api" / "page.html").write_text('<h1 id="here">x</h1><a href="../index.html#top">back</a>')
    bad = check_links.broken_links(tmp_path)
    assert bad == ["index.html: api/page.html#gone (no such anchor)", "index.html: nowhere.html (no such page)"]
    assert check_links.main(["check_links", str(tmp_path)]) == 1
    (tmp_path / "index.html").write_text('<a href="api/page.html#here">ok</a><div id="top"></div>')
    assert check_links.main(["check_links", str(tmp_path)]) == 0
