"""Packaging: heavy dependencies are extras with a one-line hint; the sdist carries what its tests need."""
import subprocess
import sys
import tarfile
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]


def _project():
    with open(ROOT / "pyproject.toml", "rb") as fh:
        return tomllib.load(fh)["project"]


def test_heavy_dependencies_are_extras_and_the_test_extra_installs_them():
    project = _project()
    hard = " ".join(project["dependencies"])
    extras = project["optional-dependencies"]
    for heavy in ("cvxopt", "dask", "pyarrow"):
        assert heavy not in hard
        assert any(r.startswith(heavy) for r in extras["test"]), heavy  # make test / make reproduce get them
        assert any(r.startswith(heavy) for r in extras["all"]), heavy
    assert project["classifiers"] and any(c.startswith("Programming Language") for c in project["classifiers"])


@pytest.mark.parametrize("module, extra", [("cvxopt", "large"), ("pyarrow", "populations"),
                                           ("distributed", "populations")])
def test_a_missing_extra_is_one_line_with_the_install_hint(module, extra):
    # a fresh interpreter where the module cannot be imported
    code = (f"import sys; sys.modules[{module!r}] = None\n"
            "from tenscell._optional import require, MissingDependency\n"
            f"try:\n    require({module!r})\nexcept MissingDependency as e:\n    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert "\n" not in out and f"pip install 'tenscell[{extra}]'" in out


def test_fitting_a_sweep_imports_no_heavy_dependency():
    code = ("import sys\nimport tenscell as tc\n"
            "tc.fit(tc.bundled('fabry2001'), tendons='uniform', starts=1, progress=False)\n"
            "print(sorted(m for m in ('cvxopt', 'dask', 'distributed', 'pyarrow') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "[]"


def test_sdist_carries_docs_and_tests(tmp_path):
    pytest.importorskip("setuptools", minversion="77")  # the pyproject license form of PEP 639
    build_meta = pytest.importorskip("setuptools.build_meta")
    import os

    here = os.getcwd()
    os.chdir(ROOT)
    try:
        name = build_meta.build_sdist(str(tmp_path))
    finally:
        os.chdir(here)
    with tarfile.open(tmp_path / name) as tar:
        names = {n.split("/", 1)[1] for n in tar.getnames() if "/" in n}
    for needed in ("docs/tutorial.ipynb", "docs/conf.py", "tests/test_tutorial.py", "tests/data/trios_text_creep.txt",
                   "CHANGELOG.md", "CITATION.cff", "recipe/meta.yaml", "setup.py",
                   "examples/plot_fit_lab_data.py", "src/tenscell/data/fabry2001_hasm_powerlaw.csv"):
        assert needed in names, needed
    assert not any(n.startswith("docs/_build/") for n in names)


# ---- the release's metadata (issue 36): long description, citation, conda recipe ------------------------------------
def _setup_py():
    import importlib.util

    spec = importlib.util.spec_from_file_location("tenscell_setup", ROOT / "setup.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # setup() runs only as a script (the build backend's)
    return module


_TARGETS = r"\]\(([^)\s]+)\)"


def test_the_long_description_has_no_relative_link_with_or_without_a_public_home():
    import re

    setup_py = _setup_py()
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    relative = [t for t in re.findall(_TARGETS, readme) if not re.match(r"[a-z][a-z0-9+.-]*:|#", t)]
    assert len(relative) >= 20  # the README links to its documentation by relative paths
    base = "https://example.org/tenscell/v0.3.0/"
    linked = setup_py.resolve_links(readme, base)
    assert sorted(re.findall(_TARGETS, linked)) == sorted(
        t if re.match(r"[a-z][a-z0-9+.-]*:|#", t) else base + t for t in re.findall(_TARGETS, readme))
    plain = setup_py.resolve_links(readme, "")
    assert all(re.match(r"[a-z][a-z0-9+.-]*:|#", t) for t in re.findall(_TARGETS, plain))
    for target in relative:  # each one is still there, as its path in the source distribution
        assert f"`{target.split('#')[0]}` in the source distribution" in plain, target
    assert "(docs/fitting.md)" not in plain and "(docs/fitting.md)" in readme


def test_the_project_states_no_url_it_does_not_have():
    """No public home yet: no Project-URL, and README's links are resolved as paths (pyproject [tool.tenscell])."""
    with open(ROOT / "pyproject.toml", "rb") as fh:
        config = tomllib.load(fh)
    links = config["tool"]["tenscell"]["links"]
    assert ("urls" in config["project"]) == bool(links)
    assert config["project"]["authors"] and "readme" in config["project"]["dynamic"]


def test_the_citation_names_this_version_and_the_paper():
    yaml = pytest.importorskip("yaml")
    from tenscell import __version__

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0" and str(cff["version"]) == __version__ and cff["type"] == "software"
    paper = cff["references"][0]
    assert paper["journal"] == "Annals of Biomedical Engineering" and (paper["volume"], paper["start"]) == (32, 520)
    assert [a["family-names"] for a in paper["authors"]] == ["Sultan", "Stamenović", "Ingber"]


def test_the_conda_recipe_builds_this_version_with_the_same_requirements():
    jinja2 = pytest.importorskip("jinja2")
    yaml = pytest.importorskip("yaml")
    from tenscell import __version__

    text = jinja2.Template((ROOT / "recipe" / "meta.yaml").read_text(encoding="utf-8")).render(
        RECIPE_DIR="/recipe", PYTHON="python")
    recipe = yaml.safe_load(text)
    assert str(recipe["package"]["version"]) == __version__
    assert recipe["source"]["url"].endswith(f"dist/tenscell-{__version__}.tar.gz")  # built from the sdist
    conda_name = {"matplotlib": "matplotlib-base"}
    wanted = sorted(conda_name.get(r.split(">=")[0], r.split(">=")[0]) + " >=" + r.split(">=")[1]
                    for r in _project()["dependencies"])
    run = sorted(r for r in recipe["requirements"]["run"] if not r.startswith("python"))
    assert run == wanted
    assert f"python {_project()['requires-python']}" in recipe["requirements"]["run"]
    assert "tenscell --version" in recipe["test"]["commands"]
