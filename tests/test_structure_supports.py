"""Per-direction supports (rollers) in structure files: the same structure, the same rules, errors with their line.

A file is read into the same ``Structure`` the API builds, so a roller-supported structure read back from its
file must give bit-identical K0 and G' (positions are written with repr precision, and K0 is assembled by the
same code from the same numbers in the same order); a bad entry is refused with the file, the line and the
entry, by the rules of :class:`tenscell.model.Structure` (the CLI exits 2 before any computation).
"""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import tenscell as tc
from tenscell.io.structure_files import load_structure_file, save_structure, structure_to_dict
from tenscell.model import StructureError, equilibrate, pin_jointed

from test_free_standing import snelson_prism


def _rollers():
    """The pin-jointed Snelson prism on a ball joint and two rollers (3 + 2 + 1 held directions)."""
    free = pin_jointed(snelson_prism(1.0, 1.0))
    return dataclasses.replace(free, fixed=(0,), supports=((2, "z"), (1, "zy")))


def test_a_roller_supported_file_gives_the_api_structure(tmp_path):
    api = _rollers()
    EA = np.where(np.array(api.families) == "strut", 100.0, 1.0)
    path = tmp_path / "rollers.json"
    save_structure(path, api, EA=EA, c=1.0)
    assert json.loads(path.read_text())["supports"] == [[1, "yz"], [2, "z"]]
    sf = load_structure_file(path)
    assert sf.structure.supports == api.supports == ((1, "yz"), (2, "z"))
    lin_api = tc.linearize(equilibrate(api), P=1.0, EA=EA, c=1.0)
    lin_file = tc.linearize(equilibrate(sf.structure), P=1.0, EA=sf.EA, c=sf.c)
    assert lin_file.basis is None and lin_file.K0.shape == (18 - 6, 18 - 6)  # 6 directions held, none free
    np.testing.assert_array_equal(np.asarray(lin_file.K0), np.asarray(lin_api.K0))
    f = np.logspace(-1, 1, 5)
    np.testing.assert_array_equal(tc.moduli(lin_file, f)[0], tc.moduli(lin_api, f)[0])
    # the supports change the answer: the free prism (rigid motions removed) has another stiffness
    lin_free = tc.linearize(equilibrate(pin_jointed(snelson_prism(1.0, 1.0))), P=1.0, EA=EA, c=1.0)
    assert lin_free.K0.shape[0] == 18 and lin_free.basis is not None


def test_show_counts_the_rigid_motions_supports_hold():
    """A held direction removes one rigid-body motion at most: 3 + 2 + 1 hold all six, 3 + 1 leave two, none six
    (what rigid_body_modes finds from the coordinates, independently)."""
    from tenscell.model.formfinding import rigid_body_modes
    from tenscell.summary import summarize

    free = pin_jointed(snelson_prism(1.0, 1.0))
    EA = np.where(np.array(free.families) == "strut", 1e4, 1.0)
    for s, k in ((_rollers(), 0), (dataclasses.replace(free, fixed=(0,), supports=((1, "z"),)), 2), (free, 6)):
        summary, cell, _ = summarize(s, P=1.0, EA=EA)
        assert summary.rigid_body_dof == k == rigid_body_modes(cell.coords).shape[1], s.supports


def test_supports_by_name_and_as_objects(tmp_path):
    obj = structure_to_dict(_rollers())
    for i, nd in enumerate(obj["nodes"]):
        nd["name"] = f"n{i}"
    obj["fixed"] = ["n0"]
    obj["supports"] = [{"node": "n2", "axes": "Z"}, ["n1", "zy"]]
    path = tmp_path / "named.json"
    path.write_text(json.dumps(obj))
    assert load_structure_file(path).structure.supports == ((1, "yz"), (2, "z"))


def _with_supports(tmp_path, entries, base=None) -> tuple:
    """A file whose supports list opens on line 2, one entry per line: entry k is on line 3 + k."""
    obj = structure_to_dict(base if base is not None else pin_jointed(snelson_prism(1.0, 1.0)))
    obj.pop("supports", None)
    body = json.dumps(obj, indent=1)
    text = '{\n "supports": [\n' + ",\n".join("  " + json.dumps(e) for e in entries) + "\n ],\n" + body[2:]
    path = tmp_path / "rollers.json"
    path.write_text(text)
    return path


@pytest.mark.parametrize("entries, k, message", [
    ([[3, "z"], [2, "w"]], 1, "axes 'w' must be some of 'x', 'y', 'z'"),
    ([[3, "xyz"]], 0, "node 3 is held in every direction; list it among the fixed nodes"),
    ([[3, "z"], [4, "x"], {"node": 3, "axes": "y"}], 2, "node 3 is listed twice (also in entry 0)"),
    ([[9, "z"]], 0, "refers to unknown node 9"),
    ([[3, "z"], {"node": 4, "axis": "z"}], 1, "unknown key 'axis'"),
    ([[3, 2]], 0, "'axes' must be a string"),
    ([[3, "z", 1]], 0, "must be {\"node\": ..., \"axes\": \"z\"} or [node, \"z\"]"),
    ([[3, ""]], 0, "axes '' must be some of"),
])
def test_bad_supports_are_refused_with_file_and_line(tmp_path, entries, k, message):
    path = _with_supports(tmp_path, entries)
    with pytest.raises(StructureError) as info:
        load_structure_file(path)
    text = str(info.value)
    assert text.startswith(f"rollers.json, line {3 + k}: supports entry {k}"), text
    assert message in text and "\n" not in text


def test_strut_ends_are_held_fully_or_not_at_all(tmp_path):
    """A rigid strut's end moves with the strut's angles: a roller there would be a constraint, not a
    coordinate removed; refused as in the API (the pin-jointed model, elastic struts, takes it)."""
    path = _with_supports(tmp_path, [[0, "z"]], base=snelson_prism(1.0, 1.0))
    with pytest.raises(StructureError, match=r"rollers\.json, line 3: supports entry 0: node 0 is the end of a "
                                             r"rigid strut.*pin_jointed"):
        load_structure_file(path)
    with pytest.raises(StructureError, match="end of a rigid strut"):
        dataclasses.replace(snelson_prism(1.0, 1.0), supports=((0, "z"),))


def test_cli_refuses_a_bad_support_in_one_line(tmp_path, capsys):
    from tenscell.cli import main

    path = _with_supports(tmp_path, [[3, "z"], [2, "w"]])
    out = tmp_path / "out"
    assert main(["show", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "rollers.json, line 4: supports entry 1: node 2: axes 'w'" in err[0], err
    assert not out.exists()
