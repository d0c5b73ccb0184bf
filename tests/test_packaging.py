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
            "tc.fit(tc.bundled('fabry2001'), model='voigt-uniform', starts=1, progress=False)\n"
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
                   "examples/plot_fit_lab_data.py", "src/tenscell/data/fabry2001_hasm_powerlaw.csv"):
        assert needed in names, needed
    assert not any(n.startswith("docs/_build/") for n in names)
