"""Structure files: a documented JSON format for any tensegrity.

A structure file holds everything :class:`~tenscell.model.structure.Structure`
needs (nodes, rigid struts anchored or free, tendons with their family, fixed
nodes, load, probe, equal-tension groups) plus optional per-tendon material
properties (EA, c) and an optional self-stress ``T0``. The format is
described in ``docs/structure-format.md``; in short::

    {
      "format": "tenscell-structure", "version": 1,
      "name": "two-strut example",
      "units": {"length": "um", "force": "pN", "time": "s"},
      "nodes": [{"name": "A", "xyz": [0, 0, 0]}, [1, 0, 0], ...],
      "fixed": ["A"],
      "supports": [{"node": 4, "axes": "z"}],
      "struts": [["A", "C"], [2, 3]],
      "tendons": [{"nodes": ["C", 3], "family": "actin", "EA": 1.0, "c": 1.0}, ...],
      "load":  {"nodes": [2, 3], "weights": [0.5, 0.5], "direction": [0, 0, 1]},
      "probe": {"nodes": [2, 3], "weights": [0.5, 0.5], "direction": [0, 0, 1]}
    }

Nodes may be referred to by index (from 0) or by name. Values are converted
to SI on reading (m, N, s); :func:`save_structure` always writes SI.

Every error is a :class:`~tenscell.model.structure.StructureError` (a ValueError)
whose message starts with the file name and names the offending element,
e.g. ``"cell.json: tendon 17 joins node 4 to itself"``; an entry of the
``supports`` list is also named by its line, e.g.
``"cell.json, line 12: supports entry 1: node 4 is listed twice"``.
"""
from __future__ import annotations

import json
import re
import sys
import math
from dataclasses import dataclass
from json.scanner import make_scanner
from typing import Any
from pathlib import Path

import numpy as np

from .._ranges import RANGES, range_problem
from .outputs import write_text
from ..model.structure import Point, Structure, StructureError, check_support, member_values

__all__ = [
    "StructureFile",
    "load_structure",
    "load_structure_file",
    "save_structure",
    "structure_to_dict",
    "structure_from_dict",
    "member_values",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "LENGTH_UNITS",
    "FORCE_UNITS",
    "TIME_UNITS",
]

FORMAT_NAME = "tenscell-structure"
FORMAT_VERSION = 1

#: accepted length units and their value in metres
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "nm": 1e-9}
#: accepted force units and their value in newtons
FORCE_UNITS = {"N": 1.0, "mN": 1e-3, "uN": 1e-6, "µN": 1e-6, "nN": 1e-9, "pN": 1e-12}
#: accepted time units and their value in seconds
TIME_UNITS = {"s": 1.0, "ms": 1e-3}

_TOP_KEYS = {
    "format", "version", "name", "description", "units", "nodes", "fixed", "supports", "struts", "tendons",
    "equal_tension_groups", "load", "probe",
}
_NODE_KEYS = {"name", "xyz"}
_TENDON_KEYS = {"nodes", "family", "EA", "c", "T0"}
_POINT_KEYS = {"nodes", "weights", "direction"}
_SUPPORT_KEYS = {"node", "axes"}


class _EntryError(StructureError):
    """A StructureError about item ``index`` of the top-level list ``key``: the file reader adds its line."""

    def __init__(self, message: str, key: str, index: int):
        super().__init__(message)
        self.key, self.index = key, index


@dataclass(frozen=True, eq=False, repr=False)
class StructureFile:
    """The content of a structure file.

    Attributes
    ----------
    structure : Structure
        Node positions in m.
    EA : ndarray, shape (m,)
        Tendon stiffness (N); 1 N where the file gives none.
    c : ndarray, shape (m,)
        Tendon damping (N·s/m); 1 N·s/m where the file gives none.
    T0 : ndarray, shape (m,) or None
        A self-stress (dimensionless, any scale) if the file gives one for
        every tendon; pass it to :func:`tenscell.model.equilibrate` (``T0=``) to
        skip the search for one (useful for very large structures).
    description : str
        Free text from the file.
    """

    structure: Structure
    EA: np.ndarray
    c: np.ndarray
    T0: np.ndarray | None = None
    description: str = ""

    # ---- notebook conventions (tenscell._results) ---------------------------------
    def __repr__(self) -> str:
        from .._results import format_repr, span

        about = self.description.strip().splitlines()[0][:70] if self.description.strip() else "no description"
        return format_repr(
            f"StructureFile {self.structure.name!r}: {about}",
            *(line.strip() for line in repr(self.structure).splitlines()[1:]),
            f"EA {span(self.EA, 'N')}; c {span(self.c, 'N·s/m')}; "
            f"self-stress {'given' if self.T0 is not None else 'not given'}",
        )

    def to_dataframe(self):
        """One row per tendon: the structure's columns and ``EA_N, c_Ns_per_m`` (and ``T0`` when given)."""
        extra = {} if self.T0 is None else {"T0": self.T0}
        return self.structure.to_dataframe("tendons", EA_N=self.EA, c_Ns_per_m=self.c, **extra)

    def plot(self, ax=None, **kw):
        """The structure in 3D (:func:`tenscell.plotting.structure_3d`)."""
        return self.structure.plot(ax=ax, **kw)


# ---- reading ------------------------------------------------------------------------
#: largest structure file read (bytes); a 10^6-member lattice is about 100 MB
MAX_FILE_BYTES = 1 << 30

def load_structure(path) -> Structure:
    """Read a structure file (JSON) and return its :class:`Structure` (SI units).

    Raises
    ------
    StructureError
        For a malformed file; the message names the file and the element.
    OSError
        If the file cannot be read.
    """
    return load_structure_file(path).structure


def load_structure_file(path) -> StructureFile:
    """Read a structure file with its tendon properties and optional self-stress.

    Parameters
    ----------
    path : str or Path
        A JSON file in the format of ``docs/structure-format.md``.

    Returns
    -------
    StructureFile
    """
    path = Path(path)
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise StructureError(f"{path.name}: {size / 2**20:.0f} MiB; structure files up to "
                             f"{MAX_FILE_BYTES / 2**20:.0f} MiB are read (about 10^6 members)")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as err:
        raise StructureError(f"{path.name}: not a UTF-8 text file (byte {err.start}); "
                             "a structure file is JSON (docs/structure-format.md)") from None
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as err:
        raise StructureError(f"{path.name}: not valid JSON (line {err.lineno}, column {err.colno}: {err.msg})") from None
    except RecursionError:
        raise StructureError(f"{path.name}: JSON nested too deeply to be a structure file") from None
    except ValueError:  # the only other ValueError json raises: an integer with too many digits to convert
        raise StructureError(f"{path.name}: holds an integer with more than {sys.get_int_max_str_digits()} "
                             "digits; not a structure file") from None
    try:
        return structure_from_dict(obj, default_name=path.stem)
    except _EntryError as err:
        line = _item_line(text, err.key, err.index)
        raise StructureError(f"{path.name}{'' if line is None else f', line {line}'}: {err}") from None
    except StructureError as err:
        raise StructureError(f"{path.name}: {err}") from None
    except (ValueError, TypeError, OverflowError, RecursionError) as err:
        # a value the checks above let through but that cannot be a number (an over-long integer
        # cannot even be shown); one line naming the file, never a traceback
        raise StructureError(f"{path.name}: not a valid structure file ({type(err).__name__}: "
                             f"{str(err)[:200]})") from None


def structure_from_dict(obj, default_name: str = "structure") -> StructureFile:
    """Build a :class:`StructureFile` from the parsed JSON object (see module docstring).

    Raises
    ------
    StructureError
        Naming the offending element.
    """
    _check_header(obj)
    lu, fu, tu = _units(obj.get("units", {}))
    nodes, names = _read_nodes(obj, lu)
    index = _name_index(names)
    ref = _node_ref(len(names), index)
    fixed = [ref(r, "the fixed list") for r in _list(obj.get("fixed", []), "'fixed'")]
    struts = _read_struts(obj, ref)
    supports = _read_supports(obj, ref, len(names), fixed, struts)
    tendons, families, EA, c, T0 = _read_tendons(obj, ref, lu, fu, tu)
    groups = _read_groups(obj)
    if "load" not in obj:
        raise StructureError("missing 'load': say where the input force acts "
                             "({\"nodes\": [...], \"weights\": [...], \"direction\": [x, y, z]})")
    load = _point(obj["load"], "load", ref)
    probe = _point(obj["probe"], "probe", ref) if "probe" in obj else load
    name = _text(obj, "name", default_name)
    description = _text(obj, "description", "")
    node_names = tuple(nm if nm is not None else str(i) for i, nm in enumerate(names)) if index else ()
    structure = Structure(
        nodes=nodes, struts=tuple(struts), tendons=tuple(tendons), families=tuple(families), fixed=tuple(fixed),
        supports=tuple(supports), load=load, probe=probe, equal_tension_groups=tuple(groups), name=name, node_names=node_names,
    )
    return StructureFile(structure=structure, EA=np.array(EA), c=np.array(c), T0=T0, description=description)


def _check_header(obj) -> None:
    """StructureError unless ``obj`` is an object of known keys naming this format and version."""
    if not isinstance(obj, dict):
        raise StructureError("the top level must be a JSON object")
    _unknown(obj, _TOP_KEYS, "the top level")
    fmt = obj.get("format", FORMAT_NAME)
    if fmt != FORMAT_NAME:
        raise StructureError(f"'format' must be {FORMAT_NAME!r}, got {fmt!r}")
    version = obj.get("version", FORMAT_VERSION)
    if version != FORMAT_VERSION:
        raise StructureError(f"'version' {version!r} is not supported (this tenscell reads version {FORMAT_VERSION})")


def _read_nodes(obj: dict, lu: float) -> tuple[np.ndarray, list]:
    """The node positions (m, shape (n, 3)) and names (None where unnamed); ``lu`` is the file's length unit (m)."""
    if "nodes" not in obj:
        raise StructureError("missing 'nodes'")
    raw_nodes = obj["nodes"]
    if not isinstance(raw_nodes, list) or not raw_nodes:
        raise StructureError("'nodes' must be a non-empty list")
    xyz, names = [], []
    for i, nd in enumerate(raw_nodes):
        if isinstance(nd, dict):
            _unknown(nd, _NODE_KEYS, f"node {i}")
            if "xyz" not in nd:
                raise StructureError(f"node {i} has no 'xyz'")
            name = nd.get("name")
            if name is not None and not isinstance(name, str):
                raise StructureError(f"node {i}: 'name' must be a string, got {name!r}")
            names.append(name)
            pos = nd["xyz"]
        else:
            names.append(None)
            pos = nd
        xyz.append(_vector(pos, 3, f"node {i}{'' if names[-1] is None else ' ' + repr(names[-1])} position"))
    nodes = np.array(xyz) * lu
    _check_coordinates(nodes, names, lu)
    return nodes, names


def _name_index(names: list) -> dict[str, int]:
    """Node index by name (named nodes only); StructureError for a name given twice."""
    index: dict[str, int] = {}
    for i, nm in enumerate(names):
        if nm is None:
            continue
        if nm in index:
            raise StructureError(f"node {i} repeats the name {nm!r} of node {index[nm]}")
        index[nm] = i
    return index


def _node_ref(n: int, index: dict[str, int]):
    """``ref(r, what)``: the node index a file's reference ``r`` (an index or a name) means, among ``n`` nodes."""
    def ref(r, what):
        if isinstance(r, bool):
            raise StructureError(f"{what} refers to node {r!r}; use an index or a node name")
        if isinstance(r, int):
            if not 0 <= r < n:
                raise StructureError(f"{what} refers to unknown node {r} (there are {n} nodes, 0 to {n - 1})")
            return r
        if isinstance(r, str):
            if r not in index:
                raise StructureError(f"{what} refers to unknown node {r!r}")
            return index[r]
        raise StructureError(f"{what} refers to node {r!r}; use an index or a node name")

    return ref


def _read_struts(obj: dict, ref) -> list[tuple[int, int]]:
    """The struts as pairs of node indices (each given as a pair or as ``{"nodes": pair}``)."""
    struts = []
    for k, s in enumerate(_list(obj.get("struts", []), "'struts'")):
        pair = s.get("nodes") if isinstance(s, dict) else s
        if isinstance(s, dict):
            _unknown(s, {"nodes"}, f"strut {k}")
        if not isinstance(pair, list) or len(pair) != 2:
            raise StructureError(f"strut {k} must join exactly two nodes, got {pair!r}")
        struts.append((ref(pair[0], f"strut {k}"), ref(pair[1], f"strut {k}")))
    return struts


def _read_supports(obj: dict, ref, n: int, fixed: list, struts: list) -> list[tuple[int, str]]:
    """The per-direction supports as ``(node, axes)`` pairs, each entry ``{"node": r, "axes": "z"}`` or
    ``[r, "z"]``, checked by the rules of :class:`Structure` (:func:`~tenscell.model.structure.check_support`).

    An error is an :class:`_EntryError` naming the entry, so that the file reader can give its line.
    """
    on_strut = {i for pair in struts for i in pair}
    seen: dict[int, int] = {}
    out = []
    for k, item in enumerate(_list(obj.get("supports", []), "'supports'")):
        where = f"supports entry {k}"
        try:
            if isinstance(item, dict):
                _unknown(item, _SUPPORT_KEYS, where)
                raw = (item.get("node"), item.get("axes"))
            elif isinstance(item, list) and len(item) == 2:
                raw = (item[0], item[1])
            else:
                raise StructureError(f"{where} must be {{\"node\": ..., \"axes\": \"z\"}} or [node, \"z\"], "
                                     f"got {item!r}")
            if not isinstance(raw[1], str):
                raise StructureError(f"{where}: 'axes' must be a string of the held directions such as \"z\" "
                                     f"or \"xy\", got {raw[1]!r}")
            try:
                node, axes = check_support((ref(raw[0], where), raw[1]), n, set(fixed), on_strut)
            except StructureError as err:
                raise StructureError(f"{where}: {str(err).removeprefix('supports: ')}") from None
            if node in seen:
                raise StructureError(f"{where}: node {node} is listed twice (also in entry {seen[node]})")
        except StructureError as err:
            raise _EntryError(str(err), "supports", k) from None
        seen[node] = k
        out.append((node, axes))
    return out


def _item_line(text: str, key: str, index: int) -> int | None:
    """The line (from 1) where item ``index`` of the top-level list ``key`` starts in a JSON text, or None.

    Walks the top-level object with the standard library's own JSON scanner (the text has already been parsed,
    so it is valid JSON); the last occurrence of a repeated key counts, as for :func:`json.loads`.
    """
    scan = make_scanner(json.JSONDecoder())  # type: ignore[arg-type]  # typeshed types the context oddly
    found = None
    i = _skip(text, 0) + 1  # past the '{'
    try:
        while True:
            name, i = scan(text, _skip(text, i))
            i = _skip(text, _skip(text, i) + 1)  # past the ':'
            if name == key and text[i] == "[":
                found = _list_item_start(text, i, index, scan)
            _, i = scan(text, i)
            i = _skip(text, i)
            if text[i] != ",":
                break
            i += 1
    except (StopIteration, IndexError, ValueError):
        pass
    return None if found is None else text.count("\n", 0, found) + 1


def _list_item_start(text: str, i: int, index: int, scan) -> int | None:
    """Offset of item ``index`` of the JSON list that opens at offset ``i`` (None if it is shorter)."""
    i += 1
    for k in range(index + 1):
        i = _skip(text, i)
        if text[i] == "]":
            return None
        if k == index:
            return i
        _, i = scan(text, i)
        i = _skip(text, i) + 1  # past the ','
    return None


_WHITESPACE = re.compile(r"[ \t\n\r]*")


def _skip(text: str, i: int) -> int:
    """The offset of the first non-whitespace character (JSON's whitespace) at or after ``i``."""
    m = _WHITESPACE.match(text, i)
    return i if m is None else m.end()


def _read_tendons(obj: dict, ref, lu: float, fu: float, tu: float):
    """(pairs, families, EA (N), c (N·s/m), T0 or None) of the tendons; ``lu, fu, tu``: the file's units (m, N, s)."""
    tendons, families, EA, c, T0 = [], [], [], [], []
    raw_t = _list(obj.get("tendons", []), "'tendons'")
    for j, t in enumerate(raw_t):
        if not isinstance(t, dict):
            raise StructureError(f"tendon {j} must be an object with 'nodes' and 'family'")
        _unknown(t, _TENDON_KEYS, f"tendon {j}")
        pair = t.get("nodes")
        if not isinstance(pair, list) or len(pair) != 2:
            raise StructureError(f"tendon {j} must join exactly two nodes, got {pair!r}")
        tendons.append((ref(pair[0], f"tendon {j}"), ref(pair[1], f"tendon {j}")))
        fam = t.get("family")
        if not isinstance(fam, str) or not fam:
            raise StructureError(f"tendon {j} needs a 'family' (e.g. \"actin\", \"intermediate_filament\", \"strut\")")
        families.append(fam)
        EA.append(_in_range(_positive(t.get("EA", 1.0 / fu), f"tendon {j}: EA") * fu, "EA", f"tendon {j}: EA"))
        c.append(_in_range(_positive(t.get("c", 1.0 / (fu * tu / lu)), f"tendon {j}: c") * fu * tu / lu, "c",
                           f"tendon {j}: c"))
        T0.append(t.get("T0"))
    return tendons, families, EA, c, _self_stress(T0, families)


def _self_stress(T0: list, families: list) -> np.ndarray | None:
    """The tendons' self-stress (dimensionless) if every tendon gives one, None if none does."""
    have_T0 = [v is not None for v in T0]
    if any(have_T0) and not all(have_T0):
        missing = have_T0.index(False)
        raise StructureError(f"tendon {missing} has no 'T0' although other tendons do; give all or none")
    if not T0 or not all(have_T0):
        return None
    # any scale, but inside the library's window: the norm of a T0 of 1e300 overflows (and reads as zero)
    T0a = np.array([_finite(v, f"tendon {j}: T0") for j, v in enumerate(T0)])
    for k, v in enumerate(T0a.tolist()):
        if v:
            _in_window(abs(v), f"tendon {k}: |T0|")
    _check_tensions(T0a, families)
    return T0a


def _read_groups(obj: dict) -> list[tuple]:
    """The equal-tension groups, each a tuple of tendon indices."""
    groups = []
    for g, grp in enumerate(_list(obj.get("equal_tension_groups", []), "'equal_tension_groups'")):
        if not isinstance(grp, list) or not all(isinstance(v, int) and not isinstance(v, bool) for v in grp):
            raise StructureError(f"equal-tension group {g} must be a list of tendon indices")
        groups.append(tuple(grp))
    return groups


def _text(obj: dict, key: str, default: str) -> str:
    """The string under ``key`` (``default`` when absent); StructureError for any other type."""
    value = obj.get(key, default)
    if not isinstance(value, str):
        raise StructureError(f"'{key}' must be a string, got {value!r}")
    return value


#: largest distance of a node from the origin (m): the --L flag's upper bound (tenscell._ranges). Beyond it,
#: squared lengths and the stiffness terms of the strut rotations (EA·L²) leave float64's comfortable range
MAX_COORDINATE_M = RANGES["L"][1]


def _check_coordinates(nodes: np.ndarray, names: list, lu: float) -> None:
    """StructureError naming the first node farther than :data:`MAX_COORDINATE_M` from the origin (in the file's unit)."""
    far = np.abs(nodes).max(axis=1) > MAX_COORDINATE_M
    if far.any():
        i = int(np.flatnonzero(far)[0])
        label = f"node {i}" + ("" if names[i] is None else f" {names[i]!r}")
        raise StructureError(f"{label} position {(nodes[i] / lu).tolist()}: a coordinate beyond "
                             f"{MAX_COORDINATE_M / lu:g} (the file's length unit; {MAX_COORDINATE_M:g} m)")


def _in_range(v: float, quantity: str, what: str) -> float:
    """``v`` (SI) inside the range of ``quantity`` shared with the flags and the data files (tenscell._ranges)."""
    problem = range_problem(quantity, v)
    if problem is not None:
        raise StructureError(f"{what}: {problem}")
    return v


def _in_window(v: float, what: str) -> float:
    """``v`` (dimensionless, > 0) inside the library's window of values (:data:`tenscell._checks.MAGNITUDE`)."""
    from .._checks import positive_scalar

    try:
        return positive_scalar(what, v)
    except ValueError as err:
        raise StructureError(str(err)) from None


def _check_tensions(T0: np.ndarray, families: list) -> None:
    """A self-stress puts every cable in tension (T0 > 0); only compressible families (struts, nucleus) may push."""
    from ..model.structure import cable_mask

    cable = cable_mask(families)
    bad = [j for j in np.flatnonzero(cable).tolist() if T0[j] <= 0]
    if not bad:
        return
    j = bad[0]
    n_cables = int(cable.sum())
    hint = (" (every tendon's T0 is <= 0: if the file counts tension as negative, flip the signs)"
            if len(bad) == n_cables else "")
    raise StructureError(f"tendon {j}: T0 = {float(T0[j])!r}, but tendons carry tension only (T0 > 0; "
                         f"{len(bad)} of {n_cables} tendons have T0 <= 0){hint}; omit T0 to let tenscell "
                         "find a self-stress")


def _unknown(d: dict, allowed: set, where: str) -> None:
    extra = sorted(set(d) - allowed)
    if extra:
        raise StructureError(f"{where} has unknown key {extra[0]!r}; allowed keys: {', '.join(sorted(allowed))}")


def _list(v, what):
    if not isinstance(v, list):
        raise StructureError(f"{what} must be a list, got {type(v).__name__}")
    return v


def _finite(v, what) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise StructureError(f"{what} must be a finite number, got {v!r}")
    return float(v)


def _positive(v, what) -> float:
    x = _finite(v, what)
    if x <= 0:
        raise StructureError(f"{what} must be > 0, got {v!r}")
    return x


def _vector(v, n, what) -> list[float]:
    if not isinstance(v, list) or len(v) != n:
        raise StructureError(f"{what} must be a list of {n} numbers, got {v!r}")
    return [_finite(x, what) for x in v]


def _units(u):
    if not isinstance(u, dict):
        raise StructureError("'units' must be an object like {\"length\": \"m\", \"force\": \"N\", \"time\": \"s\"}")
    _unknown(u, {"length", "force", "time"}, "'units'")
    out = []
    for key, table, default in (("length", LENGTH_UNITS, "m"), ("force", FORCE_UNITS, "N"), ("time", TIME_UNITS, "s")):
        name = u.get(key, default)
        if name not in table:
            raise StructureError(f"unknown {key} unit {name!r}; allowed: {', '.join(table)}")
        out.append(table[name])
    return out


def _point(p, what, ref) -> Point:
    if not isinstance(p, dict):
        raise StructureError(f"'{what}' must be an object with 'nodes', 'weights' and 'direction'")
    _unknown(p, _POINT_KEYS, f"the {what}")
    nodes = [ref(r, f"the {what}") for r in _list(p.get("nodes", []), f"the {what}'s 'nodes'")]
    if not nodes:
        raise StructureError(f"the {what} needs at least one node")
    weights = p.get("weights", [1.0 / len(nodes)] * len(nodes))
    weights = _vector(weights, len(nodes), f"the {what}'s weights (one per node)")
    direction = _vector(p.get("direction", [0.0, 0.0, 1.0]), 3, f"the {what}'s direction")
    norm = math.sqrt(sum(d * d for d in direction))
    if norm == 0:
        raise StructureError(f"the {what}'s direction must not be the zero vector")
    try:
        unit = (direction[0] / norm, direction[1] / norm, direction[2] / norm)
        return Point(nodes=tuple(nodes), weights=tuple(weights), direction=unit)
    except StructureError as err:
        raise StructureError(f"the {what}: {err}") from None


# ---- writing ------------------------------------------------------------------------
def structure_to_dict(structure: Structure, EA=None, c=None, T0=None, description: str = "") -> dict:
    """The JSON object of :func:`save_structure` (SI units).

    Parameters
    ----------
    structure : Structure
    EA, c : float or array_like, shape (m,), optional
        Tendon stiffness (N) and damping (N·s/m) to record.
    T0 : array_like, shape (m,), optional
        A self-stress to record (dimensionless).
    description : str
    """
    s = structure
    m = s.n_tendons
    EA = None if EA is None else np.broadcast_to(np.asarray(EA, dtype=float), (m,))
    c = None if c is None else np.broadcast_to(np.asarray(c, dtype=float), (m,))
    T0 = None if T0 is None else np.asarray(T0, dtype=float).reshape(m)
    named = bool(s.node_names)
    label = (lambda i: s.node_names[i]) if named else (lambda i: int(i))
    nodes = []
    for i, x in enumerate(s.nodes):
        d: dict[str, Any] = {"xyz": [float(v) for v in x]}
        if named:
            d = {"name": s.node_names[i], **d}
        nodes.append(d)
    tendons = []
    for j, (a, b) in enumerate(s.tendons):
        d = {"nodes": [label(a), label(b)], "family": s.families[j]}
        if EA is not None:
            d["EA"] = float(EA[j])
        if c is not None:
            d["c"] = float(c[j])
        if T0 is not None:
            d["T0"] = float(T0[j])
        tendons.append(d)

    def point(p):
        return {"nodes": [label(i) for i in p.nodes], "weights": list(p.weights), "direction": list(p.direction)}

    out = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "name": s.name,
        "units": {"length": "m", "force": "N", "time": "s"},
        "nodes": nodes,
        "fixed": [label(i) for i in s.fixed],
        **({"supports": [[label(i), axes] for i, axes in s.supports]} if s.supports else {}),
        "struts": [[label(a), label(b)] for a, b in s.struts],
        "tendons": tendons,
        "load": point(s.load),
        "probe": point(s.probe),
    }
    if description:
        out["description"] = description
    if s.equal_tension_groups:
        out["equal_tension_groups"] = [list(g) for g in s.equal_tension_groups]
    return out


def save_structure(path, structure: Structure, EA=None, c=None, T0=None, description: str = "") -> None:
    """Write a structure file (JSON, SI units) atomically; one node or tendon per line.

    Floats are written with ``repr`` precision, so reading the file back gives
    bit-identical node positions.
    """
    obj = structure_to_dict(structure, EA=EA, c=c, T0=T0, description=description)
    write_text(path, _dumps(obj))


def _dumps(obj: dict) -> str:
    """Readable JSON: scalars inline, list items one per line (large files stay diffable)."""
    lines = ["{"]
    keys = list(obj)
    for k, key in enumerate(keys):
        v = obj[key]
        comma = "," if k < len(keys) - 1 else ""
        if isinstance(v, list) and v and isinstance(v[0], (dict, list)):
            lines.append(f"  {json.dumps(key)}: [")
            for i, item in enumerate(v):
                lines.append("    " + json.dumps(item, allow_nan=False) + ("," if i < len(v) - 1 else ""))
            lines.append("  ]" + comma)
        else:
            lines.append(f"  {json.dumps(key)}: {json.dumps(v, allow_nan=False)}{comma}")
    lines.append("}")
    return "\n".join(lines) + "\n"
