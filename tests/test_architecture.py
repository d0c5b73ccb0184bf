"""The two promises of docs/architecture.md, checked on the source (ast, nothing is imported or run).

1. **Data flow one way.** The import graph of ``tenscell`` (module-level *and*
   function-level imports; ``if TYPE_CHECKING:`` blocks excluded, they never
   run) has no cycle, and no module imports from a later stage of the
   pipeline than its own (:data:`STAGES`, the order of docs/architecture.md).
2. **linear/ owns every decomposition.** No module outside ``tenscell/linear/``
   refers to a factorization or decomposition of numpy/scipy
   (:data:`DECOMPOSITIONS`), except the few places listed in :data:`EXCEPTIONS`
   with the reason each one is not a decomposition of a structure's (K0, C0).

Each check has a companion test that plants a violation in a copy of the
source tree and asserts that the check finds it, so neither can pass vacuously.
"""
from __future__ import annotations

import ast
import functools
import shutil
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parent.parent / "src" / "tenscell"

#: the pipeline, earliest stage first (docs/architecture.md); a module may import from its own stage or earlier ones
STAGES: tuple[tuple[str, ...], ...] = (
    # shared plumbing: leaf modules
    ("_checks", "_errors", "_progress", "_results", "_threads", "_parallel", "_version", "_ranges", "_optional"),
    ("model",),
    ("laws",),
    ("linear",),
    ("response", "timedomain"),
    # measured data in, output sets out (structure files need model/)
    ("io",),
    # analyses
    ("dynamics", "fitting", "sensitivity", "summary", "studies", "population"),
    ("reports", "plotting"),
    ("cli", "__main__", ""),  # "" is the top-level package (tenscell/__init__.py)
)

#: numpy / scipy functions that factorize or decompose a matrix
DECOMPOSITIONS = frozenset({
    "cholesky", "cho_factor", "cho_solve", "cho_solve_banded", "cholesky_banded", "lu", "lu_factor", "lu_solve",
    "ldl", "qr", "rq", "svd", "svdvals", "eig", "eigh", "eigvals", "eigvalsh", "eig_banded", "eigh_tridiagonal",
    "eigs", "eigsh", "lobpcg", "schur", "solve", "solve_triangular", "solve_banded", "solveh_banded", "inv", "pinv",
    "lstsq", "null_space", "orth", "matrix_rank", "splu", "spilu", "spsolve", "spsolve_triangular", "factorized",
})
_LINALG = ("numpy.linalg.", "scipy.linalg.", "scipy.sparse.linalg.")

#: (module, enclosing function) -> why a decomposition there is not one of a structure's (K0, C0)
EXCEPTIONS: dict[tuple[str, str], str] = {
    ("model.formfinding", "rigid_body_modes"): "form-finding's own geometry: null space of the support constraints",
    ("model.formfinding", "find_form"): "form-finding's own geometry: equilibrium-matrix null space and the "
                                        "energy Hessian of the trial geometry, before any linear model exists",
    ("model.formfinding", "_lm_step"): "form-finding's Newton steps on its own energy",
    ("model.shapes", "find_cylindrical_reference"): "form-finding of the cylindrical reference: stability of trial "
                                                    "geometries, before any linear model exists (model/ precedes "
                                                    "linear/)",
    ("model.shapes", "nucleated_cell"): "equilibrium: the prestressed nucleus shell's member forces (its equilibrium "
                                        "matrix block is statically determinate), before any linear model exists",
    ("model.equilibrium", "self_stress_basis"): "geometry: the SVD of the equilibrium matrix A gives the self-stress "
                                                "states and mechanisms (the equilibrium stage)",
    ("model.lattices", "lattice_module_tensions"): "geometry: self-stress of a lattice module (null space of A·G)",
    ("summary", "_rigid_dof"): "geometry: rank of the support constraints",
    ("summary", "_ranks"): "geometry: rank of the equilibrium matrix A of a structure that has no cell",
    ("dynamics.equations", "_factor"): "the nonlinear equations of motion at the current state q (implicit steps), "
                                       "not the reference pencil",
    ("dynamics.equations", "_apply"): "solves with the factors of _factor (the same matrices at a state q)",
    ("dynamics.integration", "_scale"): "a size estimate for the solver's tolerances at the initial state of a "
                                        "nonlinear simulation (least squares: it never fails)",
    ("timedomain", "stress_relaxation"): "zeros of J(s) from the retardation spectrum: a (k+1)×(k+1) modal matrix, "
                                         "not a structure matrix",
    ("fitting.identifiability", "identifiability"): "SVD of the fit's Jacobian (parameter space)",
    ("fitting.models.population", "_block_analysis"): "SVDs of a population fit's Jacobian block by block (each "
                                                       "cell's own columns, the reduced shared columns) and the "
                                                       "inverse of the unseen shared directions' small Gram matrix "
                                                       "(parameter space)",
}


#: what other work in progress will remove, each with who removes it; a test fails once an entry has gone, so
#: that the list is emptied as the work lands (never add to it to make a new violation pass)
PENDING_CYCLES: dict[frozenset[str], str] = {}
PENDING_BACKWARD: dict[tuple[str, str], str] = {}


# ---- reading the source -------------------------------------------------------------------------------
@functools.cache
def _parse(text: str) -> ast.Module:
    return ast.parse(text)


def _modules(root: Path) -> dict[str, Path]:
    """Module name relative to the package ("" for tenscell itself, "fitting.search"...) -> file."""
    out = {}
    for path in root.rglob("*.py"):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _runtime_nodes(tree: ast.AST):
    """Every node of ``tree`` except those under ``if TYPE_CHECKING:``, with the chain of enclosing functions."""
    stack: list[tuple[ast.AST, tuple[str, ...]]] = [(tree, ())]
    while stack:
        node, funcs = stack.pop()
        yield node, funcs
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            children: list[ast.AST] = list(node.orelse)
        else:
            children = list(ast.iter_child_nodes(node))
        inner = funcs + (node.name,) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) else funcs
        stack.extend((child, inner) for child in children)


def _import_targets(module: str, is_package: bool, node: ast.AST, known: set[str]) -> list[str]:
    """The tenscell modules (relative names) an import statement loads."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            base = module.split(".") if module else []
            if not is_package:
                base = base[:-1]
            base = base[: len(base) - (node.level - 1)]
            prefix = ".".join(base + ([node.module] if node.module else []))
            names = ["tenscell" + ("." + prefix if prefix else "")]
        else:
            names = [node.module or ""]
        names = [f"{names[0]}.{a.name}" if f"{names[0]}.{a.name}".removeprefix("tenscell.") in known else names[0]
                 for a in node.names]
    else:
        return []
    out = []
    for name in names:
        if name == "tenscell" or name.startswith("tenscell."):
            rel = name.removeprefix("tenscell").removeprefix(".")
            while rel and rel not in known:  # "tenscell.fitting.FitResult" -> the package "fitting"
                rel = rel.rpartition(".")[0]
            out.append(rel)
    return out


def import_graph(root: Path = SRC) -> dict[str, dict[str, int]]:
    """module -> {imported module: line of the first such import}, over module- and function-level imports.

    An import of ``a.b.c`` is an edge to ``a.b.c`` and to the packages ``a`` and ``a.b`` whose ``__init__`` it
    runs (except a module's own ancestors, which are already running).
    """
    mods = _modules(root)
    known = set(mods)
    graph: dict[str, dict[str, int]] = {}
    for module, path in mods.items():
        edges: dict[str, int] = {}
        tree = _parse(path.read_text(encoding="utf-8"))
        for node, _ in _runtime_nodes(tree):
            for target in _import_targets(module, path.name == "__init__.py", node, known):
                # importing a.b.c runs a/__init__ and a/b/__init__ first (the top-level package is lazy: not an edge)
                parts = target.split(".")
                for t in [".".join(parts[:k]) for k in range(1, len(parts))] + [target]:
                    if t and t != module and not module.startswith(t + "."):
                        edges.setdefault(t, node.lineno)  # type: ignore[attr-defined]
        graph[module] = edges
    return graph


def stage(module: str) -> int:
    """Position of ``module`` in :data:`STAGES` (by its first component; "" is the top-level package)."""
    head = module.split(".")[0]
    for i, names in enumerate(STAGES):
        if head in names:
            return i
    raise AssertionError(f"tenscell.{module} belongs to no stage of the pipeline: add it to STAGES (and to "
                         "docs/architecture.md)")


def _name(module: str) -> str:
    return "tenscell" + ("." + module if module else "")


def backward_imports(graph) -> list[str]:
    """Every import from a later stage into an earlier one, as 'a (stage) imports b (later stage) at line n'."""
    out = []
    for a, edges in graph.items():
        for b, line in edges.items():
            if stage(b) > stage(a):
                out.append(f"{_name(a)} (line {line}) imports {_name(b)}, a later stage")
    return sorted(out)


def cycles(graph) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on, stack, out = set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def decompositions(root: Path = SRC) -> list[tuple[str, str, int, str]]:
    """Every reference to a numpy/scipy decomposition outside linear/: (module, enclosing functions, line, name)."""
    found = []
    for module, path in _modules(root).items():
        if module == "linear" or module.startswith("linear."):
            continue
        tree = _parse(path.read_text(encoding="utf-8"))
        aliases: dict[str, str] = {}
        for node in ast.walk(tree):  # every binding of numpy / scipy names, wherever it is
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.asname:
                        aliases[a.asname] = a.name
                    else:
                        aliases[a.name.split(".")[0]] = a.name.split(".")[0]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                for a in node.names:
                    aliases[a.asname or a.name] = f"{node.module}.{a.name}"
        for node, funcs in _runtime_nodes(tree):
            if not isinstance(node, (ast.Attribute, ast.Name)) or not isinstance(node.ctx, ast.Load):
                continue
            dotted = ast.unparse(node)
            head, _, rest = dotted.partition(".")
            if head not in aliases:
                continue
            full = aliases[head] + ("." + rest if rest else "")
            full = full.replace("numpy.linalg.linalg.", "numpy.linalg.")
            if full.startswith(_LINALG) and full.rpartition(".")[2] in DECOMPOSITIONS:
                found.append((module, ".".join(funcs) or "<module>", node.lineno, full))
    return found


def unexplained(found) -> list[str]:
    """The decompositions no entry of :data:`EXCEPTIONS` covers (an entry covers a function and all it encloses)."""
    out = []
    for module, funcs, line, name in found:
        chain = funcs.split(".")
        if not any((module, f) in EXCEPTIONS for f in chain):
            out.append(f"tenscell.{module}:{line} ({funcs}) calls {name}: decompose through tenscell.linear "
                       "(Pencil, linear.whitening) or list the reason in EXCEPTIONS")
    return sorted(set(out))


# ---- the promises ----------------------------------------------------------------------------------------
def test_every_module_has_a_stage():
    for module in _modules(SRC):
        stage(module)


def test_no_import_cycles():
    found = [c for c in cycles(import_graph()) if frozenset(c) not in PENDING_CYCLES]
    assert not found, "import cycles:\n" + "\n".join(" -> ".join(c) for c in found)


def test_no_import_runs_back_up_the_pipeline():
    found = [line for line in backward_imports(import_graph())
             if not any(line.startswith(f"{_name(a)} (") and line.endswith(f"imports {_name(b)}, a later stage")
                        for a, b in PENDING_BACKWARD)]
    assert not found, "\n".join(found)


def test_pending_work_is_still_pending():
    """An entry of PENDING_* that no longer occurs is removed, so the lists only ever shrink."""
    graph = import_graph()
    gone = [sorted(c) for c in PENDING_CYCLES if sorted(c) not in cycles(graph)]
    gone += [f"{a} -> {b}" for a, b in PENDING_BACKWARD if b not in graph.get(a, {})]
    assert not gone, f"no longer occurring, remove from PENDING_*: {gone}"


def test_linear_owns_every_decomposition():
    found = unexplained(decompositions())
    assert not found, "\n".join(found)


def test_every_exception_is_still_needed():
    """An entry of EXCEPTIONS whose decomposition has gone is removed (the list stays the truth)."""
    used = {(m, f) for m, funcs, _, _ in decompositions() for f in funcs.split(".")}
    stale = sorted(set(EXCEPTIONS) - used)
    assert not stale, f"EXCEPTIONS lists places without a decomposition: {stale}"


# ---- the checks can fail -----------------------------------------------------------------------------------
@pytest.fixture()
def tree_copy(tmp_path) -> Path:
    root = tmp_path / "tenscell"
    shutil.copytree(SRC, root, ignore=shutil.ignore_patterns("__pycache__", "*.csv"))
    return root


def _append(path: Path, code: str) -> None:
    path.write_text(path.read_text(encoding="utf-8") + "\n\n" + code + "\n", encoding="utf-8")


def test_a_planted_backward_import_is_found(tree_copy):
    # a function-level import, as the .plot() methods had: model/ reaching down to plotting/
    _append(tree_copy / "model" / "structure.py", "def _draw():\n    from ..plotting import save\n    return save\n")
    line = (tree_copy / "model" / "structure.py").read_text().splitlines().index("    from ..plotting import save") + 1
    new = set(backward_imports(import_graph(tree_copy))) - set(backward_imports(import_graph()))
    assert new == {f"tenscell.model.structure (line {line}) imports tenscell.plotting, a later stage"}


def test_a_planted_cycle_is_found(tree_copy):
    _append(tree_copy / "_checks.py", "def _f():\n    from ._progress import progress_bar\n    return progress_bar\n")
    _append(tree_copy / "_progress.py", "def _g():\n    from ._checks import positive_scalar\n    return positive_scalar\n")
    assert ["_checks", "_progress"] in cycles(import_graph(tree_copy))


def test_type_checking_imports_are_not_edges(tree_copy):
    _append(tree_copy / "model" / "structure.py",
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..plotting import save\n")
    assert backward_imports(import_graph(tree_copy)) == backward_imports(import_graph())


@pytest.mark.parametrize("code", [
    "import numpy as np\n\ndef _stable(K):\n    return np.linalg.eigvalsh(K)[0] > 0\n",
    "import scipy.linalg\n\ndef _solve(K, b):\n    solve = scipy.linalg.cho_solve\n    return solve(K, b)\n",
    "from scipy.sparse.linalg import splu\n\ndef _solve(K, b):\n    return splu(K).solve(b)\n",
])
def test_a_planted_decomposition_is_found(tree_copy, code):
    _append(tree_copy / "sensitivity.py", code)
    new = set(unexplained(decompositions(tree_copy))) - set(unexplained(decompositions()))
    assert len(new) == 1 and new.pop().startswith("tenscell.sensitivity:"), new


def test_an_exception_covers_only_its_function(tree_copy):
    # summary.summarize may take a rank; a new function of summary.py may not decompose
    _append(tree_copy / "summary.py", "import numpy as np\n\ndef _new(K):\n    return np.linalg.cholesky(K)\n")
    new = set(unexplained(decompositions(tree_copy))) - set(unexplained(decompositions()))
    assert len(new) == 1 and "(_new)" in new.pop()


# ---- one error hierarchy ------------------------------------------------------------------------------------
def test_every_error_is_a_tenscell_error():
    """Every exception class tenscell defines subclasses TenscellError (so one ``except`` catches them all)."""
    import importlib
    import inspect

    from tenscell import TenscellError

    defined = []
    for module in sorted(_modules(SRC)):
        if module in ("", "__main__", "cli.__main__"):
            continue
        mod = importlib.import_module(f"tenscell.{module}")
        defined += [obj for _, obj in inspect.getmembers(mod, inspect.isclass)
                    if issubclass(obj, BaseException) and obj.__module__ == mod.__name__]
    assert len(defined) >= 13, defined  # the check looks at the real classes
    outside = [f"{c.__module__}.{c.__qualname__}" for c in defined if not issubclass(c, TenscellError)]
    assert not outside, outside
