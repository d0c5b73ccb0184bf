"""The array-based structure validation and lattice construction against plain loops written here.

``Structure`` validates its members with numpy and ``lattice_structure`` numbers its nodes with
``np.unique``; both must give exactly what a member-by-member loop gives: the same error message
naming the same first offending member or node, and the same node numbering, members, fixed
nodes and load.
"""
from __future__ import annotations

import itertools
import re

import numpy as np
import pytest

import tenscell
from tenscell.model.lattices import DEFAULT_OFFSET, _module, lattice_module_tensions
from tenscell.model.structure import ACTIN, INTERMEDIATE_FILAMENT, STRUT, Point, Structure, StructureError


# ---- the validation -----------------------------------------------------------------------------------
def reference_error(nodes, struts, tendons, families, fixed) -> str | None:
    """The first error a member-by-member loop finds (the rules as stated in Structure's docstring)."""
    n = len(nodes)
    fixed = sorted(set(fixed))
    for i in fixed:
        if _unknown(i, "fixed list", n):
            return _unknown(i, "fixed list", n)
    found = _strut_error(nodes, struts, fixed)
    if found:
        return found
    if len(families) != len(tendons):
        return f"{len(families)} families for {len(tendons)} tendons"
    seen: dict = {}
    for j, (a, b) in enumerate(tendons):
        if _member(nodes, f"tendon {j}", a, b):
            return _member(nodes, f"tendon {j}", a, b)
        key = frozenset((a, b))
        if key in seen:
            return f"tendon {j} duplicates tendon {seen[key]} (nodes {a}-{b})"
        seen[key] = j  # a tendon between two fixed nodes is left out with a note, not refused
    return None


def _unknown(i, what, n) -> str | None:
    return None if 0 <= i < n else f"{what} refers to unknown node {i} (there are {n} nodes)"


def _member(nodes, what, a, b) -> str | None:
    for i in (a, b):
        if _unknown(i, what, len(nodes)):
            return _unknown(i, what, len(nodes))
    if a == b:
        return f"{what} joins node {a} to itself"
    if np.linalg.norm(nodes[a] - nodes[b]) <= 0:
        return f"{what} has zero length"
    return None


def _strut_error(nodes, struts, fixed) -> str | None:
    owner: dict = {}
    for k, (a, b) in enumerate(struts):
        if _member(nodes, f"strut {k}", a, b):
            return _member(nodes, f"strut {k}", a, b)
        if b in fixed and a not in fixed:  # a strut between two fixed nodes is left out with a note
            return f"strut {k}: its head node {b} is fixed; put the anchored (fixed) node first"
        for end in (a, b):
            if end in owner and end not in fixed:
                return f"node {end} belongs to struts {owner[end]} and {k}"
            owner[end] = k
    return None


def _error(nodes, struts, tendons, families, fixed, load) -> str | None:
    try:
        Structure(nodes=nodes, struts=struts, tendons=tendons, families=families, fixed=fixed, load=load, probe=load)
    except StructureError as err:
        return str(err)
    return None


def _break(rng, nodes, struts, tendons, fixed):
    """One random defect of the kinds the validation names (may also be harmless)."""
    n = len(nodes)
    kind = rng.integers(9)
    pool, j = (struts, rng.integers(len(struts))) if kind < 4 and struts else (tendons, rng.integers(len(tendons)))
    a, b = pool[j]
    if kind in (0, 4):  # an unknown node, at either end
        bad = int(rng.choice([-1, n, n + 7]))
        pool[j] = (bad, b) if rng.integers(2) else (a, bad)
    elif kind in (1, 5):  # a self-loop
        pool[j] = (a, a)
    elif kind in (2, 6):  # a node shared with another member (a duplicate tendon; a node on two struts)
        pool[j] = pool[rng.integers(len(pool))][:: int(rng.choice([1, -1]))]
    elif kind in (3, 7):  # zero length: a new node on top of an existing one
        nodes = np.vstack([nodes, nodes[a if 0 <= a < n else 0]])
        pool[j] = (a, n)
    else:  # a member between fixed nodes, or a fixed strut head
        f = sorted(fixed)
        if struts and rng.integers(2):
            k = rng.integers(len(struts))
            struts[k] = (struts[k][0], int(rng.choice(f)))
        else:
            tendons[j] = (f[0], f[-1])
    return nodes


@pytest.mark.parametrize("base", ["paper", "lattice"])
def test_validation_matches_a_member_by_member_loop(base):
    if base == "paper":
        s = tenscell.model.paper_structure(0.0, tenscell.model.DEFAULT_DELTA, 1.0)
    else:
        s = tenscell.model.lattice_structure(2, 2, 1)[0]
    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(300):
        nodes, struts, tendons = np.array(s.nodes), list(s.struts), list(s.tendons)
        for _ in range(rng.integers(1, 4)):
            nodes = _break(rng, nodes, struts, tendons, s.fixed)
        expected = reference_error(nodes, struts, tendons, s.families, s.fixed)
        assert _error(nodes, struts, tendons, s.families, s.fixed, s.load) == expected
        seen.add(re.sub(r"-?\d+", "#", str(expected)))
    assert len(seen) >= (9 if base == "paper" else 5), seen  # the random defects reached most rules


def _paper_parts():
    s = tenscell.model.paper_structure(0.0, tenscell.model.DEFAULT_DELTA, 1.0)
    return s, dict(nodes=s.nodes, struts=list(s.struts), tendons=list(s.tendons), families=s.families,
                   fixed=s.fixed, load=s.load, probe=s.probe)


@pytest.mark.parametrize("edit, message", [
    (lambda p: p["tendons"].__setitem__(5, p["tendons"][2][::-1]), "tendon 5 duplicates tendon 2"),
    (lambda p: p["tendons"].__setitem__(9, (3, 3)), "tendon 9 joins node 3 to itself"),
    (lambda p: p["tendons"].__setitem__(4, (3, 40)), "tendon 4 refers to unknown node 40 (there are 13 nodes)"),
    (lambda p: p["struts"].__setitem__(4, (9, 3)), "node 3 belongs to struts 0 and 4"),
    (lambda p: p["struts"].__setitem__(1, (4, 1)), "strut 1: its head node 1 is fixed"),
    (lambda p: p["struts"].__setitem__(2, (2, 2)), "strut 2 joins node 2 to itself"),
    (lambda p: p["struts"].__setitem__(3, (7, -1)), "strut 3 refers to unknown node -1"),
    (lambda p: p.__setitem__("fixed", (0, 1, 2, 13)), "fixed list refers to unknown node 13"),
    (lambda p: p.__setitem__("nodes", np.vstack([p["nodes"][:12], p["nodes"][8]])), "tendon 29 has zero length"),
])
def test_each_rule_names_the_first_offender(edit, message):
    _, parts = _paper_parts()
    edit(parts)
    with pytest.raises(StructureError) as info:
        Structure(**parts)
    assert message in str(info.value)
    assert str(info.value) == reference_error(parts["nodes"], parts["struts"], parts["tendons"], parts["families"],
                                              parts["fixed"])


def test_member_lists_of_any_integer_form_are_stored_as_python_int_pairs():
    s, parts = _paper_parts()
    for form in (np.asarray(s.tendons, dtype=np.int32), np.asarray(s.tendons, dtype=float), [list(t) for t in s.tendons]):
        t = Structure(**{**parts, "tendons": form}).tendons
        assert t == s.tendons and all(type(i) is int for pair in t for i in pair)
    empty = Structure(**{**parts, "tendons": (), "families": ()})
    assert empty.tendons == () and empty.struts == s.struts


# ---- the lattice --------------------------------------------------------------------------------------
def reference_lattice(nx, ny, nz, L=1.0, offset=DEFAULT_OFFSET, intermediate_filaments=True):
    """The lattice built module by module, numbering a node when it first appears (a dict of rounded positions)."""
    t = lattice_module_tensions(offset, intermediate_filaments)
    Xm, struts, cables = _module(L, offset * L)
    index: dict = {}
    coords: list = []

    def node(p):
        key = tuple(int(round(v * 1e6 / L)) for v in p)
        if key not in index:
            index[key] = len(coords)
            coords.append(p)
        return index[key]

    tendons, families, T0, fixed = [], [], [], []
    for k, j, i in itertools.product(range(nz), range(ny), range(nx)):
        c = np.array([i * L, j * L, k * L])
        ids = [node(c + x) for x in Xm]
        members = [(ids[p], ids[q], ACTIN) for p, q in cables] + [(ids[p], ids[q], STRUT) for p, q in struts]
        if intermediate_filaments:
            cid = node(c)
            members += [(ids[p], cid, INTERMEDIATE_FILAMENT) for p in range(12)]
        for a, b, fam in members:
            tendons.append((a, b))
            families.append(fam)
            T0.append(t[fam])
        if k == 0:
            fixed += [ids[0], ids[1]]
        if (i, j, k) == (nx // 2, ny // 2, nz - 1):
            load = (ids[5], ids[7])
    return np.array(coords), tuple(tendons), tuple(families), tuple(sorted(set(fixed))), load, np.array(T0)


@pytest.mark.parametrize("shape, kw", [
    ((3, 2, 2), {}), ((3, 2, 2), {"intermediate_filaments": False, "offset": 0.25}), ((4, 3, 1), {}),
    ((1, 1, 1), {}), ((2, 3, 2), {"L": 2.5e-6, "offset": 0.15}),
])
def test_lattice_matches_a_module_by_module_construction(shape, kw):
    st, T0 = tenscell.model.lattice_structure(*shape, **kw)
    nodes, tendons, families, fixed, load, T0_ref = reference_lattice(*shape, **kw)
    np.testing.assert_array_equal(st.nodes, nodes)
    assert st.tendons == tendons and st.families == families and st.fixed == fixed and st.struts == ()
    assert st.load == Point(load, (0.5, 0.5), (0.0, 0.0, 1.0)) == st.probe
    np.testing.assert_array_equal(T0, T0_ref)
