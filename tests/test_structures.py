"""Structure files, validation, the node-based formulation, and the free-standing icosahedron cross-check."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.linalg

import tenscell
from tenscell.model.formfinding import pin_jointed, rigid_body_modes
from tenscell.model.lattices import _module
from tenscell.io.structure_files import load_structure, load_structure_file, member_values, save_structure, structure_to_dict
from tenscell.model.structure import Point, Structure, StructureError
from tenscell.summary import relaxation_modes, summarize

FREQS = np.logspace(-2, 3, 25)


# ---- file round trip ------------------------------------------------------------------
def test_paper_cell_round_trip(tmp_path):
    cell = tenscell.paper_cell()
    rng = np.random.default_rng(6)
    EA = rng.uniform(0.5, 2.0, cell.m)
    c = rng.uniform(0.5, 2.0, cell.m)
    path = tmp_path / "paper.json"
    save_structure(path, cell.structure, EA=EA, c=c, T0=cell.T0, description="the paper's cell")
    sf = load_structure_file(path)
    s, t = sf.structure, cell.structure
    assert np.array_equal(s.nodes, t.nodes)  # repr precision: bit-identical
    assert s.struts == t.struts and s.tendons == t.tendons and s.families == t.families
    assert s.fixed == t.fixed and s.load == t.load and s.probe == t.probe
    assert s.equal_tension_groups == t.equal_tension_groups and s.node_names == t.node_names
    assert s.name == t.name and sf.description == "the paper's cell"
    assert np.array_equal(sf.EA, EA) and np.array_equal(sf.c, c) and np.array_equal(sf.T0, cell.T0)
    # the physics of the reloaded structure is the same: self-stress found again, same compliance
    cell2 = tenscell.model.equilibrate(s)
    np.testing.assert_allclose(cell2.T0, cell.T0, rtol=0, atol=1e-14)
    J1 = tenscell.compliance(tenscell.linearize(cell, 1000.0, EA, c), FREQS)
    J2 = tenscell.compliance(tenscell.linearize(cell2, 1000.0, sf.EA, sf.c), FREQS)
    np.testing.assert_allclose(J2, J1, rtol=1e-13)
    # and a second save gives the same text (stable format)
    save_structure(tmp_path / "again.json", s, EA=sf.EA, c=sf.c, T0=sf.T0, description=sf.description)
    assert (tmp_path / "again.json").read_text() == path.read_text()


def test_lattice_round_trip_keeps_self_stress(tmp_path):
    cell = tenscell.model.lattice_cell(2, 2, 1)
    path = tmp_path / "lattice.json"
    save_structure(path, cell.structure, T0=cell.T0)
    sf = load_structure_file(path)
    assert sf.structure.node_names == ()  # unnamed nodes are written as indices
    cell2 = tenscell.model.equilibrate(sf.structure, "local", T0=sf.T0)
    np.testing.assert_array_equal(cell2.T0, cell.T0)
    assert load_structure(path).n_tendons == cell.m


def _small(tmp_path, edit=None, name="cell.json"):
    """A two-strut structure as a JSON object (µm, pN), optionally edited, written to a file."""
    obj = {
        "format": "tenscell-structure", "version": 1, "name": "pair",
        "units": {"length": "um", "force": "pN", "time": "s"},
        "nodes": [{"name": "A", "xyz": [0, 0, 0]}, {"name": "C", "xyz": [0, 0, 2]},
                  [1, 0, 1], [3, 0, 1], {"name": "N", "xyz": [1.5, 0.5, 1]}],
        "fixed": ["A"],
        "struts": [["A", "C"], [2, 3]],
        "tendons": [{"nodes": ["C", 2], "family": "actin", "EA": 2.0, "c": 3.0},
                    {"nodes": ["C", 3], "family": "actin"},
                    {"nodes": [2, "N"], "family": "intermediate_filament"},
                    {"nodes": [3, "N"], "family": "intermediate_filament"},
                    {"nodes": ["A", 2], "family": "actin"}],
        "load": {"nodes": [2, 3], "weights": [0.5, 0.5], "direction": [0, 0, 2]},
    }
    if edit:
        edit(obj)
    path = tmp_path / name
    path.write_text(json.dumps(obj))
    return path


def test_units_and_defaults(tmp_path):
    sf = load_structure_file(_small(tmp_path))
    s = sf.structure
    np.testing.assert_allclose(s.nodes[3], [3e-6, 0, 1e-6])
    np.testing.assert_allclose(sf.EA[:2], [2e-12, 1.0])  # pN -> N; a missing EA is 1 N
    np.testing.assert_allclose(sf.c[:2], [3e-12 / 1e-6, 1.0])  # pN·s/µm -> N·s/m
    assert s.probe == s.load and s.load.direction == (0.0, 0.0, 1.0)  # probe defaults to the load
    assert s.is_anchored(0) and not s.is_anchored(1)
    assert s.node_names == ("A", "C", "2", "3", "N")
    assert sf.T0 is None


def _set(path, value):
    def edit(obj):
        target = obj
        for k in path[:-1]:
            target = target[k]
        if value is _DELETE:
            del target[path[-1]]
        else:
            target[path[-1]] = value
    return edit


_DELETE = object()


@pytest.mark.parametrize(
    "edit, message",
    [
        (_set(["tendons", 1, "nodes"], ["C", 9]), "tendon 1 refers to unknown node 9"),
        (_set(["tendons", 1, "nodes"], ["C", "X"]), "tendon 1 refers to unknown node 'X'"),
        (_set(["tendons", 3, "nodes"], [4, 4]), "tendon 3 joins node 4 to itself"),
        (_set(["tendons", 3, "nodes"], ["N", 2]), "tendon 3 duplicates tendon 2"),
        (_set(["nodes", 3], [1, 0, 1]), "strut 1 has zero length"),
        (_set(["load"], _DELETE), "missing 'load'"),
        (_set(["tendons", 0, "EA"], -1), "tendon 0: EA must be > 0"),
        (_set(["tendons", 0, "stiffness"], 1), "tendon 0 has unknown key 'stiffness'"),
        (_set(["tendns"], []), "unknown key 'tendns'"),
        (_set(["units", "length"], "inch"), "unknown length unit 'inch'"),
        (_set(["nodes", 4], {"name": "A", "xyz": [1, 1, 1]}), "node 4 repeats the name 'A'"),
        (_set(["nodes", 2], [1, 0]), "node 2 position must be a list of 3 numbers"),
        (_set(["tendons", 0, "T0"], 0.5), "tendon 1 has no 'T0'"),
        (_set(["struts", 1], [2, "C"]), "node 1 belongs to struts 0 and 1"),
        (_set(["load", "weights"], [0.5, 0.6]), "weights must sum to 1"),
        (_set(["tendons", 2, "family"], _DELETE), "tendon 2 needs a 'family'"),
    ],
)
def test_validation_errors_name_the_element(tmp_path, edit, message):
    path = _small(tmp_path, edit)
    with pytest.raises(StructureError) as info:
        load_structure(path)
    text = str(info.value)
    assert text.startswith(f"{path.name}: "), text
    assert message in text, text


def test_bad_json_reports_line(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{\n  "nodes": [\n    [0, 0, 0],\n  ]\n}\n')
    with pytest.raises(StructureError, match=r"broken\.json: not valid JSON \(line 4"):
        load_structure(path)


def test_structure_error_for_tendon_to_itself_in_constructor():
    with pytest.raises(StructureError, match="tendon 17 joins node 4 to itself"):
        Structure(nodes=np.random.default_rng(0).standard_normal((8, 3)), struts=(),
                  tendons=[(i, j) for i in range(8) for j in range(i + 1, 8)][:17] + [(4, 4)],
                  families=["actin"] * 18, fixed=(0,), load=Point((1,), (1.0,)), probe=Point((1,), (1.0,)))


def test_member_values():
    s = tenscell.model.lattice_structure(1, 1, 1)[0]
    EA = member_values(s, {"strut": 1e3, "default": 2.0})
    fam = np.array(s.families)
    assert np.all(EA[fam == "strut"] == 1e3) and np.all(EA[fam != "strut"] == 2.0)
    assert member_values(s, 3.0).shape == (s.n_tendons,)
    with pytest.raises(ValueError, match="no value for family 'actin'"):
        member_values(s, {"strut": 1.0})
    with pytest.raises(ValueError, match="EA must be a scalar"):
        member_values(s, [1.0, 2.0], "EA")


def test_structure_to_dict_is_json():
    obj = structure_to_dict(tenscell.model.paper_structure(0.0, math.radians(50), 1.0))
    assert json.loads(json.dumps(obj)) == obj


# ---- node-based formulation ---------------------------------------------------------------
def test_pin_jointed_paper_cell_has_same_tendon_self_stress_and_converges_to_rigid():
    rigid = tenscell.paper_cell()
    pj = tenscell.model.equilibrate(pin_jointed(rigid.structure), "local")
    assert pj.n == 3 * 10  # 10 movable nodes, 3 coordinates each
    np.testing.assert_allclose(pj.T0[:33], rigid.T0, atol=1e-12)  # normalized over the cables in both
    assert np.all(pj.T0[33:] < 0)  # struts in compression
    J_rigid = tenscell.compliance(tenscell.linearize(rigid, 1000.0), FREQS)
    errs = []
    for EA_strut in (1e6, 1e8):
        EA = np.r_[np.ones(33), np.full(6, EA_strut)]
        J = tenscell.compliance(tenscell.linearize(pj, 1000.0, EA, np.r_[np.ones(33), np.full(6, 1e-9)]), FREQS)
        errs.append(np.max(np.abs(J - J_rigid) / np.abs(J_rigid)))
    # axially rigid struts are the limit EA -> oo, approached like 1/EA
    assert errs[1] < 2e-5 and 50 < errs[0] / errs[1] < 200, errs


# ---- cross-check: the free-standing regular icosahedron ------------------------------------
def _icosahedron(L=1.0):
    X, struts, cables = _module(L, L / 4)
    p = Point(nodes=(4, 6), weights=(0.5, 0.5), direction=(0.0, 0.0, 1.0))
    return Structure(nodes=X, struts=tuple(struts), tendons=tuple(cables), families=("actin",) * 24, fixed=(),
                     load=p, probe=p, name="regular 6-strut icosahedron")


def _independent_stiffness(X, members, T, EA, c):
    """Nodal assembly written from scratch: k = (EA/l0) eeᵀ + (T/l)(I − eeᵀ) per member, l0 from T = EA(l/l0 − 1)."""
    n = X.shape[0]
    K = np.zeros((3 * n, 3 * n))
    C = np.zeros((3 * n, 3 * n))
    for j, (a, b) in enumerate(members):
        d = X[b] - X[a]
        l = np.linalg.norm(d)
        e = d / l
        l0 = l / (1.0 + T[j] / EA[j])
        k3 = EA[j] / l0 * np.outer(e, e) + T[j] / l * (np.eye(3) - np.outer(e, e))
        c3 = c[j] * np.outer(e, e)
        for p, sp_ in ((a, 1.0), (b, -1.0)):
            for q, sq in ((a, 1.0), (b, -1.0)):
                K[3 * p:3 * p + 3, 3 * q:3 * q + 3] += sp_ * sq * k3
                C[3 * p:3 * p + 3, 3 * q:3 * q + 3] += sp_ * sq * c3
    return K, C


def _rigid_motions(X):
    n = X.shape[0]
    R = np.zeros((3 * n, 6))
    for i, x in enumerate(X - X.mean(axis=0)):
        R[3 * i:3 * i + 3, :3] = np.eye(3)
        R[3 * i:3 * i + 3, 3:] = -np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]])
    return R


def test_free_icosahedron_matches_independent_nodal_assembly():
    P = 100.0
    st = _icosahedron()
    cell = tenscell.model.equilibrate(pin_jointed(st), "local")
    assert cell.self_stress_dim == 1 and cell.n == 36
    members = list(cell.structure.tendons)
    fam = np.array(cell.structure.families)
    EA = np.where(fam == "strut", 1e4, 1.0)
    c = np.where(fam == "strut", 0.5, 1.0)
    lin = tenscell.linearize(cell, P=P, EA=EA, c=c, check=False)  # singular: 6 rigid-body motions
    # the self-stress of the regular icosahedron: equal cables, struts -sqrt(6) times a cable
    T0_ind = np.where(fam == "strut", -math.sqrt(6.0), 1.0) / math.sqrt(24.0)
    np.testing.assert_allclose(cell.T0, T0_ind, atol=1e-13)
    K_ind, C_ind = _independent_stiffness(st.nodes, members, P * T0_ind, EA, c)
    scale = np.abs(K_ind).max()
    assert np.max(np.abs(lin.K0 - K_ind)) < 1e-10 * scale
    assert np.max(np.abs(lin.C0 - C_ind)) < 1e-12
    # modes without the rigid-body motions: independent complement and eigensolver
    R = _rigid_motions(st.nodes)
    assert np.max(np.abs(K_ind @ R)) < 1e-10 * scale  # rigid motions cost nothing
    Q = scipy.linalg.null_space(R.T)
    mu_ind = scipy.linalg.eigh(Q.T @ C_ind @ Q, Q.T @ K_ind @ Q, eigvals_only=True)[::-1]  # mu = 1/lambda
    modes = relaxation_modes(lin, k=30)
    mu_lib = np.where(np.isfinite(modes.rates), 1.0 / modes.rates, 0.0)
    assert np.max(np.abs(mu_lib - mu_ind)) < 1e-8 * mu_ind.max()
    finite = mu_ind > 1e-9 * mu_ind.max()
    np.testing.assert_allclose(modes.rates[finite], 1.0 / mu_ind[finite], rtol=1e-8)
    assert np.sum(~finite) == 1  # one infinitesimal mechanism, undamped (C0 singular along it)
    # the library's rigid-body modes span the same space as the independent ones
    Rl = rigid_body_modes(cell.coords)
    assert Rl.shape[1] == 6
    assert np.linalg.norm(Rl - R @ np.linalg.lstsq(R, Rl, rcond=None)[0]) < 1e-10


def test_free_icosahedron_rigid_struts_summary():
    s, cell, lin = summarize(_icosahedron(), P=100.0)
    assert s.rigid_body_dof == 6 and s.prestressable and s.stable
    assert s.rank == 23 and s.self_stress_dim == 1 and s.mechanisms == 30 - 23  # 6 rigid + 1 mechanism
    assert "free-standing" in s.verdict and "prestressable and stable" in s.verdict


def test_summary_reports_not_prestressable():
    st = tenscell.model.paper_structure(0.0, math.radians(60), 1.0)  # beyond the regular member: IFs compressed
    s, cell, lin = summarize(st)
    assert not s.prestressable and cell is None and lin is None
    assert s.verdict.startswith("NOT prestressable") and s.rank == 24 and s.self_stress_dim == 9


# ---- the show command ------------------------------------------------------------------
def test_cli_show_paper_and_a_saved_lattice(tmp_path, capsys):
    from tenscell.cli import main

    shown = tmp_path / "show"
    assert main(["show", "paper", "--out", str(shown)]) == 0
    out = capsys.readouterr().out
    assert "rank of A      24" in out and "self-stresses  9" in out and "prestressable and stable" in out
    for name in ("paper_structure.png", "paper_modes.png", "paper_summary.txt"):
        assert (shown / name).stat().st_size > 0
    lattice = shown / "lattice.json"  # --save inside --out: part of the output set
    assert main(["show", "sheet", "--size", "2x2", "--out", str(shown), "--modes", "0", "--save", str(lattice)]) == 0
    assert "lattice.json" in (shown / "manifest.json").read_text()
    capsys.readouterr()
    assert main(["show", str(lattice), "--out", str(tmp_path / "again"), "--modes", "1"]) == 0
    out = capsys.readouterr().out
    assert "members        168 (actin 96, intermediate_filament 48, strut 24)" in out
    assert (tmp_path / "again" / "lattice_structure.png").exists()
    assert (tmp_path / "again" / "lattice_modes.png").exists()


def test_cli_show_errors_are_one_line(tmp_path, capsys):
    from tenscell.cli import main

    bad = _small(tmp_path, _set(["tendons", 3, "nodes"], [4, 4]))
    out = tmp_path / "out"  # an output set replaces its directory: never the one holding the input
    assert main(["show", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cell.json: tendon 3 joins node 4 to itself" in err[0]
    assert main(["show", "nonesuch", "--out", str(out)]) == 2
    assert "neither a file nor a built-in" in capsys.readouterr().err
    assert not out.exists() and [p.name for p in tmp_path.iterdir()] == ["cell.json"]  # nothing half-written


def test_cli_show_draws_a_structure_that_is_not_prestressable(tmp_path, capsys):
    from tenscell.cli import main

    path = tmp_path / "flat.json"
    save_structure(path, tenscell.model.paper_structure(0.0, math.radians(60.0), 1.0))
    assert main(["show", str(path), "--out", str(tmp_path / "out")]) == 0
    assert "NOT prestressable" in capsys.readouterr().out
    assert (tmp_path / "out" / "flat_structure.png").exists() and not (tmp_path / "out" / "flat_modes.png").exists()
