"""The two promises of docs/architecture.md, checked on the source (ast, nothing is imported or run).

1. **Data flow one way.** The import graph of ``tenscell`` (module-level *and*
   function-level imports; ``if TYPE_CHECKING:`` blocks excluded, they never
   run) has no cycle, and no module imports from a later stage of the
   pipeline than its own (:data:`STAGES`, the order of docs/architecture.md).
2. **linear/ owns every decomposition.** No module outside ``tenscell/linear/``
   refers to a name of a linear-algebra namespace (numpy.linalg, scipy.linalg and
   its LAPACK wrappers, scipy.sparse.linalg, CHOLMOD...: :data:`LINALG_NAMESPACES`)
   other than the few that decompose nothing (an allow-list, :data:`HARMLESS`),
   nor passes such a namespace around (``getattr(np.linalg, name)``), except in
   the few places listed in :data:`EXCEPTIONS` (the allow-list of who may
   decompose) with the reason each one is not a decomposition of a structure's
   (K0, C0).

3. **One criterion of positive definiteness.** Outside ``linear/`` no eigenvalue
   (of numpy, scipy or ``linear/``'s own eigensolvers: :data:`EIGEN_ROUTINES`),
   nor anything computed from one, is compared with a threshold
   (:func:`eigen_thresholds`): definiteness is asked of ``linear.definite``
   (a Cholesky factor exists), except in the places :data:`CRITERIA_EXCEPTIONS`
   lists with the reason.
4. **Modules keep their privates.** No private name (``_x``, a function, a class or
   a module) is imported from another subpackage (:func:`private_imports`;
   :data:`PENDING_PRIVATE` lists what work in progress removes), no module imports
   ``*``, and no project module is imported by name at run time
   (``importlib.import_module``, ``__import__``: the import graph could not see
   it), except the registries :data:`DYNAMIC_IMPORTS` lists with the reason.

Each check has companion tests that plant a violation in a copy of the
source tree and assert that the check finds it — for the decompositions, one of
each kind (:data:`PLANTED`) — so none can pass vacuously.
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
    ("_checks", "_errors", "_progress", "_results", "_threads", "_parallel", "_version", "_ranges", "_optional",
     "_deprecated"),
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

#: the namespaces of linear algebra: every name in them decomposes, factorizes or solves a matrix unless it is
#: listed in HARMLESS (an allow-list: a new scipy function, a LAPACK or CHOLMOD call, is caught without a list)
LINALG_NAMESPACES = ("numpy.linalg", "scipy.linalg", "scipy.sparse.linalg", "cvxopt.cholmod", "cvxopt.lapack",
                     "cvxopt.umfpack", "sksparse", "pymetis")
#: names in those namespaces that decompose nothing (``norm`` only as a vector or Frobenius norm: with ``ord`` 2,
#: -2 or "nuc" it is an SVD, see :func:`_norm_decomposes`)
HARMLESS = frozenset({"norm", "LinAlgError", "multi_dot", "matmul", "vecdot", "matrix_transpose", "outer", "cross",
                      "diagonal", "trace", "block_diag", "LinearOperator", "aslinearoperator", "MatrixRankWarning",
                      "LinAlgWarning"})
#: (module, enclosing function) -> why a decomposition there is not one of a structure's (K0, C0)
EXCEPTIONS: dict[tuple[str, str], str] = {
    ("model.formfinding", "rigid_body_modes"): "form-finding's own geometry: null space of the support constraints",
    ("model.formfinding", "find_form"): "form-finding's own geometry: equilibrium-matrix null space and the "
                                        "energy Hessian of the trial geometry, before any linear model exists",
    ("model.formfinding", "_lm_step"): "form-finding's Newton steps on its own energy",
    ("model.shapes", "_if_free_det"): "geometry: the determinant of the IF-free cell's 9×9 equilibrium block, "
                                      "whose root in δ is the IF-free reference (Appendix)",
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


#: the names of eigenvalue routines, wherever they come from (numpy, scipy, LAPACK, ``linear/``'s own kernels): an
#: eigenvalue compared with a threshold is a home-made criterion (of definiteness, stability or rank)
EIGEN_ROUTINES = frozenset({"eig", "eigh", "eigvals", "eigvalsh", "eigs", "eigsh", "eig_banded", "eigvals_banded",
                            "eigh_tridiagonal", "eigvalsh_tridiagonal", "lobpcg", "syevd", "syev", "syevr", "heevd",
                            "heev", "symmetric_eigen", "prestress_grid_modes", "slow_modes", "damping_modes"})
#: (module, enclosing function) -> why eigenvalues are compared with a threshold there, and it is not a criterion of
#: positive definiteness of a structure's matrices
CRITERIA_EXCEPTIONS: dict[tuple[str, str], str] = {
    ("model.formfinding", "find_form"): "the found form's stability is reported from its own energy Hessian at the "
                                        "trial geometry (a relative eigenvalue floor), before any linear model "
                                        "exists; model/ precedes linear/, so it cannot ask linear.definite",
    ("timedomain", "stress_relaxation"): "a realness test of the zeros of J(s) (eigenvalues of a small modal "
                                         "matrix): whether the relaxation is a sum of real exponentials, no "
                                         "definiteness",
    ("summary", "relaxation_modes"): "the slowest modes' times τ turned into rates (τ = 0: an instantaneous mode, "
                                     "rate ∞) and their shapes scaled for a figure; the model's definiteness was "
                                     "asked of its pencil",
}
#: (module, enclosing function) -> the registry whose project modules it imports by name at run time, and why
DYNAMIC_IMPORTS: dict[tuple[str, str], str] = {
    ("", "__getattr__"): "the top level's lazy names (_EXPORTS, _MOVED: `import tenscell` stays quick); "
                         "tests/test_startup.py resolves every one",
    ("io", "__getattr__"): "tenscell.io's lazy names (`import tenscell.io` imports none of its modules)",
    ("population", "__getattr__"): "tenscell.population's lazy names (Dask is imported on first use)",
    ("io.readers", "_reader"): "the readers' registry (READERS: one module per format, two files to add one)",
    ("cli.study", "load_study"): "the studies' table (STUDIES: name -> module:attribute; building the parser "
                                 "imports no study)",
    ("cli", "build_parser"): "the command modules' registry (COMMAND_MODULES: building the parser imports only "
                             "the standard library)",
    ("_results", "_renderer"): "the renderers' registry: plotting/ and reports/ register on import, and the "
                               "analyses upstream of them may not import them (data flows one way)",
    ("population._warm", "setup"): "the modules a worker process imports before its first task (names given by "
                                   "the caller)",
    ("_optional", "require"): "optional third-party dependencies by name (never a tenscell module), with the "
                              "command that installs a missing one",
    ("_deprecated", "moved"): "the new home of a name of the last release that moved (MOVED): imported only when "
                              "the old name is used, with its DeprecationWarning; removed with the shims",
}

#: what other work in progress will remove, each with who removes it; a test fails once an entry has gone, so
#: that the list is emptied as the work lands (never add to it to make a new violation pass)
PENDING_CYCLES: dict[frozenset[str], str] = {}
PENDING_BACKWARD: dict[tuple[str, str], str] = {}
#: (importing module, imported private name) of private imports across subpackages that pending work removes
PENDING_PRIVATE: dict[tuple[str, str], str] = {}


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


@functools.cache
def _walk(text: str) -> tuple:
    """:func:`_runtime_nodes` of a module's source, once per distinct text."""
    return tuple(_runtime_nodes(_parse(text)))


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
        for node, _ in _walk(path.read_text(encoding="utf-8")):
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


def _aliases(tree: ast.AST) -> dict[str, str]:
    """Every binding of an imported name in ``tree`` (wherever it is): local name -> dotted module path."""
    aliases: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.asname:
                    aliases[a.asname] = a.name
                else:
                    aliases[a.name.split(".")[0]] = a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for a in node.names:
                aliases[a.asname or a.name] = f"{node.module}.{a.name}"
    return aliases


def _namespace(full: str) -> str | None:
    """The linear-algebra namespace ``full`` is or lies in (:data:`LINALG_NAMESPACES`), or None."""
    full = full.replace("numpy.linalg.linalg.", "numpy.linalg.").replace("numpy.linalg._linalg.", "numpy.linalg.")
    for ns in LINALG_NAMESPACES:
        if full == ns or full.startswith(ns + "."):
            return ns
    return None


def _norm_decomposes(call: ast.AST | None) -> bool:
    """Whether a call of ``norm`` asks for a spectral (2, -2) or nuclear norm: an SVD of its matrix."""
    if not isinstance(call, ast.Call):
        return False
    args = call.args[1:2] + [k.value for k in call.keywords if k.arg == "ord"]
    return any(isinstance(a, ast.UnaryOp) and isinstance(a.operand, ast.Constant) and a.operand.value == 2
               or isinstance(a, ast.Constant) and a.value in (2, "nuc") and a.value is not True for a in args)


def _reference(node: ast.AST, parent: ast.AST | None, aliases: dict[str, str]) -> str | None:
    """The linear-algebra name a Load of a Name/Attribute refers to, when it decomposes; None otherwise.

    A name of a namespace not in :data:`HARMLESS` decomposes; so does ``norm`` asked for a 2- or nuclear norm;
    so does a namespace itself used as a value (``getattr(np.linalg, name)``, ``la = scipy.linalg``), which would
    hide what is called. An attribute chain is judged once, at its longest (``np.linalg.eigh``, not ``np.linalg``).
    """
    if isinstance(parent, ast.Attribute) and parent.value is node:
        return None  # the enclosing attribute is judged instead
    base = node
    while isinstance(base, ast.Attribute):
        base = base.value
    if not isinstance(base, ast.Name):
        return None  # an attribute of a value (``norm(v).mean``): its dotted part is judged on its own
    dotted = ast.unparse(node)
    head, _, rest = dotted.partition(".")
    if head not in aliases:
        return None
    full = aliases[head] + ("." + rest if rest else "")
    ns = _namespace(full)
    if ns is None:
        return None
    if full == ns:
        return full  # the namespace itself, passed around
    name = full[len(ns) + 1:].split(".")[0]
    if name == "norm":
        return full if _norm_decomposes(parent) else None
    return None if name in HARMLESS else full


def decompositions(root: Path = SRC) -> list[tuple[str, str, int, str]]:
    """Every reference to linear algebra that decomposes, outside linear/: (module, enclosing functions, line, name)."""
    found = []
    for module, path in _modules(root).items():
        if module == "linear" or module.startswith("linear."):
            continue
        found += _decompositions_in(module, path.read_text(encoding="utf-8"))
    return found


@functools.cache
def _decompositions_in(module: str, text: str) -> tuple:
    """:func:`decompositions` of one module's source (cached by its text: a planted copy of the tree re-reads only
    the file it changed)."""
    tree = _parse(text)
    aliases = _aliases(tree)
    parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
    found = []
    for node, funcs in _walk(text):  # the nodes of the same cached tree
        if not isinstance(node, (ast.Attribute, ast.Name)) or not isinstance(node.ctx, ast.Load):
            continue
        full = _reference(node, parents.get(node), aliases)
        if full is not None:
            found.append((module, ".".join(funcs) or "<module>", node.lineno, full))
    return tuple(found)


def unexplained(found) -> list[str]:
    """The decompositions no entry of :data:`EXCEPTIONS` covers (an entry covers a function and all it encloses)."""
    out = []
    for module, funcs, line, name in found:
        chain = funcs.split(".")
        if not any((module, f) in EXCEPTIONS for f in chain):
            out.append(f"tenscell.{module}:{line} ({funcs}) calls {name}: decompose through tenscell.linear "
                       "(Pencil, linear.whitening) or list the reason in EXCEPTIONS")
    return sorted(set(out))


def _call_name(call: ast.Call) -> str | None:
    """The last name of what a call calls (``np.linalg.eigvalsh(...)`` -> ``eigvalsh``)."""
    f = call.func
    return f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else None


def _eigen_calls(node: ast.AST) -> list[str]:
    return [n for c in ast.walk(node) if isinstance(c, ast.Call) and (n := _call_name(c)) in EIGEN_ROUTINES]


def _names(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _tainted(func: ast.AST) -> set[str]:
    """The names in ``func`` bound to an eigenvalue routine's result or to anything computed from one (a fixpoint
    over assignments and loops: ``lam, _ = symmetric_eigen(K)``, ``low = lam[0]``, ``for x in lam``)."""
    tainted: set[str] = set()
    while True:
        before = len(tainted)
        for node in ast.walk(func):
            if isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign, ast.NamedExpr)) and node.value is not None:
                source, targets = node.value, (node.targets if isinstance(node, ast.Assign) else [node.target])
            elif isinstance(node, (ast.For, ast.comprehension)):
                source, targets = node.iter, [node.target]
            else:
                continue
            if _eigen_calls(source) or _names(source) & tainted:
                for t in targets:
                    tainted |= _names(t)
        if len(tainted) == before:
            return tainted


def eigen_thresholds(root: Path = SRC) -> list[tuple[str, str, int, str]]:
    """Every comparison of an eigenvalue (or of what is computed from one) outside linear/: (module, enclosing
    functions, line, the eigenvalue routine or name compared)."""
    found: set = set()
    for module, path in _modules(root).items():
        if module == "linear" or module.startswith("linear."):
            continue
        found |= _eigen_thresholds_in(module, path.read_text(encoding="utf-8"))
    return sorted(found)


@functools.cache
def _eigen_thresholds_in(module: str, text: str) -> frozenset:
    """:func:`eigen_thresholds` of one module's source (cached by its text)."""
    tree = _parse(text)
    chain = {id(node): ".".join(funcs) or "<module>" for node, funcs in _walk(text)  # nodes of the same cached tree
             if isinstance(node, ast.Compare)}
    found = set()
    for func in [tree] + [f for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))]:
        tainted = _tainted(func) if func is not tree else set()
        for node in ast.walk(func):
            if not isinstance(node, ast.Compare) or id(node) not in chain:
                continue
            bad = set(_eigen_calls(node)) | (_names(node) & tainted)
            if bad:
                found.add((module, chain[id(node)], node.lineno, sorted(bad)[0]))
    return frozenset(found)


def unexplained_criteria(found) -> list[str]:
    """The eigenvalue comparisons no entry of :data:`CRITERIA_EXCEPTIONS` covers."""
    return sorted({f"tenscell.{m}:{line} ({funcs}) compares {name} with a threshold: ask linear.definite "
                   "(positive_definite_factor, is_positive_definite) or list the reason in CRITERIA_EXCEPTIONS"
                   for m, funcs, line, name in found if not any((m, f) in CRITERIA_EXCEPTIONS for f in funcs.split("."))})


def _subpackage(module: str, is_package: bool) -> str:
    return module if is_package else module.rpartition(".")[0]


def _from_module(module: str, is_package: bool, node: ast.ImportFrom) -> str | None:
    """The tenscell module (relative name) a ``from ... import`` reads from; None for another package."""
    if node.level:
        base = module.split(".") if module else []
        if not is_package:
            base = base[:-1]
        base = base[: len(base) - (node.level - 1)]
        return ".".join(base + ([node.module] if node.module else []))
    if node.module == "tenscell" or (node.module or "").startswith("tenscell."):
        return node.module.removeprefix("tenscell").removeprefix(".")
    return None


def private_imports(root: Path = SRC) -> list[str]:
    """Every private name (``_x``) imported from another subpackage, and every star import, as
    'importer imports name (line n)'."""
    mods = _modules(root)
    out = []
    for module, path in mods.items():
        is_package = path.name == "__init__.py"
        mine = _subpackage(module, is_package)
        for node, _ in _walk(path.read_text(encoding="utf-8")):
            if not isinstance(node, ast.ImportFrom):
                continue
            source = _from_module(module, is_package, node)
            for alias in node.names:
                if alias.name == "*":
                    out.append(f"tenscell.{module} (line {node.lineno}) imports * from {node.module or '.'}")
                    continue
                if source is None or not alias.name.startswith("_") or alias.name.startswith("__"):
                    continue
                full = f"{source}.{alias.name}".strip(".")
                if full in mods:  # a private module: it belongs to its package
                    home = full.rpartition(".")[0]
                else:
                    home = _subpackage(source, source in mods and mods[source].name == "__init__.py")
                if home != mine and (module, full) not in PENDING_PRIVATE:
                    out.append(f"tenscell.{module} (line {node.lineno}) imports {full}, private to "
                               f"tenscell{'.' + home if home else ''}: make it public or move the code")
    return sorted(out)


def dynamic_imports(root: Path = SRC) -> list[tuple[str, str, int]]:
    """Every call of ``importlib.import_module`` or ``__import__`` whose module may be a project module (anything
    but a string naming another package): (module, enclosing functions, line)."""
    found = []
    for module, path in _modules(root).items():
        for node, funcs in _walk(path.read_text(encoding="utf-8")):
            if not isinstance(node, ast.Call) or _call_name(node) not in ("import_module", "__import__"):
                continue
            first = node.args[0] if node.args else None
            if isinstance(first, ast.Constant) and isinstance(first.value, str) and not (
                    first.value.startswith(".") or first.value.split(".")[0] == "tenscell"):
                continue  # another package by its literal name (an optional dependency)
            found.append((module, ".".join(funcs) or "<module>", node.lineno))
    return found


def unexplained_dynamic(found) -> list[str]:
    return sorted({f"tenscell.{m}:{line} ({funcs}) imports a module by name at run time: import it (the "
                   "architecture test then sees the edge) or list the registry in DYNAMIC_IMPORTS"
                   for m, funcs, line in found if not any((m, f) in DYNAMIC_IMPORTS for f in funcs.split("."))})


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


def test_no_home_made_criterion_of_definiteness():
    found = unexplained_criteria(eigen_thresholds())
    assert not found, "\n".join(found)


def test_every_criterion_exception_is_still_needed():
    used = {(m, f) for m, funcs, _, _ in eigen_thresholds() for f in funcs.split(".")}
    stale = sorted(set(CRITERIA_EXCEPTIONS) - used)
    assert not stale, f"CRITERIA_EXCEPTIONS lists places without an eigenvalue comparison: {stale}"


def test_no_private_import_across_subpackages_and_no_star_import():
    found = private_imports()
    assert not found, "\n".join(found)


def test_pending_private_imports_are_still_pending():
    mods = _modules(SRC)
    gone = []
    for module, full in PENDING_PRIVATE:
        text = mods[module].read_text(encoding="utf-8")
        if full.rpartition(".")[2] not in text:
            gone.append((module, full))
    assert not gone, f"no longer occurring, remove from PENDING_PRIVATE: {gone}"


def test_no_project_module_imported_by_name():
    found = unexplained_dynamic(dynamic_imports())
    assert not found, "\n".join(found)


def test_every_dynamic_import_entry_is_still_needed():
    used = {(m, f) for m, funcs, _ in dynamic_imports() for f in funcs.split(".")}
    stale = sorted(set(DYNAMIC_IMPORTS) - used)
    assert not stale, f"DYNAMIC_IMPORTS lists places without a dynamic import: {stale}"


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


#: one planted violation of each kind the allow-list must catch: (what, source appended to sensitivity.py)
PLANTED = {
    "eigvalsh": "import numpy as np\n\ndef _stable(K):\n    return np.linalg.eigvalsh(K)[0] > 0\n",
    "a local alias": "import scipy.linalg\n\ndef _solve(K, b):\n    solve = scipy.linalg.cho_solve\n    return solve(K, b)\n",
    "splu": "from scipy.sparse.linalg import splu\n\ndef _solve(K, b):\n    return splu(K).solve(b)\n",
    "det": "import numpy as np\n\ndef _stable(K):\n    return np.linalg.det(K) > 0\n",
    "slogdet": "import numpy\n\ndef _stable(K):\n    return numpy.linalg.slogdet(K)[0] > 0\n",
    "cond": "from numpy.linalg import cond\n\ndef _ill(K):\n    return cond(K) > 1e12\n",
    "norm(., 2)": "import numpy as np\n\ndef _big(K):\n    return np.linalg.norm(K, 2)\n",
    "norm(ord=2)": "import scipy.linalg as la\n\ndef _big(K):\n    return la.norm(K, ord=2)\n",
    "norm(ord=-2)": "import numpy as np\n\ndef _small(K):\n    return np.linalg.norm(K, ord=-2)\n",
    "nuclear norm": "import numpy as np\n\ndef _nuc(K):\n    return np.linalg.norm(K, 'nuc')\n",
    "LAPACK module": "import scipy.linalg.lapack\n\ndef _chol(K):\n    return scipy.linalg.lapack.dpotrf(K)\n",
    "LAPACK from-import": "from scipy.linalg import lapack\n\ndef _chol(K):\n    return lapack.dpotrf(K)[1] == 0\n",
    "get_lapack_funcs": "from scipy.linalg import get_lapack_funcs\n\ndef _chol(K):\n"
                        "    potrf, = get_lapack_funcs(('potrf',), (K,))\n    return potrf(K)\n",
    "getattr(np.linalg, ...)": "import numpy as np\n\ndef _any(K, name='cholesky'):\n"
                               "    return getattr(np.linalg, name)(K)\n",
    "a namespace bound to a name": "from numpy import linalg\n\ndef _any(K):\n    la = linalg\n    return la\n",
    "cvxopt.cholmod": "from cvxopt import cholmod\n\ndef _factor(M):\n    return cholmod.symbolic(M)\n",
    "import cvxopt.cholmod": "import cvxopt.cholmod\n\ndef _factor(M):\n    return cvxopt.cholmod.symbolic(M)\n",
    "an iterative solver": "import scipy.sparse.linalg as spla\n\ndef _solve(K, b):\n    return spla.cg(K, b)[0]\n",
}


@pytest.mark.parametrize("kind", sorted(PLANTED))
def test_a_planted_decomposition_is_found(tree_copy, kind):
    _append(tree_copy / "sensitivity.py", PLANTED[kind])
    new = set(unexplained(decompositions(tree_copy))) - set(unexplained(decompositions()))
    assert len(new) == 1 and new.pop().startswith("tenscell.sensitivity:"), new


def test_what_decomposes_nothing_is_not_flagged(tree_copy):
    """Vector and Frobenius norms, the error class, products and block matrices are allowed anywhere."""
    _append(tree_copy / "sensitivity.py",
            "import numpy as np\nimport scipy.linalg\n\ndef _fine(v, K):\n"
            "    try:\n        return np.linalg.norm(v) + np.linalg.norm(K, 'fro') + np.linalg.norm(v, np.inf)"
            " + np.linalg.norm(v, axis=0).sum()\n"
            "    except np.linalg.LinAlgError:\n        return scipy.linalg.block_diag(K, K)\n")
    assert set(unexplained(decompositions(tree_copy))) == set(unexplained(decompositions()))


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


#: home-made criteria the eigenvalue check must catch: (what, source appended to sensitivity.py)
PLANTED_CRITERIA = {
    "linear's own eigensolver and a relative floor": (
        "from .linear.definite import symmetric_eigen\n\ndef _stable(K):\n    lam, _ = symmetric_eigen(K)\n"
        "    return lam[0] > 1e-12 * abs(lam[-1])\n"),
    "numpy's eigvalsh through a name": (
        "import numpy as np\n\ndef _stable(K):\n    ev = np.linalg.eigvalsh(K)\n    low = ev.min()\n"
        "    if low <= 1e-9:\n        return False\n    return True\n"),
    "a loop over eigenvalues": (
        "import scipy.linalg\n\ndef _stable(K):\n    return all(x > 0 for x in scipy.linalg.eigh(K)[0])\n"),
}


@pytest.mark.parametrize("kind", sorted(PLANTED_CRITERIA))
def test_a_planted_criterion_is_found(tree_copy, kind):
    _append(tree_copy / "sensitivity.py", PLANTED_CRITERIA[kind])
    new = set(unexplained_criteria(eigen_thresholds(tree_copy))) - set(unexplained_criteria(eigen_thresholds()))
    assert len(new) == 1 and new.pop().startswith("tenscell.sensitivity:"), new


def test_eigenvalues_that_are_not_compared_are_not_flagged(tree_copy):
    """Eigenvalues used as numbers (a spectrum, a sum) are no criterion."""
    _append(tree_copy / "sensitivity.py", "from .linear.definite import symmetric_eigen\n\ndef _spectrum(K):\n"
                                          "    lam, U = symmetric_eigen(K)\n    return lam.sum(), U\n")
    assert eigen_thresholds(tree_copy) == eigen_thresholds()


PLANTED_IMPORTS = {
    "a private function of another subpackage": "def _f():\n    from .fitting.search import _least_squares\n"
                                                "    return _least_squares\n",
    "a private module of another subpackage": "def _f():\n    from .population import _engine\n    return _engine\n",
    "a star import": "from .fitting.search import *  # noqa: F403\n",
}


@pytest.mark.parametrize("kind", sorted(PLANTED_IMPORTS))
def test_a_planted_private_import_is_found(tree_copy, kind):
    _append(tree_copy / "sensitivity.py", PLANTED_IMPORTS[kind])
    new = set(private_imports(tree_copy)) - set(private_imports())
    assert len(new) == 1 and new.pop().startswith("tenscell.sensitivity (line"), new


def test_a_private_import_within_a_subpackage_is_allowed(tree_copy):
    _append(tree_copy / "fitting" / "shares.py", "def _f():\n    from .search import _least_squares\n"
                                                 "    return _least_squares\n")
    assert private_imports(tree_copy) == private_imports()


@pytest.mark.parametrize("code", [
    "import importlib\n\ndef _f():\n    return importlib.import_module('tenscell.fitting')\n",
    "from importlib import import_module\n\ndef _f(name):\n    return import_module(f'.{name}', 'tenscell')\n",
    "def _f():\n    return __import__('tenscell.fitting.search')\n",
])
def test_a_planted_dynamic_import_is_found(tree_copy, code):
    _append(tree_copy / "sensitivity.py", code)
    new = set(unexplained_dynamic(dynamic_imports(tree_copy))) - set(unexplained_dynamic(dynamic_imports()))
    assert len(new) == 1 and new.pop().startswith("tenscell.sensitivity:"), new
