"""``import tenscell`` is light, and every public name still resolves (lazily)."""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

import tenscell

HEAVY = ("numpy", "scipy", "scipy.optimize", "matplotlib", "pandas")


def _loaded_after(code: str) -> set[str]:
    """The heavy modules in sys.modules after running ``code`` in a fresh interpreter."""
    probe = (f"{code}\nimport sys\n"
             f"print('loaded:', *(m for m in {HEAVY!r} if m in sys.modules), file=sys.__stdout__)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    words = out.stdout.split()
    assert words[:1] == ["loaded:"], out.stdout  # the probe ran to the end
    return set(words[1:])


def test_import_tenscell_loads_no_heavy_module():
    assert _loaded_after("import tenscell") == set()


def test_help_needs_only_the_standard_library():
    code = ("import contextlib, io\nfrom tenscell.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()) as text:\n    assert main(['--help']) == 0\n"
            "assert 'usage: tenscell' in text.getvalue()")
    assert _loaded_after(code) == set()


def test_building_the_paper_cell_needs_no_optimizer_or_plotting():
    # scipy.optimize is imported inside the functions that call it (LP, root finding), not at import
    assert not {"scipy.optimize", "matplotlib", "pandas"} & _loaded_after("import tenscell; tenscell.paper_cell()")


def test_moduli_loads_only_what_it_computes_with():
    # tenscell moduli needs numpy, scipy.linalg and scipy.sparse; scipy.optimize (0.1-0.16 s of CPU to import, used
    # by one nnls call of the springpots' Prony fit) and the plotting, table and cluster libraries are not loaded
    code = ("import contextlib, io, sys\nfrom tenscell.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()) as text:\n    assert main(['moduli']) == 0\n"
            "assert text.getvalue().startswith('prestress_Pa,frequency_Hz')\n"
            "unused = ('scipy.optimize', 'scipy.special', 'scipy.integrate', 'scipy.stats', 'matplotlib', 'pandas', "
            "'dask', 'distributed', 'pyarrow')\n"
            "print('loaded:', *(m for m in unused if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["loaded:"], out.stdout


def test_every_public_name_resolves_to_its_module():
    for name in tenscell.__all__:
        obj = getattr(tenscell, name)
        module = tenscell._WHERE[name]
        assert obj is getattr(sys.modules[f"tenscell.{module}"], name), name


def test_type_checking_imports_match_the_lazy_table():
    tree = ast.parse(Path(tenscell.__file__).read_text())
    block = next(n for n in tree.body if isinstance(n, ast.If) and getattr(n.test, "id", "") == "TYPE_CHECKING")
    seen = {}
    for node in block.body:
        if isinstance(node, ast.ImportFrom) and node.module:
            for alias in node.names:
                seen[alias.name] = node.module
    assert {n: m for n, m in seen.items() if n in tenscell._WHERE} == tenscell._WHERE
    assert set(tenscell._WHERE) <= set(seen)


def test_submodules_as_attributes_and_unknown_names():
    assert tenscell.plotting.__name__ == "tenscell.plotting"
    assert "plotting" in dir(tenscell) and "paper_cell" in dir(tenscell)
    with pytest.raises(AttributeError, match="no attribute 'no_such_thing'"):
        tenscell.no_such_thing
    with pytest.raises(AttributeError):
        tenscell._private_probe


def test_the_top_level_is_the_entry_points():
    # what a user types in the first hour; the rest is reached through its subpackage
    assert 18 <= len(tenscell.__all__) <= 25, tenscell.__all__
    assert {"paper_cell", "linearize", "moduli", "frequency_response", "fit", "read_csv", "TenscellError"} \
        <= set(tenscell.__all__)


def test_every_subpackage_states_its_public_names():
    import importlib
    import pkgutil

    for info in pkgutil.iter_modules(tenscell.__path__):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"tenscell.{info.name}")
        names = getattr(module, "__all__", None)
        assert names, f"tenscell.{info.name} has no __all__"
        missing = [n for n in names if not hasattr(module, n)]
        assert not missing, f"tenscell.{info.name}.__all__ names what it does not have: {missing}"


def test_old_top_level_names_are_gone_in_0_3_and_name_their_home():
    """Deprecated in 0.2.0 'until 0.3.0': now an AttributeError that names where the name lives."""
    import importlib

    assert not set(tenscell._REMOVED) & set(tenscell._WHERE)
    # every name of 0.1.0, TenscellError, and read_data (the one reader of any file, issue 20)
    assert len(tenscell._REMOVED) + len(tenscell._WHERE) == 103 + 2
    for name, home in tenscell._REMOVED.items():
        with pytest.raises(AttributeError, match=rf"tenscell\.{name} was removed in 0\.3\.0 .* tenscell\.{home}\.{name}"):
            getattr(tenscell, name)
        assert name in importlib.import_module(f"tenscell.{home}").__all__, (home, name)
